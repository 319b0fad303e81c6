// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <iomanip>
#include <map>
#include <numbers>
#include <random>
#include <sstream>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "nurbsfront/core/error.h"
#include "nurbsfront/front2d/cholesky2.h"
#include "nurbsfront/front2d/front.h"
#include "nurbsfront/front2d/predicates.h"
#include "support/test_data.h"

namespace nurbsfront {
namespace {

using Vec = Eigen::Vector2d;
__extension__ typedef __int128 Int128;

// ---------------------------------------------------------------- predicates

TEST(Front2dPredicates, Orient2dIsExactWhereNaiveFails) {
  // Points on the line y = x, the first moved by a few ulps: coordinates are multiples of
  // 2^-53, so 2^53 times them are integers and the exact sign comes from 128-bit products.
  const double ulp = std::ldexp(1.0, -53);
  const Vec b(12, 12), c(24, 24);
  int naive_wrong = 0;
  for (int i = -64; i <= 64; ++i)
    for (int j = -64; j <= 64; ++j) {
      const Vec a(0.5 + i * ulp, 0.5 + j * ulp);
      const auto s = [](double v) { return static_cast<Int128>(std::ldexp(v, 53)); };
      const Int128 det = (s(a.x()) - s(c.x())) * (s(b.y()) - s(c.y())) - (s(a.y()) - s(c.y())) * (s(b.x()) - s(c.x()));
      const int exact = det > 0 ? 1 : (det < 0 ? -1 : 0);
      ASSERT_EQ(front2d::orient2d(a, b, c), exact) << i << " " << j;
      ASSERT_EQ(front2d::orient2d_exact(a, b, c), exact) << i << " " << j;
      ASSERT_EQ(front2d::orient2d(b, c, a), exact);
      ASSERT_EQ(front2d::orient2d(b, a, c), -exact);
      const double n = front2d::orient2d_naive(a, b, c);
      if ((n > 0 ? 1 : (n < 0 ? -1 : 0)) != exact) ++naive_wrong;
    }
  EXPECT_GT(naive_wrong, 0) << "the test must contain cases where double evaluation fails";
}

TEST(Front2dPredicates, Orient2dShortcutForEqualCoordinates) {
  // Points sharing an x or a y coordinate (axis-parallel boundaries) are decided without
  // the expansion; the answer must equal the exact one, also a few ulps off the line.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  int decided_zero = 0;
  for (int i = 0; i < 20000; ++i) {
    const double x = u(rng), y = u(rng);
    Vec a(x, u(rng)), b(x, u(rng)), c(x, u(rng));  // on the line x = const
    const int which = i % 3;
    Vec& m = which == 0 ? a : (which == 1 ? b : c);
    const int k = static_cast<int>(i / 3 % 5) - 2;  // move one point by -2..2 ulps
    m.x() = k == 0 ? m.x() : std::nextafter(m.x(), k > 0 ? 2.0 : -2.0);
    if (std::abs(k) == 2) m.x() = std::nextafter(m.x(), k > 0 ? 2.0 : -2.0);
    ASSERT_EQ(front2d::orient2d(a, b, c), front2d::orient2d_exact(a, b, c)) << i;
    const Vec p(a.y(), y), q(b.y(), y), r(c.y(), y);  // on the line y = const
    ASSERT_EQ(front2d::orient2d(p, q, r), front2d::orient2d_exact(p, q, r)) << i;
    decided_zero += front2d::orient2d(a, b, c) == 0;
  }
  EXPECT_GT(decided_zero, 1000);
}

TEST(Front2dPredicates, Orient2dAdaptiveStageIsExact) {
  // Nearly collinear points close together (exact differences) and far apart (inexact
  // ones): the second stage must agree with the full expansion.
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.5, 1.0);
  for (int i = 0; i < 20000; ++i) {
    const double scale = i % 2 == 0 ? 1e-3 : 1e3;
    const Vec a(u(rng), u(rng));
    const Vec d(u(rng) - 0.75, u(rng) - 0.75);
    const double t = u(rng);
    Vec b = a + scale * d, c = a + scale * t * d;
    for (int k = 0; k < static_cast<int>(i % 4); ++k) c.y() = std::nextafter(c.y(), i % 3 == 0 ? 2.0 : -2.0);
    const int exact = front2d::orient2d_exact(a, b, c);
    ASSERT_EQ(front2d::orient2d_adapt(a, b, c), exact) << i;
    ASSERT_EQ(front2d::orient2d(a, b, c), exact) << i;
  }
  const Vec p(0.5, 0.5), q(0.75, 0.75), r(0.625, 0.625);  // exactly collinear
  EXPECT_EQ(front2d::orient2d_adapt(p, q, r), 0);
  EXPECT_EQ(front2d::orient2d(p, q, r), 0);
  EXPECT_EQ(front2d::orient2d_adapt(p, r, Vec(0.625, std::nextafter(0.625, 1.0))), 1);
}

TEST(Front2dPredicates, SegmentsIntersect) {
  EXPECT_TRUE(front2d::segments_intersect({0, 0}, {2, 2}, {0, 2}, {2, 0}));
  EXPECT_FALSE(front2d::segments_intersect({0, 0}, {1, 1}, {2, 2}, {3, 3}));
  EXPECT_TRUE(front2d::segments_intersect({0, 0}, {2, 2}, {1, 1}, {3, 3}));
  EXPECT_TRUE(front2d::segments_intersect({0, 0}, {2, 0}, {1, 0}, {1, 5}));  // touching
  EXPECT_FALSE(front2d::segments_intersect({0, 0}, {2, 0}, {1, 1e-300}, {1, 5}));
}

// ---------------------------------------------------------------- invariants

struct Stats {
  double area = 0, mean_alpha = 0, min_alpha = 1, min_angle_deg = 180;
};

double angle_at(const Vec& p, const Vec& q, const Vec& r) {  // angle at p
  const Vec u = q - p, v = r - p;
  return std::atan2(std::abs(u.x() * v.y() - u.y() * v.x()), u.dot(v)) * 180.0 / std::numbers::pi;
}

// Checks a mesh: status, orientation, conformity, edge manifoldness, no overlap, area.
// Returns an empty string when everything holds.
std::string check_mesh(const Pslg& pslg, const Mesh2d& m, double expected_area, Stats* stats = nullptr) {
  std::ostringstream err;
  if (m.report.status != FrontStatus::Ok) err << "status not Ok: " << m.report.message << "; ";
  const auto n = static_cast<int>(m.points.size());
  std::map<std::pair<int, int>, int> dir;
  double area = 0, sum_alpha = 0;
  Stats s;
  for (const auto& t : m.triangles) {
    for (int v : t)
      if (v < 0 || v >= n) return "index out of range";
    const Vec &a = m.points[t[0]], &b = m.points[t[1]], &c = m.points[t[2]];
    if (front2d::orient2d(a, b, c) <= 0) err << "triangle not counter-clockwise; ";
    area += 0.5 * front2d::orient2d_naive(a, b, c);
    const double al = triangle_alpha_2d(a, b, c);
    sum_alpha += al;
    s.min_alpha = std::min(s.min_alpha, al);
    s.min_angle_deg = std::min({s.min_angle_deg, angle_at(a, b, c), angle_at(b, c, a), angle_at(c, a, b)});
    for (int i = 0; i < 3; ++i)
      if (++dir[{t[i], t[(i + 1) % 3]}] > 1) err << "directed edge used twice; ";
  }
  s.area = area;
  s.mean_alpha = m.triangles.empty() ? 0 : sum_alpha / static_cast<double>(m.triangles.size());
  if (stats) *stats = s;
  if (std::abs(area - expected_area) > 1e-9 * std::max(1.0, std::abs(expected_area)))
    err << std::setprecision(17) << "area " << area << " != " << expected_area << "; ";
  // Conformity: every input segment is a chain of mesh edges from one endpoint to the other.
  if (m.segment_chains.size() != pslg.segments.size()) err << "wrong number of segment chains; ";
  for (std::size_t k = 0; k < m.segment_chains.size(); ++k) {
    const auto& ch = m.segment_chains[k];
    if (ch.front() != pslg.segments[k][0] || ch.back() != pslg.segments[k][1]) err << "chain endpoints differ; ";
    for (std::size_t i = 0; i + 1 < ch.size(); ++i)
      if (!dir.count({ch[i], ch[i + 1]}) && !dir.count({ch[i + 1], ch[i]})) {
        err << "segment " << k << " not conforming; ";
        break;
      }
  }
  for (std::size_t i = 0; i < pslg.points.size(); ++i)
    if (m.points[i] != pslg.points[i]) err << "input point moved; ";
  // No overlap: interiors of two triangles are disjoint iff an edge of one separates them.
  std::vector<std::array<double, 4>> box;
  for (const auto& t : m.triangles) {
    const Vec lo = m.points[t[0]].cwiseMin(m.points[t[1]]).cwiseMin(m.points[t[2]]);
    const Vec hi = m.points[t[0]].cwiseMax(m.points[t[1]]).cwiseMax(m.points[t[2]]);
    box.push_back({lo.x(), hi.x(), lo.y(), hi.y()});
  }
  std::vector<int> order(m.triangles.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int i, int j) { return box[i][0] < box[j][0]; });
  auto separated = [&](const std::array<int, 3>& t, const std::array<int, 3>& u) {
    for (int i = 0; i < 3; ++i) {
      bool all = true;
      for (int v : u) all = all && front2d::orient2d(m.points[t[i]], m.points[t[(i + 1) % 3]], m.points[v]) <= 0;
      if (all) return true;
    }
    return false;
  };
  std::size_t overlaps = 0;
  for (std::size_t i = 0; i < order.size(); ++i)
    for (std::size_t j = i + 1; j < order.size() && box[order[j]][0] < box[order[i]][1]; ++j) {
      const auto& A = box[order[i]];
      const auto& B = box[order[j]];
      if (B[2] >= A[3] || B[3] <= A[2]) continue;
      const auto& t = m.triangles[order[i]];
      const auto& u = m.triangles[order[j]];
      if (!separated(t, u) && !separated(u, t)) ++overlaps;
    }
  if (overlaps) err << overlaps << " overlapping triangle pairs; ";
  return err.str();
}

