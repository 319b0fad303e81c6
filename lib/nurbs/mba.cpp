// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/nurbs/mba.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <utility>

#include <Eigen/Dense>

#include "nurbsfront/core/error.h"
#include "nurbsfront/core/tolerances.h"
#include "nurbsfront/nurbs/mba_internal.h"

namespace nurbsfront::mba_detail {
namespace {

// The terms of one element (i, j) of mu D^T D x + eps x, added to o in the order in which
// the pass-by-pass product added them: the xx differences at i, i - 1 and i - 2 of the row;
// the yy differences of rows j - 2, j - 1 and j (ya, yb, yc; null where a row has none);
// the mixed ones of rows j - 1 (md) and j (me) at i and i - 1; then eps x. kAll: i is inside
// (2 <= i <= nx - 3), so every term of the row exists.
template <bool kAll>
inline double element(double o, std::size_t i, std::size_t nx, const double* xx, const double* ya, const double* yb,
                      const double* yc, const double* md, const double* me, double eps, double x) {
  if (kAll || i + 2 < nx) o += xx[i];
  if (kAll || (i >= 1 && i + 1 < nx)) o -= 2.0 * xx[i - 1];
  if (kAll || i >= 2) o += xx[i - 2];
  if (ya != nullptr) o += ya[i];
  if (yb != nullptr) o -= 2.0 * yb[i];
  if (yc != nullptr) o += yc[i];
  if (md != nullptr) {
    if (kAll || i + 1 < nx) o -= md[i];
    if (kAll || i >= 1) o += md[i - 1];
  }
  if (me != nullptr) {
    if (kAll || i + 1 < nx) o += me[i];
    if (kAll || i >= 1) o -= me[i - 1];
  }
  return o + eps * x;
}

// The inside elements 2 <= i <= nx - 3 of one row, the rows' terms known at compile time
// (a loop that vectorises); the same terms as element<true>.
template <bool kA, bool kB, bool kC, bool kD, bool kE>
void inside_row(double* o, const double* x, std::size_t nx, const double* xx, const double* ya, const double* yb,
                const double* yc, const double* md, const double* me, double eps) {
  for (std::size_t i = 2; i + 2 < nx; ++i) {
    double v = o[i];
    v += xx[i];
    v -= 2.0 * xx[i - 1];
    v += xx[i - 2];
    if constexpr (kA) v += ya[i];
    if constexpr (kB) v -= 2.0 * yb[i];
    if constexpr (kC) v += yc[i];
    if constexpr (kD) {
      v -= md[i];
      v += md[i - 1];
    }
    if constexpr (kE) {
      v += me[i];
      v -= me[i - 1];
    }
    o[i] = v + eps * x[i];
  }
}

}  // namespace

double add_thin_plate_product(const std::vector<double>& x, std::size_t nx, std::size_t ny, double mu, double eps,
                              std::vector<double>& out, std::vector<double>& scratch) {
  NURBSFRONT_ASSERT(nx >= 4 && ny >= 4 && x.size() == nx * ny && out.size() == nx * ny);
  // Rows of differences: xx of the current row, yy of the last three rows, mixed of the last two.
  scratch.resize(6 * nx);
  double* xx = scratch.data();
  double* yy[3] = {xx + nx, xx + 2 * nx, xx + 3 * nx};
  double* mixed[2] = {xx + 4 * nx, xx + 5 * nx};
  const double mu2 = 2.0 * mu;
  double dot = 0.0;
  for (std::size_t j = 0; j < ny; ++j) {
    const double* x0 = x.data() + j * nx;
    for (std::size_t i = 0; i + 2 < nx; ++i) xx[i] = mu * (x0[i] - 2.0 * x0[i + 1] + x0[i + 2]);
    if (j + 2 < ny) {
      const double *x1 = x0 + nx, *x2 = x1 + nx;
      double* d = yy[j % 3];
      for (std::size_t i = 0; i < nx; ++i) d[i] = mu * (x0[i] - 2.0 * x1[i] + x2[i]);
    }
    if (j + 1 < ny) {
      const double* x1 = x0 + nx;
      double* d = mixed[j % 2];
      for (std::size_t i = 0; i + 1 < nx; ++i) d[i] = mu2 * (x0[i] - x0[i + 1] - x1[i] + x1[i + 1]);
    }
    // The yy rows j - 2, j - 1, j and the mixed rows j - 1, j that have a difference.
    const double* ya = j >= 2 ? yy[(j - 2) % 3] : nullptr;
    const double* yb = j >= 1 && j + 1 < ny ? yy[(j - 1) % 3] : nullptr;
    const double* yc = j + 2 < ny ? yy[j % 3] : nullptr;
    const double* md = j >= 1 ? mixed[(j - 1) % 2] : nullptr;
    const double* me = j + 1 < ny ? mixed[j % 2] : nullptr;
    double* o = out.data() + j * nx;
    for (const std::size_t i : {std::size_t{0}, std::size_t{1}}) o[i] = element<false>(o[i], i, nx, xx, ya, yb, yc, md, me, eps, x0[i]);
    if (j == 0) {
      inside_row<false, false, true, false, true>(o, x0, nx, xx, ya, yb, yc, md, me, eps);
    } else if (j == 1) {
      inside_row<false, true, true, true, true>(o, x0, nx, xx, ya, yb, yc, md, me, eps);
    } else if (j + 2 < ny) {
      inside_row<true, true, true, true, true>(o, x0, nx, xx, ya, yb, yc, md, me, eps);
    } else if (j + 2 == ny) {
      inside_row<true, true, false, true, true>(o, x0, nx, xx, ya, yb, yc, md, me, eps);
    } else {
      inside_row<true, false, false, true, false>(o, x0, nx, xx, ya, yb, yc, md, me, eps);
    }
    for (const std::size_t i : {nx - 2, nx - 1}) o[i] = element<false>(o[i], i, nx, xx, ya, yb, yc, md, me, eps, x0[i]);
    for (std::size_t i = 0; i < nx; ++i) dot += x0[i] * o[i];
  }
  return dot;
}

}  // namespace nurbsfront::mba_detail

