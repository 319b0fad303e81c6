// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/isosurface/marching_cubes.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <Eigen/Geometry>

#include "nurbsfront/core/error.h"

namespace nurbsfront {

void MarchingCubesOptions::validate() const {
  if (!std::isfinite(iso)) throw InvalidInput("nurbsfront: MarchingCubesOptions::iso must be finite");
}

namespace {

// ---------------------------------------------------------------------------------------------
// Case table, derived once from the per-face rule (see marching_cubes.h).

Eigen::Vector3d corner_position(int c) { return {double(c & 1), double((c >> 1) & 1), double((c >> 2) & 1)}; }

// Cube edge joining corners a and b (which differ in exactly one bit).
int edge_between(int a, int b) {
  const int diff = a ^ b;
  const int dx = a & b & 1, dy = ((a & b) >> 1) & 1, dz = ((a & b) >> 2) & 1;
  if (diff == 1) return dy + 2 * dz;
  if (diff == 2) return 4 + dx + 2 * dz;
  return 8 + dx + 2 * dy;
}

std::array<int, 2> edge_corners(int e) {
  const int axis = e / 4, r = e % 4;
  const int lo_bits[3] = {(r & 1) << 1 | (r >> 1) << 2, (r & 1) | (r >> 1) << 2, (r & 1) | (r >> 1) << 1};
  const int lo = lo_bits[axis];
  return {lo, lo | (1 << axis)};
}

// Corners of face (axis, side) in counter-clockwise order seen from outside the cube.
std::array<int, 4> face_corners(int axis, int side) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  const int base = side << axis;
  // (u, v) = (0,0), (1,0), (1,1), (0,1) is CCW about e_u x e_v = +e_axis.
  std::array<int, 4> q = {base, base | (1 << u), base | (1 << u) | (1 << v), base | (1 << v)};
  if (side == 0) std::swap(q[1], q[3]);  // normal -e_axis: reverse the cycle
  return q;
}

double triangle_quality(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const double area = 0.5 * (b - a).cross(c - a).norm();
  const double sum = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
  return 4.0 * std::sqrt(3.0) * area / sum;
}

struct CaseTable {
  std::array<MarchingCubesCase, 256> cases{};
};

// Triangulates one loop of cube edges: no diagonal may join two edges of one cube face (such a
// diagonal could be chosen by the neighbouring cube too and lie in the shared face). Among the
// admissible triangulations the one maximising the worst triangle (on edge midpoints) is taken.
void triangulate_loop(const std::vector<int>& loop, const std::array<unsigned, 12>& edge_faces,
                      MarchingCubesCase& out) {
  const int n = static_cast<int>(loop.size());
  std::vector<Eigen::Vector3d> mid(n);
  for (int i = 0; i < n; ++i) {
    const auto [a, b] = edge_corners(loop[i]);
    mid[i] = 0.5 * (corner_position(a) + corner_position(b));
  }
  auto allowed = [&](int i, int j) {
    if (j - i == 1 || (i == 0 && j == n - 1)) return true;
    return (edge_faces[loop[i]] & edge_faces[loop[j]]) == 0;
  };
  constexpr double kNone = -1.0;
  std::vector<double> score(n * n, kNone);
  std::vector<int> split(n * n, -1);
  for (int i = 0; i + 1 < n; ++i) score[i * n + i + 1] = 2.0;  // an edge: no triangle yet
  for (int len = 2; len < n; ++len) {
    for (int i = 0; i + len < n; ++i) {
      const int j = i + len;
      if (!allowed(i, j)) continue;
      for (int k = i + 1; k < j; ++k) {
        const double s1 = score[i * n + k], s2 = score[k * n + j];
        if (s1 < 0.0 || s2 < 0.0) continue;
        const double s = std::min({s1, s2, triangle_quality(mid[i], mid[k], mid[j])});
        if (s > score[i * n + j]) {
          score[i * n + j] = s;
          split[i * n + j] = k;
        }
      }
    }
  }
  if (score[n - 1] < 0.0) throw InternalError("nurbsfront: marching cubes loop without admissible triangulation");
  std::vector<std::array<int, 2>> stack = {{0, n - 1}};
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    if (j - i < 2) continue;
    const int k = split[i * n + j];
    if (out.n_triangles >= out.triangles.size()) throw InternalError("nurbsfront: marching cubes case overflow");
    out.triangles[out.n_triangles++] = {static_cast<std::uint8_t>(loop[i]), static_cast<std::uint8_t>(loop[k]),
                                        static_cast<std::uint8_t>(loop[j])};
    stack.push_back({i, k});
    stack.push_back({k, j});
  }
}