Pslg polygon(const std::vector<Vec>& pts) {
  Pslg p;
  p.points = pts;
  for (std::size_t i = 0; i < pts.size(); ++i) p.segments.push_back({static_cast<int>(i), static_cast<int>((i + 1) % pts.size())});
  return p;
}

void add_loop(Pslg& p, const std::vector<Vec>& pts) {
  const int base = static_cast<int>(p.points.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    p.points.push_back(pts[i]);
    p.segments.push_back({base + static_cast<int>(i), base + static_cast<int>((i + 1) % pts.size())});
  }
}

double loop_area(const std::vector<Vec>& p);

FrontOptions uniform(double h) {
  FrontOptions o;
  o.sizing = SizingField::uniform(h);
  return o;
}

// ---------------------------------------------------------------- simple domains

TEST(Front2d, UnitSquareUniformQuality) {
  const Pslg sq = polygon({{0, 0}, {1, 0}, {1, 1}, {0, 1}});
  const Mesh2d m = mesh_pslg(sq, uniform(0.05));
  Stats s;
  EXPECT_EQ(check_mesh(sq, m, 1.0, &s), "");
  EXPECT_GE(s.mean_alpha, 0.92);
  EXPECT_GE(s.min_angle_deg, 30.0);
  // Edge lengths near the target.
  std::size_t n = 0, inside = 0;
  for (const auto& t : m.triangles)
    for (int i = 0; i < 3; ++i) {
      const double l = (m.points[t[i]] - m.points[t[(i + 1) % 3]]).norm();
      ++n;
      if (l > 0.5 * 0.05 && l < 1.5 * 0.05) ++inside;
    }
  EXPECT_GT(static_cast<double>(inside), 0.95 * static_cast<double>(n));
  EXPECT_NEAR(static_cast<double>(m.triangles.size()), 1.0 / (std::sqrt(3.0) / 4 * 0.05 * 0.05), 0.25 * 462.0);
}

TEST(Front2d, SquareWithHoleAndRegions) {
  Pslg p = polygon({{0, 0}, {3, 0}, {3, 3}, {0, 3}});
  add_loop(p, {{1, 1}, {2, 1}, {2, 2}, {1, 2}});
  p.holes.push_back({1.5, 1.5});
  const Mesh2d m = mesh_pslg(p, uniform(0.2));
  Stats s;
  EXPECT_EQ(check_mesh(p, m, 8.0, &s), "");
  EXPECT_GE(s.mean_alpha, 0.92);
  EXPECT_GE(s.min_angle_deg, 30.0);
  // Same without the hole but with two region markers: two regions, 1 and 7.
  Pslg q = p;
  q.holes.clear();
  q.regions = {{{0.5, 0.5}, 7}, {{1.5, 1.5}, 1}};
  const Mesh2d r = mesh_pslg(q, uniform(0.2));
  EXPECT_EQ(check_mesh(q, r, 9.0), "");
  double area1 = 0, area7 = 0;
  for (std::size_t i = 0; i < r.triangles.size(); ++i) {
    const auto& t = r.triangles[i];
    const double a = 0.5 * front2d::orient2d_naive(r.points[t[0]], r.points[t[1]], r.points[t[2]]);
    (r.triangle_regions[i] == 1 ? area1 : area7) += a;
    EXPECT_TRUE(r.triangle_regions[i] == 1 || r.triangle_regions[i] == 7);
  }
  EXPECT_NEAR(area1, 1.0, 1e-9);
  EXPECT_NEAR(area7, 8.0, 1e-9);
}

TEST(Front2d, InteriorSegmentsAndIsolatedPointsAreKept) {
  Pslg p = polygon({{0, 0}, {2, 0}, {2, 1}, {0, 1}});
  p.points.push_back({0.5, 0.5});
  p.points.push_back({1.5, 0.5});
  p.segments.push_back({4, 5});   // dangling interior segment
  p.points.push_back({1.0, 0.8});  // isolated point
  const Mesh2d m = mesh_pslg(p, uniform(0.1));
  EXPECT_EQ(check_mesh(p, m, 2.0), "");
  bool used = false;
  for (const auto& t : m.triangles)
    for (int v : t) used = used || v == 6;
  EXPECT_TRUE(used);
}

TEST(Front2d, PreDiscretisedBoundaryIsNotSplit) {
  std::vector<Vec> circle;
  for (int i = 0; i < 40; ++i) circle.emplace_back(std::cos(2 * std::numbers::pi * i / 40), std::sin(2 * std::numbers::pi * i / 40));
  const Pslg p = polygon(circle);
  FrontOptions o = uniform(2 * std::numbers::pi / 40);
  o.split_segments = false;
  o.enclose_convex_hull = false;
  const Mesh2d m = mesh_pslg(p, o);
  double area = 0;
  for (int i = 0; i < 40; ++i) area += 0.5 * circle[i].x() * circle[(i + 1) % 40].y() - 0.5 * circle[(i + 1) % 40].x() * circle[i].y();
  Stats s;
  EXPECT_EQ(check_mesh(p, m, area, &s), "");
  for (const auto& ch : m.segment_chains) EXPECT_EQ(ch.size(), 2u);
  EXPECT_GE(s.mean_alpha, 0.9);
}

// The obtuse angles of m: how many in all, and how many at a vertex v with marked(v).
template <class Marked>
std::pair<int, int> obtuse_angles(const Mesh2d& m, Marked marked) {
  std::pair<int, int> count{0, 0};
  for (const auto& t : m.triangles)
    for (int i = 0; i < 3; ++i) {
      const Vec& a = m.points[t[i]];
      if ((m.points[t[(i + 1) % 3]] - a).dot(m.points[t[(i + 2) % 3]] - a) >= 0) continue;
      ++count.first;
      if (marked(t[i])) ++count.second;
    }
  return count;
}

