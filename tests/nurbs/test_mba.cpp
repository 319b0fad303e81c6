// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <random>

#include "nurbsfront/core/error.h"
#include "nurbsfront/nurbs/height_field.h"
#include "nurbsfront/nurbs/mba.h"
#include "nurbsfront/nurbs/mba_internal.h"

namespace nurbsfront {
namespace {

using Function = std::function<double(double, double)>;

std::vector<Eigen::Vector3d> random_samples(const Function& f, std::size_t n, const Rectangle& r, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(r.min.x(), r.max.x());
  std::uniform_real_distribution<double> uy(r.min.y(), r.max.y());
  std::vector<Eigen::Vector3d> pts;
  for (std::size_t k = 0; k < n; ++k) {
    const double x = ux(rng);
    const double y = uy(rng);
    pts.emplace_back(x, y, f(x, y));
  }
  return pts;
}

double max_error_at(const BicubicHeightField& field, const std::vector<Eigen::Vector3d>& pts) {
  double e = 0.0;
  for (const auto& p : pts) e = std::max(e, std::abs(field.value(p.x(), p.y()) - p.z()));
  return e;
}

Rectangle rect(double x0, double y0, double x1, double y1) {
  Rectangle r;
  r.min = {x0, y0};
  r.max = {x1, y1};
  return r;
}

TEST(HeightField, EvaluationMatchesTheDefinitionAndDerivativesMatchFiniteDifferences) {
  BicubicHeightField f(rect(-1.0, 2.0, 3.0, 4.0), 5, 3);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> c(-1.0, 1.0);
  for (auto& x : f.mutable_coefficients()) x = c(rng);
  // Direct sum at a hand-chosen point: x = -1 + 4/5 * (2 + 0.25), cell 2, s = 0.25.
  const double x = -1.0 + 0.8 * 2.25;
  const double y = 2.0 + (2.0 / 3.0) * 1.5;  // cell 1, t = 0.5
  double bx[4];
  double by[4];
  detail::cubic_weights(0.25, bx);
  detail::cubic_weights(0.5, by);
  double expected = 0.0;
  for (int l = 0; l < 4; ++l)
    for (int k = 0; k < 4; ++k) expected += bx[k] * by[l] * f.coefficient(2 + k - 1, 1 + l - 1);
  EXPECT_NEAR(f.value(x, y), expected, 1e-14);
  const double h = 1e-6;
  for (double px : {-0.9, 0.3, 1.7, 2.95}) {
    for (double py : {2.1, 2.9, 3.5}) {
      const HeightJet j = f.jet(px, py);
      EXPECT_NEAR(j.z, f.value(px, py), 1e-14);
      EXPECT_NEAR(j.zx, (f.value(px + h, py) - f.value(px - h, py)) / (2 * h), 1e-6);
      EXPECT_NEAR(j.zy, (f.value(px, py + h) - f.value(px, py - h)) / (2 * h), 1e-6);
      EXPECT_NEAR(j.zxx, (f.jet(px + h, py).zx - f.jet(px - h, py).zx) / (2 * h), 1e-5);
      EXPECT_NEAR(j.zxy, (f.jet(px, py + h).zx - f.jet(px, py - h).zx) / (2 * h), 1e-5);
      EXPECT_NEAR(j.zyy, (f.jet(px, py + h).zy - f.jet(px, py - h).zy) / (2 * h), 1e-5);
      const Eigen::Matrix2d g = f.metric(px, py);
      EXPECT_NEAR(g(0, 0), 1.0 + j.zx * j.zx, 1e-14);
      EXPECT_NEAR(g(0, 1), j.zx * j.zy, 1e-14);
      EXPECT_NEAR(f.normal(px, py).dot(Eigen::Vector3d(1, 0, j.zx)), 0.0, 1e-14);
    }
  }
}

// gradient() pairs the value and derivative sums of each lattice row (two doubles per
// instruction, for the front's metric): the same operations in the same order as jet(), so the
// same numbers bit for bit, inside and beyond the rectangle (its corners and edges included),
// on a fitted field.
TEST(HeightField, GradientIsTheJetsFirstDerivativesBitForBit) {
  const Function f = [](double x, double y) { return std::sin(1.3 * x) * std::cos(0.9 * y) + 0.2 * x * y; };
  const Rectangle r = rect(-1.0, 0.5, 3.0, 2.5);
  FitOptions o;
  o.max_levels = 5;
  o.least_squares_iterations = 10;
  const BicubicHeightField field = fit_height_field(random_samples(f, 400, r, 7), o).field;
  ASSERT_GT(field.n_cells_x(), 4);
  int n = 0;
  for (int i = -8; i <= 48; ++i) {
    for (int j = -8; j <= 28; ++j) {
      // A regular grid from a fifth of the rectangle before it to a fifth after it.
      const double x = r.min.x() + i * r.width() / 40.0, y = r.min.y() + j * r.height() / 20.0;
      const Eigen::Vector2d g = field.gradient(x, y);
      const HeightJet jet = field.jet(x, y);
      ASSERT_EQ(g.x(), jet.zx) << x << " " << y;
      ASSERT_EQ(g.y(), jet.zy) << x << " " << y;
      ++n;
    }
  }
  EXPECT_EQ(n, 57 * 37);
}

TEST(HeightField, RefinementIsExact) {
  BicubicHeightField f(rect(0.0, 0.0, 2.0, 1.0), 3, 2);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> c(-1.0, 1.0);
  for (auto& x : f.mutable_coefficients()) x = c(rng);
  const BicubicHeightField g = f.refined().refined();
  EXPECT_EQ(g.n_cells_x(), 12);
  EXPECT_EQ(g.n_cells_y(), 8);
  for (int a = 0; a <= 40; ++a) {
    for (int b = 0; b <= 40; ++b) {
      const double x = 2.0 * a / 40.0;
      const double y = 1.0 * b / 40.0;
      EXPECT_NEAR(g.value(x, y), f.value(x, y), 1e-14);
      EXPECT_NEAR(g.jet(x, y).zxy, f.jet(x, y).zxy, 1e-11);
    }
  }
}

TEST(HeightField, NurbsConversionAgreesToRoundOff) {
  BicubicHeightField f(rect(-3.0, 1.0, 2.0, 2.5), 7, 4);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> c(-2.0, 2.0);
  for (auto& x : f.mutable_coefficients()) x = c(rng);
  const NurbsSurface s = f.to_nurbs();
  ASSERT_NO_THROW(s.validate());
  EXPECT_EQ(s.u.degree, 3);
  EXPECT_EQ(s.n_u, 10u);
  EXPECT_EQ(s.n_v, 7u);
  EXPECT_EQ(s.u.domain_min(), 0.0);
  EXPECT_EQ(s.u.domain_max(), 1.0);
  for (double w : s.weights) EXPECT_EQ(w, 1.0);
  double max_err = 0.0;
  for (int a = 0; a <= 60; ++a) {
    for (int b = 0; b <= 60; ++b) {
      const double u = a / 60.0;
      const double v = b / 60.0;
      const double x = -3.0 + 5.0 * u;
      const double y = 1.0 + 1.5 * v;
      const Eigen::Vector3d p = s.evaluate(u, v);
      max_err = std::max(max_err, (p - f.lift(x, y)).norm());
      // Chain rule: dS/du = width * (1, 0, f_x).
      const SurfaceDerivatives d = s.derivatives(u, v);
      const HeightJet j = f.jet(x, y);
      EXPECT_NEAR(d.su.x(), 5.0, 1e-11);
      EXPECT_NEAR(d.su.z(), 5.0 * j.zx, 1e-10 * (1 + std::abs(j.zx)));
      EXPECT_NEAR(d.svv.z(), 1.5 * 1.5 * j.zyy, 1e-9 * (1 + std::abs(j.zyy)));
    }
  }
  EXPECT_LE(max_err, 1e-12);
}

// The least-squares polish's product out += mu D^T D x + eps x and the dot product x . out as
// they were made before session 17: pass by pass over whole lattice rows (xx, then yy, then
// mixed differences, then eps), the dot product in a last pass.
double thin_plate_product_by_passes(const std::vector<double>& x, std::size_t nx, std::size_t ny, double mu, double eps,
                                    std::vector<double>& out) {
  std::vector<double> d(nx);
  for (std::size_t j = 0; j < ny; ++j) {
    const double* xr = x.data() + j * nx;
    double* o = out.data() + j * nx;
    const std::size_t n = nx - 2;
    for (std::size_t i = 0; i < n; ++i) d[i] = mu * (xr[i] - 2.0 * xr[i + 1] + xr[i + 2]);
    for (std::size_t i = 0; i < n; ++i) o[i] += d[i];
    for (std::size_t i = 0; i < n; ++i) o[i + 1] -= 2.0 * d[i];
    for (std::size_t i = 0; i < n; ++i) o[i + 2] += d[i];
  }
  for (std::size_t j = 0; j + 2 < ny; ++j) {
    const double *x0 = x.data() + j * nx, *x1 = x0 + nx, *x2 = x1 + nx;
    double *o0 = out.data() + j * nx, *o1 = o0 + nx, *o2 = o1 + nx;
    for (std::size_t i = 0; i < nx; ++i) d[i] = mu * (x0[i] - 2.0 * x1[i] + x2[i]);
    for (std::size_t i = 0; i < nx; ++i) o0[i] += d[i];
    for (std::size_t i = 0; i < nx; ++i) o1[i] -= 2.0 * d[i];
    for (std::size_t i = 0; i < nx; ++i) o2[i] += d[i];
  }
  for (std::size_t j = 0; j + 1 < ny; ++j) {
    const double *x0 = x.data() + j * nx, *x1 = x0 + nx;
    double *o0 = out.data() + j * nx, *o1 = o0 + nx;
    const std::size_t n = nx - 1;
    for (std::size_t i = 0; i < n; ++i) d[i] = 2.0 * mu * (x0[i] - x0[i + 1] - x1[i] + x1[i + 1]);
    for (std::size_t i = 0; i < n; ++i) o0[i] += d[i];
    for (std::size_t i = 0; i < n; ++i) o0[i + 1] -= d[i];
    for (std::size_t i = 0; i < n; ++i) o1[i] -= d[i];
    for (std::size_t i = 0; i < n; ++i) o1[i + 1] += d[i];
  }
  for (std::size_t k = 0; k < out.size(); ++k) out[k] += eps * x[k];
  double dot = 0.0;
  for (std::size_t k = 0; k < out.size(); ++k) dot += x[k] * out[k];
  return dot;
}

TEST(Mba, ThinPlateProductInOnePassIsThePassByPassOneBitForBit) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> scratch;
  // Every row and column case: the smallest lattice (4 x 4, no inside element), narrow and
  // wide ones; values of mixed magnitudes so that the order of the additions shows.
  for (const auto& [nx, ny] : std::vector<std::pair<std::size_t, std::size_t>>{{4, 4}, {4, 9}, {5, 4}, {6, 7}, {13, 5}, {21, 18}}) {
    std::vector<double> x(nx * ny), base(nx * ny);
    for (std::size_t k = 0; k < x.size(); ++k) {
      x[k] = u(rng) * std::pow(10.0, 6.0 * u(rng));
      base[k] = u(rng) * std::pow(10.0, 6.0 * u(rng));
    }
    const double mu = 1e-3 * std::abs(u(rng)) + 1e-6, eps = 1e-9;
    std::vector<double> expected = base, got = base;
    const double expected_dot = thin_plate_product_by_passes(x, nx, ny, mu, eps, expected);
    const double got_dot = mba_detail::add_thin_plate_product(x, nx, ny, mu, eps, got, scratch);
    for (std::size_t k = 0; k < x.size(); ++k) ASSERT_EQ(std::bit_cast<std::uint64_t>(got[k]), std::bit_cast<std::uint64_t>(expected[k])) << nx << " x " << ny << " at " << k;
    EXPECT_EQ(std::bit_cast<std::uint64_t>(got_dot), std::bit_cast<std::uint64_t>(expected_dot)) << nx << " x " << ny;
    // And a real product: the thin plate annihilates a plane (the second differences of a
    // linear function are zero), so only eps x is left.
    for (std::size_t j = 0; j < ny; ++j)
      for (std::size_t i = 0; i < nx; ++i) x[j * nx + i] = 0.5 + 0.25 * static_cast<double>(i) - 0.125 * static_cast<double>(j);
    std::vector<double> plane(nx * ny, 0.0);
    mba_detail::add_thin_plate_product(x, nx, ny, mu, 0.0, plane, scratch);
    for (const double v : plane) EXPECT_NEAR(v, 0.0, 1e-15);
  }
}

TEST(Mba, PlaneAndBilinearDataAreReproducedToRoundOff) {
  const Rectangle r = rect(-2.0, 10.0, 5.0, 13.0);
  const std::vector<Function> functions = {
      [](double x, double y) { return 3.0 - 0.25 * x + 1.75 * y; },
      [](double x, double y) { return 100.0 + 0.5 * x - 2.0 * y + 0.3 * x * y; }};
  for (const auto& f : functions) {
    const auto pts = random_samples(f, 500, r, 5);
    FitOptions o;
    o.max_levels = 6;
    const FitResult fit = fit_height_field(pts, o);
    double scale = 0.0;
    for (const auto& p : pts) scale = std::max(scale, std::abs(p.z()));
    EXPECT_LE(max_error_at(fit.field, pts), 1e-12 * scale);
    EXPECT_LE(fit.max_residual(), 1e-12 * scale);
    // Everywhere, not only at the samples.
    for (int a = 0; a <= 20; ++a) {
      for (int b = 0; b <= 20; ++b) {
        const double x = -2.0 + 7.0 * a / 20.0;
        const double y = 10.0 + 3.0 * b / 20.0;
        EXPECT_NEAR(fit.field.value(x, y), f(x, y), 1e-12 * scale);
      }
    }
  }
}

TEST(Mba, WithoutLinearPrecisionTheLevelsStillDriveAPlaneDown) {
  const Rectangle r = rect(0.0, 0.0, 1.0, 1.0);
  const auto pts = random_samples([](double x, double y) { return 0.2 + x - 0.5 * y; }, 400, r, 6);
  FitOptions o;
  o.linear_precision = false;
  o.tolerance = 1e-6;
  o.max_levels = 12;
  const FitResult fit = fit_height_field(pts, o);
  EXPECT_LT(fit.levels.back().max_residual, fit.levels.front().max_residual);
  EXPECT_LE(max_error_at(fit.field, pts), 1e-6 * (1 + 1e-9));
}

struct Analytic {
  const char* name;
  Function f;
  Rectangle domain;
};

std::vector<Analytic> analytic_patches() {
  const double radius = 1.5;
  return {
      {"paraboloid", [](double x, double y) { return 0.5 * (x * x + y * y); }, rect(-1.0, -1.0, 1.0, 1.0)},
      {"sine bump", [](double x, double y) { return 0.2 * std::sin(3.0 * x) * std::cos(2.0 * y); }, rect(0.0, 0.0, 2.0, 1.5)},
      {"sphere cap", [radius](double x, double y) { return std::sqrt(radius * radius - x * x - y * y); },
       rect(-0.8, -0.8, 0.8, 0.8)},
  };
}

TEST(Mba, AnalyticSurfacesConvergeAsLevelsAreAdded) {
  for (const auto& a : analytic_patches()) {
    const auto pts = random_samples(a.f, 3000, a.domain, 8);
    FitOptions o;
    o.relative_tolerance = 1e-4;
    o.max_levels = 12;
    const FitResult fit = fit_height_field(pts, o);
    const double size = std::max(a.domain.width(), a.domain.height());
    ASSERT_GE(fit.levels.size(), 4u) << a.name;
    // The residual falls: never more than a few percent up from one level to the next, and
    // overall by orders of magnitude.
    for (std::size_t k = 1; k < fit.levels.size(); ++k) {
      EXPECT_LE(fit.levels[k].max_residual, 1.05 * fit.levels[k - 1].max_residual) << a.name << " level " << k;
      EXPECT_LT(fit.levels[k].rms_residual, fit.levels[k - 1].rms_residual) << a.name << " level " << k;
      EXPECT_EQ(fit.levels[k].n_cells_x, 2 * fit.levels[k - 1].n_cells_x);
    }
    EXPECT_LT(fit.levels.back().max_residual, 1e-3 * size) << a.name;
    EXPECT_LT(fit.levels.back().max_residual, 0.01 * fit.levels.front().max_residual) << a.name;
    // The report is honest: the merged field has the reported residual at the points.
    EXPECT_NEAR(max_error_at(fit.field, pts), fit.max_residual(), 1e-12 * size) << a.name;
    EXPECT_EQ(fit.stop, FitStop::kTolerance) << a.name;
    EXPECT_LE(fit.max_residual(), fit.tolerance);
  }
}

TEST(Mba, CappedLevelsApproximateTheFunctionBetweenTheSamples) {
  // With the spacing capped at a few sample spacings the field does not interpolate: it is a
  // smooth approximation, close to the function between the samples as well. (Plain MBA
  // smooths at the finest level; the final passes reduce that.)
  for (const auto& a : analytic_patches()) {
    const auto pts = random_samples(a.f, 4000, a.domain, 9);
    const auto probes = random_samples(a.f, 1000, a.domain, 10);
    const auto interior_error = [&](const BicubicHeightField& field) {
      double e = 0.0;
      for (const auto& p : probes) {
        const Eigen::Vector2d d = (p.head<2>() - a.domain.min).cwiseQuotient(a.domain.max - a.domain.min);
        if (d.minCoeff() < 0.1 || d.maxCoeff() > 0.9) continue;  // border cells are poorly constrained
        e = std::max(e, std::abs(field.value(p.x(), p.y()) - p.z()));
      }
      return e;
    };
    FitOptions o;
    o.tolerance = 1e-12;
    o.min_spacing = 0.05 * std::min(a.domain.width(), a.domain.height());
    const FitResult fit = fit_height_field(pts, o);
    EXPECT_EQ(fit.stop, FitStop::kSpacingLimit) << a.name;
    EXPECT_GE(std::min(fit.field.spacing_x(), fit.field.spacing_y()), o.min_spacing);
    ASSERT_EQ(fit.final_pass_max_residual.size(), static_cast<std::size_t>(o.final_passes));
    EXPECT_LT(fit.max_residual(), fit.levels.back().max_residual) << a.name;
    FitOptions plain = o;
    plain.final_passes = 0;
    const FitResult plain_fit = fit_height_field(pts, plain);
    EXPECT_LT(interior_error(fit.field), interior_error(plain_fit.field)) << a.name;
    EXPECT_LT(interior_error(fit.field), 2e-3 * a.domain.diagonal()) << a.name;
  }
}

TEST(Mba, LeastSquaresPolishReproducesABicubicOnTheCappedLattice) {
  // A cubic polynomial is in the span of the capped lattice, so its least-squares fit is
  // exact; the BA passes alone stop well short of it (their smoothing bias).
  const Function f = [](double x, double y) { return x * x * x - 2.0 * x * y * y + 3.0 * y * y + 0.5 * x; };
  const Rectangle domain = rect(-1.0, -1.0, 1.0, 1.0);
  const auto pts = random_samples(f, 1500, domain, 21);
  FitOptions o;
  o.tolerance = 1e-12;
  o.min_spacing = 0.2;
  o.domain = domain;
  const FitResult passes = fit_height_field(pts, o);
  o.least_squares_iterations = 500;
  o.least_squares_smoothing = 0.0;
  const FitResult polished = fit_height_field(pts, o);
  EXPECT_EQ(polished.stop, FitStop::kSpacingLimit);
  ASSERT_EQ(polished.final_pass_max_residual.size(), static_cast<std::size_t>(o.final_passes) + 1);
  EXPECT_GT(passes.max_residual(), 1e-4);
  EXPECT_LT(polished.max_residual(), 1e-5);
  EXPECT_LT(max_error_at(polished.field, random_samples(f, 500, domain, 22)), 1e-5);
}

TEST(Mba, LeastSquaresPolishLowersTheErrorOnASteepSphereCap) {
  // z = sqrt(R^2 - x^2 - y^2) up to a 60 deg slope at the square's corners: the capped BA
  // passes leave an error of about h^2 f'' / 6 there; the polish (default smoothing) lowers
  // the error inside the square (its outermost cells, where the fourth derivatives are
  // largest and the lattice is cut off, are left out: least squares is not a max norm).
  const double radius = 1.0;
  const double reach = radius * std::sin(60.0 * std::acos(-1.0) / 180.0) / std::sqrt(2.0);
  const Rectangle domain = rect(-reach, -reach, reach, reach);
  const Function f = [radius](double x, double y) { return std::sqrt(radius * radius - x * x - y * y); };
  const auto pts = random_samples(f, 10000, domain, 23);
  const auto probes = random_samples(f, 1000, rect(-0.8 * reach, -0.8 * reach, 0.8 * reach, 0.8 * reach), 24);
  FitOptions o;
  o.tolerance = 1e-12;
  o.min_spacing = 0.05;
  const FitResult passes = fit_height_field(pts, o);
  o.least_squares_iterations = 60;
  const FitResult polished = fit_height_field(pts, o);
  const double e_passes = max_error_at(passes.field, probes), e_polished = max_error_at(polished.field, probes);
  SCOPED_TRACE("inner max error: passes " + std::to_string(e_passes) + ", polished " + std::to_string(e_polished));
  EXPECT_LT(e_polished, 0.6 * e_passes);
  EXPECT_LT(max_error_at(polished.field, probes), 1e-3 * radius);
}

TEST(Mba, FinePolishRemovesTheSagAtTheEdgeOfTheData) {
  // A round sphere cap (slope up to 53 deg at its rim) in a square domain larger than it, as
  // surfmesh fits a patch: the coefficients beyond the rim carry little data weight, the
  // first polish's second-difference term holds them near MBA's values, and the fit sags
  // along the rim. The second polish with a small smoothing removes most of that sag.
  const double radius = 1.0, rim = 0.8;
  const Function f = [radius](double x, double y) { return std::sqrt(radius * radius - x * x - y * y); };
  auto in_disk = [](std::vector<Eigen::Vector3d> pts, double r0, double r1) {
    std::vector<Eigen::Vector3d> kept;
    for (const auto& p : pts) {
      const double r = p.head<2>().norm();
      if (r >= r0 && r <= r1) kept.push_back(p);
    }
    return kept;
  };
  const auto pts = in_disk(random_samples(f, 12000, rect(-rim, -rim, rim, rim), 31), 0.0, rim);
  const auto rim_probes = in_disk(random_samples(f, 20000, rect(-rim, -rim, rim, rim), 32), 0.9 * rim, rim);
  ASSERT_GT(rim_probes.size(), 500u);
  FitOptions o;
  o.tolerance = 1e-12;
  o.min_spacing = 0.05;
  o.domain = rect(-0.95, -0.95, 0.95, 0.95);
  o.least_squares_iterations = 30;
  const FitResult first = fit_height_field(pts, o);
  o.least_squares_fine_smoothing = 1e-5;
  o.least_squares_fine_below = 1.0;  // every residual is below: the second polish runs
  const FitResult fine = fit_height_field(pts, o);
  EXPECT_EQ(fine.final_pass_max_residual.size(), first.final_pass_max_residual.size() + 1);
  const double e_first = max_error_at(first.field, rim_probes), e_fine = max_error_at(fine.field, rim_probes);
  SCOPED_TRACE("rim max error: first polish " + std::to_string(e_first) + ", second polish " + std::to_string(e_fine));
  EXPECT_LT(e_fine, 0.5 * e_first);
  // A bound below the first polish's largest residual keeps the first polish's field.
  o.least_squares_fine_below = 0.5 * first.max_residual();
  const FitResult kept = fit_height_field(pts, o);
  EXPECT_EQ(kept.final_pass_max_residual.size(), first.final_pass_max_residual.size());
  EXPECT_EQ(kept.field.coefficients(), first.field.coefficients());
}

TEST(Mba, FittedSphereCapHasCurvatureOneOverR) {
  const double radius = 2.0;
  std::vector<Eigen::Vector3d> pts;
  for (int a = 0; a <= 100; ++a) {
    for (int b = 0; b <= 100; ++b) {
      const double x = -1.0 + 0.02 * a;
      const double y = -1.0 + 0.02 * b;
      pts.emplace_back(x, y, std::sqrt(radius * radius - x * x - y * y));
    }
  }
  FitOptions o;
  o.tolerance = 1e-9;
  o.min_spacing = 0.06;  // 3 sample spacings: smooth second derivatives
  const FitResult fit = fit_height_field(pts, o);
  for (double x : {-0.4, 0.0, 0.3}) {
    for (double y : {-0.4, 0.0, 0.4}) {
      const SurfaceCurvature c = curvature_from_derivatives(fit.field.derivatives(x, y));
      // Upward normal, sphere bending away from it: both curvatures -1/R.
      EXPECT_NEAR(c.k1, -1.0 / radius, 0.03 / radius) << x << " " << y;
      EXPECT_NEAR(c.k2, -1.0 / radius, 0.03 / radius) << x << " " << y;
      EXPECT_NEAR(c.gaussian, 1.0 / (radius * radius), 0.06 / (radius * radius));
    }
  }
  // The same through the exact NURBS form.
  const NurbsSurface s = fit.field.to_nurbs();
  const SurfaceCurvature c = s.curvature(0.5, 0.5);
  EXPECT_NEAR(std::abs(c.mean), 1.0 / radius, 0.03 / radius);
}

TEST(Mba, EdgePointsDuplicatesAndClustersAreFine) {
  const Function f = [](double x, double y) { return std::sin(x) + y * y; };
  std::vector<Eigen::Vector3d> pts;
  // Corners and edges exactly.
  for (double x : {0.0, 1.0})
    for (double y : {0.0, 0.5, 1.0}) pts.emplace_back(x, y, f(x, y));
  // A tight cluster and exact duplicates (one with a different z).
  for (int k = 0; k < 200; ++k) pts.emplace_back(0.3 + 1e-9 * k, 0.7, f(0.3, 0.7));
  pts.emplace_back(0.3, 0.7, f(0.3, 0.7) + 0.01);
  for (int k = 0; k < 50; ++k) pts.emplace_back(0.6, 0.2, f(0.6, 0.2));
  FitOptions o;
  o.max_levels = 8;
  const FitResult fit = fit_height_field(pts, o);
  EXPECT_EQ(fit.n_outside, 0u);
  EXPECT_TRUE(std::isfinite(fit.max_residual()));
  for (double c : fit.field.coefficients()) ASSERT_TRUE(std::isfinite(c));
  // The duplicated point with two values: the fit takes (nearly) their mean.
  EXPECT_NEAR(fit.field.value(0.3, 0.7), f(0.3, 0.7), 0.01);
  EXPECT_NEAR(fit.field.value(0.6, 0.2), f(0.6, 0.2), 1e-6);
  EXPECT_NEAR(fit.field.value(1.0, 1.0), f(1.0, 1.0), 1e-6);
  EXPECT_EQ(fit.stop, FitStop::kLevelLimit);  // conflicting duplicates cannot reach the tolerance
}

TEST(Mba, PointsOutsideAGivenRectangleAreClampedAndCounted) {
  const Function f = [](double x, double y) { return x + 2.0 * y; };
  auto pts = random_samples(f, 300, rect(-0.5, -0.5, 1.5, 1.5), 12);
  FitOptions o;
  o.domain = rect(0.0, 0.0, 1.0, 1.0);
  const FitResult fit = fit_height_field(pts, o);
  std::size_t outside = 0;
  for (const auto& p : pts) outside += (p.x() < 0 || p.x() > 1 || p.y() < 0 || p.y() > 1) ? 1 : 0;
  EXPECT_EQ(fit.n_outside, outside);
  EXPECT_GT(outside, 0u);
  for (double c : fit.field.coefficients()) ASSERT_TRUE(std::isfinite(c));
}

TEST(Mba, BadInputGivesClearErrors) {
  const auto expect_invalid = [](const std::vector<Eigen::Vector3d>& pts, const FitOptions& o, const std::string& word) {
    try {
      (void)fit_height_field(pts, o);
      ADD_FAILURE() << "no exception, expected one mentioning '" << word << "'";
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
  };
  expect_invalid({}, {}, "no points");
  expect_invalid({{0, 0, 0}, {1, 2, 1}, {2, 4, 0}, {-1, -2, 3}}, {}, "collinear");
  expect_invalid({{0, 0, 0}, {1, 0, 1}, {2, 0, 0}}, {}, "collinear");
  expect_invalid({{0, 0, 0}, {1, NAN, 1}, {0, 1, 0}}, {}, "non-finite");
  expect_invalid({{0, 0, 0}, {1, 0, std::numeric_limits<double>::infinity()}, {0, 1, 0}}, {}, "non-finite");
  expect_invalid({{1, 1, 0}, {1, 1, 1}, {1, 1, 2}}, {}, "zero-size");
  const std::vector<Eigen::Vector3d> good = {{0, 0, 0}, {1, 0, 1}, {0, 1, 0}, {1, 1, 1}};
  FitOptions zero;
  zero.domain = rect(0.0, 0.0, 0.0, 1.0);
  expect_invalid(good, zero, "zero-size");
  FitOptions bad;
  bad.max_levels = 0;
  expect_invalid(good, bad, "max_levels");
  bad = {};
  bad.tolerance = -1.0;
  expect_invalid(good, bad, "tolerance");
  bad = {};
  bad.min_spacing = NAN;
  expect_invalid(good, bad, "min_spacing");
  bad = {};
  bad.least_squares_iterations = -1;
  expect_invalid(good, bad, "least_squares_iterations");
  bad = {};
  bad.least_squares_smoothing = -1.0;
  expect_invalid(good, bad, "least_squares_smoothing");
  bad = {};
  bad.least_squares_fine_smoothing = -1.0;
  expect_invalid(good, bad, "least_squares_fine_smoothing");
  bad = {};
  bad.least_squares_fine_below = INFINITY;
  expect_invalid(good, bad, "least_squares_fine_below");
}

TEST(Mba, ProgressCanCancel) {
  const auto pts = random_samples([](double x, double y) { return x * y; }, 100, rect(0, 0, 1, 1), 13);
  FitOptions o;
  int calls = 0;
  o.progress = [&calls](std::string_view, double) { return ++calls < 3; };
  EXPECT_THROW((void)fit_height_field(pts, o), Cancelled);
  EXPECT_EQ(calls, 3);
}

}  // namespace
}  // namespace nurbsfront
