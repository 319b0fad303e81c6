// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/quality/report.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <functional>
#include <limits>
#include <numbers>
#include <numeric>
#include <optional>
#include <string>
#include <system_error>
#include <thread>

#include <Eigen/Geometry>

#include "nurbsfront/core/disjoint_sets.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/core/tolerances.h"
#include "nurbsfront/quality/aabb_tree.h"
#include "nurbsfront/quality/internal.h"

namespace nurbsfront {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;
constexpr double kSmallAngleDeg = 30.0;       // DESIGN.md: share of triangles with min angle < 30 deg
constexpr double kPercentileFraction = 0.01;  // alpha_p1

bool repeats_index(const std::array<std::uint32_t, 3>& t) { return t[0] == t[1] || t[1] == t[2] || t[2] == t[0]; }

}  // namespace

double triangle_alpha(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const double sum_sq = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
  if (!(sum_sq > 0.0)) return 0.0;
  const double area = 0.5 * (b - a).cross(c - a).norm();
  return 4.0 * std::numbers::sqrt3 * area / sum_sq;
}

std::array<double, 3> triangle_angles_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                          const Eigen::Vector3d& c) {
  auto angle = [](const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
    return std::atan2(u.cross(v).norm(), u.dot(v)) * kRadToDeg;
  };
  return {angle(b - a, c - a), angle(c - b, a - b), angle(a - c, b - c)};
}

double tetrahedron_gamma(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                         const Eigen::Vector3d& d) {
  const double sum_sq = (b - a).squaredNorm() + (c - a).squaredNorm() + (d - a).squaredNorm() +
                        (c - b).squaredNorm() + (d - b).squaredNorm() + (d - c).squaredNorm();
  if (!(sum_sq > 0.0)) return 0.0;
  const double volume = std::abs((b - a).dot((c - a).cross(d - a))) / 6.0;
  return 72.0 * std::numbers::sqrt3 * volume / std::pow(sum_sq, 1.5);
}

namespace quality_detail {

void validate_soup(const TriangleSoup& soup, const char* what) {
  const auto n = soup.points.size();
  for (std::size_t i = 0; i < soup.triangles.size(); ++i) {
    const auto& t = soup.triangles[i];
    if (t[0] >= n || t[1] >= n || t[2] >= n) {
      throw InvalidInput(std::string("nurbsfront: ") + what + ": triangle " + std::to_string(i) +
                         " has a vertex index out of range (" + std::to_string(n) + " points)");
    }
  }
  for (const auto& p : soup.points) {
    if (!p.allFinite()) {
      throw InvalidInput(std::string("nurbsfront: ") + what + ": mesh has non-finite (NaN or infinite) coordinates");
    }
  }
}

bool is_closed_surface(const TriangleSoup& soup) {
  if (soup.triangles.empty()) return false;
  std::vector<std::uint64_t> keys;
  keys.reserve(soup.triangles.size() * 3);
  for (const auto& t : soup.triangles) {
    if (repeats_index(t)) return false;
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t lo = std::min(t[k], t[(k + 1) % 3]), hi = std::max(t[k], t[(k + 1) % 3]);
      keys.push_back(lo << 32 | hi);
    }
  }
  bucket_sort(keys, soup.points.size(), [](std::uint64_t key) { return key >> 32; }, std::less<>());
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i;
    while (j < keys.size() && keys[j] == keys[i]) ++j;
    if (j - i != 2) return false;
    i = j;
  }
  return true;
}

}  // namespace quality_detail

std::vector<double> face_alpha(const TriangleSoup& soup) {
  quality_detail::validate_soup(soup, "face_alpha");
  std::vector<double> alpha(soup.triangles.size());
  for (std::size_t i = 0; i < alpha.size(); ++i) {
    const auto& t = soup.triangles[i];
    alpha[i] = triangle_alpha(soup.points[t[0]], soup.points[t[1]], soup.points[t[2]]);
  }
  return alpha;
}