// A sheared strip 1 x 0.31 with fixed border nodes (6 pieces along, 2 across: the surface
// mesher's narrow patch), two corners of 95 deg and two of 85 deg. The old rule closes each
// 95-deg corner with one triangle (obtuse at the corner); the corner rule puts a node on its
// bisector instead and the mesh has no obtuse triangle at all.
TEST(Front2d, ObtuseBorderCornerGetsANodeOnItsBisector) {
  const double shear = std::tan(5.0 * std::numbers::pi / 180.0), w = 0.31;
  const std::vector<Vec> corners{{0, 0}, {1, 0}, {1 + w * shear, w}, {w * shear, w}};
  Pslg p;
  std::vector<int> corner_index;
  for (std::size_t i = 0; i < 4; ++i) {
    const Vec a = corners[i], b = corners[(i + 1) % 4];
    const int n = i % 2 == 0 ? 6 : 2;
    corner_index.push_back(static_cast<int>(p.points.size()));
    for (int k = 0; k < n; ++k) p.points.push_back(a + (b - a) * (static_cast<double>(k) / n));
  }
  const auto n = static_cast<int>(p.points.size());
  for (int i = 0; i < n; ++i) p.segments.push_back({i, (i + 1) % n});
  // Obtuse triangles in all, and those with the obtuse angle at one of the four corners.
  auto obtuse = [&](const Mesh2d& m) {
    return obtuse_angles(m, [&](int v) { return std::find(corner_index.begin(), corner_index.end(), v) != corner_index.end(); });
  };
  FrontOptions o = uniform(0.167);
  o.split_segments = false;
  o.corner_split_angle_deg = 180.0;  // off: the old closure
  const Mesh2d before = mesh_pslg(p, o);
  EXPECT_EQ(check_mesh(p, before, w), "");
  EXPECT_EQ(before.report.n_corner_points, 0u);
  EXPECT_EQ(obtuse(before).second, 2) << "the domain no longer exercises the rule";
  o.corner_split_angle_deg = 89.5;
  const Mesh2d after = mesh_pslg(p, o);
  Stats s;
  EXPECT_EQ(check_mesh(p, after, w, &s), "");
  EXPECT_EQ(after.report.n_corner_points, 2u);
  EXPECT_EQ(obtuse(after), std::make_pair(0, 0));
  EXPECT_GE(s.min_angle_deg, 30.0);
  o.corner_split_angle_deg = 0.0;  // out of (0, 180]
  EXPECT_THROW((void)mesh_pslg(p, o), InvalidInput);
}

// Rectangles of fixed border nodes (nx pieces along, ny across; the surface mesher's narrow
// patches) where the front's first triangles leave a corner wider than 90 deg at a border node
// between two new points. Issue 5: the corner rule applies at every input node, whatever its
// two neighbours, so these meshes have no obtuse triangle at all; without the rule (180) they
// have obtuse angles at input nodes (the rule restricted to corners of three input nodes left
// them too: 2 in the first domain, 2 in the second).
TEST(Front2d, CornerRuleAtBorderNodesBetweenNewPoints) {
  struct Domain {
    double height;
    int nx, ny;
  };
  for (const Domain d : {Domain{0.3, 5, 2}, Domain{0.45, 5, 3}}) {
    SCOPED_TRACE(::testing::Message() << "1 x " << d.height << ", " << d.nx << " x " << d.ny << " pieces");
    const std::vector<Vec> corners{{0, 0}, {1, 0}, {1, d.height}, {0, d.height}};
    Pslg p;
    for (std::size_t i = 0; i < 4; ++i) {
      const int n = i % 2 == 0 ? d.nx : d.ny;
      for (int k = 0; k < n; ++k) p.points.push_back(corners[i] + (corners[(i + 1) % 4] - corners[i]) * (static_cast<double>(k) / n));
    }
    const auto n_input = static_cast<int>(p.points.size());
    for (int i = 0; i < n_input; ++i) p.segments.push_back({i, (i + 1) % n_input});
    // Obtuse angles in all, and those at input nodes.
    auto obtuse = [&](const Mesh2d& m) { return obtuse_angles(m, [&](int v) { return v < n_input; }); };
    FrontOptions o = uniform(0.18);
    o.split_segments = false;
    o.corner_split_angle_deg = 180.0;
    const Mesh2d off = mesh_pslg(p, o);
    EXPECT_EQ(check_mesh(p, off, d.height), "");
    EXPECT_GT(obtuse(off).second, 0) << "the domain no longer exercises the rule";
    o.corner_split_angle_deg = 89.5;
    const Mesh2d on = mesh_pslg(p, o);
    EXPECT_EQ(check_mesh(p, on, d.height), "");
    EXPECT_GT(on.report.n_corner_points, 0u);
    EXPECT_EQ(obtuse(on), std::make_pair(0, 0));
  }
}

TEST(Front2d, GradedAndAnisotropicSizing) {
  const Pslg sq = polygon({{0, 0}, {1, 0}, {1, 1}, {0, 1}});
  FrontOptions o;
  o.sizing = SizingField::per_vertex({0.01, 0.2, 0.2, 0.2});
  const Mesh2d a = mesh_pslg(sq, o);
  EXPECT_EQ(check_mesh(sq, a, 1.0), "");
  o.sizing = SizingField::from_callback([](const Vec& x) { return 0.02 + 0.1 * x.x(); });
  const Mesh2d b = mesh_pslg(sq, o);
  EXPECT_EQ(check_mesh(sq, b, 1.0), "");
  struct Stretch : Metric {
    Eigen::Matrix2d tensor(const Vec&) const override { return Eigen::Vector2d(1.0, 4.0).asDiagonal(); }
  };
  FrontOptions c = uniform(0.1);
  c.metric = std::make_shared<Stretch>();
  const Mesh2d mc = mesh_pslg(sq, c);
  EXPECT_EQ(check_mesh(sq, mc, 1.0), "");
  // In the metric, lengths in y count double: the mesh has about twice the triangles.
  const Mesh2d iso = mesh_pslg(sq, uniform(0.1));
  EXPECT_GT(mc.triangles.size(), 1.5 * iso.triangles.size());
}

// ---------------------------------------------------------------- metric

struct ConstantMetric : Metric {
  Eigen::Matrix2d m;
  explicit ConstantMetric(Eigen::Matrix2d t) : m(std::move(t)) {}
  Eigen::Matrix2d tensor(const Vec&) const override { return m; }
};

// First fundamental form of the height field f(x, y) = c (x^2 + y^2).
struct ParaboloidMetric : Metric {
  double c;
  explicit ParaboloidMetric(double cc) : c(cc) {}
  Eigen::Matrix2d tensor(const Vec& x) const override {
    const Vec g = 2.0 * c * x;
    return Eigen::Matrix2d::Identity() + g * g.transpose();
  }
};

// Quality of the mesh mapped by a linear map L (e.g. M^{1/2} of a constant metric).
Stats mapped_stats(const Mesh2d& m, const Eigen::Matrix2d& L) {
  Stats s;
  double sum = 0;
  for (const auto& t : m.triangles) {
    const Vec a = L * m.points[t[0]], b = L * m.points[t[1]], c = L * m.points[t[2]];
    const double al = triangle_alpha_2d(a, b, c);
    sum += al;
    s.min_alpha = std::min(s.min_alpha, al);
    s.min_angle_deg = std::min({s.min_angle_deg, angle_at(a, b, c), angle_at(b, c, a), angle_at(c, a, b)});
  }
  s.mean_alpha = sum / static_cast<double>(m.triangles.size());
  return s;
}

TEST(Front2dMetric, QualityInMetricHandComputed) {
  // Under M = diag(1, 4), y-lengths double: (0,0), (1,0), (1/2, sqrt(3)/4) is equilateral.
  const Eigen::Matrix2d M = Eigen::Vector2d(1.0, 4.0).asDiagonal();
  const Vec a(0, 0), b(1, 0), c(0.5, std::sqrt(3.0) / 4);
  EXPECT_NEAR(triangle_alpha_in_metric(a, b, c, M), 1.0, 1e-14);
  EXPECT_NEAR(triangle_min_angle_in_metric_deg(a, b, c, M), 60.0, 1e-9);
  EXPECT_NEAR(triangle_alpha_in_metric(a, c, b, M), -1.0, 1e-14);
  // Euclidean: sides 1, l, l with l^2 = 1/4 + 3/16 = 7/16; area sqrt(3)/8.
  EXPECT_NEAR(triangle_alpha_in_metric(a, b, c, Eigen::Matrix2d::Identity()),
              4 * std::sqrt(3.0) * (std::sqrt(3.0) / 8) / (1 + 2 * 7.0 / 16), 1e-14);
  EXPECT_DOUBLE_EQ(triangle_alpha_in_metric(a, b, c, Eigen::Matrix2d::Identity()), triangle_alpha_2d(a, b, c));
  // Right isosceles triangle in the identity: smallest angle 45 deg, alpha = sqrt(3)/2.
  EXPECT_NEAR(triangle_min_angle_in_metric_deg({0, 0}, {1, 0}, {0, 1}, Eigen::Matrix2d::Identity()), 45.0, 1e-9);
  const ParaboloidMetric par(0.5);
  const Eigen::Matrix2d tm = triangle_metric(par, a, b, c);
  EXPECT_NEAR(tm(0, 0), 1.0 + (0.0 + 1.0 + 0.25) / 3, 1e-14);
  EXPECT_NEAR(tm(1, 1), 1.0 + (0.0 + 0.0 + 3.0 / 16) / 3, 1e-14);
}