namespace nurbsfront {
namespace {

struct Lattice {
  int n_x = 0;
  int n_y = 0;
  std::vector<double> phi;
  [[nodiscard]] std::size_t stride() const { return static_cast<std::size_t>(n_x) + 3; }
};

// Position of a point in lattice units (level 0), clamped to [0, n].
struct LatticePoint {
  double u;
  double v;
};

// Cell offsets and cubic B-spline weights of a block of consecutive points at one level,
// stored by weight index so that the loops computing them vectorise.
constexpr std::size_t kBlock = 64;
struct WeightBlock {
  std::size_t offset[kBlock];  // index of phi_{i-1, j-1}
  double bx[4][kBlock];
  double by[4][kBlock];
};

inline void block_weights(const LatticePoint* p, std::size_t n, double scale, const Lattice& lattice, WeightBlock& w) {
  double s[kBlock];
  double t[kBlock];
  const int last_x = lattice.n_x - 1, last_y = lattice.n_y - 1;
  for (std::size_t q = 0; q < n; ++q) {
    const double u = p[q].u * scale;
    const double v = p[q].v * scale;
    const int i = std::min(static_cast<int>(u), last_x);
    const int j = std::min(static_cast<int>(v), last_y);
    s[q] = u - i;
    t[q] = v - j;
    w.offset[q] = static_cast<std::size_t>(j) * lattice.stride() + static_cast<std::size_t>(i);
  }
  constexpr double kSixth = 1.0 / 6.0;
  for (std::size_t q = 0; q < n; ++q) {  // detail::cubic_weights, written out per array
    const double s2 = s[q] * s[q], s3 = s2 * s[q], r = 1.0 - s[q];
    w.bx[0][q] = r * r * r * kSixth;
    w.bx[1][q] = (3.0 * s3 - 6.0 * s2 + 4.0) * kSixth;
    w.bx[2][q] = (-3.0 * s3 + 3.0 * s2 + 3.0 * s[q] + 1.0) * kSixth;
    w.bx[3][q] = s3 * kSixth;
  }
  for (std::size_t q = 0; q < n; ++q) {
    const double t2 = t[q] * t[q], t3 = t2 * t[q], r = 1.0 - t[q];
    w.by[0][q] = r * r * r * kSixth;
    w.by[1][q] = (3.0 * t3 - 6.0 * t2 + 4.0) * kSixth;
    w.by[2][q] = (-3.0 * t3 + 3.0 * t2 + 3.0 * t[q] + 1.0) * kSixth;
    w.by[3][q] = t3 * kSixth;
  }
}

// The cell offsets and weights of the points at one lattice resolution, block by block:
// stored once and shared by every sweep over the points at that resolution (a level's
// scatter and residual update; the final passes and both least-squares polishes with their
// sweep per iteration), or, with more points than kMaxCachedPoints, computed in each sweep:
// stored weights (72 bytes a point) that do not stay in cache cost more to stream than to
// compute (BM_MbaFit/1000000/10: 0.93 s stored, 0.35 s computed, CPU at load 15). The same
// numbers either way, so the same fit bit for bit.
class PointWeights {
 public:
  static constexpr std::size_t kMaxCachedPoints = std::size_t{1} << 16;
  PointWeights(const std::vector<LatticePoint>& pts, double scale, int n_x, int n_y, bool cache)
      : pts_(pts), scale_(scale), shape_{n_x, n_y, {}} {
    if (!cache) return;
    blocks_.resize(n_blocks());
    for (std::size_t b = 0; b < blocks_.size(); ++b) block_weights(pts.data() + b * kBlock, size(b), scale, shape_, blocks_[b]);
  }
  [[nodiscard]] std::size_t n_blocks() const { return (pts_.size() + kBlock - 1) / kBlock; }
  [[nodiscard]] bool cached() const { return !blocks_.empty(); }
  [[nodiscard]] std::size_t size(std::size_t b) const { return std::min(kBlock, pts_.size() - b * kBlock); }
  //! Block b: the stored one, or computed into `scratch`.
  [[nodiscard]] const WeightBlock& block(std::size_t b, WeightBlock& scratch) const {
    if (!blocks_.empty()) return blocks_[b];
    block_weights(pts_.data() + b * kBlock, size(b), scale_, shape_, scratch);
    return scratch;
  }

