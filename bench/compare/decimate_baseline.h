// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The vertex-removal baseline of the comparison: OpenMesh's DecimaterT (halfedge
// collapses) with ModQuadricT as priority and ModNormalFlippingT and ModAspectRatioT as
// binary guards; optionally ModRoundnessT as a further binary guard.
#include <cstddef>

#include "nurbsfront/core/mesh_types.h"

namespace nurbsfront::bench {

struct DecimateOptions {
  //! Also guard with ModRoundnessT (binary: no collapse may create a triangle whose
  //! smallest angle is below roundness_min_angle_deg). When that stops the decimation
  //! before the target, the angle is halved (quadrics kept) until the target is met or the
  //! angle is below 1 deg.
  bool roundness = false;
  double roundness_min_angle_deg = 20.0;
  //! ModNormalFlippingT: largest normal change of a face by a collapse (OpenMesh default 90).
  double max_normal_deviation_deg = 90.0;
  //! ModAspectRatioT: largest aspect ratio a collapse may create (OpenMesh default 5).
  double max_aspect_ratio = 5.0;
};

struct DecimateResult {
  TriMesh mesh;                 //!< without deleted elements
  double roundness_angle = 0.0;  //!< the roundness guard's last min angle (0 without it)
};

//! Decimates a copy of `input` to `target_vertices` vertices (or as close as the guards
//! allow).
[[nodiscard]] DecimateResult decimate(const TriMesh& input, std::size_t target_vertices, const DecimateOptions& options);

}  // namespace nurbsfront::bench