// detail::cholesky_upper replaces M.llt().matrixU() in the front and the swaps: the same
// doubles bit for bit, metric tensors and sums of them, steep and flat, and the inputs where
// Eigen's factorisation stops (a pivot <= 0, NaN).
TEST(Front2dMetric, CholeskyFactorIsEigensBitForBit) {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<Eigen::Matrix2d> cases;
  for (int i = 0; i < 4000; ++i) {
    const double scale = std::pow(10.0, 4.0 * unit(rng));
    const Eigen::Vector2d g(scale * unit(rng), scale * unit(rng));
    const Eigen::Matrix2d m = Eigen::Matrix2d::Identity() + g * g.transpose();
    cases.push_back(m);
    const Eigen::Vector2d h(unit(rng), unit(rng));
    const Eigen::Matrix2d n = Eigen::Matrix2d::Identity() + h * h.transpose();
    cases.push_back((m + n + cases[static_cast<std::size_t>(i) / 2] + n) * 0.25);
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  cases.push_back(Eigen::Vector2d(4.0, 9.0).asDiagonal());
  cases.push_back((Eigen::Matrix2d() << 0.0, 1.0, 1.0, 2.0).finished());    // first pivot 0
  cases.push_back((Eigen::Matrix2d() << -1.0, 0.5, 0.5, 2.0).finished());   // first pivot < 0
  cases.push_back((Eigen::Matrix2d() << 1.0, 2.0, 2.0, 1.0).finished());    // second pivot < 0
  cases.push_back((Eigen::Matrix2d() << 1.0, 1.0, 1.0, 1.0).finished());    // second pivot 0
  cases.push_back((Eigen::Matrix2d() << nan, 0.0, 0.0, 1.0).finished());
  cases.push_back((Eigen::Matrix2d() << 2.0, nan, nan, 1.0).finished());
  for (const Eigen::Matrix2d& m : cases) {
    const Eigen::Matrix2d eigen = m.llt().matrixU();
    const Eigen::Matrix2d ours = detail::cholesky_upper(m);
    EXPECT_EQ(std::memcmp(eigen.data(), ours.data(), sizeof(double) * 4), 0) << m;
  }
}

TEST(Front2dMetric, IdentityMetricGivesTheSameMesh) {
  Pslg p = polygon({{0, 0}, {3, 0}, {3, 2}, {0, 2}});
  add_loop(p, {{1, 0.5}, {2, 0.7}, {1.6, 1.4}});
  p.holes.push_back({1.5, 0.9});
  for (const Pslg& dom : {p, read_pslg(test::test_data("pslg/fish.poly"))}) {
    FrontOptions o;
    const Mesh2d plain = mesh_pslg(dom, o);
    o.metric = std::make_shared<ConstantMetric>(Eigen::Matrix2d::Identity());
    const Mesh2d ident = mesh_pslg(dom, o);
    ASSERT_EQ(plain.points.size(), ident.points.size());
    EXPECT_EQ(plain.points, ident.points);
    EXPECT_EQ(plain.triangles, ident.triangles);
    EXPECT_EQ(plain.report.n_swaps, ident.report.n_swaps);
  }
}

TEST(Front2dMetric, ConstantAnisotropicMetricGivesIsotropicImage) {
  // M = diag(1, 4): the mesh mapped by M^{1/2} = diag(1, 2) is a mesh of the 1 x 2 rectangle
  // at h, and must be as good as an isotropic mesh of that rectangle.
  const Eigen::Matrix2d M = Eigen::Vector2d(1.0, 4.0).asDiagonal();
  const Eigen::Matrix2d L = Eigen::Vector2d(1.0, 2.0).asDiagonal();
  Pslg p = polygon({{0, 0}, {1, 0}, {1, 1}, {0, 1}});
  add_loop(p, {{0.3, 0.3}, {0.3, 0.45}, {0.6, 0.45}, {0.6, 0.3}});
  p.holes.push_back({0.4, 0.4});
  FrontOptions o = uniform(0.05);
  o.metric = std::make_shared<ConstantMetric>(M);
  const Mesh2d m = mesh_pslg(p, o);
  EXPECT_EQ(check_mesh(p, m, 1.0 - 0.3 * 0.15), "");
  const Stats s = mapped_stats(m, L);
  // The isotropic reference: the image domain meshed without a metric.
  Pslg q = p;
  for (auto& x : q.points) x = L * x;
  for (auto& x : q.holes) x = L * x;
  const Mesh2d iso = mesh_pslg(q, uniform(0.05));
  const Stats r = mapped_stats(iso, Eigen::Matrix2d::Identity());
  EXPECT_GE(s.mean_alpha, 0.9);
  // Comparable to the isotropic mesh (a Euclidean optimiser left 17 deg here).
  EXPECT_GE(s.min_angle_deg, std::min(25.0, r.min_angle_deg - 5.0));
  EXPECT_NEAR(static_cast<double>(m.triangles.size()), static_cast<double>(iso.triangles.size()), 0.1 * static_cast<double>(iso.triangles.size()));
}

TEST(Front2dMetric, ParaboloidHeightFieldMetric) {
  // f = c (x^2 + y^2) over the unit disk with slope 60 deg at its rim (2 c = tan 60 deg).
  const double c = std::sqrt(3.0) / 2.0;
  std::vector<Vec> circle;
  for (int i = 0; i < 64; ++i) circle.emplace_back(std::cos(2 * std::numbers::pi * i / 64), std::sin(2 * std::numbers::pi * i / 64));
  const Pslg p = polygon(circle);
  FrontOptions o = uniform(0.08);
  o.metric = std::make_shared<ParaboloidMetric>(c);
  const Mesh2d m = mesh_pslg(p, o);
  EXPECT_EQ(check_mesh(p, m, m.report.domain_area), "");
  auto lift = [&](const Vec& x) { return Eigen::Vector3d(x.x(), x.y(), c * x.squaredNorm()); };
  double sum = 0, min_angle = 180, sum_plain = 0;
  for (const auto& t : m.triangles) {
    const Eigen::Vector3d a = lift(m.points[t[0]]), b = lift(m.points[t[1]]), d = lift(m.points[t[2]]);
    const double area = 0.5 * (b - a).cross(d - a).norm();
    sum += 4 * std::sqrt(3.0) * area / ((b - a).squaredNorm() + (d - b).squaredNorm() + (a - d).squaredNorm());
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d& x = i == 0 ? a : (i == 1 ? b : d);
      const Eigen::Vector3d& y = i == 0 ? b : (i == 1 ? d : a);
      const Eigen::Vector3d& z = i == 0 ? d : (i == 1 ? a : b);
      min_angle = std::min(min_angle, std::acos((y - x).normalized().dot((z - x).normalized())) * 180 / std::numbers::pi);
    }
    sum_plain += triangle_alpha_2d(m.points[t[0]], m.points[t[1]], m.points[t[2]]);
  }
  const double mean = sum / static_cast<double>(m.triangles.size());
  EXPECT_GE(mean, 0.9);
  EXPECT_GE(min_angle, 25.0);  // a Euclidean optimiser left 19 deg here
  // In the plane the triangles are stretched along the slope: worse than on the surface.
  EXPECT_LT(sum_plain / static_cast<double>(m.triangles.size()), mean);
}

// ---------------------------------------------------------------- touching loops

// Points along the closed polyline `corners` (the first point not repeated), about `step`
// apart on each side; returns their indices appended to p.points (the corners included).
std::vector<int> discretise(Pslg& p, const std::vector<Vec>& corners, double step, std::vector<int> fixed = {}) {
  std::vector<int> idx;
  for (std::size_t i = 0; i < corners.size(); ++i) {
    const Vec a = corners[i], b = corners[(i + 1) % corners.size()];
    const int n = std::max(1, static_cast<int>(std::lround((b - a).norm() / step)));
    for (int k = 0; k < n; ++k) {
      if (k == 0 && i < fixed.size() && fixed[i] >= 0) {
        idx.push_back(fixed[i]);
        continue;
      }
      idx.push_back(static_cast<int>(p.points.size()));
      p.points.push_back(a + (b - a) * (static_cast<double>(k) / n));
    }
  }
  for (std::size_t i = 0; i < idx.size(); ++i) p.segments.push_back({idx[i], idx[(i + 1) % idx.size()]});
  return idx;
}

