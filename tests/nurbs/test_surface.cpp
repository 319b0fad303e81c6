// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Geometry>

#include "nurbsfront/core/error.h"
#include "nurbsfront/nurbs/nurbs_surface.h"
#include "nurbsfront/nurbs/projection.h"

namespace nurbsfront {
namespace {

KnotVector knots(int degree, std::vector<double> values) {
  KnotVector kv;
  kv.degree = degree;
  kv.knots = std::move(values);
  return kv;
}

// One eighth of a sphere as a rational biquadratic patch: the quarter circle from the
// equator to the pole (in u) revolved by 90 degrees about z (in v). The pole (u = 1) is a
// collapsed edge.
NurbsSurface sphere_octant(double radius) {
  NurbsSurface s;
  s.u = knots(2, {0, 0, 0, 1, 1, 1});
  s.v = knots(2, {0, 0, 0, 1, 1, 1});
  s.n_u = 3;
  s.n_v = 3;
  const double profile_r[3] = {radius, radius, 0.0};
  const double profile_z[3] = {0.0, radius, radius};
  const double w[3] = {1.0, std::sqrt(0.5), 1.0};
  const double cx[3] = {1.0, 1.0, 0.0};
  const double cy[3] = {0.0, 1.0, 1.0};
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) {
      s.control_points.emplace_back(profile_r[i] * cx[j], profile_r[i] * cy[j], profile_z[i]);
      s.weights.push_back(w[i] * w[j]);
    }
  }
  return s;
}

// A general rational surface: degrees 3 x 2, non-uniform knots with a double knot, uneven weights.
NurbsSurface wavy_surface() {
  NurbsSurface s;
  s.u = knots(3, {0, 0, 0, 0, 0.3, 0.3, 0.6, 1, 1, 1, 1});
  s.v = knots(2, {-1, -1, -1, 0, 0.5, 2, 2, 2});
  s.n_u = 7;
  s.n_v = 5;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> z(-0.5, 0.5);
  std::uniform_real_distribution<double> w(0.5, 2.0);
  for (std::size_t j = 0; j < s.n_v; ++j) {
    for (std::size_t i = 0; i < s.n_u; ++i) {
      s.control_points.emplace_back(static_cast<double>(i), static_cast<double>(j) + 0.2 * z(rng), z(rng));
      s.weights.push_back(w(rng));
    }
  }
  return s;
}

TEST(NurbsSurface, SphereOctantLiesOnTheSphere) {
  const double radius = 3.0;
  const NurbsSurface s = sphere_octant(radius);
  s.validate();
  EXPECT_TRUE(s.is_rational());
  for (int a = 0; a <= 20; ++a) {
    for (int b = 0; b <= 20; ++b) {
      const Eigen::Vector3d p = s.evaluate(a / 20.0, b / 20.0);
      EXPECT_NEAR(p.norm(), radius, 1e-14 * radius);
      EXPECT_GE(p.minCoeff(), -1e-15);
    }
  }
}

TEST(NurbsSurface, SphereCurvaturesAreOneOverR) {
  const double radius = 3.0;
  const NurbsSurface s = sphere_octant(radius);
  for (double u : {0.0, 0.2, 0.5, 0.8}) {
    for (double v : {0.0, 0.3, 0.5, 1.0}) {
      const SurfaceCurvature c = s.curvature(u, v);
      const Eigen::Vector3d p = s.evaluate(u, v);
      // Su x Sv points into the sphere here: both curvatures are +1/R.
      EXPECT_NEAR(c.normal.dot(p / radius), -1.0, 1e-12);
      // An umbilic: k1,2 = H +- sqrt(H^2 - K) turns round-off in H^2 - K into sqrt(eps).
      EXPECT_NEAR(c.k1, 1.0 / radius, 1e-7);
      EXPECT_NEAR(c.k2, 1.0 / radius, 1e-7);
      EXPECT_NEAR(c.mean, 1.0 / radius, 1e-10);
      EXPECT_NEAR(c.gaussian, 1.0 / (radius * radius), 1e-10);
    }
  }
  // The collapsed pole has no tangent plane: zero, not NaN.
  const SurfaceCurvature pole = s.curvature(1.0, 0.5);
  EXPECT_EQ(pole.normal.norm(), 0.0);
}

