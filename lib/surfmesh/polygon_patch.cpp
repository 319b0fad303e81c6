// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/surfmesh/polygon_patch.h"

#include <cmath>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include <Eigen/Geometry>

#include "nurbsfront/core/error.h"
#include "nurbsfront/nurbs/frame.h"
#include "nurbsfront/surfmesh/height_field_metric.h"

namespace nurbsfront {

namespace {

bool finite(const Eigen::Vector3d& p) { return p.allFinite(); }

// Newell's normal: twice the vector area of a (possibly non-planar) polygon.
Eigen::Vector3d newell_normal(const std::vector<Eigen::Vector3d>& polygon) {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < polygon.size(); ++i) n += polygon[i].cross(polygon[(i + 1) % polygon.size()]);
  return n;
}

void validate_input(const PolygonPatch& patch) {
  const std::size_t n = patch.polygon.size();
  if (n < 3) throw InvalidInput("polygon patch: the polygon needs at least 3 vertices, got " + std::to_string(n));
  if (patch.densities.size() != n) {
    throw InvalidInput("polygon patch: " + std::to_string(patch.densities.size()) + " densities for " +
                       std::to_string(n) + " polygon vertices");
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!finite(patch.polygon[i])) throw InvalidInput("polygon patch: polygon vertex " + std::to_string(i) + " is not finite");
    const double d = patch.densities[i];
    if (!std::isfinite(d) || d <= 0.0) {
      throw InvalidInput("polygon patch: density " + std::to_string(i) + " must be finite and > 0");
    }
  }
  for (std::size_t i = 0; i < patch.points.size(); ++i) {
    if (!finite(patch.points[i])) throw InvalidInput("polygon patch: scattered point " + std::to_string(i) + " is not finite");
  }
}

}  // namespace

void PolygonPatchOptions::validate() const {
  if (!std::isfinite(relative_tolerance) || relative_tolerance <= 0.0) {
    throw InvalidInput("polygon patch: relative_tolerance must be finite and > 0");
  }
  if (max_levels < 1 || max_levels > 20) throw InvalidInput("polygon patch: max_levels must be in [1, 20]");
  if (!std::isfinite(gradation) || gradation <= 1.0) throw InvalidInput("polygon patch: gradation must be > 1");
  if (smoothing_passes < 0) throw InvalidInput("polygon patch: smoothing_passes must be >= 0");
}

PolygonPatchMesh mesh_polygon_patch(const PolygonPatch& patch, const PolygonPatchOptions& options) {
  options.validate();
  validate_input(patch);

  // 1. Rotate onto the xy-plane: z along the polygon's normal, so its vertices run
  //    counter-clockwise in the plane.
  const Eigen::Vector3d area_vector = newell_normal(patch.polygon);
  double extent = 0.0;
  for (const auto& p : patch.polygon) extent = std::max(extent, (p - patch.polygon.front()).norm());
  if (!(area_vector.norm() > 1e-12 * extent * extent)) {
    throw InvalidInput("polygon patch: the polygon has no area (its vertices are collinear or coincide)");
  }
  const Eigen::Vector3d normal = area_vector.normalized();
  PolygonPatchMesh out;
  const PatchFrame frame =
      patch_frame(patch.polygon, std::vector<Eigen::Vector3d>(patch.polygon.size(), normal));
  const std::vector<Eigen::Vector3d> polygon_local = frame.to_local(patch.polygon);

  // 2. Fit z = f(x, y) to the scattered points and the polygon's vertices.
  std::vector<Eigen::Vector3d> samples = polygon_local;
  const std::vector<Eigen::Vector3d> points_local = frame.to_local(patch.points);
  samples.insert(samples.end(), points_local.begin(), points_local.end());
  FitOptions fit_options;
  fit_options.relative_tolerance = options.relative_tolerance;
  fit_options.max_levels = options.max_levels;
  fit_options.progress = options.progress;
  out.fit = fit_height_field(samples, fit_options);
  out.surface.frame = frame;
  out.surface.field = out.fit.field;

  // 3. The polygon as a PSLG, meshed with the surface metric and the vertices' densities.
  Pslg pslg;
  const std::size_t n = patch.polygon.size();
  for (std::size_t i = 0; i < n; ++i) {
    pslg.points.emplace_back(polygon_local[i].x(), polygon_local[i].y());
    pslg.segments.push_back({static_cast<int>(i), static_cast<int>((i + 1) % n)});
  }
  FrontOptions front_options;
  front_options.sizing = SizingField::per_vertex(patch.densities);
  front_options.sizing.gradation = options.gradation;
  front_options.metric = std::make_shared<HeightFieldMetric>(out.surface.field);
  front_options.smoothing_passes = options.smoothing_passes;
  front_options.progress = options.progress;
  const Mesh2d mesh = mesh_pslg(pslg, front_options);
  if (mesh.report.status != FrontStatus::Ok) {
    throw SolverError("polygon patch: the advancing front did not close: " + mesh.report.message);
  }
  out.front = mesh.report;

  // 4. Lift every node onto the fitted surface and rotate back.
  out.nodes.reserve(mesh.points.size());
  for (std::size_t i = 0; i < mesh.points.size(); ++i) {
    if (options.keep_polygon_vertices && i < n) {
      out.nodes.push_back(patch.polygon[i]);
    } else {
      const Eigen::Vector2d& q = mesh.points[i];
      out.nodes.push_back(frame.to_world(out.surface.field.lift(q.x(), q.y())));
    }
  }
  out.triangles = mesh.triangles;
  return out;
}