 private:
  const std::vector<LatticePoint>& pts_;
  double scale_;
  Lattice shape_;
  std::vector<WeightBlock> blocks_;
};

// The function of the coefficients phi (a lattice of the given stride) at point q of a
// weight block.
inline double block_value(const double* phi, std::size_t stride, const WeightBlock& w, std::size_t q) {
  // Rows weighted by by_l summed first (vectorised), then one dot product with bx.
  const double* c = phi + w.offset[q];
  Eigen::Array4d column = w.by[0][q] * Eigen::Map<const Eigen::Array4d>(c);
  for (std::size_t l = 1; l < 4; ++l) column += w.by[l][q] * Eigen::Map<const Eigen::Array4d>(c + l * stride);
  return w.bx[0][q] * column[0] + w.bx[1][q] * column[1] + w.bx[2][q] * column[2] + w.bx[3][q] * column[3];
}

// One level of B-spline approximation (BA) of the residuals r: every point proposes
// phi_c = w_c r / sum w^2 for its 16 coefficients, each coefficient takes the
// w^2-weighted mean of its proposals. `omega` holds each coefficient's sum of w^2, which
// depends on the weights only: when it has the lattice's size it is read and only the sums
// of w^2 phi_c are made (the final passes on one lattice share it: half the scatter's
// products), else it is made here beside them and stored. The same sums in the same order
// either way, so the same lattice bit for bit.
//
// With omega known and the weights stored, the per-point products that do not depend on r
// (bx_k^3, by_l^3 and sum w^2) are made once, in `cubes`, for all the passes on that lattice.
struct CubeBlock {
  double bx3[4][kBlock];
  double by3[4][kBlock];
  double sum_sq[kBlock];  // sum of w^2: (sum_k bx_k^2) (sum_l by_l^2)
};
Lattice approximate_level(const PointWeights& weights, const std::vector<double>& r, int n_x, int n_y,
                          std::vector<double>& omega, std::vector<CubeBlock>& cubes) {
  Lattice lattice{n_x, n_y, {}};
  const std::size_t size = lattice.stride() * (static_cast<std::size_t>(n_y) + 3);
  const std::size_t stride = lattice.stride();
  const bool known = omega.size() == size;
  // Without omega: delta (sum of w^2 phi_c) and omega side by side, one cache line per update.
  std::vector<double> acc(known ? size : 2 * size, 0.0);
  // Per point, the update of coefficient (k, l) is (w^3 r / sum w^2, w^2) with
  // w = bx_k by_l: the product of the pairs (bx_k^3, bx_k^2) and (by_l^3 r / sum w^2, by_l^2),
  // one row of four (delta, omega) pairs at a time (vectorised, two doubles per instruction);
  // with omega known, of bx_k^3 and by_l^3 r / sum w^2.
  using Row = Eigen::Array<double, 8, 1>;
  double factor[kBlock];
  WeightBlock scratch;
  if (known && weights.cached() && cubes.empty()) {
    cubes.resize(weights.n_blocks());
    for (std::size_t b = 0; b < weights.n_blocks(); ++b) {
      const WeightBlock& w = weights.block(b, scratch);
      CubeBlock& c = cubes[b];
      const std::size_t n = weights.size(b);
      for (std::size_t k = 0; k < 4; ++k)
        for (std::size_t q = 0; q < n; ++q) c.bx3[k][q] = (w.bx[k][q] * w.bx[k][q]) * w.bx[k][q];
      for (std::size_t l = 0; l < 4; ++l)
        for (std::size_t q = 0; q < n; ++q) c.by3[l][q] = (w.by[l][q] * w.by[l][q]) * w.by[l][q];
      for (std::size_t q = 0; q < n; ++q) {
        const double sx = w.bx[0][q] * w.bx[0][q] + w.bx[1][q] * w.bx[1][q] + w.bx[2][q] * w.bx[2][q] + w.bx[3][q] * w.bx[3][q];
        const double sy = w.by[0][q] * w.by[0][q] + w.by[1][q] * w.by[1][q] + w.by[2][q] * w.by[2][q] + w.by[3][q] * w.by[3][q];
        c.sum_sq[q] = sx * sy;
      }
    }
  }
  for (std::size_t b = 0; b < weights.n_blocks(); ++b) {
    const WeightBlock& w = weights.block(b, scratch);
    const std::size_t first = b * kBlock, n = weights.size(b);
    if (known && !cubes.empty()) {
      const CubeBlock& c = cubes[b];
      for (std::size_t q = 0; q < n; ++q) factor[q] = r[first + q] / c.sum_sq[q];
      for (std::size_t q = 0; q < n; ++q) {
        const Eigen::Array4d x(c.bx3[0][q], c.bx3[1][q], c.bx3[2][q], c.bx3[3][q]);
        for (std::size_t l = 0; l < 4; ++l) {
          Eigen::Map<Eigen::Array4d> a(acc.data() + w.offset[q] + l * stride);
          a += x * (c.by3[l][q] * factor[q]);
        }
      }
      continue;
    }
    for (std::size_t q = 0; q < n; ++q) {
      const double sx = w.bx[0][q] * w.bx[0][q] + w.bx[1][q] * w.bx[1][q] + w.bx[2][q] * w.bx[2][q] + w.bx[3][q] * w.bx[3][q];
      const double sy = w.by[0][q] * w.by[0][q] + w.by[1][q] * w.by[1][q] + w.by[2][q] * w.by[2][q] + w.by[3][q] * w.by[3][q];
      factor[q] = r[first + q] / (sx * sy);
    }
    if (known) {
      for (std::size_t q = 0; q < n; ++q) {
        Eigen::Array4d x;
        for (int k = 0; k < 4; ++k) x[k] = (w.bx[k][q] * w.bx[k][q]) * w.bx[k][q];
        for (int l = 0; l < 4; ++l) {
          const double b2 = w.by[l][q] * w.by[l][q];
          Eigen::Map<Eigen::Array4d> a(acc.data() + w.offset[q] + static_cast<std::size_t>(l) * stride);
          a += x * (b2 * w.by[l][q] * factor[q]);
        }
      }
      continue;
    }
    for (std::size_t q = 0; q < n; ++q) {
      Row x;
      for (int k = 0; k < 4; ++k) {
        const double b2 = w.bx[k][q] * w.bx[k][q];
        x[2 * k] = b2 * w.bx[k][q];
        x[2 * k + 1] = b2;
      }

      for (int l = 0; l < 4; ++l) {
        const double b2 = w.by[l][q] * w.by[l][q];
        Eigen::Map<Row> a(acc.data() + 2 * (w.offset[q] + static_cast<std::size_t>(l) * stride));
        a += x * Eigen::Array2d(b2 * w.by[l][q] * factor[q], b2).replicate<4, 1>();
      }
    }
  }
  lattice.phi.assign(size, 0.0);
  if (known) {
    for (std::size_t k = 0; k < size; ++k) {
      if (omega[k] > 0.0) lattice.phi[k] = acc[k] / omega[k];
    }
    return lattice;
  }
  omega.resize(size);
  for (std::size_t k = 0; k < size; ++k) {
    omega[k] = acc[2 * k + 1];
    if (acc[2 * k + 1] > 0.0) lattice.phi[k] = acc[2 * k] / acc[2 * k + 1];
  }
  return lattice;
}

// Subtracts the lattice's function from the residuals r; returns (max |r|, sum r^2).
std::pair<double, double> subtract_level(const Lattice& lattice, const PointWeights& weights, std::vector<double>& r) {
  double max_residual = 0.0;
  double sum_sq = 0.0;
  WeightBlock scratch;
  for (std::size_t b = 0; b < weights.n_blocks(); ++b) {
    const WeightBlock& w = weights.block(b, scratch);
    const std::size_t first = b * kBlock, n = weights.size(b);
    for (std::size_t q = 0; q < n; ++q) {
      const double z = block_value(lattice.phi.data(), lattice.stride(), w, q);
      double& rc = r[first + q];
      rc -= z;
      max_residual = std::max(max_residual, std::abs(rc));
      sum_sq += rc * rc;
    }
  }
  return {max_residual, sum_sq};
}

// out = B^T y (each point's value spread onto its 16 coefficients by their weights), and
// diagonal += the squared weights when diagonal is not null. With x not null, y is not read:
// each point's value is B x at that point instead (out = B^T B x, one sweep).
void scatter_points(const PointWeights& weights, const std::vector<double>* y, const std::vector<double>* x,
                    std::size_t stride, std::vector<double>& out, std::vector<double>* diagonal) {
  std::fill(out.begin(), out.end(), 0.0);
  WeightBlock scratch;
  for (std::size_t b = 0; b < weights.n_blocks(); ++b) {
    const WeightBlock& w = weights.block(b, scratch);
    const std::size_t first = b * kBlock, n = weights.size(b);
    for (std::size_t q = 0; q < n; ++q) {
      const double value = x != nullptr ? block_value(x->data(), stride, w, q) : (*y)[first + q];
      const Eigen::Array4d bx(w.bx[0][q], w.bx[1][q], w.bx[2][q], w.bx[3][q]);
      for (int l = 0; l < 4; ++l) {
        const std::size_t at = w.offset[q] + static_cast<std::size_t>(l) * stride;
        Eigen::Map<Eigen::Array4d>(out.data() + at) += (w.by[l][q] * value) * bx;
        if (diagonal != nullptr) Eigen::Map<Eigen::Array4d>(diagonal->data() + at) += (w.by[l][q] * w.by[l][q]) * bx * bx;
      }
    }
  }
}

// out += mu * diag(D^T D) for the thin-plate second differences D of a (n_x + 3) x (n_y + 3)
// coefficient lattice: xx and yy differences of three neighbours, and the mixed one of a
// 2 x 2 block weighted by 2 (the product D^T D x: add_thin_plate_product).
void add_thin_plate_diagonal(std::size_t nx, std::size_t ny, double mu, std::vector<double>& out) {
  auto at = [nx](std::size_t i, std::size_t j) { return j * nx + i; };
  auto stencil = [&](const std::size_t* idx, const double* coef, int size, double weight) {
    for (int k = 0; k < size; ++k) out[idx[k]] += weight * mu * (coef[k] * coef[k]);
  };
  constexpr double kSecond[3] = {1.0, -2.0, 1.0};
  constexpr double kMixed[4] = {1.0, -1.0, -1.0, 1.0};
  for (std::size_t j = 0; j < ny; ++j) {
    for (std::size_t i = 0; i < nx; ++i) {
      if (i + 2 < nx) {
        const std::size_t idx[3] = {at(i, j), at(i + 1, j), at(i + 2, j)};
        stencil(idx, kSecond, 3, 1.0);
      }
      if (j + 2 < ny) {
        const std::size_t idx[3] = {at(i, j), at(i, j + 1), at(i, j + 2)};
        stencil(idx, kSecond, 3, 1.0);
      }
      if (i + 1 < nx && j + 1 < ny) {
        const std::size_t idx[4] = {at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)};
        stencil(idx, kMixed, 4, 2.0);
      }
    }
  }
}

// B^T B of the points at one lattice resolution, stored as the 7 x 7 band of each coefficient
// that a point touches (the other rows are zero): the polishes' conjugate gradients apply it
// at every iteration, 49 products per touched coefficient instead of 32 per point (a finest
// cell holds several points), and both polishes of a fit share it. Built from the upper half
// (each pair of a point's 16 coefficients once) and mirrored.
class NormalMatrix {
 public:
  static constexpr std::size_t kBand = 7;
  static constexpr std::size_t kEntries = kBand * kBand;
  NormalMatrix(const PointWeights& weights, std::size_t nx, std::size_t ny) : nx_(nx), ny_(ny) {
    row_of_.assign(nx * ny, -1);
    WeightBlock scratch;
    for (std::size_t b = 0; b < weights.n_blocks(); ++b) {
      const WeightBlock& w = weights.block(b, scratch);
      for (std::size_t q = 0; q < weights.size(b); ++q)
        for (std::size_t l = 0; l < 4; ++l)
          for (std::size_t k = 0; k < 4; ++k) row_of_[w.offset[q] + l * nx + k] = 0;
    }
    for (std::size_t c = 0; c < row_of_.size(); ++c) {
      if (row_of_[c] < 0) continue;
      row_of_[c] = static_cast<int>(touched_.size());
      touched_.push_back(c);
    }
  }
  //! Rows that some point touches: the matrix is worth building when these are few.
  [[nodiscard]] std::size_t n_rows() const { return touched_.size(); }
  [[nodiscard]] bool built() const { return !pairs_.empty(); }
  void build(const PointWeights& weights) {
    band_.assign(touched_.size() * kEntries, 0.0);
    WeightBlock scratch;
    for (std::size_t b = 0; b < weights.n_blocks(); ++b) {
      const WeightBlock& w = weights.block(b, scratch);
      for (std::size_t q = 0; q < weights.size(b); ++q) {
        // Local copies: the band's stores cannot alias them.
        const double bx[4] = {w.bx[0][q], w.bx[1][q], w.bx[2][q], w.bx[3][q]};
        const double by[4] = {w.by[0][q], w.by[1][q], w.by[2][q], w.by[3][q]};
        const Eigen::Array4d bx4(bx[0], bx[1], bx[2], bx[3]);
        for (std::size_t l1 = 0; l1 < 4; ++l1) {
          // The four coefficients of a lattice row are touched together: consecutive rows.
          double* row = band_.data() + static_cast<std::size_t>(row_of_[w.offset[q] + l1 * nx_]) * kEntries;
          for (std::size_t k1 = 0; k1 < 4; ++k1, row += kEntries) {
            const double w1 = by[l1] * bx[k1];
            // Coefficients (l2, k2) after (l1, k1) in lattice order: the rest of row l1, rows below.
            const double w11 = w1 * by[l1];
            for (std::size_t k2 = k1; k2 < 4; ++k2) row[3 * kBand + 3 + k2 - k1] += w11 * bx[k2];
            for (std::size_t l2 = l1 + 1; l2 < 4; ++l2) {
              const double w12 = w1 * by[l2];
              // The four products and sums of a lattice row two at a time (the same numbers).
              Eigen::Map<Eigen::Array4d>(row + (3 + l2 - l1) * kBand + 3 - k1) += w12 * bx4;
            }
          }
        }
      }
    }
    // The lower half: entry (c, c + d) of row c is entry (c + d, c) of row c + d.
    const std::ptrdiff_t snx = static_cast<std::ptrdiff_t>(nx_);
    for (std::size_t r = 0; r < touched_.size(); ++r) {
      const std::ptrdiff_t c = static_cast<std::ptrdiff_t>(touched_[r]);
      for (std::size_t m = kEntries / 2 + 1; m < kEntries; ++m) {
        const double v = band_[r * kEntries + m];
        if (v == 0.0) continue;
        const std::ptrdiff_t dj = static_cast<std::ptrdiff_t>(m / kBand) - 3, di = static_cast<std::ptrdiff_t>(m % kBand) - 3;
        const auto other = static_cast<std::size_t>(row_of_[static_cast<std::size_t>(c + dj * snx + di)]);
        band_[other * kEntries + (kEntries - 1 - m)] = v;
      }
    }
    // Rows 2p and 2p + 1 interleaved entry by entry (an odd last row beside zeros), so that
    // apply() makes two rows' sums side by side, two doubles per instruction.
    const std::size_t n_pairs = (touched_.size() + 1) / 2;
    pairs_.assign(n_pairs * 2 * kEntries, 0.0);
    for (std::size_t r = 0; r < touched_.size(); ++r)
      for (std::size_t m = 0; m < kEntries; ++m) pairs_[(r / 2) * 2 * kEntries + 2 * m + r % 2] = band_[r * kEntries + m];
    band_.clear();
    band_.shrink_to_fit();
    padded_.assign((nx_ + 6) * (ny_ + 6), 0.0);
  }
  //! out = B^T B x (x and out: the nx x ny coefficients).
  void apply(const std::vector<double>& x, std::vector<double>& out) {
    const std::size_t pnx = nx_ + 6;
    for (std::size_t j = 0; j < ny_; ++j) std::copy_n(x.data() + j * nx_, nx_, padded_.data() + (j + 3) * pnx + 3);
    std::fill(out.begin(), out.end(), 0.0);
    // Two rows at a time: each lane sums its row's 49 products in the same order as one row
    // alone (the same numbers). Two coefficients side by side in a lattice row (most pairs)
    // read their two x values with one load.
    using Pair = Eigen::Array2d;
    for (std::size_t r = 0; r < touched_.size(); r += 2) {
      const bool two = r + 1 < touched_.size();
      const std::size_t c0 = touched_[r], c1 = two ? touched_[r + 1] : c0;
      const std::size_t i0 = c0 % nx_, j0 = c0 / nx_, i1 = c1 % nx_, j1 = c1 / nx_;
      const double* a = pairs_.data() + r * kEntries;  // pair r / 2
      Pair sum = Pair::Zero();
      if (j1 == j0 && i1 == i0 + 1) {
        for (std::size_t dj = 0; dj < kBand; ++dj, a += 2 * kBand) {
          const double* xr = padded_.data() + (j0 + dj) * pnx + i0;
          for (std::size_t di = 0; di < kBand; ++di) sum += Eigen::Map<const Pair>(a + 2 * di) * Eigen::Map<const Pair>(xr + di);
        }
      } else {
        for (std::size_t dj = 0; dj < kBand; ++dj, a += 2 * kBand) {
          const double* xr0 = padded_.data() + (j0 + dj) * pnx + i0;
          const double* xr1 = padded_.data() + (j1 + dj) * pnx + i1;
          for (std::size_t di = 0; di < kBand; ++di) sum += Eigen::Map<const Pair>(a + 2 * di) * Pair(xr0[di], xr1[di]);
        }
      }
      out[c0] = sum[0];
      if (two) out[c1] = sum[1];
    }
  }

