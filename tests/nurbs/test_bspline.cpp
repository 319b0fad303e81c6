// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include "nurbsfront/core/error.h"
#include "nurbsfront/nurbs/bspline.h"

namespace nurbsfront {
namespace {

KnotVector knots(int degree, std::vector<double> values) {
  KnotVector kv;
  kv.degree = degree;
  kv.knots = std::move(values);
  return kv;
}

TEST(BSplineBasis, SpanSearchFindsTheHalfOpenSpan) {
  const KnotVector kv = knots(2, {0, 0, 0, 1, 2, 2, 3, 4, 4, 4});  // NURBS Book ex. 2.3 (n = 6)
  kv.validate(7, "test");
  EXPECT_EQ(kv.find_span(0.0), 2u);
  EXPECT_EQ(kv.find_span(0.5), 2u);
  EXPECT_EQ(kv.find_span(1.0), 3u);
  EXPECT_EQ(kv.find_span(2.5), 5u);  // the double knot 2 leaves span 4 empty
  EXPECT_EQ(kv.find_span(2.0), 5u);
  EXPECT_EQ(kv.find_span(4.0), 6u);  // end of the domain: last non-empty span
  EXPECT_EQ(kv.find_span(-1.0), 2u); // clamped
  EXPECT_EQ(kv.find_span(9.0), 6u);
}

TEST(BSplineBasis, HandComputedQuadraticValues) {
  // NURBS Book ex. 2.3: at u = 5/2, N_{2,2} = 1/8, N_{3,2} = 6/8, N_{4,2} = 1/8
  // for U = {0,0,0,1,2,3,4,4,5,5,5}.
  const KnotVector kv = knots(2, {0, 0, 0, 1, 2, 3, 4, 4, 5, 5, 5});
  const std::size_t span = kv.find_span(2.5);
  ASSERT_EQ(span, 4u);
  const BasisRows n = kv.basis(span, 2.5, 2);
  EXPECT_NEAR(n[0][0], 1.0 / 8.0, 1e-15);
  EXPECT_NEAR(n[0][1], 6.0 / 8.0, 1e-15);
  EXPECT_NEAR(n[0][2], 1.0 / 8.0, 1e-15);
  // Derivatives on this span: N_{2,2}' = -(3 - u) = -0.5, N_{3,2}' = 0, N_{4,2}' = u - 2 = 0.5;
  // second derivatives 1, -2, 1.
  EXPECT_NEAR(n[1][0], -0.5, 1e-14);
  EXPECT_NEAR(n[1][1], 0.0, 1e-14);
  EXPECT_NEAR(n[1][2], 0.5, 1e-14);
  EXPECT_NEAR(n[2][0], 1.0, 1e-13);
  EXPECT_NEAR(n[2][1], -2.0, 1e-13);
  EXPECT_NEAR(n[2][2], 1.0, 1e-13);
}

TEST(BSplineBasis, PartitionOfUnityAndDerivativesForManyDegrees) {
  for (int p = 1; p <= 7; ++p) {
    KnotVector kv;
    kv.degree = p;
    kv.knots.assign(static_cast<std::size_t>(p) + 1, 0.0);
    for (double k : {0.3, 0.3, 0.55, 0.8}) kv.knots.push_back(k);
    kv.knots.insert(kv.knots.end(), static_cast<std::size_t>(p) + 1, 1.0);
    kv.validate(kv.knots.size() - static_cast<std::size_t>(p) - 1, "test");
    for (double u = 0.0; u <= 1.0; u += 0.0173) {
      const std::size_t span = kv.find_span(u);
      const BasisRows n = kv.basis(span, u, 2);
      double sum = 0.0;
      double dsum = 0.0;
      for (int r = 0; r <= p; ++r) {
        EXPECT_GE(n[0][r], -1e-15);
        sum += n[0][r];
        dsum += n[1][r];
      }
      EXPECT_NEAR(sum, 1.0, 1e-14) << "p=" << p << " u=" << u;
      EXPECT_NEAR(dsum, 0.0, 1e-10) << "p=" << p << " u=" << u;
      // First derivative against central differences, inside the span.
      const double h = 1e-6;
      if (u - h > kv.knots[span] && u + h < kv.knots[span + 1]) {
        const BasisRows a = kv.basis(span, u + h);
        const BasisRows b = kv.basis(span, u - h);
        for (int r = 0; r <= p; ++r) EXPECT_NEAR(n[1][r], (a[0][r] - b[0][r]) / (2 * h), 1e-5 * (1 + std::abs(n[1][r])));
        const BasisRows a1 = kv.basis(span, u + h, 1);
        const BasisRows b1 = kv.basis(span, u - h, 1);
        for (int r = 0; r <= p; ++r) EXPECT_NEAR(n[2][r], (a1[1][r] - b1[1][r]) / (2 * h), 1e-4 * (1 + std::abs(n[2][r])));
      }
    }
  }
}

TEST(BSplineBasis, ValidateRejectsBadKnotVectors) {
  EXPECT_NO_THROW(knots(3, {0, 0, 0, 0, 1, 1, 1, 1}).validate(4, "k"));
  EXPECT_THROW(knots(3, {0, 0, 0, 0, 1, 1, 1}).validate(4, "k"), InvalidInput);          // wrong size
  EXPECT_THROW(knots(3, {0, 0, 0, 0.5, 0.2, 1, 1, 1}).validate(4, "k"), InvalidInput);   // decreasing
  EXPECT_THROW(knots(3, {0, 0, 0, 0, 0, 1, 1, 1, 1}).validate(5, "k"), InvalidInput);    // multiplicity 5
  EXPECT_THROW(knots(1, {0, 0, NAN, 1}).validate(2, "k"), InvalidInput);                  // NaN
  EXPECT_THROW(knots(0, {0, 1}).validate(1, "k"), InvalidInput);                          // degree 0
  EXPECT_THROW(knots(kMaxDegree + 1, std::vector<double>(2 * kMaxDegree + 4, 0.0)).validate(kMaxDegree + 2, "k"),
               InvalidInput);
  EXPECT_THROW(knots(1, {0, 0, 0, 0}).validate(2, "k"), InvalidInput);  // empty domain
}

NurbsCurve quarter_circle(double radius) {
  NurbsCurve c;
  c.u = knots(2, {0, 0, 0, 1, 1, 1});
  c.control_points = {{radius, 0, 0}, {radius, radius, 0}, {0, radius, 0}};
  c.weights = {1.0, std::sqrt(0.5), 1.0};
  return c;
}

TEST(NurbsCurve, RationalQuarterCircleLiesExactlyOnTheCircle) {
  const double radius = 2.5;
  const NurbsCurve c = quarter_circle(radius);
  c.validate();
  EXPECT_TRUE(c.is_rational());
  double max_polynomial_error = 0.0;
  NurbsCurve poly = c;
  poly.weights.clear();  // the same net without weights: a parabola, NOT the circle
  for (int k = 0; k <= 100; ++k) {
    const double u = k / 100.0;
    const Eigen::Vector3d p = c.evaluate(u);
    EXPECT_NEAR(p.norm(), radius, 1e-14 * radius) << u;
    EXPECT_EQ(p.z(), 0.0);
    // Tangent is perpendicular to the radius.
    const auto d = c.derivatives(u);
    EXPECT_NEAR(d[1].dot(p) / (d[1].norm() * radius), 0.0, 1e-13);
    max_polynomial_error = std::max(max_polynomial_error, std::abs(poly.evaluate(u).norm() - radius));
  }
  EXPECT_GT(max_polynomial_error, 0.05 * radius);  // the weights really matter
  // Midpoint at 45 degrees.
  const Eigen::Vector3d mid = c.evaluate(0.5);
  EXPECT_NEAR(mid.x(), radius * std::sqrt(0.5), 1e-14 * radius);
  EXPECT_NEAR(mid.y(), radius * std::sqrt(0.5), 1e-14 * radius);
}

TEST(NurbsCurve, DerivativesAgreeWithFiniteDifferences) {
  NurbsCurve c;
  c.u = knots(3, {0, 0, 0, 0, 0.25, 0.25, 0.7, 1, 1, 1, 1});
  c.control_points = {{0, 0, 0}, {1, 2, 0}, {2, -1, 1}, {3, 0, 2}, {4, 3, 0}, {5, 1, -1}, {6, 0, 0}};
  c.weights = {1.0, 0.5, 2.0, 1.5, 0.7, 1.2, 1.0};
  c.validate();
  const double h = 1e-6;
  for (double u : {0.1, 0.2, 0.4, 0.65, 0.8, 0.95}) {
    const auto d = c.derivatives(u);
    const Eigen::Vector3d fd1 = (c.evaluate(u + h) - c.evaluate(u - h)) / (2 * h);
    const Eigen::Vector3d fd2 = (c.derivatives(u + h)[1] - c.derivatives(u - h)[1]) / (2 * h);
    EXPECT_LT((d[1] - fd1).norm(), 1e-6 * (1 + d[1].norm())) << u;
    EXPECT_LT((d[2] - fd2).norm(), 1e-5 * (1 + d[2].norm())) << u;
  }
}

TEST(NurbsCurve, ValidateRejectsBadWeightsAndPoints) {
  NurbsCurve c = quarter_circle(1.0);
  c.weights[1] = 0.0;
  EXPECT_THROW(c.validate(), InvalidInput);
  c.weights[1] = -1.0;
  EXPECT_THROW(c.validate(), InvalidInput);
  c.weights = {1.0, 1.0};
  EXPECT_THROW(c.validate(), InvalidInput);
  c = quarter_circle(1.0);
  c.control_points[2].y() = std::numeric_limits<double>::infinity();
  EXPECT_THROW(c.validate(), InvalidInput);
  c = quarter_circle(1.0);
  c.control_points.pop_back();
  EXPECT_THROW(c.validate(), InvalidInput);
}

TEST(KnotInsertion, LeavesTheCurveUnchanged) {
  const NurbsCurve c = quarter_circle(1.0);
  BSplineRows homogeneous;
  homogeneous.u = c.u;
  homogeneous.coefficients.resize(3, 4);
  for (int i = 0; i < 3; ++i) {
    homogeneous.coefficients.row(i) << c.weights[i] * c.control_points[i].transpose(), c.weights[i];
  }
  const BSplineRows once = insert_knot(homogeneous, 0.3, 1);
  const BSplineRows twice = insert_knot(once, 0.6, 2);
  EXPECT_EQ(twice.u.knots.size(), 9u);
  EXPECT_EQ(twice.coefficients.rows(), 6);
  NurbsCurve d;
  d.u = twice.u;
  for (int i = 0; i < twice.coefficients.rows(); ++i) {
    const double w = twice.coefficients(i, 3);
    d.control_points.emplace_back(twice.coefficients.row(i).head<3>().transpose() / w);
    d.weights.push_back(w);
  }
  d.validate();
  for (int k = 0; k <= 50; ++k) EXPECT_LT((d.evaluate(k / 50.0) - c.evaluate(k / 50.0)).norm(), 1e-15 * 4);
  EXPECT_THROW((void)insert_knot(twice, 0.6, 1), InvalidInput);  // multiplicity 3 > degree 2
  EXPECT_THROW((void)insert_knot(twice, 1.5, 1), InvalidInput);  // outside
}

}  // namespace
}  // namespace nurbsfront