// Mesh with split_segments on and off; both must be valid, oriented, conforming, of the area.
void expect_touching_domain(const Pslg& p, double area, double h) {
  for (bool split : {false, true}) {
    SCOPED_TRACE(split ? "split_segments" : "segments final");
    FrontOptions o = uniform(h);
    o.split_segments = split;
    const Mesh2d m = mesh_pslg(p, o);
    Stats s;
    EXPECT_EQ(check_mesh(p, m, area, &s), "");
    EXPECT_NEAR(m.report.domain_area, area, 1e-12);
    EXPECT_GE(s.mean_alpha, 0.85);
  }
}

TEST(Front2dTouching, OuterLoopTouchesHoleAtOneVertex) {
  // The square [0, 4]^2 and a diamond hole whose bottom vertex is the point (2, 0) of the
  // square's bottom side: that point has 4 incident segments.
  const double h = 0.25;
  Pslg p;
  const std::vector<int> outer = discretise(p, {{0, 0}, {2, 0}, {4, 0}, {4, 4}, {0, 4}}, h);
  const int touch = outer[8];
  ASSERT_EQ(p.points[touch], Vec(2, 0));
  discretise(p, {{2, 0}, {1, 1}, {2, 2}, {3, 1}}, h, {touch});
  p.holes.push_back({2, 1});
  expect_touching_domain(p, 16.0 - 2.0, h);
  // A hole touching the outer loop at a corner of both (the outer corner of 90 deg is split
  // into angles of about 26.6 deg, the hole's own and 26.6 deg).
  Pslg q;
  const std::vector<int> o2 = discretise(q, {{0, 0}, {4, 0}, {4, 4}, {0, 4}}, h);
  discretise(q, {{0, 0}, {1, 2}, {1.5, 1.5}, {2, 1}}, h, {o2[0]});
  q.holes.push_back({1.2, 1.2});
  expect_touching_domain(q, 16.0 - 1.5, h);
}

TEST(Front2dTouching, TwoLobesJoinedAtOneVertex) {
  const double h = 0.2;
  Pslg p;
  const std::vector<int> a = discretise(p, {{0, 0}, {2, 0}, {2, 2}, {0, 2}}, h);
  discretise(p, {{2, 2}, {4, 2}, {4, 4}, {2, 4}}, h, {a[20]});
  ASSERT_EQ(p.points[a[20]], Vec(2, 2));
  expect_touching_domain(p, 8.0, h);
  // Lobes meeting at a sharp vertex (input angles 30 deg on both sides).
  Pslg q;
  const std::vector<int> b = discretise(q, {{0, 0}, {2, -0.5}, {2, 0.5}}, 0.1);
  const int apex = b[0];
  discretise(q, {{0, 0}, {-2, 0.5}, {-2, -0.5}}, 0.1, {apex});
  expect_touching_domain(q, 2.0, 0.1);
}

TEST(Front2dTouching, VeryNonUniformFinalBoundary) {
  // Border nodes spaced 0.2 h .. 3 h (random), segments final (split_segments = false).
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.2, 3.0);
  const double h = 0.05;
  for (int shape = 0; shape < 2; ++shape) {
    SCOPED_TRACE(shape);
    std::vector<Vec> pts;
    if (shape == 0) {  // circle of radius 1
      double t = 0;
      while (t < 2 * std::numbers::pi - 0.2 * h) {
        pts.emplace_back(std::cos(t), std::sin(t));
        t += u(rng) * h;
      }
    } else {  // unit square with random spacing on each side
      const std::vector<Vec> c = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      for (int side = 0; side < 4; ++side) {
        double t = 0;
        while (t < 1.0 - 0.2 * h) {
          pts.push_back(c[side] + t * (c[(side + 1) % 4] - c[side]));
          t += u(rng) * h;
        }
      }
    }
    const Pslg p = polygon(pts);
    FrontOptions o = uniform(h);
    o.split_segments = false;
    const Mesh2d m = mesh_pslg(p, o);
    Stats s;
    EXPECT_EQ(check_mesh(p, m, loop_area(pts), &s), "");
    for (const auto& ch : m.segment_chains) EXPECT_EQ(ch.size(), 2u);
    EXPECT_GE(s.mean_alpha, 0.85);
  }
}

// ---------------------------------------------------------------- files

double bbox_diagonal(const Pslg& p) {
  Vec lo = p.points[0], hi = p.points[0];
  for (const auto& x : p.points) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  return (hi - lo).norm();
}

// The segments' own faces, or the convex hull when they enclose nothing (open polylines).
Mesh2d mesh_file(const Pslg& p, double h) {
  FrontOptions o = uniform(h);
  try {
    return mesh_pslg(p, o);
  } catch (const InvalidInput& e) {
    if (std::string(e.what()).find("empty") == std::string::npos) throw;
  }
  o.enclose_convex_hull = true;
  return mesh_pslg(p, o);
}

std::size_t count_unexcused_small_angles(const Pslg& p, const Mesh2d& m);

// Every CGAL demo file at h = diag / divisor: the invariants, mean alpha >= 0.92, and the
// min-angle rule of issue 4 (below).
void mesh_cgal_files(double divisor) {
  for (const char* name : {"fish.poly", "clusters.poly", "trivial.poly", "butterfly.edg", "clusters2.edg", "img5.edg",
                           "img6.edg", "lettre_A.edg"}) {
    SCOPED_TRACE(name);
    const Pslg p = read_pslg(test::test_data(std::string("pslg/") + name));
    const Mesh2d m = mesh_file(p, bbox_diagonal(p) / divisor);
    Stats s;
    EXPECT_EQ(check_mesh(p, m, m.report.domain_area, &s), "");
    EXPECT_GT(m.report.domain_area, 0);
    EXPECT_GE(s.mean_alpha, 0.92);
    EXPECT_EQ(count_unexcused_small_angles(p, m), 0u);
  }
}

// Triangles with an angle below 30 deg not excused. The boundary segments are the input
// segments and the convex hull edges the mesher added (Mesh2d::hull_chains: with
// enclose_convex_hull they are segments of the domain, as with Triangle's -c). Excused:
// - a triangle that touches an input vertex where two consecutive boundary segments make
//   less than 60 deg (a dangling segment end counts as 0);
// - one whose shortest edge joins split points of two boundary segments that meet at an
//   input vertex under less than 60 deg (it lies in the narrow wedge of that angle, where the
//   two segments are closer than h: Shewchuk's rule in Delaunay refinement).
std::size_t count_unexcused_small_angles(const Pslg& p, const Mesh2d& m) {
  std::vector<std::array<int, 2>> segs = p.segments;
  std::vector<int> segment_of(m.points.size(), -1);  // boundary segment of each split point
  for (std::size_t k = 0; k < m.segment_chains.size(); ++k)
    for (std::size_t i = 1; i + 1 < m.segment_chains[k].size(); ++i) segment_of[m.segment_chains[k][i]] = static_cast<int>(k);
  for (const auto& ch : m.hull_chains) {
    for (std::size_t i = 1; i + 1 < ch.size(); ++i) segment_of[ch[i]] = static_cast<int>(segs.size());
    segs.push_back({ch.front(), ch.back()});
  }
  std::vector<std::vector<double>> dirs(p.points.size());
  for (const auto& s : segs)
    for (int e = 0; e < 2; ++e) {
      const Vec d = p.points[s[1 - e]] - p.points[s[e]];
      dirs[s[e]].push_back(std::atan2(d.y(), d.x()));
    }
  std::vector<bool> small(p.points.size(), false);
  for (std::size_t v = 0; v < dirs.size(); ++v) {
    auto& d = dirs[v];
    if (d.size() == 1) small[v] = true;
    if (d.size() < 2) continue;
    std::sort(d.begin(), d.end());
    for (std::size_t i = 0; i < d.size(); ++i) {
      double gap_angle = (i + 1 < d.size() ? d[i + 1] : d[0] + 2 * std::numbers::pi) - d[i];
      if (gap_angle * 180.0 / std::numbers::pi < 60.0) small[v] = true;
    }
  }
  // Whether segments x and y meet under less than 60 deg (or share no vertex).
  auto apart = [&](std::size_t x, std::size_t y) {
    const auto& s1 = segs[x];
    const auto& s2 = segs[y];
    for (int a : s1)
      for (int b : s2)
        if (a == b) {
          const Vec d1 = p.points[s1[0] == a ? s1[1] : s1[0]] - p.points[a];
          const Vec d2 = p.points[s2[0] == a ? s2[1] : s2[0]] - p.points[a];
          return angle_at(Vec(0, 0), d1, d2) < 60.0;
        }
    return true;
  };
  auto in_wedge = [&](int a, int b) {
    if (segment_of[a] < 0 || segment_of[b] < 0 || segment_of[a] == segment_of[b]) return false;
    const auto x = static_cast<std::size_t>(segment_of[a]), y = static_cast<std::size_t>(segment_of[b]);
    const auto& s1 = segs[x];
    const auto& s2 = segs[y];
    const bool share = s1[0] == s2[0] || s1[0] == s2[1] || s1[1] == s2[0] || s1[1] == s2[1];
    return share && apart(x, y);
  };
  std::size_t bad = 0;
  for (const auto& t : m.triangles) {
    const Vec &a = m.points[t[0]], &b = m.points[t[1]], &c = m.points[t[2]];
    if (std::min({angle_at(a, b, c), angle_at(b, c, a), angle_at(c, a, b)}) >= 30.0) continue;
    bool excused = false;
    for (int v : t) excused = excused || (static_cast<std::size_t>(v) < small.size() && small[v]);
    const std::array<double, 3> len = {(b - c).squaredNorm(), (c - a).squaredNorm(), (a - b).squaredNorm()};
    const auto i = static_cast<std::size_t>(std::min_element(len.begin(), len.end()) - len.begin());
    excused = excused || in_wedge(t[(i + 1) % 3], t[(i + 2) % 3]);
    if (!excused) ++bad;
  }
  return bad;
}