 private:
  std::size_t nx_, ny_;
  std::vector<int> row_of_;
  std::vector<std::size_t> touched_;
  std::vector<double> band_;   // while building: row r's 7 x 7 entries at r * kEntries
  std::vector<double> pairs_;  // built: rows 2p and 2p + 1 interleaved
  std::vector<double> padded_;
};

// The least-squares polish (FitOptions::least_squares_iterations): the change delta of the
// n_x x n_y lattice's coefficients minimising |B delta - r|^2 + mu |D delta|^2 + eps |delta|^2
// by Jacobi-preconditioned conjugate gradients on the normal equations (matrix-free: B is
// applied point by point, D by its stencils). mu = smoothing x the mean data weight of a
// coefficient with data; eps = 1e-9 of it keeps coefficients without data at 0 change.
// `n_data` (optional) receives the number of coefficients with data.
Lattice least_squares_polish(const PointWeights& weights, const std::vector<double>& r, int n_x, int n_y, int iterations,
                             double smoothing, std::unique_ptr<NormalMatrix>& normal, std::size_t* n_data = nullptr) {
  Lattice delta{n_x, n_y, {}};
  const std::size_t nx = delta.stride(), ny = static_cast<std::size_t>(n_y) + 3, size = nx * ny;
  delta.phi.assign(size, 0.0);
  std::vector<double> b(size), diagonal(size, 0.0);
  scatter_points(weights, &r, nullptr, nx, b, &diagonal);
  double data_weight = 0.0;
  std::size_t n_with_data = 0;
  for (const double d : diagonal) {
    if (d > 0.0) {
      data_weight += d;
      ++n_with_data;
    }
  }
  if (n_data != nullptr) *n_data = n_with_data;
  if (n_with_data == 0) return delta;
  data_weight /= static_cast<double>(n_with_data);
  const double mu = smoothing * data_weight, eps = 1e-9 * data_weight;
  add_thin_plate_diagonal(nx, ny, mu, diagonal);
  for (double& d : diagonal) d += eps;

  std::vector<double> residual = b, z(size), a_p(size);
  // B^T B as a stored band when a touched coefficient has more than a few points (49
  // products a row against 32 a point), else by a sweep over the points.
  if (!normal) {
    normal = std::make_unique<NormalMatrix>(weights, nx, ny);
    constexpr std::size_t kMinPointsPerRow = 3;
    if (normal->n_rows() * kMinPointsPerRow <= r.size()) normal->build(weights);
  }
  const bool banded = normal->built();
  std::vector<double> scratch;
  auto apply = [&](const std::vector<double>& x, std::vector<double>& out) {  // out = A x; returns x . out
    if (banded) {
      normal->apply(x, out);
    } else {
      scatter_points(weights, nullptr, &x, nx, out, nullptr);
    }
    return mba_detail::add_thin_plate_product(x, nx, ny, mu, eps, out, scratch);
  };
  for (std::size_t k = 0; k < size; ++k) z[k] = residual[k] / diagonal[k];
  std::vector<double> p = z;
  double rz = 0.0, b_norm = 0.0;
  for (std::size_t k = 0; k < size; ++k) {
    rz += residual[k] * z[k];
    b_norm += b[k] * b[k];
  }
  for (int it = 0; it < iterations && rz > 0.0; ++it) {
    const double p_ap = apply(p, a_p);
    if (!(p_ap > 0.0)) break;
    const double alpha = rz / p_ap;
    // The preconditioned residual in the same loop (unused when the loop stops here).
    double r_norm = 0.0, rz_next = 0.0;
    for (std::size_t k = 0; k < size; ++k) {
      delta.phi[k] += alpha * p[k];
      residual[k] -= alpha * a_p[k];
      r_norm += residual[k] * residual[k];
      z[k] = residual[k] / diagonal[k];
      rz_next += residual[k] * z[k];
    }
    if (r_norm <= tolerance::kLeastSquaresCgRelative * tolerance::kLeastSquaresCgRelative * b_norm) break;
    const double beta = rz_next / rz;
    rz = rz_next;
    for (std::size_t k = 0; k < size; ++k) p[k] = z[k] + beta * p[k];
  }
  return delta;
}

struct Bilinear {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  Eigen::Vector2d half = Eigen::Vector2d::Ones();
  Eigen::Vector4d c = Eigen::Vector4d::Zero();
  [[nodiscard]] double operator()(double x, double y) const {
    const double a = (x - centre.x()) / half.x();
    const double b = (y - centre.y()) / half.y();
    return c[0] + c[1] * a + c[2] * b + c[3] * a * b;
  }
};

// Least-squares bilinear function in coordinates normalised to the rectangle ([-1, 1]^2),
// which keeps the 4x4 normal equations well conditioned. Rank-deficient samples (e.g. all
// points on two lines x = const) get the minimum-norm solution.
Bilinear fit_bilinear(const std::vector<Eigen::Vector3d>& xyz, const Rectangle& rect) {
  Bilinear g;
  g.centre = 0.5 * (rect.min + rect.max);
  g.half = 0.5 * (rect.max - rect.min);
  Eigen::Matrix4d ata = Eigen::Matrix4d::Zero();
  Eigen::Vector4d atz = Eigen::Vector4d::Zero();
  for (const auto& p : xyz) {
    const double a = (p.x() - g.centre.x()) / g.half.x();
    const double b = (p.y() - g.centre.y()) / g.half.y();
    const Eigen::Vector4d row(1.0, a, b, a * b);
    ata.noalias() += row * row.transpose();
    atz += row * p.z();
  }
  g.c = ata.completeOrthogonalDecomposition().solve(atz);
  return g;
}

void check_points(const std::vector<Eigen::Vector3d>& points) {
  if (points.empty()) throw InvalidInput("fit_height_field: no points");
  for (std::size_t k = 0; k < points.size(); ++k) {
    if (!points[k].allFinite()) {
      throw InvalidInput("fit_height_field: point " + std::to_string(k) + " has a non-finite coordinate");
    }
  }
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : points) mean += p.head<2>();
  mean /= static_cast<double>(points.size());
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const auto& p : points) {
    const Eigen::Vector2d d = p.head<2>() - mean;
    cov.noalias() += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
  const double big = std::max(eig.eigenvalues()[1], 0.0);
  const double small = std::max(eig.eigenvalues()[0], 0.0);
  if (!(big > 0.0)) throw InvalidInput("fit_height_field: all points coincide in the xy-plane (zero-size rectangle)");
  if (std::sqrt(small) <= tolerance::kCollinearRelative * std::sqrt(big)) {
    throw InvalidInput("fit_height_field: all points are collinear in the xy-plane; no height field over a line");
  }
}

}  // namespace

