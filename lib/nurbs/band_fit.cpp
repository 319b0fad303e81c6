// SPDX-License-Identifier: BSD-3-Clause
// Band-constrained height-field fit: a P-spline (third-difference penalty) on the bicubic
// lattice, solved by sparse Cholesky, with an active set of the bands the surface misses.
// Not built on fit_height_field (MBA): MBA has no smoothness prior, so a flat terrace that
// lies inside all its bands stays flat; the third-derivative prior is what carries the
// curvature of the neighbouring terraces over it.

#include "nurbsfront/nurbs/band_fit.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>

#include "nurbsfront/core/error.h"
#include "nurbsfront/core/tolerances.h"

namespace nurbsfront {
namespace {

using Triplets = std::vector<Eigen::Triplet<double>>;

// Diagonal regularisation (the data weights are about 1 per sample): only makes the system
// definite should the samples not determine the penalty's null space (the quadrics); far
// below any data term, and not scaled with the penalty, which would bias quadrics.
constexpr double kRidge = 1e-12;
// Bisection steps for a crossing (2^-40 of the band's length).
constexpr int kBisectionSteps = 40;
// Step halvings of the line search at most.
constexpr int kLineSearchSteps = 12;
// Preconditioned conjugate gradient steps at most before a new factorisation (their
// stopping residual: tolerance::kBandPcgRelative).
constexpr int kMaxPcgSteps = 40;
// Bands whose state may differ from the last factorisation's for a solve by preconditioned
// conjugate gradients instead of a new factorisation (occupancy torus at 64 cells: 4 to 32
// cut the fits' CPU time by 6-12%; with no limit, the steps cost 35% more than they saved).
constexpr std::size_t kMaxChangedBands = 16;

// The 16 coefficient indices and tensor weights of the field at (x, y), matching
// BicubicHeightField::value (border cells extrapolate outside the rectangle).
struct Stencil {
  std::array<int, 16> index{};
  std::array<double, 16> weight{};
};

// The cell holding x on the field's lattice, as the field's own evaluation finds it.
int locate(double x, double x0, double h, int n, double& s) {
  const detail::Cell c = detail::locate_cell(x, x0, 1.0 / h, n);
  s = c.s;
  return c.index;
}

Stencil stencil(const BicubicHeightField& field, double x, double y) {
  double s = 0.0;
  double t = 0.0;
  const int i = locate(x, field.domain().min.x(), field.spacing_x(), field.n_cells_x(), s);
  const int j = locate(y, field.domain().min.y(), field.spacing_y(), field.n_cells_y(), t);
  double bx[4];
  double by[4];
  detail::cubic_weights(s, bx);
  detail::cubic_weights(t, by);
  const int stride = field.n_cells_x() + 3;
  Stencil out;
  for (int l = 0; l < 4; ++l)
    for (int k = 0; k < 4; ++k) {
      out.index[static_cast<std::size_t>(4 * l + k)] = (j + l) * stride + (i + k);
      out.weight[static_cast<std::size_t>(4 * l + k)] = bx[k] * by[l];
    }
  return out;
}

void add_data(const Stencil& st, double z, double w, Triplets& a, Eigen::VectorXd& rhs) {
  for (std::size_t u = 0; u < 16; ++u) {
    rhs[st.index[u]] += w * z * st.weight[u];
    for (std::size_t v = 0; v < 16; ++v) a.emplace_back(st.index[u], st.index[v], w * st.weight[u] * st.weight[v]);
  }
}

// Calls visit(ax, ay, i, j, idx, coef, m, scale) for every third difference
// Delta_x^ax Delta_y^ay (ax + ay = 3) of the coefficients, with the m coefficient indices and
// signed binomial weights it combines and the weight scale = lambda C(3, ax) h_x h_y /
// (h_x^(2 ax) h_y^(2 ay)) of its square in the discrete third-derivative energy
// lambda sum over nodes of C(3, a) (Delta_x^a Delta_y^b c / (h_x^a h_y^b))^2 h_x h_y
// (rotation invariant in the continuum). (i, j) is the first coefficient of the difference.
template <typename Visit>
void for_each_third_difference(int n_x, int n_y, double h_x, double h_y, double lambda, Visit&& visit) {
  const int nx = n_x + 3;
  const int ny = n_y + 3;
  static constexpr std::array<std::array<double, 4>, 4> kBinomialSigned{{
      {1.0, 0.0, 0.0, 0.0}, {-1.0, 1.0, 0.0, 0.0}, {1.0, -2.0, 1.0, 0.0}, {-1.0, 3.0, -3.0, 1.0}}};
  static constexpr std::array<double, 4> kMultiplicity{1.0, 3.0, 3.0, 1.0};
  for (int ax = 0; ax <= 3; ++ax) {
    const int ay = 3 - ax;
    const double scale = lambda * kMultiplicity[static_cast<std::size_t>(ax)] * h_x * h_y /
                         (std::pow(h_x, 2 * ax) * std::pow(h_y, 2 * ay));
    for (int j = 0; j + ay < ny; ++j)
      for (int i = 0; i + ax < nx; ++i) {
        std::array<int, 16> idx{};
        std::array<double, 16> coef{};
        int m = 0;
        for (int q = 0; q <= ay; ++q)
          for (int p = 0; p <= ax; ++p) {
            idx[static_cast<std::size_t>(m)] = (j + q) * nx + (i + p);
            coef[static_cast<std::size_t>(m)] = kBinomialSigned[static_cast<std::size_t>(ax)][static_cast<std::size_t>(p)] *
                                                kBinomialSigned[static_cast<std::size_t>(ay)][static_cast<std::size_t>(q)];
            ++m;
          }
        visit(ax, ay, i, j, idx, coef, m, scale);
      }
  }
}

// The penalty's matrix: scale (sum_u coef_u c_u)^2 for every third difference.
void add_penalty(int n_x, int n_y, double h_x, double h_y, double lambda, Triplets& a) {
  for_each_third_difference(n_x, n_y, h_x, h_y, lambda,
                            [&](int, int, int, int, const std::array<int, 16>& idx, const std::array<double, 16>& coef, int m,
                                double scale) {
                              for (int u = 0; u < m; ++u)
                                for (int v = 0; v < m; ++v)
                                  a.emplace_back(idx[static_cast<std::size_t>(u)], idx[static_cast<std::size_t>(v)],
                                                 scale * coef[static_cast<std::size_t>(u)] * coef[static_cast<std::size_t>(v)]);
                            });
}

// The third derivative d^3 f / dx^ax dy^ay that a surface with the second derivatives and
// slope of `j` and a parallel second fundamental form (nabla II = 0: spheres, cylinders,
// planes; locally nearly so for any smooth surface of slowly varying curvature) has. For a
// graph, nabla_k II_ij = (f_ijk - (f_ij a_k + f_ik a_j + f_jk a_i) / W^2) / W with
// a = Hess f grad f and W^2 = 1 + |grad f|^2, so its target is the bracket's second term.
double parallel_third_derivative(const HeightJet& j, int ax) {
  const double w2 = 1.0 + j.zx * j.zx + j.zy * j.zy;
  const double a_x = j.zxx * j.zx + j.zxy * j.zy;
  const double a_y = j.zxy * j.zx + j.zyy * j.zy;
  switch (ax) {
    case 3: return 3.0 * j.zxx * a_x / w2;
    case 2: return (j.zxx * a_y + 2.0 * j.zxy * a_x) / w2;
    case 1: return (j.zyy * a_x + 2.0 * j.zxy * a_y) / w2;
    default: return 3.0 * j.zyy * a_y / w2;
  }
}

// The penalty's right-hand side when every third difference is pulled towards the third
// derivative a surface of parallel second fundamental form with the first and second
// derivatives of `field` would have (at the difference's centre), where that centre lies in
// an occupied lattice cell (elsewhere the target stays 0: the field is extrapolated there).
void add_penalty_target(const BicubicHeightField& field, const std::vector<std::uint8_t>& occupied, double lambda,
                        Eigen::VectorXd& rhs) {
  const int n_x = field.n_cells_x();
  const int n_y = field.n_cells_y();
  const double h_x = field.spacing_x();
  const double h_y = field.spacing_y();
  const Eigen::Vector2d origin = field.domain().min;
  for_each_third_difference(
      n_x, n_y, h_x, h_y, lambda,
      [&](int ax, int ay, int i, int j, const std::array<int, 16>& idx, const std::array<double, 16>& coef, int m, double scale) {
        // Coefficient k is the B-spline centred at origin + (k - 1) h.
        const double u = static_cast<double>(i) - 1.0 + 0.5 * ax;
        const double v = static_cast<double>(j) - 1.0 + 0.5 * ay;
        if (u < 0.0 || v < 0.0 || u >= n_x || v >= n_y) return;
        if (occupied[static_cast<std::size_t>(v) * static_cast<std::size_t>(n_x) + static_cast<std::size_t>(u)] == 0) return;
        const HeightJet jet = field.jet(origin.x() + u * h_x, origin.y() + v * h_y);
        const double target = parallel_third_derivative(jet, ax) * std::pow(h_x, ax) * std::pow(h_y, ay);
        for (int k = 0; k < m; ++k) rhs[idx[static_cast<std::size_t>(k)]] += scale * target * coef[static_cast<std::size_t>(k)];
      });
}

// Coefficients of `target`'s lattice that reproduce `source` (exactly where it is a cubic
// polynomial): the cubic B-spline quasi-interpolant c_k = (-g_(k-1) + 8 g_k - g_(k+1)) / 6 in
// each direction, g being source's values at target's knots (coefficient k is centred at
// min + (k - 1) h).
Eigen::VectorXd quasi_interpolant(const BicubicHeightField& source, const BicubicHeightField& target) {
  const int nx = target.n_cells_x() + 3;
  const int ny = target.n_cells_y() + 3;
  const Eigen::Vector2d origin = target.domain().min;
  // Values at the knots min + (i - 2) h, i = 0 .. n + 4, in both directions.
  Eigen::MatrixXd g(nx + 2, ny + 2);
  for (int j = 0; j < ny + 2; ++j)
    for (int i = 0; i < nx + 2; ++i)
      g(i, j) = source.value(origin.x() + (i - 2) * target.spacing_x(), origin.y() + (j - 2) * target.spacing_y());
  Eigen::MatrixXd gx(nx, ny + 2);
  for (int i = 0; i < nx; ++i) gx.row(i) = (8.0 * g.row(i + 1) - g.row(i) - g.row(i + 2)) / 6.0;
  Eigen::VectorXd c(static_cast<Eigen::Index>(nx) * ny);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) c[j * nx + i] = (8.0 * gx(i, j + 1) - gx(i, j) - gx(i, j + 2)) / 6.0;
  return c;
}

Eigen::Vector3d band_end(const BandSample& s, double t) { return s.point + t * s.half_length * s.direction; }

double gap(const BicubicHeightField& field, const Eigen::Vector3d& q) { return q.z() - field.value(q.x(), q.y()); }

void validate_samples(const std::vector<BandSample>& samples) {
  if (samples.size() < 3) throw InvalidInput("fit_height_field_to_bands: at least 3 samples are needed, got " + std::to_string(samples.size()));
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const BandSample& s = samples[i];
    if (!s.point.allFinite() || !s.direction.allFinite() || !std::isfinite(s.half_length))
      throw InvalidInput("fit_height_field_to_bands: sample " + std::to_string(i) + " is not finite");
    if (s.half_length < 0.0) throw InvalidInput("fit_height_field_to_bands: sample " + std::to_string(i) + " has a negative half length");
    if (s.half_length > 0.0 && !(std::abs(s.direction.norm() - 1.0) <= tolerance::kUnitDirectionRelative))
      throw InvalidInput("fit_height_field_to_bands: sample " + std::to_string(i) + " has a band direction that is not a unit vector");
    mean += s.point.head<2>();
  }
  mean /= static_cast<double>(samples.size());
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const auto& s : samples) {
    const Eigen::Vector2d d = s.point.head<2>() - mean;
    cov += d * d.transpose();
  }
  const Eigen::Vector2d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(cov, Eigen::EigenvaluesOnly).eigenvalues();
  if (!(ev[1] > 0.0) || !(ev[0] > 1e-12 * ev[1]))
    throw InvalidInput("fit_height_field_to_bands: the samples are coincident or collinear in the xy-plane");
}

}  // namespace