// Mean alpha >= 0.92 and the min-angle rule at h = diag / 60 on every file, img5 included
// since the convex hull edges its contour follows are left out (its slivers along them made
// it 0.88 before).
TEST(Front2dFiles, CgalDemoDomains) {
  mesh_cgal_files(60);
  // trivial.poly: a quadrilateral of area 8 and a point outside it (dropped); with the
  // convex hull enclosed, the area is 8.2 and the point is a mesh vertex.
  const Pslg t = read_poly(test::test_data("pslg/trivial.poly"));
  ASSERT_EQ(t.points.size(), 5u);
  const Mesh2d quad = mesh_pslg(t, uniform(0.3));
  EXPECT_NEAR(quad.report.domain_area, 8.0, 1e-12);
  EXPECT_EQ(quad.report.n_dropped_points, 1u);
  FrontOptions hull = uniform(0.3);
  hull.enclose_convex_hull = true;
  const Mesh2d with_hull = mesh_pslg(t, hull);
  EXPECT_NEAR(with_hull.report.domain_area, 8.2, 1e-12);
  EXPECT_EQ(check_mesh(t, with_hull, 8.2), "");
  EXPECT_EQ(with_hull.report.n_dropped_points, 0u);
}

// Issue 4: with uniform sizing, min angle >= 30 deg except at input angles below 60 deg
// (convex hull edges included), with mean alpha >= 0.92, at h = diag / 100.
void expect_min_angle_rule(const Pslg& p) {
  const double h = bbox_diagonal(p) / 100;
  const Mesh2d m = mesh_file(p, h);
  Stats s;
  EXPECT_EQ(check_mesh(p, m, m.report.domain_area, &s), "");
  EXPECT_GE(s.mean_alpha, 0.92);
  EXPECT_EQ(count_unexcused_small_angles(p, m), 0u);
}

TEST(Front2dFiles, MinAngleRuleAtDiagOver100) {
  expect_min_angle_rule(polygon({Vec(0, 0), Vec(1, 0), Vec(1, 1), Vec(0, 1)}));
  for (const char* name : {"fish.poly", "trivial.poly", "butterfly.edg", "lettre_A.edg", "clusters.poly", "clusters2.edg", "img5.edg",
                           "img6.edg"}) {
    SCOPED_TRACE(name);
    expect_min_angle_rule(read_pslg(test::test_data(std::string("pslg/") + name)));
  }
  const auto dir = test::shared_data("pslg/triangle_examples");
  if (!dir) GTEST_SKIP() << "../shared/data absent";
  for (const char* name : {"A.poly", "face.poly", "box.poly", "double_hex.poly", "double_hex2.poly", "double_hex3.poly"}) {
    SCOPED_TRACE(name);
    expect_min_angle_rule(read_pslg(*dir / name));
  }
}

// The open polyline (0, 0), (5, offset), (10, 0), (5, 5): the convex hull closes it with the
// edges (0, 0) -> (10, 0) and (5, 5) -> (0, 0).
Pslg polyline_along_hull_edge(double offset) {
  Pslg p;
  p.points = {Vec(0, 0), Vec(5, offset), Vec(10, 0), Vec(5, 5)};
  p.segments = {{0, 1}, {1, 2}, {2, 3}};
  return p;
}

// A polyline running 1e-5 above a convex hull edge, h = 0.5: the strip between them is
// narrower than h / 200, so the edge is left out and the polyline bounds the domain there
// (FrontOptions::hull_gap_fraction): no strip, no sliver. The strip's area (the triangle
// (0, 0), (5, 1e-5), (10, 0): 5e-5) is reported and is exactly the area the domain loses
// against the exact hull. No triangle has an angle below 30 deg except at the input angles
// below 60 deg (45 deg at (0, 0) and at (10, 0)), without the gap excuse.
TEST(Front2dFiles, HullEdgeFollowedByTheInputIsLeftOut) {
  const Pslg p = polyline_along_hull_edge(1e-5);
  FrontOptions o = uniform(0.5);
  o.enclose_convex_hull = true;
  const Mesh2d m = mesh_pslg(p, o);
  EXPECT_EQ(m.report.n_hull_edges_followed, 1u);
  EXPECT_NEAR(m.report.hull_gap_area, 5e-5, 1e-17);
  EXPECT_NEAR(m.report.domain_area, 25.0 - 5e-5, 1e-12);
  EXPECT_EQ(check_mesh(p, m, 25.0 - 5e-5), "");
  ASSERT_EQ(m.hull_chains.size(), 1u);  // only 3 -> 0 is added
  EXPECT_EQ(m.hull_chains[0].front(), 3);
  EXPECT_EQ(m.hull_chains[0].back(), 0);
  for (const auto& t : m.triangles) {
    bool in_strip = true;
    for (int v : t) in_strip = in_strip && m.points[v].y() <= 1e-5;
    EXPECT_FALSE(in_strip);
  }
  EXPECT_EQ(count_unexcused_small_angles(p, m), 0u);
  o.hull_gap_fraction = 0;  // the exact hull (Triangle's -c)
  const Mesh2d exact = mesh_pslg(p, o);
  EXPECT_EQ(exact.report.n_hull_edges_followed, 0u);
  EXPECT_NEAR(exact.report.domain_area, 25.0, 1e-12);
  EXPECT_NEAR(exact.report.domain_area - m.report.domain_area, m.report.hull_gap_area, 1e-12);

  // Kept: the polyline 0.01 from the edge (beyond h / 200 = 0.0025) ...
  const Pslg far = polyline_along_hull_edge(0.01);
  o.hull_gap_fraction = FrontOptions{}.hull_gap_fraction;
  const Mesh2d mf = mesh_pslg(far, o);
  EXPECT_EQ(mf.report.n_hull_edges_followed, 0u);
  EXPECT_NEAR(mf.report.domain_area, 25.0, 1e-12);
  EXPECT_EQ(mf.hull_chains.size(), 2u);
  // ... and an input point inside the strip (it would be left outside the domain).
  Pslg inside = p;
  inside.points.push_back(Vec(2, 1e-6));  // the polyline is at y = 4e-6 there
  const Mesh2d mi = mesh_pslg(inside, o);
  EXPECT_EQ(mi.report.n_hull_edges_followed, 0u);
  EXPECT_EQ(mi.report.n_dropped_points, 0u);
  EXPECT_NEAR(mi.report.domain_area, 25.0, 1e-12);
  EXPECT_EQ(check_mesh(inside, mi, 25.0), "");
  // The polyline alone (no segment to (5, 5)): leaving the edge out would leave no domain,
  // so the exact hull, the strip itself, is meshed.
  Pslg alone;
  alone.points = {Vec(0, 0), Vec(5, 1e-5), Vec(10, 0)};
  alone.segments = {{0, 1}, {1, 2}};
  const Mesh2d ma = mesh_pslg(alone, o);
  EXPECT_EQ(ma.report.n_hull_edges_followed, 0u);
  EXPECT_NEAR(ma.report.domain_area, 5e-5, 1e-15);
  EXPECT_EQ(check_mesh(alone, ma, 5e-5), "");
  // Bad fraction.
  o.hull_gap_fraction = 1.0;
  EXPECT_THROW((void)mesh_pslg(p, o), InvalidInput);
  o.hull_gap_fraction = -0.1;
  EXPECT_THROW((void)mesh_pslg(p, o), InvalidInput);
}