void FitOptions::validate() const {
  if (!(tolerance >= 0.0) || !std::isfinite(tolerance)) throw InvalidInput("FitOptions: tolerance must be >= 0 and finite");
  if (!(relative_tolerance >= 0.0) || !std::isfinite(relative_tolerance)) {
    throw InvalidInput("FitOptions: relative_tolerance must be >= 0 and finite");
  }
  if (max_levels < 1 || max_levels > 20) throw InvalidInput("FitOptions: max_levels must be in [1, 20]");
  if (!(min_spacing >= 0.0) || !std::isfinite(min_spacing)) {
    throw InvalidInput("FitOptions: min_spacing must be >= 0 and finite");
  }
  if (base_cells < 1 || base_cells > 4096) throw InvalidInput("FitOptions: base_cells must be in [1, 4096]");
  if (max_control_points < 16) throw InvalidInput("FitOptions: max_control_points must be at least 16");
  if (final_passes < 0 || final_passes > 1000) throw InvalidInput("FitOptions: final_passes must be in [0, 1000]");
  if (least_squares_iterations < 0 || least_squares_iterations > 100000) {
    throw InvalidInput("FitOptions: least_squares_iterations must be in [0, 100000]");
  }
  if (!(least_squares_smoothing >= 0.0) || !std::isfinite(least_squares_smoothing)) {
    throw InvalidInput("FitOptions: least_squares_smoothing must be >= 0 and finite");
  }
  if (!(least_squares_fine_smoothing >= 0.0) || !std::isfinite(least_squares_fine_smoothing)) {
    throw InvalidInput("FitOptions: least_squares_fine_smoothing must be >= 0 and finite");
  }
  if (!(least_squares_fine_below >= 0.0) || !std::isfinite(least_squares_fine_below)) {
    throw InvalidInput("FitOptions: least_squares_fine_below must be >= 0 and finite");
  }
  if (domain) domain->validate();
}