void BandFitOptions::validate() const {
  if (!(std::isfinite(spacing) && spacing > 0.0)) throw InvalidInput("BandFitOptions: spacing must be finite and > 0, got " + std::to_string(spacing));
  if (!(std::isfinite(smoothing_length) && smoothing_length >= 0.0))
    throw InvalidInput("BandFitOptions: smoothing_length must be finite and >= 0, got " + std::to_string(smoothing_length));
  if (!(centre_weight >= 0.0 && centre_weight <= 1.0))
    throw InvalidInput("BandFitOptions: centre_weight must be in [0, 1], got " + std::to_string(centre_weight));
  if (!(std::isfinite(band_weight) && band_weight >= 1.0))
    throw InvalidInput("BandFitOptions: band_weight must be finite and >= 1, got " + std::to_string(band_weight));
  if (max_iterations < 1 || max_iterations > 1000)
    throw InvalidInput("BandFitOptions: max_iterations must be in [1, 1000], got " + std::to_string(max_iterations));
  if (curvature_passes < 0 || curvature_passes > 10)
    throw InvalidInput("BandFitOptions: curvature_passes must be in [0, 10], got " + std::to_string(curvature_passes));
  if (domain) domain->validate();
  if (start != nullptr && start->is_empty()) throw InvalidInput("BandFitOptions: the start field has no coefficients");
  if (start != nullptr) {
    const auto& c = start->coefficients();
    if (!std::all_of(c.begin(), c.end(), [](double x) { return std::isfinite(x); }))
      throw InvalidInput("BandFitOptions: the start field has a non-finite coefficient");
  }
  if (std::isnan(skip_passes_max_miss)) throw InvalidInput("BandFitOptions: skip_passes_max_miss must not be NaN");
}