// img5's traced contour runs 2e-5 .. 6e-4 inside 7 of its convex hull's 11 edges (one more is
// an input segment): all 7 are left out at h = diag / 100 (h / 200 = 0.036), and the domain
// loses exactly the strips' area, which is less than h / 200 times the hull edges' length.
TEST(Front2dFiles, Img5HullEdgesFollowedByItsContour) {
  const Pslg p = read_pslg(test::test_data("pslg/img5.edg"));
  const double h = bbox_diagonal(p) / 100;
  FrontOptions o = uniform(h);
  o.enclose_convex_hull = true;
  const Mesh2d m = mesh_pslg(p, o);
  o.hull_gap_fraction = 0;
  const Mesh2d exact = mesh_pslg(p, o);
  ASSERT_EQ(exact.hull_chains.size(), 10u);
  EXPECT_EQ(m.report.n_hull_edges_followed, 7u);
  EXPECT_EQ(m.hull_chains.size(), 3u);
  double perimeter = 0;
  for (const auto& ch : exact.hull_chains) perimeter += (exact.points[ch.front()] - exact.points[ch.back()]).norm();
  EXPECT_GT(m.report.hull_gap_area, 0);
  EXPECT_LT(m.report.hull_gap_area, h / 200 * perimeter);
  EXPECT_NEAR(exact.report.domain_area - m.report.domain_area, m.report.hull_gap_area, 1e-9 * exact.report.domain_area);
  EXPECT_EQ(check_mesh(p, m, m.report.domain_area), "");
}

// With the exact hull (hull_gap_fraction = 0, Triangle's -c) the strip between a polyline
// running 1e-5 above a hull edge and that edge stays in the domain: it is meshed (its
// slivers cannot be refined away: Ruppert's bound asks for points at the strip's width all
// along it, and the refinement stops at its cap), and the mesh keeps every invariant.
TEST(Front2dFiles, ExactHullKeepsANarrowStrip) {
  const Pslg p = polyline_along_hull_edge(1e-5);
  FrontOptions o = uniform(0.5);
  o.enclose_convex_hull = true;
  o.hull_gap_fraction = 0;
  const Mesh2d m = mesh_pslg(p, o);
  EXPECT_EQ(m.report.n_hull_edges_followed, 0u);
  EXPECT_EQ(check_mesh(p, m, 25.0), "");
  ASSERT_EQ(m.hull_chains.size(), 2u);
  std::size_t in_strip = 0;
  for (const auto& t : m.triangles) {
    bool all = true;
    for (int v : t) all = all && m.points[v].y() <= 1e-5;
    in_strip += all ? 1 : 0;
  }
  EXPECT_GT(in_strip, 0u);
}

// The Delaunay refinement is what gives clusters* the rule (the front and its optimisation
// leave unexcused triangles in their narrow wedges), and it never makes a file worse.
TEST(Front2dFiles, MinAngleRefinement) {
  for (const char* name : {"clusters.poly", "clusters2.edg", "img5.edg", "img6.edg"}) {
    SCOPED_TRACE(name);
    const Pslg p = read_pslg(test::test_data(std::string("pslg/") + name));
    FrontOptions o = uniform(bbox_diagonal(p) / 100);
    o.enclose_convex_hull = std::string(name) != "clusters.poly";
    o.refine_min_angle = false;
    const Mesh2d plain = mesh_pslg(p, o);
    o.refine_min_angle = true;
    const Mesh2d refined = mesh_pslg(p, o);
    EXPECT_EQ(plain.report.n_refinement_points, 0u);
    EXPECT_GT(refined.report.n_refinement_points, 0u);
    EXPECT_EQ(check_mesh(p, refined, refined.report.domain_area), "");
    const std::size_t before = count_unexcused_small_angles(p, plain);
    const std::size_t after = count_unexcused_small_angles(p, refined);
    EXPECT_LT(after, before);
    if (std::string(name).starts_with("clusters")) {
      EXPECT_GT(before, 0u);
      EXPECT_EQ(after, 0u);
    }
  }
}

TEST(Front2dFilesSlow, CgalDemoDomainsFine) { mesh_cgal_files(200); }

TEST(Front2dFiles, TriangleExamples) {
  const auto dir = test::shared_data("pslg/triangle_examples");
  if (!dir) GTEST_SKIP() << "../shared/data absent";
  for (const char* name : {"A.poly", "box.poly", "face.poly", "double_hex.poly", "double_hex2.poly", "double_hex3.poly",
                           "dots.node", "spiral.node", "diamond_02_00009.node"}) {
    SCOPED_TRACE(name);
    const Pslg p = read_pslg(*dir / name);
    Vec lo = p.points[0], hi = p.points[0];
    for (const auto& x : p.points) {
      lo = lo.cwiseMin(x);
      hi = hi.cwiseMax(x);
    }
    const Mesh2d m = mesh_file(p, (hi - lo).norm() / 60);
    EXPECT_EQ(check_mesh(p, m, m.report.domain_area), "");
    EXPECT_GT(m.report.domain_area, 0);
    EXPECT_EQ(count_unexcused_small_angles(p, m), 0u);
  }
}

TEST(Front2dFiles, ReadersOnHandWrittenFiles) {
  const auto dir = test::temp_dir("front2d_readers");
  {
    std::ofstream f(dir / "sq.poly");
    f << "# 1-based, one attribute, markers\n4 2 1 1\n1 0 0 0.1 1\n2 2 0 0.1 1\n3 2 2 0.1 1\n4 0 2 0.1 1\n"
         "4 1\n1 1 2 1\n2 2 3 1\n3 3 4 1\n4 4 1 1\n0\n1\n1 1 1 5 0.1\n";
  }
  const Pslg p = read_poly(dir / "sq.poly");
  ASSERT_EQ(p.points.size(), 4u);
  ASSERT_EQ(p.segments.size(), 4u);
  EXPECT_EQ(p.segments[0], (std::array<int, 2>{0, 1}));
  ASSERT_EQ(p.point_sizes.size(), 4u);
  ASSERT_EQ(p.regions.size(), 1u);
  EXPECT_EQ(p.regions[0].marker, 5);
  FrontOptions o;
  o.sizing = SizingField::per_vertex(p.point_sizes);
  const Mesh2d m = mesh_pslg(p, o);
  EXPECT_EQ(check_mesh(p, m, 4.0), "");
  for (int r : m.triangle_regions) EXPECT_EQ(r, 5);
  {
    std::ofstream f(dir / "pts.node");
    f << "5 2 0 0\n0 0 0\n1 1 0\n2 1 1\n3 0 1\n4 0.5 0.5\n";
  }
  const Pslg n = read_pslg(dir / "pts.node");
  EXPECT_TRUE(n.segments.empty());
  const Mesh2d mn = mesh_pslg(n, uniform(0.2));  // no segments: the convex hull
  EXPECT_EQ(check_mesh(n, mn, 1.0), "");
  {
    std::ofstream f(dir / "tri.edg");
    f << "4\n0 0 1 0\n1 0 0 1\n0 1 0 0\n0.2 0.2 0.2 0.2\n";
  }
  const Pslg e = read_pslg(dir / "tri.edg");
  EXPECT_EQ(e.points.size(), 4u);   // the zero-length segment's point is read ...
  EXPECT_EQ(e.segments.size(), 3u); // ... but the segment is skipped
  EXPECT_EQ(check_mesh(e, mesh_pslg(e, uniform(0.1)), 0.5), "");
  {
    std::ofstream f(dir / "bad.poly");
    f << "3 2 0 0\n1 0 0\n2 1 x\n";
  }
  EXPECT_THROW((void)read_pslg(dir / "bad.poly"), IoError);
  EXPECT_THROW((void)read_pslg(dir / "sq.txt"), IoError);
}