const char* to_string(FitStop stop) {
  switch (stop) {
    case FitStop::kTolerance: return "tolerance reached";
    case FitStop::kLevelLimit: return "level limit";
    case FitStop::kSpacingLimit: return "minimum spacing";
    case FitStop::kSizeLimit: return "lattice size limit";
  }
  return "unknown";
}

FitResult fit_height_field(const std::vector<Eigen::Vector3d>& points, const FitOptions& options) {
  options.validate();
  check_points(points);

  Rectangle rect;
  if (options.domain) {
    rect = *options.domain;
  } else {
    rect.min = points.front().head<2>();
    rect.max = rect.min;
    for (const auto& p : points) {
      rect.min = rect.min.cwiseMin(p.head<2>());
      rect.max = rect.max.cwiseMax(p.head<2>());
    }
  }
  if (!(rect.width() > tolerance::kZeroLengthRelative * rect.diagonal()) ||
      !(rect.height() > tolerance::kZeroLengthRelative * rect.diagonal())) {
    throw InvalidInput("fit_height_field: zero-size rectangle (width " + std::to_string(rect.width()) + ", height " +
                       std::to_string(rect.height()) + ")");
  }

  FitResult result;
  result.n_points = points.size();
  result.tolerance = options.tolerance > 0.0 ? options.tolerance : options.relative_tolerance * rect.diagonal();

  // Level-0 lattice: base_cells along the shorter side.
  const double shorter = std::min(rect.width(), rect.height());
  const int n_x0 = std::max(1, static_cast<int>(std::lround(options.base_cells * rect.width() / shorter)));
  const int n_y0 = std::max(1, static_cast<int>(std::lround(options.base_cells * rect.height() / shorter)));
  const auto lattice_size = [](double nx, double ny) { return (nx + 3.0) * (ny + 3.0); };
  if (lattice_size(n_x0, n_y0) > static_cast<double>(options.max_control_points)) {
    throw InvalidInput("fit_height_field: the rectangle's aspect ratio needs a level-0 lattice above max_control_points");
  }

  // Points clamped into the rectangle, in level-0 lattice units.
  std::vector<Eigen::Vector3d> clamped(points.size());
  std::vector<LatticePoint> pts(points.size());
  for (std::size_t c = 0; c < points.size(); ++c) {
    const Eigen::Vector2d xy = points[c].head<2>().cwiseMax(rect.min).cwiseMin(rect.max);
    if (xy != points[c].head<2>()) ++result.n_outside;
    clamped[c] = {xy.x(), xy.y(), points[c].z()};
    pts[c] = {std::clamp((xy.x() - rect.min.x()) / rect.width() * n_x0, 0.0, static_cast<double>(n_x0)),
              std::clamp((xy.y() - rect.min.y()) / rect.height() * n_y0, 0.0, static_cast<double>(n_y0))};
  }

  // Visit the points in cell order (stable sort by the cell on a lattice of up to 128 x 128
  // level-0 cells): the scattered updates of every level then stay in cache. Only the
  // internal order changes; the fitted function does not depend on it beyond round-off.
  // A counting sort when there are fewer cells than a few per point; otherwise (a patch
  // whose lattice was fitted to its spacing can have millions of cells and a few thousand
  // points) the keys (cell, index) are sorted, which gives the same order.
  {
    const int sort_level = std::min(options.max_levels - 1, 7);
    const std::size_t bx = static_cast<std::size_t>(n_x0) << sort_level;
    const std::size_t by = static_cast<std::size_t>(n_y0) << sort_level;
    constexpr std::size_t kMaxKey = std::size_t{1} << 32;
    if (pts.size() > 1 && bx * by <= options.max_control_points && bx * by <= kMaxKey && pts.size() <= kMaxKey) {
      const double sx = static_cast<double>(std::size_t{1} << sort_level);
      std::vector<std::uint64_t> key(pts.size());  // cell << 32 | point index
      for (std::size_t c = 0; c < pts.size(); ++c) {
        const std::size_t i = std::min(static_cast<std::size_t>(pts[c].u * sx), bx - 1);
        const std::size_t j = std::min(static_cast<std::size_t>(pts[c].v * sx), by - 1);
        key[c] = (static_cast<std::uint64_t>(j * bx + i) << 32) | c;
      }
      constexpr std::size_t kCellsPerPoint = 4;
      if (bx * by <= kCellsPerPoint * pts.size()) {
        std::vector<std::size_t> start(bx * by + 1, 0);
        for (const std::uint64_t k : key) ++start[(k >> 32) + 1];
        for (std::size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
        std::vector<std::uint64_t> sorted(key.size());
        for (const std::uint64_t k : key) sorted[start[k >> 32]++] = k;
        key.swap(sorted);
      } else {
        std::sort(key.begin(), key.end());
      }
      std::vector<LatticePoint> sorted_pts(pts.size());
      std::vector<Eigen::Vector3d> sorted_clamped(pts.size());
      for (std::size_t at = 0; at < pts.size(); ++at) {
        const std::size_t c = key[at] & (kMaxKey - 1);
        sorted_pts[at] = pts[c];
        sorted_clamped[at] = clamped[c];
      }
      pts.swap(sorted_pts);
      clamped.swap(sorted_clamped);
    }
  }

  BicubicHeightField field(rect, n_x0, n_y0);
  std::vector<double> r(points.size());
  if (options.linear_precision) {
    const Bilinear g = fit_bilinear(clamped, rect);
    // A bilinear function is reproduced exactly by coefficients at the Greville points.
    for (int j = -1; j <= n_y0 + 1; ++j) {
      for (int i = -1; i <= n_x0 + 1; ++i) {
        field.set_coefficient(i, j, g(rect.min.x() + i * field.spacing_x(), rect.min.y() + j * field.spacing_y()));
      }
    }
    for (std::size_t c = 0; c < points.size(); ++c) r[c] = clamped[c].z() - g(clamped[c].x(), clamped[c].y());
  } else {
    for (std::size_t c = 0; c < points.size(); ++c) r[c] = clamped[c].z();
  }
  double max_residual = 0.0;
  for (double x : r) max_residual = std::max(max_residual, std::abs(x));
  result.base_max_residual = max_residual;

  report_progress(options.progress, "fit", 0.0);
  // The last level's weights and sums of squared weights (approximate_level): the final
  // passes and the polishes run on that lattice and reuse them.
  std::optional<PointWeights> finest;
  std::vector<double> omega;
  std::vector<CubeBlock> cubes;
  for (int level = 0;; ++level) {
    const double scale = std::ldexp(1.0, level);
    const double n_xd = n_x0 * scale;  // doubles: no int overflow before the size check
    const double n_yd = n_y0 * scale;
    if (level > 0) {
      if (max_residual <= result.tolerance) {
        result.stop = FitStop::kTolerance;
        break;
      }
      if (level >= options.max_levels) {
        result.stop = FitStop::kLevelLimit;
        break;
      }
      if (std::min(rect.width() / n_xd, rect.height() / n_yd) < options.min_spacing) {
        result.stop = FitStop::kSpacingLimit;
        break;
      }
      if (lattice_size(n_xd, n_yd) > static_cast<double>(options.max_control_points)) {
        result.stop = FitStop::kSizeLimit;
        break;
      }
    }
    const int n_x = static_cast<int>(n_xd);
    const int n_y = static_cast<int>(n_yd);
    omega.clear();
    cubes.clear();
    const PointWeights& weights = finest.emplace(pts, scale, n_x, n_y, pts.size() <= PointWeights::kMaxCachedPoints);
    const Lattice lattice = approximate_level(weights, r, n_x, n_y, omega, cubes);
    double sum_sq = 0.0;
    std::tie(max_residual, sum_sq) = subtract_level(lattice, weights, r);
    FitLevel report;
    report.level = level;
    report.n_cells_x = n_x;
    report.n_cells_y = n_y;
    report.spacing_x = rect.width() / n_x;
    report.spacing_y = rect.height() / n_y;
    report.max_residual = max_residual;
    report.rms_residual = std::sqrt(sum_sq / static_cast<double>(pts.size()));
    result.levels.push_back(report);

    if (level > 0) field = field.refined();
    auto& coefficients = field.mutable_coefficients();
    NURBSFRONT_ASSERT(coefficients.size() == lattice.phi.size());
    for (std::size_t k = 0; k < coefficients.size(); ++k) coefficients[k] += lattice.phi[k];
    report_progress(options.progress, "fit", static_cast<double>(level + 1) / options.max_levels);
    if (level + 1 >= options.max_levels && max_residual > result.tolerance) {
      result.stop = FitStop::kLevelLimit;
      break;
    }
    if (level + 1 >= options.max_levels) {
      result.stop = FitStop::kTolerance;
      break;
    }
  }
  if (result.stop != FitStop::kTolerance) {
    // Further passes on the finest lattice: same BA, same resolution, residual shrinking.
    const int n_x = field.n_cells_x();
    const int n_y = field.n_cells_y();
    // The finest level's lattice (the loop always makes level 0, and the field was refined
    // with every level): its weights are the ones at scale n_x / n_x0.
    NURBSFRONT_ASSERT(finest && !result.levels.empty() && result.levels.back().n_cells_x == n_x &&
                      result.levels.back().n_cells_y == n_y);
    const PointWeights& weights = *finest;
    for (int pass = 0; pass < options.final_passes && max_residual > result.tolerance; ++pass) {
      const Lattice lattice = approximate_level(weights, r, n_x, n_y, omega, cubes);
      max_residual = subtract_level(lattice, weights, r).first;
      auto& coefficients = field.mutable_coefficients();
      for (std::size_t k = 0; k < coefficients.size(); ++k) coefficients[k] += lattice.phi[k];
      result.final_pass_max_residual.push_back(max_residual);
    }
    if (options.least_squares_iterations > 0 && max_residual > result.tolerance) {
      std::size_t n_data = 0;
      std::unique_ptr<NormalMatrix> normal;  // shared by both polishes
      const Lattice delta = least_squares_polish(weights, r, n_x, n_y, options.least_squares_iterations,
                                                 options.least_squares_smoothing, normal, &n_data);
      max_residual = subtract_level(delta, weights, r).first;
      auto& coefficients = field.mutable_coefficients();
      for (std::size_t k = 0; k < coefficients.size(); ++k) coefficients[k] += delta.phi[k];
      result.final_pass_max_residual.push_back(max_residual);
      if (options.least_squares_fine_smoothing > 0.0 && max_residual <= options.least_squares_fine_below &&
          pts.size() >= n_data) {
        const Lattice fine = least_squares_polish(weights, r, n_x, n_y, options.least_squares_iterations,
                                                  options.least_squares_fine_smoothing, normal);
        max_residual = subtract_level(fine, weights, r).first;
        for (std::size_t k = 0; k < coefficients.size(); ++k) coefficients[k] += fine.phi[k];
        result.final_pass_max_residual.push_back(max_residual);
      }
    }
  }
  report_progress(options.progress, "fit", 1.0);
  result.field = std::move(field);
  return result;
}

}  // namespace nurbsfront