PolygonPatch read_polygon_patch(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw IoError("cannot open polygon patch file '" + path.string() + "'");
  PolygonPatch patch;
  std::string line;
  std::size_t line_no = 0;
  enum class Section { None, Polygon, Points } section = Section::None;
  std::size_t expected = 0;
  auto fail = [&](const std::string& why) {
    throw IoError(path.string() + ":" + std::to_string(line_no) + ": " + why);
  };
  bool seen_polygon = false;
  while (std::getline(in, line)) {
    ++line_no;
    if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    std::istringstream ls(line);
    std::string word;
    if (!(ls >> word)) continue;
    if (word == "polygon" || word == "points") {
      if (expected != 0) fail("section '" + word + "' starts before the previous one has all its lines");
      long long count = -1;
      if (!(ls >> count) || count < 0) fail("expected a count after '" + word + "'");
      if (word == "polygon") {
        if (seen_polygon) fail("a second 'polygon' section");
        seen_polygon = true;
        section = Section::Polygon;
      } else {
        section = Section::Points;
      }
      expected = static_cast<std::size_t>(count);
      continue;
    }
    if (expected == 0) fail("unexpected line (a 'polygon N' or 'points M' header was expected)");
    std::istringstream values(line);
    Eigen::Vector3d p;
    if (!(values >> p.x() >> p.y() >> p.z())) fail("expected x y z");
    if (section == Section::Polygon) {
      double density = 0.0;
      if (!(values >> density)) fail("expected x y z density");
      patch.polygon.push_back(p);
      patch.densities.push_back(density);
    } else {
      patch.points.push_back(p);
    }
    --expected;
  }
  if (!seen_polygon) throw IoError(path.string() + ": no 'polygon N' section");
  if (expected != 0) throw IoError(path.string() + ": truncated: " + std::to_string(expected) + " lines missing");
  return patch;
}

PolygonPatch example_polygon_patch() {
  // A smooth bump with a gentle tilt, z = 1.6 exp(-|p - c|^2 / 8) + 0.15 x.
  const auto surface = [](double x, double y) {
    const double dx = x - 0.6;
    const double dy = y + 0.4;
    return 1.6 * std::exp(-(dx * dx + dy * dy) / 8.0) + 0.15 * x;
  };
  PolygonPatch patch;
  const double corners[6][3] = {{-5.0, -3.5, 0.35}, {1.0, -4.8, 0.45}, {5.2, -2.0, 0.6},
                                {4.4, 3.6, 0.5},    {-0.6, 5.0, 0.4},  {-4.8, 2.2, 0.35}};
  for (const auto& c : corners) {
    patch.polygon.emplace_back(c[0], c[1], surface(c[0], c[1]));
    patch.densities.push_back(c[2]);
  }
  // 20 x 20 scattered points over the polygon's bounding box, jittered deterministically
  // (golden-ratio offsets).
  const double golden = 0.6180339887498949;
  for (int j = 0; j < 20; ++j) {
    for (int i = 0; i < 20; ++i) {
      const double jx = std::fmod((i * 20 + j) * golden, 1.0);
      const double jy = std::fmod((i * 20 + j) * golden * golden, 1.0);
      const double x = -5.2 + 10.6 * (i + jx) / 20.0;
      const double y = -5.0 + 10.2 * (j + jy) / 20.0;
      patch.points.emplace_back(x, y, surface(x, y));
    }
  }
  return patch;
}

}  // namespace nurbsfront