TEST(Front2d, ProgressCanCancel) {
  const Pslg sq = polygon({{0, 0}, {1, 0}, {1, 1}, {0, 1}});
  FrontOptions o = uniform(0.05);
  int calls = 0;
  o.progress = [&](std::string_view, double f) {
    ++calls;
    EXPECT_GE(f, 0.0);
    EXPECT_LE(f, 1.0);
    return true;
  };
  (void)mesh_pslg(sq, o);
  EXPECT_GE(calls, 2);
  o.progress = [](std::string_view, double) { return false; };
  EXPECT_THROW((void)mesh_pslg(sq, o), Cancelled);
}

// ---------------------------------------------------------------- bad input

TEST(Front2dErrors, BadInputThrowsClearly) {
  auto throws_with = [](const Pslg& p, const std::string& what) {
    try {
      (void)mesh_pslg(p, uniform(0.1));
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
      return;
    }
    ADD_FAILURE() << "no InvalidInput for " << what;
  };
  throws_with(Pslg{}, "empty");
  Pslg cross = polygon({{0, 0}, {1, 0}, {0, 1}, {1, 1}});  // bow tie
  throws_with(cross, "cross");
  Pslg dup = polygon({{0, 0}, {1, 0}, {1, 1}, {0, 1}});
  dup.points.push_back({1, 0});
  throws_with(dup, "duplicate");
  Pslg hole = polygon({{0, 0}, {1, 0}, {1, 1}, {0, 1}});
  hole.holes.push_back({5, 5});
  throws_with(hole, "outside");
  Pslg nan = polygon({{0, 0}, {1, 0}, {1, std::numeric_limits<double>::quiet_NaN()}});
  throws_with(nan, "finite");
  Pslg on = polygon({{0, 0}, {2, 0}, {2, 2}, {0, 2}});
  on.points.push_back({1, 0});
  throws_with(on, "lies on segment");
  throws_with(polygon({{0, 0}, {1, 1}, {2, 2}}), "collinear");
  FrontOptions bad;
  bad.sizing.gradation = 0.5;
  EXPECT_THROW((void)mesh_pslg(polygon({{0, 0}, {1, 0}, {0, 1}}), bad), InvalidInput);
  EXPECT_THROW((void)read_pslg("no_such_file.poly"), IoError);
}

// ---------------------------------------------------------------- property tests

// A random star-shaped polygon around c with n vertices and radii in [r0, r1].
std::vector<Vec> star(std::mt19937_64& rng, Vec c, int n, double r0, double r1) {
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<double> ang;
  // Jittered even angles: every gap < pi for n >= 4, so c is inside.
  for (int i = 0; i < n; ++i) ang.push_back(2 * std::numbers::pi * (i + 0.8 * u(rng)) / n);
  std::vector<Vec> pts;
  for (double a : ang) {
    const double r = r0 + (r1 - r0) * u(rng);
    pts.push_back(c + r * Vec(std::cos(a), std::sin(a)));
  }
  return pts;
}

double loop_area(const std::vector<Vec>& p) {
  double a = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Vec& u = p[i];
    const Vec& w = p[(i + 1) % p.size()];
    a += 0.5 * (u.x() * w.y() - w.x() * u.y());
  }
  return a;
}

// One random domain of a kind chosen by the seed; returns the expected area.
double random_domain(std::uint64_t seed, Pslg& p, double& h) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  const int kind = static_cast<int>(seed % 5);
  p = Pslg{};
  double area = 0;
  switch (kind) {
    case 0: {  // star polygon with star holes
      auto outer = star(rng, {0, 0}, 8 + static_cast<int>(rng() % 30), 0.7, 1.0);
      if (outer.size() < 3) outer = {{1, 0}, {0, 1}, {-1, -1}};
      area = loop_area(outer);
      p = polygon(outer);
      const int n_holes = static_cast<int>(rng() % 3);
      for (int k = 0; k < n_holes; ++k) {
        const Vec c(-0.3 + 0.6 * k / std::max(1, n_holes - 1) * (n_holes > 1), 0.0);
        auto hl = star(rng, c, 4 + static_cast<int>(rng() % 8), 0.05, 0.12);
        if (hl.size() < 3) continue;
        std::reverse(hl.begin(), hl.end());
        add_loop(p, hl);
        p.holes.push_back(c);
        area += loop_area(hl);
      }
      h = 0.05 + 0.15 * u(rng);
      break;
    }
    case 1: {  // near-collinear and near-duplicate points along the edges of a square
      std::vector<Vec> pts;
      const double eps = std::pow(10.0, -4.0 - 10.0 * u(rng));
      const int n = 2 + static_cast<int>(rng() % 6);
      for (int side = 0; side < 4; ++side) {
        const Vec a = side == 0 ? Vec(0, 0) : side == 1 ? Vec(1, 0) : side == 2 ? Vec(1, 1) : Vec(0, 1);
        const Vec b = side == 0 ? Vec(1, 0) : side == 1 ? Vec(1, 1) : side == 2 ? Vec(0, 1) : Vec(0, 0);
        const Vec nrm(-(b - a).y(), (b - a).x());
        for (int i = 0; i < n; ++i) {
          const double t = static_cast<double>(i) / n + (i > 0 && u(rng) < 0.3 ? eps : 0.0);
          pts.push_back(a + t * (b - a) + (i > 0 ? eps * (u(rng) - 0.5) : 0.0) * nrm);
        }
      }
      area = loop_area(pts);
      p = polygon(pts);
      h = 0.05 + 0.2 * u(rng);
      break;
    }
    case 2: {  // a tiny input angle: a thin wedge
      const double ang = std::pow(10.0, -0.5 - 2.0 * u(rng));
      const std::vector<Vec> pts = {{0, 0}, {1, 0}, {std::cos(ang), std::sin(ang)}};
      area = loop_area(pts);
      p = polygon(pts);
      h = 0.03 + 0.1 * u(rng);
      break;
    }
    case 3: {  // size ratio up to 1:1000: tiny hole in a big square
      const double s = std::pow(10.0, -1.0 - 2.0 * u(rng));
      const Vec c(0.2 + 0.6 * u(rng), 0.2 + 0.6 * u(rng));
      p = polygon({{0, 0}, {1, 0}, {1, 1}, {0, 1}});
      std::vector<Vec> hl = {c + Vec(s, 0), c + Vec(0, -s), c + Vec(-s, 0), c + Vec(0, s)};
      add_loop(p, hl);
      p.holes.push_back(c);
      area = 1.0 + loop_area(hl);
      h = 0.05 + 0.1 * u(rng);
      break;
    }
    default: {  // long thin rectangle, possibly rotated
      const double w = std::pow(10.0, -1.0 - 1.5 * u(rng));
      const double t = u(rng);
      const Vec ex(std::cos(t), std::sin(t)), ey(-std::sin(t), std::cos(t));
      const std::vector<Vec> pts = {Vec::Zero(), ex, ex + w * ey, w * ey};
      area = loop_area(pts);
      p = polygon(pts);
      h = 0.01 + 0.05 * u(rng);
      break;
    }
  }
  return area;
}

void run_property(std::uint64_t first, std::uint64_t count) {
  std::size_t failures = 0;
  for (std::uint64_t seed = first; seed < first + count && failures < 5; ++seed) {
    Pslg p;
    double h = 0.1;
    const double area = random_domain(seed, p, h);
    try {
      const Mesh2d m = mesh_pslg(p, uniform(h));
      const std::string e = check_mesh(p, m, area);
      if (!e.empty()) {
        ++failures;
        ADD_FAILURE() << "seed " << seed << ": " << e;
      }
    } catch (const std::exception& ex) {
      ++failures;
      ADD_FAILURE() << "seed " << seed << ": exception " << ex.what();
    }
  }
}

TEST(Front2dProperty, RandomDomains) { run_property(1, 150); }
TEST(Front2dPropertySlow, ThousandsOfRandomDomains) { run_property(1000, 4000); }

}  // namespace
}  // namespace nurbsfront