CaseTable build_case_table() {
  CaseTable table;
  std::array<std::array<int, 4>, 6> faces{};
  std::array<unsigned, 12> edge_faces{};
  for (int f = 0; f < 6; ++f) {
    faces[f] = face_corners(f / 2, f % 2);
    for (int k = 0; k < 4; ++k) edge_faces[edge_between(faces[f][k], faces[f][(k + 1) % 4])] |= 1u << f;
  }
  for (int mask = 0; mask < 256; ++mask) {
    auto inside = [mask](int c) { return ((mask >> c) & 1) != 0; };
    std::array<int, 12> next;
    next.fill(-1);
    for (const auto& q : faces) {
      for (int k = 0; k < 4; ++k) {
        if (inside(q[k]) || !inside(q[(k + 1) % 4])) continue;  // not an outside -> inside edge
        // The rule: pair it with the next inside -> outside edge counter-clockwise. On an
        // ambiguous face this separates the two inside corners.
        for (int step = 1; step < 4; ++step) {
          const int m = (k + step) % 4;
          if (inside(q[m]) && !inside(q[(m + 1) % 4])) {
            next[edge_between(q[k], q[(k + 1) % 4])] = edge_between(q[m], q[(m + 1) % 4]);
            break;
          }
        }
      }
    }
    std::array<bool, 12> seen{};
    MarchingCubesCase& out = table.cases[mask];
    for (int e0 = 0; e0 < 12; ++e0) {
      if (next[e0] < 0 || seen[e0]) continue;
      std::vector<int> loop;
      for (int e = e0; !seen[e]; e = next[e]) {
        if (next[e] < 0) throw InternalError("nurbsfront: marching cubes loop is not closed");
        seen[e] = true;
        loop.push_back(e);
      }
      if (loop.size() < 3) throw InternalError("nurbsfront: marching cubes loop too short");
      triangulate_loop(loop, edge_faces, out);
    }
  }
  return table;
}

const CaseTable& case_table() {
  static const CaseTable table = build_case_table();  // immutable after thread-safe initialisation
  return table;
}

// ---------------------------------------------------------------------------------------------
// The sweep.

ScalarGrid padded_grid(const ScalarGrid& grid, const MarchingCubesOptions& options) {
  const auto [lo, hi] = grid.value_range();
  // An "outside" value: the most outside of the data and the iso-value, nudged in float until
  // the classification below agrees (a double iso may round to the inside side as a float).
  float pad = options.inside_above ? std::min(lo, static_cast<float>(options.iso))
                                   : std::max(hi, static_cast<float>(options.iso));
  const float away = options.inside_above ? -std::numeric_limits<float>::infinity()
                                          : std::numeric_limits<float>::infinity();
  while (options.inside_above ? (double(pad) > options.iso) : (double(pad) < options.iso)) {
    pad = std::nextafter(pad, away);
  }
  ScalarGrid out;
  out.dims = {grid.dims[0] + 2, grid.dims[1] + 2, grid.dims[2] + 2};
  out.origin = grid.origin - grid.spacing;
  out.spacing = grid.spacing;
  out.values.assign(out.size(), pad);
  for (int k = 0; k < grid.dims[2]; ++k) {
    for (int j = 0; j < grid.dims[1]; ++j) {
      const float* src = grid.values.data() + grid.index(0, j, k);
      std::copy(src, src + grid.dims[0], out.values.data() + out.index(1, j + 1, k + 1));
    }
  }
  return out;
}

class Sweep {
 public:
  Sweep(const ScalarGrid& grid, const MarchingCubesOptions& options)
      : g_(grid), opt_(options), nx_(grid.dims[0]), ny_(grid.dims[1]), nz_(grid.dims[2]) {}

  TriangleSoup run() {
    const std::size_t plane = static_cast<std::size_t>(nx_) * ny_;
    in0_.assign(plane, 0);
    in1_.assign(plane, 0);
    xe0_.assign(static_cast<std::size_t>(nx_ - 1) * ny_, kNoVertex);
    xe1_ = xe0_;
    ye0_.assign(static_cast<std::size_t>(nx_) * (ny_ - 1), kNoVertex);
    ye1_ = ye0_;
    ze_.assign(plane, kNoVertex);
    const MarchingCubesCase* cases = case_table().cases.data();

    classify_plane(0, in0_);
    plane_vertices(0, in0_, xe0_, ye0_);
    const int report_every = std::max(1, (nz_ - 1) / 100);
    for (int k = 0; k + 1 < nz_; ++k) {
      if (k % report_every == 0) report_progress(opt_.progress, "marching cubes", double(k) / double(nz_ - 1));
      classify_plane(k + 1, in1_);
      plane_vertices(k + 1, in1_, xe1_, ye1_);
      z_vertices(k);
      for (int j = 0; j + 1 < ny_; ++j) {
        const std::size_t r0 = static_cast<std::size_t>(j) * nx_, r1 = r0 + nx_;
        const std::size_t xr0 = static_cast<std::size_t>(j) * (nx_ - 1), xr1 = xr0 + (nx_ - 1);
        for (int i = 0; i + 1 < nx_; ++i) {
          const unsigned mask = in0_[r0 + i] | in0_[r0 + i + 1] << 1 | in0_[r1 + i] << 2 | in0_[r1 + i + 1] << 3 |
                                in1_[r0 + i] << 4 | in1_[r0 + i + 1] << 5 | in1_[r1 + i] << 6 |
                                in1_[r1 + i + 1] << 7;
          if (mask == 0 || mask == 255) continue;
          const std::uint32_t ev[12] = {xe0_[xr0 + i], xe0_[xr1 + i], xe1_[xr0 + i], xe1_[xr1 + i],
                                        ye0_[r0 + i],  ye0_[r0 + i + 1], ye1_[r0 + i], ye1_[r0 + i + 1],
                                        ze_[r0 + i],   ze_[r0 + i + 1],  ze_[r1 + i],  ze_[r1 + i + 1]};
          const MarchingCubesCase& c = cases[mask];
          for (int t = 0; t < c.n_triangles; ++t) {
            soup_.triangles.push_back({ev[c.triangles[t][0]], ev[c.triangles[t][1]], ev[c.triangles[t][2]]});
          }
        }
      }
      std::swap(in0_, in1_);
      std::swap(xe0_, xe1_);
      std::swap(ye0_, ye1_);
    }
    report_progress(opt_.progress, "marching cubes", 1.0);
    return std::move(soup_);
  }