std::vector<double> face_min_angle_deg(const TriangleSoup& soup) {
  quality_detail::validate_soup(soup, "face_min_angle_deg");
  std::vector<double> angle(soup.triangles.size());
  for (std::size_t i = 0; i < angle.size(); ++i) {
    const auto& t = soup.triangles[i];
    const auto a = triangle_angles_deg(soup.points[t[0]], soup.points[t[1]], soup.points[t[2]]);
    angle[i] = std::min({a[0], a[1], a[2]});
  }
  return angle;
}

double enclosed_volume(const TriangleSoup& soup) {
  quality_detail::validate_soup(soup, "enclosed_volume");
  // Relative to the first point, which keeps the sum accurate far from the origin.
  if (soup.points.empty()) return 0.0;
  const Eigen::Vector3d o = soup.points.front();
  double six_volume = 0.0;
  for (const auto& t : soup.triangles) {
    six_volume += (soup.points[t[0]] - o).dot((soup.points[t[1]] - o).cross(soup.points[t[2]] - o));
  }
  return six_volume / 6.0;
}

void DistanceOptions::validate() const {
  if (!(sample_spacing_relative > 0.0) || !std::isfinite(sample_spacing_relative)) {
    throw InvalidInput("nurbsfront: DistanceOptions::sample_spacing_relative must be a positive number");
  }
  if (max_samples == 0) throw InvalidInput("nurbsfront: DistanceOptions::max_samples must be positive");
  if (n_threads == 0) throw InvalidInput("nurbsfront: DistanceOptions::n_threads must be at least 1");
}

void ReportOptions::validate() const {
  if (n_threads == 0) throw InvalidInput("nurbsfront: ReportOptions::n_threads must be at least 1");
  distance.validate();
}

namespace {

struct EdgeEntry {
  std::uint64_t key;    // lo << 32 | hi
  std::uint32_t face;   // face index
  std::uint32_t forward;  // 1 if the face traverses lo -> hi
};

// The topology's counts that read each face alone: degenerate faces and duplicate faces
// (the same three vertex ids in any order), into r.
void count_degenerate_and_duplicate_faces(const TriangleSoup& soup, TopologyReport& r) {
  const std::size_t n_points = soup.points.size();
  const std::size_t n_faces = soup.triangles.size();
  // Degenerate faces.
  const double diagonal = bounding_box(soup).diagonal();
  const double area_floor = tolerance::kDegenerateAreaRelative * diagonal * diagonal;
  for (const auto& t : soup.triangles) {
    if (repeats_index(t)) {
      ++r.n_degenerate_faces;
      continue;
    }
    const double area = 0.5 * (soup.points[t[1]] - soup.points[t[0]]).cross(soup.points[t[2]] - soup.points[t[0]]).norm();
    if (area <= area_floor) ++r.n_degenerate_faces;
  }

  // Duplicate faces: the same three vertex ids in any order.
  std::vector<std::pair<std::array<std::uint32_t, 3>, std::uint32_t>> keys(n_faces);
  for (std::size_t f = 0; f < n_faces; ++f) {
    auto key = soup.triangles[f];
    std::sort(key.begin(), key.end());
    keys[f] = {key, static_cast<std::uint32_t>(f)};
  }
  quality_detail::bucket_sort(keys, n_points, [](const auto& key) { return key.first[0]; }, std::less<>());
  for (std::size_t i = 1; i < keys.size(); ++i) {
    if (keys[i].first == keys[i - 1].first) ++r.n_duplicate_faces;
  }
}

// The topology but for count_degenerate_and_duplicate_faces()'s counts (left 0): the caller
// adds them.
TopologyReport compute_topology(const TriangleSoup& soup, std::vector<EdgeEntry>& edges,
                                std::vector<double>& edge_lengths) {
  TopologyReport r;
  const std::size_t n_points = soup.points.size();
  const std::size_t n_faces = soup.triangles.size();
  r.n_faces = n_faces;

  std::vector<char> referenced(n_points, 0);
  for (const auto& t : soup.triangles) {
    for (auto v : t) referenced[v] = 1;
  }
  r.n_vertices = static_cast<std::size_t>(std::count(referenced.begin(), referenced.end(), 1));
  r.n_unreferenced_points = n_points - r.n_vertices;

  // Edges of the faces that do not repeat an index.
  edges.clear();
  edges.reserve(n_faces * 3);
  for (std::size_t f = 0; f < n_faces; ++f) {
    const auto& t = soup.triangles[f];
    if (repeats_index(t)) continue;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t from = t[k], to = t[(k + 1) % 3];
      const std::uint64_t lo = std::min(from, to), hi = std::max(from, to);
      edges.push_back({lo << 32 | hi, static_cast<std::uint32_t>(f), from < to ? 1u : 0u});
    }
  }
  quality_detail::bucket_sort(
      edges, n_points, [](const EdgeEntry& e) { return e.key >> 32; },
      [](const EdgeEntry& x, const EdgeEntry& y) { return x.key < y.key || (x.key == y.key && x.face < y.face); });

