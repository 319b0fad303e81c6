// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Sizing fields (target edge length) and metrics for the 2D mesher.

#include <functional>
#include <memory>
#include <vector>

#include <Eigen/Core>

namespace nurbsfront {

//! A Riemannian metric on the plane: lengths are measured as sqrt(d^T M(x) d). The surface
//! mesher passes the first fundamental form of its patch (I + grad f grad f^T for a height
//! field), so that sizes in the plane are sizes on the surface.
class Metric {
 public:
  virtual ~Metric() = default;
  //! The symmetric positive definite 2x2 tensor at x.
  [[nodiscard]] virtual Eigen::Matrix2d tensor(const Eigen::Vector2d& x) const = 0;
};

//! The target edge length h(x), measured in the metric.
//!
//! Three kinds: uniform; per input vertex (as the source method's node densities),
//! interpolated by inverse distance weighting and limited by cones of slope
//! (gradation - 1) from every vertex; or a user callback, limited on a background grid.
//! Always limited by the gradation: |grad h| <= gradation - 1.
struct SizingField {
  enum class Kind { Uniform, PerVertex, Callback };
  Kind kind = Kind::Uniform;  //!< which of the three sources below is used; default Uniform
  //! Uniform target edge length (length units); 0 = automatic: 1/40 of the domain's
  //! bounding-box diagonal. Default 0.
  double uniform_size = 0.0;
  //! Per-vertex target sizes (one per Pslg point, all > 0) for Kind::PerVertex.
  std::vector<double> vertex_sizes;
  //! User sizing function for Kind::Callback; must return a finite value > 0.
  std::function<double(const Eigen::Vector2d&)> callback;
  //! Most cells per side of the background grid of Kind::Callback.
  static constexpr int kMaxCallbackGridCells = 128;
  //! Kind::Callback: cells per side of the background grid that limits the callback's sizes
  //! by the gradation, in [1, kMaxCallbackGridCells]; 0 = kMaxCallbackGridCells. A caller whose callback is already graded and
  //! varies on a coarser scale (surfmesh's sampled sizes) saves the grid's sweeps. Default 0.
  int callback_grid_cells = 0;
  //! Gradation: neighbouring sizes may grow by at most this factor per unit of size,
  //! i.e. |grad h| <= gradation - 1. Must be > 1. Default 1.5.
  double gradation = 1.5;

  [[nodiscard]] static SizingField uniform(double h) {
    SizingField s;
    s.uniform_size = h;
    return s;
  }
  [[nodiscard]] static SizingField per_vertex(std::vector<double> sizes) {
    SizingField s;
    s.kind = Kind::PerVertex;
    s.vertex_sizes = std::move(sizes);
    return s;
  }
  [[nodiscard]] static SizingField from_callback(std::function<double(const Eigen::Vector2d&)> f) {
    SizingField s;
    s.kind = Kind::Callback;
    s.callback = std::move(f);
    return s;
  }
  //! \throw InvalidInput on a negative or non-finite size, a gradation <= 1, a missing callback.
  void validate() const;
};

}  // namespace nurbsfront