 private:
  static constexpr std::uint32_t kNoVertex = std::numeric_limits<std::uint32_t>::max();

  void classify_plane(int k, std::vector<std::uint8_t>& in) const {
    const float* v = g_.values.data() + g_.index(0, 0, k);
    const std::size_t n = in.size();
    if (opt_.inside_above) {
      for (std::size_t p = 0; p < n; ++p) in[p] = double(v[p]) > opt_.iso ? 1 : 0;
    } else {
      for (std::size_t p = 0; p < n; ++p) in[p] = double(v[p]) < opt_.iso ? 1 : 0;
    }
  }

  // New vertex on the edge from sample `a` (at grid position base) along `axis`.
  std::uint32_t add_vertex(float a, float b, const Eigen::Vector3d& base, int axis) {
    double t = (opt_.iso - double(a)) / (double(b) - double(a));
    t = std::clamp(t, kMarchingCubesEdgeClamp, 1.0 - kMarchingCubesEdgeClamp);
    Eigen::Vector3d p = base;
    p[axis] += t;
    if (soup_.points.size() >= kNoVertex) throw InvalidInput("nurbsfront: marching cubes output exceeds 2^32 vertices");
    soup_.points.push_back(g_.origin + p.cwiseProduct(g_.spacing));
    return static_cast<std::uint32_t>(soup_.points.size() - 1);
  }

  void plane_vertices(int k, const std::vector<std::uint8_t>& in, std::vector<std::uint32_t>& xe,
                      std::vector<std::uint32_t>& ye) {
    const float* v = g_.values.data() + g_.index(0, 0, k);
    for (int j = 0; j < ny_; ++j) {
      const std::size_t r = static_cast<std::size_t>(j) * nx_;
      for (int i = 0; i + 1 < nx_; ++i) {
        std::uint32_t id = kNoVertex;
        if (in[r + i] != in[r + i + 1]) id = add_vertex(v[r + i], v[r + i + 1], Eigen::Vector3d(i, j, k), 0);
        xe[static_cast<std::size_t>(j) * (nx_ - 1) + i] = id;
      }
      if (j + 1 == ny_) break;
      for (int i = 0; i < nx_; ++i) {
        std::uint32_t id = kNoVertex;
        if (in[r + i] != in[r + nx_ + i]) id = add_vertex(v[r + i], v[r + nx_ + i], Eigen::Vector3d(i, j, k), 1);
        ye[r + i] = id;
      }
    }
  }

  void z_vertices(int k) {
    const float* v0 = g_.values.data() + g_.index(0, 0, k);
    const float* v1 = g_.values.data() + g_.index(0, 0, k + 1);
    for (int j = 0; j < ny_; ++j) {
      const std::size_t r = static_cast<std::size_t>(j) * nx_;
      for (int i = 0; i < nx_; ++i) {
        std::uint32_t id = kNoVertex;
        if (in0_[r + i] != in1_[r + i]) id = add_vertex(v0[r + i], v1[r + i], Eigen::Vector3d(i, j, k), 2);
        ze_[r + i] = id;
      }
    }
  }

  const ScalarGrid& g_;
  const MarchingCubesOptions& opt_;
  const int nx_, ny_, nz_;
  std::vector<std::uint8_t> in0_, in1_;
  std::vector<std::uint32_t> xe0_, xe1_, ye0_, ye1_, ze_;
  TriangleSoup soup_;
};

}  // namespace

const MarchingCubesCase& marching_cubes_case(std::uint8_t inside_mask) { return case_table().cases[inside_mask]; }

TriangleSoup marching_cubes(const ScalarGrid& grid, const MarchingCubesOptions& options) {
  options.validate();
  grid.validate();
  const int min_dim = options.pad ? 1 : 2;
  for (int a = 0; a < 3; ++a) {
    if (grid.dims[a] < min_dim) {
      throw InvalidInput("nurbsfront: marching_cubes needs at least 2 samples along each axis (or pad), got " +
                         std::to_string(grid.dims[0]) + " x " + std::to_string(grid.dims[1]) + " x " +
                         std::to_string(grid.dims[2]));
    }
  }
  if (options.pad) {
    const ScalarGrid padded = padded_grid(grid, options);
    return Sweep(padded, options).run();
  }
  return Sweep(grid, options).run();
}

}  // namespace nurbsfront