  // Components through shared vertices; numbered by their lowest face.
  DisjointSets vertex_sets(n_points);
  for (const auto& t : soup.triangles) {
    vertex_sets.unite(t[0], t[1]);
    vertex_sets.unite(t[1], t[2]);
  }
  std::vector<std::uint32_t> component_of_root(n_points, std::numeric_limits<std::uint32_t>::max());
  std::vector<std::uint32_t> face_component(n_faces);
  for (std::size_t f = 0; f < n_faces; ++f) {
    const std::uint32_t root = vertex_sets.find(soup.triangles[f][0]);
    if (component_of_root[root] == std::numeric_limits<std::uint32_t>::max()) {
      component_of_root[root] = static_cast<std::uint32_t>(r.components.size());
      r.components.emplace_back();
    }
    face_component[f] = component_of_root[root];
  }
  r.n_components = r.components.size();
  std::vector<char> comp_bad_manifold(r.n_components, 0), comp_open(r.n_components, 0),
      comp_misoriented(r.n_components, 0);
  for (std::size_t f = 0; f < n_faces; ++f) {
    ++r.components[face_component[f]].n_faces;
    if (repeats_index(soup.triangles[f])) comp_bad_manifold[face_component[f]] = 1;
  }
  for (std::size_t v = 0; v < n_points; ++v) {
    if (referenced[v]) ++r.components[component_of_root[vertex_sets.find(static_cast<std::uint32_t>(v))]].n_vertices;
  }