TEST(NurbsSurface, CylinderCurvatureIsOneOverRAndZero) {
  // Quarter cylinder of radius r along x: rational in v, linear in u.
  const double r = 0.5;
  NurbsSurface s;
  s.u = knots(1, {0, 0, 1, 1});
  s.v = knots(2, {0, 0, 0, 1, 1, 1});
  s.n_u = 2;
  s.n_v = 3;
  const double w[3] = {1.0, std::sqrt(0.5), 1.0};
  const Eigen::Vector2d yz[3] = {{r, 0}, {r, r}, {0, r}};
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 2; ++i) {
      s.control_points.emplace_back(2.0 * i, yz[j].x(), yz[j].y());
      s.weights.push_back(w[j]);
    }
  }
  s.validate();
  for (double u : {0.1, 0.5}) {
    for (double v : {0.0, 0.4, 0.9}) {
      const SurfaceCurvature c = s.curvature(u, v);
      EXPECT_NEAR(std::max(std::abs(c.k1), std::abs(c.k2)), 1.0 / r, 1e-10);
      EXPECT_NEAR(std::min(std::abs(c.k1), std::abs(c.k2)), 0.0, 1e-10);
      EXPECT_NEAR(c.gaussian, 0.0, 1e-10);
      // The zero-curvature direction is the axis.
      const Eigen::Vector3d axis_dir = std::abs(c.k1) < std::abs(c.k2) ? c.direction1 : c.direction2;
      EXPECT_NEAR(std::abs(axis_dir.x()), 1.0, 1e-10);
    }
  }
}

TEST(NurbsSurface, DerivativesAgreeWithFiniteDifferences) {
  const NurbsSurface s = wavy_surface();
  s.validate();
  const double h = 1e-6;
  for (double u : {0.05, 0.2, 0.45, 0.7, 0.93}) {
    for (double v : {-0.8, -0.2, 0.3, 1.0, 1.8}) {
      const SurfaceDerivatives d = s.derivatives(u, v);
      EXPECT_LT((d.point - s.evaluate(u, v)).norm(), 1e-14);
      const Eigen::Vector3d fu = (s.evaluate(u + h, v) - s.evaluate(u - h, v)) / (2 * h);
      const Eigen::Vector3d fv = (s.evaluate(u, v + h) - s.evaluate(u, v - h)) / (2 * h);
      EXPECT_LT((d.su - fu).norm(), 1e-6 * (1 + d.su.norm()));
      EXPECT_LT((d.sv - fv).norm(), 1e-6 * (1 + d.sv.norm()));
      const SurfaceDerivatives up = s.derivatives(u + h, v);
      const SurfaceDerivatives um = s.derivatives(u - h, v);
      const SurfaceDerivatives vp = s.derivatives(u, v + h);
      const SurfaceDerivatives vm = s.derivatives(u, v - h);
      EXPECT_LT((d.suu - (up.su - um.su) / (2 * h)).norm(), 1e-5 * (1 + d.suu.norm()));
      EXPECT_LT((d.suv - (vp.su - vm.su) / (2 * h)).norm(), 1e-5 * (1 + d.suv.norm()));
      EXPECT_LT((d.suv - (up.sv - um.sv) / (2 * h)).norm(), 1e-5 * (1 + d.suv.norm()));
      EXPECT_LT((d.svv - (vp.sv - vm.sv) / (2 * h)).norm(), 1e-5 * (1 + d.svv.norm()));
      const Eigen::Vector3d n = s.normal(u, v);
      EXPECT_NEAR(n.norm(), 1.0, 1e-14);
      EXPECT_NEAR(n.dot(d.su), 0.0, 1e-12 * d.su.norm());
    }
  }
}

