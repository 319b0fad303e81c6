// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>
#include <sstream>

#include <Eigen/Geometry>

#include "nurbsfront/core/error.h"
#include "nurbsfront/nurbs/frame.h"
#include "nurbsfront/nurbs/mba.h"
#include "nurbsfront/nurbs/surface_io.h"
#include "support/test_data.h"

namespace nurbsfront {
namespace {

NurbsSurface sample_surface() {
  BicubicHeightField f(Rectangle{{-1.0, 0.5}, {2.0, 1.75}}, 4, 3);
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> c(-1.0, 1.0);
  for (auto& x : f.mutable_coefficients()) x = c(rng) / 3.0;  // not representable in short decimals
  NurbsSurface s = f.to_nurbs();
  s.weights[5] = 0.1 + 1.0 / 7.0;  // make it rational
  return s;
}

TEST(PatchFrame, MeanNormalBecomesZAndTransformsRoundTrip) {
  const Eigen::Matrix3d rot = Eigen::AngleAxisd(1.1, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  const Eigen::Vector3d shift(3, -1, 7);
  std::vector<Eigen::Vector3d> pts;
  std::vector<Eigen::Vector3d> normals;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 200; ++k) {
    const Eigen::Vector3d local(2.0 * u(rng), 0.5 * u(rng), 0.05 * u(rng));
    pts.push_back(rot * local + shift);
    normals.push_back(rot * Eigen::Vector3d(0.1 * u(rng), 0.1 * u(rng), 1.0) * (1.0 + k % 3));  // unnormalised
  }
  const PatchFrame f = patch_frame(pts, normals);
  EXPECT_NEAR((f.axes.transpose() * f.axes - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-14);
  EXPECT_NEAR(f.axes.determinant(), 1.0, 1e-14);
  EXPECT_GT(f.axes.col(2).dot(rot.col(2)), 0.99);
  EXPECT_GT(std::abs(f.axes.col(0).dot(rot.col(0))), 0.99);  // the long side becomes x
  for (const auto& p : pts) EXPECT_LT((f.to_world(f.to_local(p)) - p).norm(), 1e-13);
  const auto local = f.to_local(pts);
  for (const auto& q : local) EXPECT_LT(std::abs(q.z()), 0.1);
  EXPECT_LT((f.direction_to_world(f.direction_to_local(Eigen::Vector3d(1, 2, 3))) - Eigen::Vector3d(1, 2, 3)).norm(), 1e-14);

  const PatchFrame g = patch_frame_pca(pts, rot.col(2));
  EXPECT_GT(g.axes.col(2).dot(rot.col(2)), 0.999);
}

TEST(PatchFrame, FitInTheFrameAndRotateBackIsExact) {
  // A tilted paraboloid patch: fit in its frame, express the NURBS in world coordinates.
  const Eigen::Matrix3d rot = Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
  std::vector<Eigen::Vector3d> world;
  std::vector<Eigen::Vector3d> normals;
  for (int a = 0; a <= 30; ++a) {
    for (int b = 0; b <= 30; ++b) {
      const double x = -1.0 + a / 15.0;
      const double y = -1.0 + b / 15.0;
      world.push_back(rot * Eigen::Vector3d(x, y, 0.1 * (x * x + y * y)));
      normals.push_back(rot * Eigen::Vector3d(-0.2 * x, -0.2 * y, 1.0).normalized());
    }
  }
  const PatchFrame f = patch_frame(world, normals);
  FitOptions o;
  o.tolerance = 1e-6;
  const FitResult fit = fit_height_field(f.to_local(world), o);
  const NurbsSurface s = fit.field.to_nurbs().transformed(f.axes, f.origin);
  const Rectangle& r = fit.field.domain();
  for (double u : {0.1, 0.5, 0.9}) {
    for (double v : {0.2, 0.7}) {
      const Eigen::Vector3d local = fit.field.lift(r.min.x() + u * r.width(), r.min.y() + v * r.height());
      EXPECT_LT((s.evaluate(u, v) - f.to_world(local)).norm(), 1e-12);
    }
  }
}

TEST(PatchFrame, BadInput) {
  EXPECT_THROW((void)patch_frame({}, {}), InvalidInput);
  EXPECT_THROW((void)patch_frame({{0, 0, 0}}, {{0, 0, 1}, {0, 0, 1}}), InvalidInput);
  EXPECT_THROW((void)patch_frame({{0, 0, 0}, {1, 0, 0}}, {{0, 0, 1}, {0, 0, -1}}), InvalidInput);  // cancel out
  EXPECT_THROW((void)patch_frame({{0, 0, NAN}}, {{0, 0, 1}}), InvalidInput);
  EXPECT_THROW((void)patch_frame_pca({{0, 0, 0}, {1, 1, 1}, {2, 2, 2}}), InvalidInput);  // collinear
}

TEST(SurfaceIo, TextFormatRoundTripsExactly) {
  const NurbsSurface s = sample_surface();
  const std::string text = surface_to_text(s);
  const NurbsSurface back = surface_from_text(text);
  EXPECT_EQ(back.u.degree, s.u.degree);
  EXPECT_EQ(back.v.degree, s.v.degree);
  EXPECT_EQ(back.u.knots, s.u.knots);
  EXPECT_EQ(back.v.knots, s.v.knots);
  ASSERT_EQ(back.control_points.size(), s.control_points.size());
  for (std::size_t k = 0; k < s.control_points.size(); ++k) {
    EXPECT_EQ(back.control_points[k], s.control_points[k]);  // bit-exact
    EXPECT_EQ(back.weights[k], s.weights[k]);
  }
  const auto dir = test::temp_dir("nurbs_io");
  write_surface(dir / "s.nurbs", s);
  const NurbsSurface file = read_surface(dir / "s.nurbs");
  EXPECT_EQ(file.evaluate(0.3, 0.6), s.evaluate(0.3, 0.6));
}

TEST(SurfaceIo, MalformedTextIsAnIoError) {
  const std::string good = surface_to_text(sample_surface());
  EXPECT_THROW((void)surface_from_text(""), IoError);
  EXPECT_THROW((void)surface_from_text("nurbsfront_surface 2\n"), IoError);
  std::string truncated = good.substr(0, good.size() / 2);
  EXPECT_THROW((void)surface_from_text(truncated), IoError);
  std::string bad_number = good;
  bad_number.replace(bad_number.find("points\n") + 7, 1, "x");
  EXPECT_THROW((void)surface_from_text(bad_number), IoError);
  // Parses but is invalid: a negative weight.
  std::string neg = good;
  const std::size_t end_pos = neg.find("\nend");
  const std::size_t line_start = neg.rfind('\n', end_pos - 1) + 1;
  neg.replace(line_start, end_pos - line_start, "0 0 0 -1");
  EXPECT_THROW((void)surface_from_text(neg), InvalidInput);
  EXPECT_THROW((void)read_surface("/nonexistent/dir/s.nurbs"), IoError);
}

// Minimal IGES reader for the test: checks the fixed-column layout and returns the
// parameter data of the first entity as numbers.
std::vector<double> iges_parameters(const std::string& iges, int* n_s, int* n_g, int* n_d, int* n_p) {
  std::istringstream in(iges);
  std::string line;
  std::string pdata;
  int counts[4] = {0, 0, 0, 0};
  std::string terminate;
  while (std::getline(in, line)) {
    EXPECT_EQ(line.size(), 80u) << line;
    const char section = line[72];
    const int seq = std::stoi(line.substr(73));
    switch (section) {
      case 'S': EXPECT_EQ(seq, ++counts[0]); break;
      case 'G': EXPECT_EQ(seq, ++counts[1]); break;
      case 'D': EXPECT_EQ(seq, ++counts[2]); break;
      case 'P':
        EXPECT_EQ(seq, ++counts[3]);
        EXPECT_EQ(std::stoi(line.substr(64, 8)), 1);  // back pointer to DE 1
        pdata += line.substr(0, 64);
        break;
      case 'T': terminate = line; break;
      default: ADD_FAILURE() << "bad section letter in: " << line;
    }
  }
  *n_s = counts[0];
  *n_g = counts[1];
  *n_d = counts[2];
  *n_p = counts[3];
  EXPECT_EQ(terminate.substr(0, 32), "S      1G" + std::string(7 - std::to_string(counts[1]).size(), ' ') +
                                         std::to_string(counts[1]) + "D      2P" +
                                         std::string(7 - std::to_string(counts[3]).size(), ' ') + std::to_string(counts[3]));
  std::vector<double> values;
  std::string token;
  for (char c : pdata) {
    if (c == ',' || c == ';') {
      values.push_back(std::stod(token));
      token.clear();
      if (c == ';') break;
    } else if (c != ' ') {
      token += c;
    }
  }
  return values;
}

TEST(SurfaceIo, IgesEntity128HoldsTheExactSurface) {
  const NurbsSurface s = sample_surface();
  const std::string iges = surfaces_to_iges({s});
  int n_s = 0;
  int n_g = 0;
  int n_d = 0;
  int n_p = 0;
  const std::vector<double> p = iges_parameters(iges, &n_s, &n_g, &n_d, &n_p);
  EXPECT_EQ(n_d, 2);
  ASSERT_GE(p.size(), 10u);
  EXPECT_EQ(p[0], 128);
  EXPECT_EQ(p[1], static_cast<double>(s.n_u - 1));
  EXPECT_EQ(p[2], static_cast<double>(s.n_v - 1));
  EXPECT_EQ(p[3], 3);
  EXPECT_EQ(p[4], 3);
  EXPECT_EQ(p[7], 0);  // rational
  const std::size_t nk_u = s.u.knots.size();
  const std::size_t nk_v = s.v.knots.size();
  const std::size_t n = s.n_u * s.n_v;
  ASSERT_EQ(p.size(), 10 + nk_u + nk_v + 4 * n + 4);
  std::size_t at = 10;
  for (double k : s.u.knots) EXPECT_EQ(p[at++], k);
  for (double k : s.v.knots) EXPECT_EQ(p[at++], k);
  for (std::size_t k = 0; k < n; ++k) EXPECT_EQ(p[at++], s.weights[k]);
  for (std::size_t k = 0; k < n; ++k)
    for (int c = 0; c < 3; ++c) EXPECT_EQ(p[at++], s.control_points[k][c]);  // 17 digits: exact
  EXPECT_EQ(p[at++], 0.0);
  EXPECT_EQ(p[at++], 1.0);
  EXPECT_THROW((void)surfaces_to_iges({}), InvalidInput);
}

TEST(SurfaceIo, XyzReadsWhatItWritesAndReportsBadLines) {
  const auto dir = test::temp_dir("nurbs_xyz");
  const std::vector<Eigen::Vector3d> pts = {{0.1, 0.2, 1.0 / 3.0}, {-1e-300, 5e10, -0.0}};
  write_xyz(dir / "p.xyz", pts);
  EXPECT_EQ(read_xyz(dir / "p.xyz"), pts);
  {
    std::ofstream out(dir / "q.xyz");
    out << "# comment\n\n1 2 3 0 0 1\n4,5,6\n\t+7 8 9\r\n";
  }
  const auto q = read_xyz(dir / "q.xyz");
  ASSERT_EQ(q.size(), 3u);
  EXPECT_EQ(q[1], Eigen::Vector3d(4, 5, 6));
  EXPECT_EQ(q[2], Eigen::Vector3d(7, 8, 9));
  {
    std::ofstream out(dir / "bad.xyz");
    out << "1 2 3\n4 5\n";
  }
  try {
    (void)read_xyz(dir / "bad.xyz");
    ADD_FAILURE() << "no exception";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("line 2"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)read_xyz(dir / "missing.xyz"), IoError);
}

}  // namespace
}  // namespace nurbsfront