  // Edge groups: multiplicity, orientation, boundary; corners linked around vertices.
  DisjointSets corners(n_faces * 3);
  auto corner = [&](std::uint32_t face, std::uint32_t vertex) {
    const auto& t = soup.triangles[face];
    const std::uint32_t k = t[0] == vertex ? 0 : (t[1] == vertex ? 1 : 2);
    return face * 3 + k;
  };
  DisjointSets boundary_sets(n_points);
  std::vector<char> on_boundary(n_points, 0);
  edge_lengths.clear();
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j].key == edges[i].key) ++j;
    const std::size_t m = j - i;
    const auto lo = static_cast<std::uint32_t>(edges[i].key >> 32);
    const auto hi = static_cast<std::uint32_t>(edges[i].key & 0xffffffffu);
    const std::uint32_t comp = face_component[edges[i].face];
    ++r.n_edges;
    ++r.components[comp].n_edges;
    edge_lengths.push_back((soup.points[hi] - soup.points[lo]).norm());
    if (m == 1) {
      ++r.n_boundary_edges;
      comp_open[comp] = 1;
      boundary_sets.unite(lo, hi);
      on_boundary[lo] = on_boundary[hi] = 1;
    } else if (m > 2) {
      ++r.n_nonmanifold_edges;
      comp_open[comp] = 1;
      comp_bad_manifold[comp] = 1;
    } else if (edges[i].forward == edges[i + 1].forward) {
      ++r.n_misoriented_edges;
      comp_misoriented[comp] = 1;
    }
    for (std::size_t k = i + 1; k < j; ++k) {
      corners.unite(corner(edges[i].face, lo), corner(edges[k].face, lo));
      corners.unite(corner(edges[i].face, hi), corner(edges[k].face, hi));
    }
    i = j;
  }
  // Fans per vertex = corner classes per vertex.
  std::vector<std::uint32_t> fans(n_points, 0);
  for (std::size_t f = 0; f < n_faces; ++f) {
    const auto& t = soup.triangles[f];
    if (repeats_index(t)) continue;
    for (std::uint32_t k = 0; k < 3; ++k) {
      const auto c = static_cast<std::uint32_t>(f * 3 + k);
      if (corners.find(c) == c) ++fans[t[k]];
    }
  }
  for (std::size_t v = 0; v < n_points; ++v) {
    if (fans[v] > 1) {
      ++r.n_nonmanifold_vertices;
      comp_bad_manifold[component_of_root[vertex_sets.find(static_cast<std::uint32_t>(v))]] = 1;
    }
  }
  for (std::size_t v = 0; v < n_points; ++v) {
    if (on_boundary[v] && boundary_sets.find(static_cast<std::uint32_t>(v)) == v) ++r.n_boundary_loops;
  }

  bool all_closed_oriented = r.n_components > 0;
  for (std::size_t c = 0; c < r.n_components; ++c) {
    auto& comp = r.components[c];
    comp.euler_characteristic = static_cast<long>(comp.n_vertices) - static_cast<long>(comp.n_edges) +
                                static_cast<long>(comp.n_faces);
    comp.is_closed = !comp_open[c];
    comp.is_manifold = !comp_bad_manifold[c];
    comp.is_oriented = !comp_misoriented[c];
    if (comp.is_closed && comp.is_manifold && comp.is_oriented && comp.euler_characteristic % 2 == 0) {
      comp.genus = (2 - comp.euler_characteristic) / 2;
    } else {
      all_closed_oriented = false;
    }
    r.euler_characteristic += comp.euler_characteristic;
  }
  r.is_closed = n_faces > 0 && r.n_boundary_edges == 0 && r.n_nonmanifold_edges == 0;
  r.is_manifold = r.n_nonmanifold_edges == 0 && r.n_nonmanifold_vertices == 0 &&
                  std::none_of(soup.triangles.begin(), soup.triangles.end(), repeats_index);
  r.is_consistently_oriented = r.n_misoriented_edges == 0;
  if (all_closed_oriented) r.volume = enclosed_volume(soup);
  return r;
}