bool band_target(const BicubicHeightField& field, const BandSample& sample, Eigen::Vector3d& target) {
  if (sample.half_length == 0.0) {
    target = sample.point;
    return true;
  }
  double lo = -1.0;
  double hi = 1.0;
  double g_lo = gap(field, band_end(sample, lo));
  const double g_hi = gap(field, band_end(sample, hi));
  if ((g_lo > 0.0 && g_hi > 0.0) || (g_lo < 0.0 && g_hi < 0.0)) {
    target = band_end(sample, std::abs(g_lo) <= std::abs(g_hi) ? lo : hi);
    return false;
  }
  for (int k = 0; k < kBisectionSteps; ++k) {
    const double mid = 0.5 * (lo + hi);
    const double g_mid = gap(field, band_end(sample, mid));
    if ((g_mid > 0.0) == (g_lo > 0.0) && g_mid != 0.0) {
      lo = mid;
      g_lo = g_mid;
    } else {
      hi = mid;
    }
  }
  target = band_end(sample, 0.5 * (lo + hi));
  return true;
}

BandFitResult fit_height_field_to_bands(const std::vector<BandSample>& samples, const BandFitOptions& options) {
  options.validate();
  validate_samples(samples);
  Rectangle domain;
  if (options.domain) {
    domain = *options.domain;
  } else {
    domain.min = domain.max = samples.front().point.head<2>();
    for (const auto& s : samples) {
      domain.min = domain.min.cwiseMin(s.point.head<2>());
      domain.max = domain.max.cwiseMax(s.point.head<2>());
    }
  }
  const int n_x = std::max(1, static_cast<int>(std::ceil(domain.width() / options.spacing)));
  const int n_y = std::max(1, static_cast<int>(std::ceil(domain.height() / options.spacing)));
  BandFitResult result;
  result.field = BicubicHeightField(domain, n_x, n_y);
  BicubicHeightField& field = result.field;
  const int n_coef = (n_x + 3) * (n_y + 3);

  // lambda: the energy integral of l^6 |D^3 f|^2 times the sample density (per area).
  const double length = options.smoothing_length > 0.0 ? options.smoothing_length : 1.5 * options.spacing;
  // Density over the cells that hold samples, not over the rectangle: a ring-shaped patch
  // covers a small part of its rectangle, and must be smoothed like a compact one.
  std::vector<std::uint8_t> occupied(static_cast<std::size_t>(n_x) * static_cast<std::size_t>(n_y), 0);
  for (const auto& s : samples) {
    double u = 0.0;
    const int i = locate(s.point.x(), domain.min.x(), field.spacing_x(), n_x, u);
    const int j = locate(s.point.y(), domain.min.y(), field.spacing_y(), n_y, u);
    occupied[static_cast<std::size_t>(j) * static_cast<std::size_t>(n_x) + static_cast<std::size_t>(i)] = 1;
  }
  const double covered = static_cast<double>(std::count(occupied.begin(), occupied.end(), std::uint8_t{1})) *
                         field.spacing_x() * field.spacing_y();
  const double density = static_cast<double>(samples.size()) / covered;
  const double lambda = density * std::pow(length, 6);

  // Fixed part: penalty, point samples (weight 1), band centres (centre_weight).
  Triplets fixed;
  Eigen::VectorXd fixed_rhs = Eigen::VectorXd::Zero(n_coef);
  add_penalty(n_x, n_y, field.spacing_x(), field.spacing_y(), lambda, fixed);
  std::vector<Stencil> centre(samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const BandSample& s = samples[i];
    centre[i] = stencil(field, s.point.x(), s.point.y());
    if (s.half_length == 0.0) {
      add_data(centre[i], s.point.z(), 1.0, fixed, fixed_rhs);
      continue;
    }
    ++result.n_bands;
    if (options.centre_weight > 0.0) add_data(centre[i], s.point.z(), options.centre_weight, fixed, fixed_rhs);
  }

  Eigen::SparseMatrix<double> fixed_matrix(n_coef, n_coef);
  fixed_matrix.setFromTriplets(fixed.begin(), fixed.end());
  for (int k = 0; k < n_coef; ++k) fixed_matrix.coeffRef(k, k) += kRidge;

  // Which end (1 = minus, 2 = plus) a band misses the surface at, or -1 when crossed.
  auto missed_end = [&](const BandSample& s) {
    const double g_minus = gap(field, band_end(s, -1.0));
    const double g_plus = gap(field, band_end(s, 1.0));
    if ((g_minus > 0.0 && g_plus > 0.0) || (g_minus < 0.0 && g_plus < 0.0)) return std::abs(g_minus) <= std::abs(g_plus) ? 1 : 2;
    return -1;
  };
  // The objective (up to a constant) at the field's current coefficients c.
  auto objective = [&](const Eigen::VectorXd& c) {
    double f = c.dot(fixed_matrix * c) - 2.0 * fixed_rhs.dot(c);
    for (const auto& s : samples) {
      if (s.half_length == 0.0) continue;
      const int end = missed_end(s);
      if (end > 0) f += options.band_weight * std::pow(gap(field, band_end(s, end == 1 ? -1.0 : 1.0)), 2);
    }
    return f;
  };
  // Stencils of both ends of every band (the lattice is fixed for the whole fit).
  std::vector<std::array<Stencil, 2>> ends(samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (samples[i].half_length == 0.0) continue;
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector3d e = band_end(samples[i], k == 0 ? -1.0 : 1.0);
      ends[i][static_cast<std::size_t>(k)] = stencil(field, e.x(), e.y());
    }
  }
  // Calls visit(stencil, z, weight) for the data term of every band in `active`: in state 0
  // pulled to its centre (weight 1), in state 1 or 2 to its minus or plus end (band_weight).
  auto for_each_term = [&](const std::vector<int>& active, auto&& visit) {
    for (std::size_t i = 0; i < samples.size(); ++i) {
      if (active[i] < 0) continue;
      const BandSample& s = samples[i];
      if (active[i] == 0)
        visit(centre[i], s.point.z(), 1.0);
      else
        visit(ends[i][static_cast<std::size_t>(active[i] - 1)], band_end(s, active[i] == 1 ? -1.0 : 1.0).z(), options.band_weight);
    }
  };
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver;
  bool factorized = false;
  std::vector<int> factor_active(samples.size(), -1);
  // The symbolic analysis (fill-reducing ordering, elimination tree) depends only on the
  // sparsity pattern, which the active set rarely changes: it is redone only when the
  // pattern differs from the last one (the factorisation is then exactly what compute()
  // gives).
  std::vector<int> pattern_outer, pattern_inner;
  // The model's matrix times x, without assembling it.
  auto apply = [&](const std::vector<int>& active, const Eigen::VectorXd& x) {
    Eigen::VectorXd y = fixed_matrix * x;
    for_each_term(active, [&](const Stencil& st, double, double w) {
      double v = 0.0;
      for (std::size_t u = 0; u < 16; ++u) v += st.weight[u] * x[st.index[u]];
      v *= w;
      for (std::size_t u = 0; u < 16; ++u) y[st.index[u]] += v * st.weight[u];
    });
    return y;
  };
  // Conjugate gradients on the model preconditioned by the last factorisation, from x: the
  // active set changes by a few bands between solves (a low-rank change of the matrix), and
  // not at all when only the right-hand side changes (curvature passes), so this converges in
  // a few steps where a new factorisation would cost much more. Returns false (x then
  // undefined) if it does not converge within kMaxPcgSteps.
  auto pcg = [&](const std::vector<int>& active, const Eigen::VectorXd& rhs, Eigen::VectorXd& x) {
    const double tolerance = tolerance::kBandPcgRelative * rhs.norm();
    Eigen::VectorXd r = rhs - apply(active, x);
    if (r.norm() <= tolerance) return true;
    Eigen::VectorXd z = solver.solve(r);
    Eigen::VectorXd d = z;
    double rz = r.dot(z);
    for (int step = 0; step < kMaxPcgSteps; ++step) {
      const Eigen::VectorXd q = apply(active, d);
      const double dq = d.dot(q);
      if (!(dq > 0.0)) return false;
      const double a = rz / dq;
      x += a * d;
      r -= a * q;
      if (r.norm() <= tolerance) return x.allFinite();
      z = solver.solve(r);
      const double rz_next = r.dot(z);
      d = z + (rz_next / rz) * d;
      rz = rz_next;
    }
    return false;
  };
  // Solves the quadratic model: the fixed part plus every band in `active` pulled to its
  // centre (0) or its nearer end (1, 2), from the guess x0.
  auto solve = [&](const std::vector<int>& active, const Eigen::VectorXd& x0) {
    Triplets a;
    Eigen::VectorXd rhs = fixed_rhs;
    for_each_term(active, [&](const Stencil& st, double z, double w) {
      for (std::size_t u = 0; u < 16; ++u) rhs[st.index[u]] += w * z * st.weight[u];
    });
    std::size_t n_changed = 0;
    for (std::size_t i = 0; i < samples.size(); ++i) n_changed += active[i] != factor_active[i] ? 1 : 0;
    if (factorized && n_changed <= kMaxChangedBands) {
      Eigen::VectorXd x = x0;
      if (pcg(active, rhs, x)) return x;
    }
    for_each_term(active, [&](const Stencil& st, double, double w) {
      for (std::size_t u = 0; u < 16; ++u)
        for (std::size_t v = 0; v < 16; ++v) a.emplace_back(st.index[u], st.index[v], w * st.weight[u] * st.weight[v]);
    });
    Eigen::SparseMatrix<double> matrix(n_coef, n_coef);
    matrix.setFromTriplets(a.begin(), a.end());
    matrix += fixed_matrix;
    matrix.makeCompressed();
    const auto* outer = matrix.outerIndexPtr();
    const auto* inner = matrix.innerIndexPtr();
    const auto n_nonzeros = static_cast<std::size_t>(matrix.nonZeros());
    if (pattern_inner.size() != n_nonzeros ||
        !std::equal(pattern_outer.begin(), pattern_outer.end(), outer) ||
        !std::equal(pattern_inner.begin(), pattern_inner.end(), inner)) {
      pattern_outer.assign(outer, outer + n_coef + 1);
      pattern_inner.assign(inner, inner + n_nonzeros);
      solver.analyzePattern(matrix);
    }
    solver.factorize(matrix);
    if (solver.info() != Eigen::Success) throw SolverError("fit_height_field_to_bands: the sparse Cholesky factorisation failed");
    factorized = true;
    factor_active = active;
    Eigen::VectorXd c = solver.solve(rhs);
    if (solver.info() != Eigen::Success || !c.allFinite()) throw SolverError("fit_height_field_to_bands: the sparse solve failed");
    return c;
  };
  auto set_coefficients = [&](const Eigen::VectorXd& c) { std::copy(c.data(), c.data() + n_coef, field.mutable_coefficients().begin()); };

  std::vector<int> active(samples.size(), -1);
  Eigen::VectorXd c;
  if (options.start != nullptr) {
    c = quasi_interpolant(*options.start, field);
    set_coefficients(c);
  } else {
    // Start: every band pulled to its centre (a plain penalised fit of the centres).
    for (std::size_t i = 0; i < samples.size(); ++i)
      if (samples[i].half_length > 0.0) active[i] = 0;
    c = solve(active, Eigen::VectorXd::Zero(n_coef));
    set_coefficients(c);
    result.iterations = 1;
  }
  // Damped active-set Newton on the convex, piecewise quadratic objective: the model with
  // the current missed bands pulled to their nearer ends is solved, and the step halved
  // until the objective decreases (a plain active-set iteration can cycle).
  auto descend = [&](int max_solves) {
    for (std::size_t i = 0; i < samples.size(); ++i)
      if (samples[i].half_length > 0.0) active[i] = missed_end(samples[i]);
    double current = objective(c);
    for (int solves = 0; solves < max_solves; ++solves) {
      const Eigen::VectorXd step = solve(active, c) - c;
      ++result.iterations;
      double alpha = 1.0;
      Eigen::VectorXd trial;
      double value = 0.0;
      for (int k = 0; k < kLineSearchSteps; ++k, alpha *= 0.5) {
        trial = c + alpha * step;
        set_coefficients(trial);
        value = objective(trial);
        if (value <= current) break;
      }
      if (!(value <= current)) {  // no decrease along the step: stationary to round-off
        set_coefficients(c);
        return true;
      }
      c = trial;
      current = value;
      bool changed = false;
      for (std::size_t i = 0; i < samples.size(); ++i) {
        if (samples[i].half_length == 0.0) continue;
        const int next = missed_end(samples[i]);
        if (next != active[i]) changed = true;
        active[i] = next;
      }
      if (!changed && alpha == 1.0) return true;  // the full step solved the model of its own active set
    }
    return false;
  };
  result.converged = descend(options.max_iterations - result.iterations);
  // How well the field meets the samples (the result's statistics).
  auto measure = [&] {
    result.n_missed = 0;
    result.max_miss = 0.0;
    result.max_point_residual = 0.0;
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const BandSample& s = samples[i];
      if (s.half_length == 0.0) {
        result.max_point_residual = std::max(result.max_point_residual, std::abs(gap(field, s.point)));
        continue;
      }
      Eigen::Vector3d target;
      if (!band_target(field, s, target)) {
        ++result.n_missed;
        result.max_miss = std::max(result.max_miss, std::abs(gap(field, target)));
      }
    }
  };
  if (options.skip_passes_max_miss >= 0.0) {
    measure();
    if (result.max_miss <= options.skip_passes_max_miss) return result;
  }
  // Curvature passes: the prior's target third derivatives are those of a surface with the
  // last fit's slope and curvature and a parallel second fundamental form, so a sphere or a
  // tube is no longer flattened by the prior (a height field's third derivatives grow with
  // the slope even where the curvature is constant).
  const Eigen::VectorXd base_rhs = fixed_rhs;
  for (int pass = 0; pass < options.curvature_passes; ++pass) {
    fixed_rhs = base_rhs;
    add_penalty_target(field, occupied, lambda, fixed_rhs);
    result.converged = descend(options.max_iterations);
    ++result.passes;
  }

  measure();
  return result;
}

}  // namespace nurbsfront
