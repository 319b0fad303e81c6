// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/isosurface/scenes.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <thread>

#include "nurbsfront/core/error.h"
#include "nurbsfront/core/parallel.h"

namespace nurbsfront {
namespace {

// sqrt(x^2 + y^2) without std::hypot's overflow care (slow, and the scenes are O(1) in size).
inline double length2(double x, double y) { return std::sqrt(x * x + y * y); }

// Exact signed distance to the box [lo, hi].
double box_sdf(const Eigen::Vector3d& p, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const Eigen::Vector3d c = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
  const Eigen::Vector3d q = (p - c).cwiseAbs() - half;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

// Exact signed distance to a cylinder with axis parallel to z through (cx, cy), z in [z0, z1].
double zcylinder_sdf(const Eigen::Vector3d& p, double cx, double cy, double radius, double z0, double z1) {
  const double dr = length2(p.x() - cx, p.y() - cy) - radius;
  const double dz = std::max(z0 - p.z(), p.z() - z1);
  return std::min(std::max(dr, dz), 0.0) + length2(std::max(dr, 0.0), std::max(dz, 0.0));
}

// Exact signed distance to a 2D box [x0, x1] x [z0, z1] in the (x, z) plane (a prism along y).
double xz_rect_sdf(double x, double z, double x0, double x1, double z0, double z1) {
  const double qx = std::abs(x - 0.5 * (x0 + x1)) - 0.5 * (x1 - x0);
  const double qz = std::abs(z - 0.5 * (z0 + z1)) - 0.5 * (z1 - z0);
  return length2(std::max(qx, 0.0), std::max(qz, 0.0)) + std::min(std::max(qx, qz), 0.0);
}

double sdf(const SphereScene& s, const Eigen::Vector3d& p) { return (p - s.center).norm() - s.radius; }

double sdf(const TorusScene& s, const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = p - s.center;
  return length2(length2(d.x(), d.y()) - s.major_radius, d.z()) - s.minor_radius;
}

double sdf(const TrenchScene& s, const Eigen::Vector3d& p) {
  const double slab = box_sdf(p, Eigen::Vector3d::Zero(), Eigen::Vector3d(s.width, s.length, s.height));
  const double x0 = 0.5 * (s.width - s.groove_width), x1 = 0.5 * (s.width + s.groove_width);
  const double bottom = s.height - s.groove_depth, top = 2.0 * s.height;  // the groove's prism reaches above the slab
  double groove = 0.0;
  if (s.rounded) {
    const double r = 0.5 * s.groove_width, axis_z = bottom + r;
    groove = std::min(xz_rect_sdf(p.x(), p.z(), x0, x1, axis_z, top),
                      length2(p.x() - 0.5 * s.width, p.z() - axis_z) - r);
  } else {
    groove = xz_rect_sdf(p.x(), p.z(), x0, x1, bottom, top);
  }
  return std::max(slab, -groove);
}

// Layout of the DRAM cell (derived from the parameters in one place).
struct DramLayout {
  double word_top, bit_top;
  std::array<double, 2> col_x, row_y;
};

DramLayout layout(const DramScene& s) {
  DramLayout l{};
  l.word_top = s.substrate_thickness + s.word_line_height;
  l.bit_top = l.word_top + s.bit_line_height;
  l.col_x = {0.25 * s.size_x, 0.75 * s.size_x};
  l.row_y = {0.25 * s.size_y, 0.75 * s.size_y};
  return l;
}

double sdf(const DramScene& s, const Eigen::Vector3d& p) {
  const DramLayout l = layout(s);
  double d = box_sdf(p, Eigen::Vector3d::Zero(), Eigen::Vector3d(s.size_x, s.size_y, s.substrate_thickness));
  for (int i = 0; i < s.n_word_lines; ++i) {
    const double x = s.size_x * (i + 0.5) / s.n_word_lines;
    d = std::min(d, box_sdf(p, Eigen::Vector3d(x - 0.5 * s.word_line_width, 0.0, s.substrate_thickness),
                            Eigen::Vector3d(x + 0.5 * s.word_line_width, s.size_y, l.word_top)));
  }
  for (const double y : l.row_y) {
    d = std::min(d, box_sdf(p, Eigen::Vector3d(0.0, y - 0.5 * s.bit_line_width, l.word_top),
                            Eigen::Vector3d(s.size_x, y + 0.5 * s.bit_line_width, l.bit_top)));
  }
  const double inner = s.cup_outer_radius - s.cup_wall;
  for (const double x : l.col_x) {
    for (const double y : l.row_y) {
      // Plug and cup are both >= (radial distance - outer radius): skip them when that cannot lower d.
      if (length2(p.x() - x, p.y() - y) - s.cup_outer_radius > d) continue;
      const double plug = zcylinder_sdf(p, x, y, s.plug_radius, 0.5 * s.substrate_thickness,
                                        s.cup_bottom_z + 0.5 * s.cup_wall);
      const double outer = zcylinder_sdf(p, x, y, s.cup_outer_radius, s.cup_bottom_z, s.size_z);
      const double hollow = zcylinder_sdf(p, x, y, inner, s.cup_bottom_z + s.cup_wall, 2.0 * s.size_z);
      d = std::min({d, plug, std::max(outer, -hollow)});
    }
  }
  return d;
}

BoundingBox box_of(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  BoundingBox b;
  b.extend(lo);
  b.extend(hi);
  return b;
}

void require(bool ok, const std::string& what) {
  if (!ok) throw InvalidInput("nurbsfront: invalid scene: " + what);
}

void check(const SphereScene& s) {
  require(s.center.allFinite() && std::isfinite(s.radius) && s.radius > 0.0, "sphere radius must be positive");
}
void check(const TorusScene& s) {
  require(s.center.allFinite() && s.minor_radius > 0.0 && s.major_radius > s.minor_radius &&
              std::isfinite(s.major_radius),
          "torus needs 0 < minor_radius < major_radius");
}
void check(const TrenchScene& s) {
  require(s.width > 0.0 && s.length > 0.0 && s.height > 0.0 && std::isfinite(s.width + s.length + s.height),
          "trench sizes must be positive");
  require(s.groove_width > 0.0 && s.groove_width < s.width, "trench needs 0 < groove_width < width");
  require(s.groove_depth > 0.0 && s.groove_depth < s.height, "trench needs 0 < groove_depth < height");
  require(!s.rounded || 0.5 * s.groove_width <= s.groove_depth, "a rounded groove needs groove_width / 2 <= groove_depth");
}
void check(const DramScene& s) {
  require(s.size_x > 0.0 && s.size_y > 0.0 && s.size_z > 0.0 && std::isfinite(s.size_x + s.size_y + s.size_z),
          "dram box sizes must be positive");
  require(s.substrate_thickness > 0.0 && s.word_line_height > 0.0 && s.bit_line_height > 0.0 &&
              s.word_line_width > 0.0 && s.bit_line_width > 0.0 && s.n_word_lines >= 1,
          "dram layer sizes must be positive");
  require(s.substrate_thickness + s.word_line_height + s.bit_line_height <= s.cup_bottom_z,
          "dram cups must stand above the bit lines");
  require(s.cup_wall > 0.0 && s.cup_wall < s.cup_outer_radius && s.cup_bottom_z + 2.0 * s.cup_wall < s.size_z,
          "dram cup wall must be thinner than the cup");
  require(s.plug_radius > 0.0 && s.plug_radius < s.cup_outer_radius, "dram plug radius must be in (0, cup radius)");
  require(s.cup_outer_radius <= 0.25 * std::min(s.size_x, s.size_y), "dram cups must fit in the box");
  require(s.word_line_width * s.n_word_lines < s.size_x && 2.0 * s.bit_line_width < s.size_y,
          "dram lines must fit in the box");
}

}  // namespace

double signed_distance(const Scene& scene, const Eigen::Vector3d& p) {
  return std::visit([&](const auto& s) { return sdf(s, p); }, scene);
}

DistanceSummary DistanceSummary::merged(const DistanceSummary& other) const {
  DistanceSummary m;
  m.count = count + other.count;
  if (m.count == 0) return m;
  m.mean = (mean * static_cast<double>(count) + other.mean * static_cast<double>(other.count)) / static_cast<double>(m.count);
  m.max = std::max(max, other.max);
  return m;
}

SceneDistance distance_to_scene(const TriangleSoup& soup, const Scene& scene, int dense_steps) {
  validate(scene);
  constexpr int kMaxDenseSteps = 64;
  if (dense_steps < 0 || dense_steps > kMaxDenseSteps) {
    throw InvalidInput("nurbsfront: distance_to_scene dense_steps must be in [0, 64], got " + std::to_string(dense_steps));
  }
  for (std::size_t t = 0; t < soup.triangles.size(); ++t)
    for (const std::uint32_t v : soup.triangles[t])
      if (v >= soup.points.size()) {
        throw InvalidInput("nurbsfront: distance_to_scene: triangle " + std::to_string(t) + " refers to point " + std::to_string(v) +
                           " of " + std::to_string(soup.points.size()));
      }
  // Sums first, means at the end.
  auto add = [&](DistanceSummary& d, const Eigen::Vector3d& p) {
    const double e = std::abs(signed_distance(scene, p));
    d.mean += e;
    d.max = std::max(d.max, e);
    ++d.count;
  };
  SceneDistance out;
  for (const auto& p : soup.points) add(out.vertices, p);
  for (const auto& t : soup.triangles) {
    const Eigen::Vector3d& a = soup.points[t[0]];
    const Eigen::Vector3d& b = soup.points[t[1]];
    const Eigen::Vector3d& c = soup.points[t[2]];
    add(out.centroids, (a + b + c) / 3.0);
    if (dense_steps < 2) continue;
    for (int i = 0; i <= dense_steps; ++i)
      for (int j = 0; i + j <= dense_steps; ++j) {
        const int k = dense_steps - i - j;
        if (i == dense_steps || j == dense_steps || k == dense_steps) continue;  // corners are vertices
        add(out.dense, (i * a + j * b + k * c) / dense_steps);
      }
  }
  for (DistanceSummary* d : {&out.vertices, &out.centroids, &out.dense})
    if (d->count > 0) d->mean /= static_cast<double>(d->count);
  return out;
}

BoundingBox bounding_box(const Scene& scene) {
  struct Visitor {
    BoundingBox operator()(const SphereScene& s) const {
      return box_of(s.center.array() - s.radius, s.center.array() + s.radius);
    }
    BoundingBox operator()(const TorusScene& s) const {
      const double r = s.major_radius + s.minor_radius;
      return box_of(s.center - Eigen::Vector3d(r, r, s.minor_radius), s.center + Eigen::Vector3d(r, r, s.minor_radius));
    }
    BoundingBox operator()(const TrenchScene& s) const {
      return box_of(Eigen::Vector3d::Zero(), Eigen::Vector3d(s.width, s.length, s.height));
    }
    BoundingBox operator()(const DramScene& s) const {
      return box_of(Eigen::Vector3d::Zero(), Eigen::Vector3d(s.size_x, s.size_y, s.size_z));
    }
  };
  return std::visit(Visitor{}, scene);
}

void validate(const Scene& scene) {
  std::visit([](const auto& s) { check(s); }, scene);
}

std::vector<std::string> scene_names() { return {"sphere", "torus", "trench", "dram"}; }

Scene scene_by_name(std::string_view name) {
  if (name == "sphere") return SphereScene{};
  if (name == "torus") return TorusScene{};
  if (name == "trench") return TrenchScene{};
  if (name == "dram") return DramScene{};
  throw InvalidInput("nurbsfront: unknown scene '" + std::string(name) + "' (known: sphere, torus, trench, dram)");
}

MarchingCubesOptions scene_marching_cubes_options(SampleMode mode) {
  MarchingCubesOptions options;
  options.iso = mode == SampleMode::LevelSet ? 0.0 : 0.5;
  options.inside_above = mode == SampleMode::Occupancy;
  return options;
}

ScalarGrid sample_scene(const Scene& scene, int resolution, SampleMode mode) {
  validate(scene);
  constexpr int kMinResolution = 4, kMaxResolution = 2048;
  if (resolution < kMinResolution || resolution > kMaxResolution) {
    throw InvalidInput("nurbsfront: sample_scene resolution must be in [4, 2048], got " + std::to_string(resolution));
  }
  const BoundingBox box = bounding_box(scene);
  const Eigen::Vector3d extent = box.max - box.min;
  const double h = extent.maxCoeff() / resolution;
  ScalarGrid grid;
  for (int a = 0; a < 3; ++a) {
    const int cells = std::max(1, static_cast<int>(std::ceil(extent[a] / h)));
    grid.dims[a] = cells + 1 + 2 * kSceneMarginCells;
  }
  grid.spacing = Eigen::Vector3d::Constant(h);
  const Eigen::Vector3d center = 0.5 * (box.min + box.max);
  grid.origin = center - 0.5 * h * Eigen::Vector3d(grid.dims[0] - 1, grid.dims[1] - 1, grid.dims[2] - 1);
  grid.values.resize(grid.size());

  const int nz = grid.dims[2];
  auto fill = [&](int k_begin, int k_end) {
    std::visit(
        [&](const auto& s) {
          for (int k = k_begin; k < k_end; ++k) {
            for (int j = 0; j < grid.dims[1]; ++j) {
              std::size_t index = grid.index(0, j, k);
              for (int i = 0; i < grid.dims[0]; ++i, ++index) {
                const double d = sdf(s, grid.point(i, j, k));
                grid.values[index] = mode == SampleMode::LevelSet ? static_cast<float>(d) : (d < 0.0 ? 1.0f : 0.0f);
              }
            }
          }
        },
        scene);
  };
  // Each sample depends only on its own position, so the thread count cannot change the result.
  const int n_threads = std::clamp(static_cast<int>(std::thread::hardware_concurrency()), 1, std::min(16, nz));
  const auto slabs = static_cast<std::size_t>(nz);
  const std::size_t chunk = (slabs + static_cast<std::size_t>(n_threads) - 1) / static_cast<std::size_t>(n_threads);
  parallel::for_chunks(slabs, static_cast<unsigned>(n_threads), chunk, [&](std::size_t begin, std::size_t end, unsigned) {
    fill(static_cast<int>(begin), static_cast<int>(end));
  });
  return grid;
}

}  // namespace nurbsfront