// False only when triangle (a, b, c) surely changes neither extreme angle: the sine of its
// smallest angle (twice the area over the product of the two longest edges) exceeds
// sin_min_bound (>= sin 30 deg) and the cosine of its largest angle (law of cosines at the
// longest edge) exceeds cos_max_bound, both by far more than their rounding and
// triangle_angles_deg()'s (with every angle above 30 deg the edges differ by at most 2x, so
// the cosine is off by a few ulps). The triangles it lets through are measured with
// triangle_angles_deg() as before, so the report does not change; most are spared its
// three atan2.
bool may_change_angle_extremes(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                               double sin_min_bound, double cos_max_bound) {
  std::array<double, 3> l2{(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()};
  std::sort(l2.begin(), l2.end());
  const double product = std::sqrt(l2[1] * l2[2]);
  if (!(product > 0.0)) return true;
  if (!((b - a).cross(c - a).norm() / product > sin_min_bound + tolerance::kAngleBoundMargin)) return true;
  const double cos_largest = (l2[0] + l2[1] - l2[2]) / (2.0 * std::sqrt(l2[0] * l2[1]));
  return !(cos_largest > cos_max_bound + tolerance::kAngleBoundMargin);
}

// The quality figures of the triangles (alpha, angles, obtuse and small-angle shares); the
// edge-length ones are left to add_edge_quality().
QualityReport compute_triangle_quality(const TriangleSoup& soup) {
  QualityReport q;
  const std::size_t n = soup.triangles.size();
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  if (n == 0) {
    q = {kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN};
    return q;
  }
  std::vector<double> alpha(n);
  double alpha_sum = 0.0;
  double min_angle = std::numeric_limits<double>::infinity(), max_angle = 0.0;
  std::size_t n_obtuse = 0, n_small = 0;
  // Triangles surely inside [max(min_angle, 30 deg), max_angle] change neither extreme nor
  // the small-angle count: not measured (before the first triangle, every one is).
  double sin_min_bound = 2.0, cos_max_bound = 2.0;
  for (std::size_t f = 0; f < n; ++f) {
    const auto& t = soup.triangles[f];
    const Eigen::Vector3d& a = soup.points[t[0]];
    const Eigen::Vector3d& b = soup.points[t[1]];
    const Eigen::Vector3d& c = soup.points[t[2]];
    alpha[f] = triangle_alpha(a, b, c);
    alpha_sum += alpha[f];
    // Obtuse by the sign of the dot products (exact for right angles on exact data).
    if ((b - a).dot(c - a) < 0.0 || (c - b).dot(a - b) < 0.0 || (a - c).dot(b - c) < 0.0) ++n_obtuse;
    if (!may_change_angle_extremes(a, b, c, sin_min_bound, cos_max_bound)) continue;
    const auto angles = triangle_angles_deg(a, b, c);
    const double lo = std::min({angles[0], angles[1], angles[2]});
    const double hi = std::max({angles[0], angles[1], angles[2]});
    min_angle = std::min(min_angle, lo);
    max_angle = std::max(max_angle, hi);
    if (lo < kSmallAngleDeg) ++n_small;
    sin_min_bound = std::sin(std::max(min_angle, kSmallAngleDeg) / kRadToDeg);
    cos_max_bound = std::cos(max_angle / kRadToDeg);
  }
  q.alpha_mean = alpha_sum / static_cast<double>(n);
  const auto rank = static_cast<std::size_t>(std::floor(kPercentileFraction * static_cast<double>(n - 1)));
  std::nth_element(alpha.begin(), alpha.begin() + static_cast<std::ptrdiff_t>(rank), alpha.end());
  q.alpha_p1 = alpha[rank];
  q.alpha_min = *std::min_element(alpha.begin(), alpha.begin() + static_cast<std::ptrdiff_t>(rank) + 1);
  q.min_angle_deg = min_angle;
  q.max_angle_deg = max_angle;
  q.obtuse_fraction = static_cast<double>(n_obtuse) / static_cast<double>(n);
  q.small_angle_fraction = static_cast<double>(n_small) / static_cast<double>(n);
  return q;
}

// compute_triangle_quality()'s q completed with the edge-length figures (nothing for a soup
// without triangles: all NaN already).
void add_edge_quality(const TriangleSoup& soup, const std::vector<double>& edge_lengths, QualityReport& q) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  if (soup.triangles.empty()) return;
  if (edge_lengths.empty()) {
    q.edge_length_mean = q.edge_length_min = q.edge_length_max = q.edge_length_stddev = kNaN;
  } else {
    double sum = 0.0;
    q.edge_length_min = std::numeric_limits<double>::infinity();
    q.edge_length_max = 0.0;
    for (double l : edge_lengths) {
      sum += l;
      q.edge_length_min = std::min(q.edge_length_min, l);
      q.edge_length_max = std::max(q.edge_length_max, l);
    }
    q.edge_length_mean = sum / static_cast<double>(edge_lengths.size());
    double var = 0.0;
    for (double l : edge_lengths) var += (l - q.edge_length_mean) * (l - q.edge_length_mean);
    q.edge_length_stddev = std::sqrt(var / static_cast<double>(edge_lengths.size()));
  }
}

}  // namespace