TEST(NurbsSurface, ValidateRejectsBadInput) {
  NurbsSurface s = sphere_octant(1.0);
  EXPECT_NO_THROW(s.validate());
  s.u.knots = {0, 0, 0, 1, 1};  // wrong size
  EXPECT_THROW(s.validate(), InvalidInput);
  s = sphere_octant(1.0);
  s.v.knots = {0, 0, 1, 0.5, 1, 1};  // non-monotone
  EXPECT_THROW(s.validate(), InvalidInput);
  s = sphere_octant(1.0);
  s.weights[4] = 0.0;
  EXPECT_THROW(s.validate(), InvalidInput);
  s.weights[4] = -2.0;
  EXPECT_THROW(s.validate(), InvalidInput);
  s = sphere_octant(1.0);
  s.control_points[3].x() = std::nan("");
  EXPECT_THROW(s.validate(), InvalidInput);
  s = sphere_octant(1.0);
  s.control_points.pop_back();
  EXPECT_THROW(s.validate(), InvalidInput);
  s = sphere_octant(1.0);
  s.weights.pop_back();
  EXPECT_THROW(s.validate(), InvalidInput);
}

TEST(NurbsSurface, TransformIsExact) {
  const NurbsSurface s = wavy_surface();
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3d t(1, -2, 0.5);
  const NurbsSurface m = s.transformed(r, t);
  for (double u : {0.0, 0.33, 1.0})
    for (double v : {-1.0, 0.1, 2.0}) EXPECT_LT((m.evaluate(u, v) - (r * s.evaluate(u, v) + t)).norm(), 1e-13);
}

TEST(Projection, ClosestPointOnTheSphereIsRadial) {
  const double radius = 2.0;
  const NurbsSurface s = sphere_octant(radius);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> a(0.1, 1.4);
  for (int k = 0; k < 30; ++k) {
    const double theta = a(rng);  // from the pole
    const double phi = a(rng);
    const Eigen::Vector3d dir(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
    const double dist = (k % 2 == 0 ? 0.3 : -0.4);
    const Eigen::Vector3d q = (radius + dist) * dir;
    const ClosestPoint cp = closest_point(s, q);
    EXPECT_TRUE(cp.converged);
    EXPECT_LT((cp.point - radius * dir).norm(), 1e-9) << k;
    EXPECT_NEAR(cp.distance, std::abs(dist), 1e-9);
  }
}

TEST(Projection, PointsBeyondTheBorderProjectOntoIt) {
  const NurbsSurface s = wavy_surface();
  // Far beyond the u = 0 border (x < 0): the closest point has u = 0.
  const Eigen::Vector3d q = s.evaluate(0.0, 0.5) + Eigen::Vector3d(-5.0, 0.0, 0.0);
  const ClosestPoint cp = closest_point(s, q);
  EXPECT_EQ(cp.u, 0.0);
  // Never worse than a dense scan.
  double best = 1e300;
  for (int a = 0; a <= 200; ++a)
    for (int b = 0; b <= 200; ++b) best = std::min(best, (s.evaluate(a / 200.0, -1.0 + 3.0 * b / 200.0) - q).norm());
  EXPECT_LE(cp.distance, best + 1e-12);
  EXPECT_THROW((void)closest_point(s, Eigen::Vector3d(NAN, 0, 0)), InvalidInput);
}

TEST(Projection, RandomQueriesMatchADenseScan) {
  const NurbsSurface s = wavy_surface();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::uniform_real_distribution<double> v(-1.0, 2.0);
  std::uniform_real_distribution<double> off(-0.2, 0.2);
  for (int k = 0; k < 20; ++k) {
    const double su = u(rng);
    const double sv = v(rng);
    const Eigen::Vector3d q = s.evaluate(su, sv) + off(rng) * s.normal(su, sv);
    const ClosestPoint cp = closest_point(s, q);
    // First-order optimality: the residual is normal to the surface (or we are on a border).
    const SurfaceDerivatives d = s.derivatives(cp.u, cp.v);
    const Eigen::Vector3d r = cp.point - q;
    const bool inside = cp.u > 0.0 && cp.u < 1.0 && cp.v > -1.0 && cp.v < 2.0;
    if (inside && r.norm() > 1e-12) {
      EXPECT_NEAR(r.normalized().dot(d.su.normalized()), 0.0, 1e-6);
      EXPECT_NEAR(r.normalized().dot(d.sv.normalized()), 0.0, 1e-6);
    }
    EXPECT_LE(cp.distance, (s.evaluate(su, sv) - q).norm() + 1e-12);
  }
}

}  // namespace
}  // namespace nurbsfront