namespace {

// The report; with `tree` given, the self-intersection count builds the soup's tree over
// all faces into it (for the distance stage to reuse).
MeshReport report_with(const TriangleSoup& soup, const ReportOptions& options, std::optional<quality_detail::AabbTree>* tree) {
  MeshReport report;
  report_progress(options.progress, "topology", 0.0);
  std::optional<quality_detail::AabbTree> own_tree;
  if (tree == nullptr) tree = &own_tree;
  auto count = [&] {
    tree->emplace(quality_detail::all_faces_tree(soup));
    return quality_detail::count_self_intersections_with(soup, **tree, options.n_threads);
  };
  // With two or more threads the self-intersection count starts on a helper thread while
  // this one computes topology and quality (its serial set-up overlaps them). Progress is
  // still reported from this thread in the same stage order; the count does not depend on
  // the thread count.
  std::size_t n_pairs = 0;
  std::exception_ptr helper_error;
  std::thread helper;
  if (options.self_intersections && options.n_threads >= 2) {
    helper = std::thread([&] {
      try {
        n_pairs = count();
      } catch (...) {
        helper_error = std::current_exception();
      }
    });
  }
  try {
    // The counts that read each face alone (degenerate and duplicate faces) and the
    // triangles' quality figures; with a thread to spare (two or more threads and no
    // self-intersection count, three or more with it) on another thread while this one
    // computes the edges' topology. The same figures either way.
    TopologyReport face_counts;
    QualityReport quality;
    auto face_part = [&] {
      count_degenerate_and_duplicate_faces(soup, face_counts);
      quality = compute_triangle_quality(soup);
    };
    std::exception_ptr face_error;
    std::thread face_thread;
    if (options.n_threads >= (options.self_intersections ? 3U : 2U)) {
      try {
        face_thread = std::thread([&] {
          try {
            face_part();
          } catch (...) {
            face_error = std::current_exception();
          }
        });
      } catch (const std::system_error&) {
        // No thread to be had: this one makes the face part below.
      }
    }
    std::vector<EdgeEntry> edges;
    std::vector<double> edge_lengths;
    try {
      report.topology = compute_topology(soup, edges, edge_lengths);
    } catch (...) {
      if (face_thread.joinable()) face_thread.join();
      throw;
    }
    edges = {};
    if (face_thread.joinable()) {
      face_thread.join();
      if (face_error) std::rethrow_exception(face_error);
    } else {
      face_part();
    }
    report.topology.n_degenerate_faces = face_counts.n_degenerate_faces;
    report.topology.n_duplicate_faces = face_counts.n_duplicate_faces;
    add_edge_quality(soup, edge_lengths, quality);
    report.quality = quality;
    report_progress(options.progress, "topology", 1.0);
    if (options.self_intersections) report_progress(options.progress, "self-intersections", 0.0);
  } catch (...) {
    if (helper.joinable()) helper.join();
    throw;
  }
  if (options.self_intersections) {
    if (helper.joinable()) {
      helper.join();
      if (helper_error) std::rethrow_exception(helper_error);
    } else {
      n_pairs = count();
    }
    report.topology.n_self_intersecting_pairs = n_pairs;
    report_progress(options.progress, "self-intersections", 1.0);
  }
  return report;
}

}  // namespace

MeshReport mesh_report(const TriangleSoup& soup, const ReportOptions& options) {
  options.validate();
  quality_detail::validate_soup(soup, "mesh_report");
  return report_with(soup, options, nullptr);
}

MeshReport mesh_report(const TriangleSoup& soup, const TriangleSoup& reference, const ReportOptions& options) {
  options.validate();
  quality_detail::validate_soup(soup, "mesh_report");
  quality_detail::validate_soup(reference, "mesh_report (reference)");
  std::optional<quality_detail::AabbTree> tree;  // the soup's, shared by both stages
  MeshReport report = report_with(soup, options, &tree);
  DistanceOptions distance_options = options.distance;
  if (!distance_options.progress) distance_options.progress = options.progress;
  report.distance = quality_detail::mesh_distance_with(soup, reference, distance_options, tree ? &*tree : nullptr);
  return report;
}

}  // namespace nurbsfront
