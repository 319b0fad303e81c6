// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <thread>
#include <vector>

#include <Eigen/Geometry>

#include "nurbsfront/core/error.h"
#include "nurbsfront/core/parallel.h"
#include "nurbsfront/quality/aabb_tree.h"
#include "nurbsfront/quality/internal.h"
#include "nurbsfront/quality/report.h"

namespace nurbsfront {
namespace {

// R2 low-discrepancy sequence (Roberts 2018): steps 1/g and 1/g^2, g the plastic number.
constexpr double kPlastic = 1.32471795724474602596;
constexpr double kR2StepU = 1.0 / kPlastic;
constexpr double kR2StepV = 1.0 / (kPlastic * kPlastic);

// Every referenced vertex plus area samples at about `spacing` apart, spread over each
// triangle by the R2 sequence folded into the triangle. Deterministic.
std::vector<Eigen::Vector3d> sample_surface(const TriangleSoup& soup, double spacing, std::size_t max_samples) {
  std::vector<char> referenced(soup.points.size(), 0);
  double total_area = 0.0;
  for (const auto& t : soup.triangles) {
    for (auto v : t) referenced[v] = 1;
    total_area += 0.5 * (soup.points[t[1]] - soup.points[t[0]]).cross(soup.points[t[2]] - soup.points[t[0]]).norm();
  }
  std::vector<Eigen::Vector3d> samples;
  for (std::size_t v = 0; v < soup.points.size(); ++v) {
    if (referenced[v]) samples.push_back(soup.points[v]);
  }
  double density = 1.0 / (spacing * spacing);  // samples per unit area
  if (total_area * density > static_cast<double>(max_samples)) density = static_cast<double>(max_samples) / total_area;
  samples.reserve(samples.size() + static_cast<std::size_t>(total_area * density) + 1);
  double carry = 0.0;
  std::uint64_t k = 0;
  for (const auto& t : soup.triangles) {
    const Eigen::Vector3d& a = soup.points[t[0]];
    const Eigen::Vector3d ab = soup.points[t[1]] - a;
    const Eigen::Vector3d ac = soup.points[t[2]] - a;
    carry += 0.5 * ab.cross(ac).norm() * density;
    for (; carry >= 1.0; carry -= 1.0, ++k) {
      double u = 0.5 + static_cast<double>(k) * kR2StepU;
      double v = 0.5 + static_cast<double>(k) * kR2StepV;
      u -= std::floor(u);
      v -= std::floor(v);
      if (u + v > 1.0) {
        u = 1.0 - u;
        v = 1.0 - v;
      }
      samples.push_back(a + u * ab + v * ac);
    }
  }
  return samples;
}

struct OneSided {
  double max = 0.0;
  double mean = 0.0;
};

OneSided one_sided(const std::vector<Eigen::Vector3d>& samples, const quality_detail::AabbTree& tree, unsigned n_threads) {
  std::vector<double> distance(samples.size());
  // Queries in Morton order of the samples: consecutive queries are near each other, so the
  // previous answer is a good hint and the tree's nodes stay in cache (the search is
  // memory-bound). Each distance is exact whatever the order; they are stored by sample.
  const std::vector<std::uint32_t> order = quality_detail::morton_order(samples);
  auto work = [&](std::size_t begin, std::size_t end) {
    std::uint32_t hint = std::numeric_limits<std::uint32_t>::max();
    for (std::size_t k = begin; k < end; ++k) {
      const std::uint32_t i = order[k];
      const auto closest = tree.closest(samples[i], hint);
      hint = closest.face;
      distance[i] = std::sqrt(closest.squared_distance);
    }
  };
  const std::size_t n = samples.size();
  const std::size_t chunk = (n + n_threads - 1) / n_threads;
  parallel::for_chunks(n, n_threads, chunk, [&](std::size_t begin, std::size_t end, unsigned) { work(begin, end); });
  // Reduced in sample order: the result does not depend on the thread count.
  OneSided r;
  double sum = 0.0;
  for (double d : distance) {
    r.max = std::max(r.max, d);
    sum += d;
  }
  r.mean = n > 0 ? sum / static_cast<double>(n) : 0.0;
  return r;
}

}  // namespace

DistanceReport mesh_distance(const TriangleSoup& mesh, const TriangleSoup& reference, const DistanceOptions& options) {
  options.validate();
  quality_detail::validate_soup(mesh, "mesh_distance (mesh)");
  quality_detail::validate_soup(reference, "mesh_distance (reference)");
  return quality_detail::mesh_distance_with(mesh, reference, options, nullptr);
}

DistanceReport quality_detail::mesh_distance_with(const TriangleSoup& mesh, const TriangleSoup& reference,
                                                  const DistanceOptions& options, const quality_detail::AabbTree* given_tree,
                                                  const quality_detail::AabbTree* given_reference_tree) {
  if (mesh.triangles.empty() || reference.triangles.empty()) {
    throw InvalidInput("nurbsfront: mesh_distance needs two surfaces with at least one triangle each");
  }
  DistanceReport r;
  r.reference_diagonal = bounding_box(reference).diagonal();
  const double spacing_floor = bounding_box(mesh).diagonal() * options.sample_spacing_relative;
  const double spacing = r.reference_diagonal > 0.0 ? r.reference_diagonal * options.sample_spacing_relative : spacing_floor;
  report_progress(options.progress, "distance", 0.0);
  // The two trees and the two sample sets are independent: with two or more threads the
  // reference's are prepared on a second thread (deterministic, no shared writes). With the
  // reference's tree given, the second thread builds the mesh's instead.
  std::optional<quality_detail::AabbTree> own_mesh_tree;
  std::optional<quality_detail::AabbTree> own_reference_tree;
  std::vector<Eigen::Vector3d> mesh_samples;
  std::vector<Eigen::Vector3d> reference_samples;
  const bool mesh_tree_second = given_reference_tree != nullptr;
  auto prepare_reference = [&] {
    if (given_reference_tree == nullptr) own_reference_tree.emplace(quality_detail::all_faces_tree(reference));
    if (mesh_tree_second && given_tree == nullptr) own_mesh_tree.emplace(quality_detail::all_faces_tree(mesh));
    mesh_samples = sample_surface(mesh, spacing, options.max_samples);
  };
  auto prepare_mesh = [&] {
    if (!mesh_tree_second && given_tree == nullptr) own_mesh_tree.emplace(quality_detail::all_faces_tree(mesh));
    reference_samples = sample_surface(reference, spacing, options.max_samples);
  };
  if (options.n_threads >= 2) {
    std::thread helper(prepare_reference);
    try {
      prepare_mesh();
    } catch (...) {
      helper.join();
      throw;
    }
    helper.join();
  } else {
    prepare_reference();
    prepare_mesh();
  }
  r.n_mesh_samples = mesh_samples.size();
  r.n_reference_samples = reference_samples.size();
  report_progress(options.progress, "distance", 0.1);
  const OneSided forward = one_sided(
      mesh_samples, given_reference_tree != nullptr ? *given_reference_tree : *own_reference_tree, options.n_threads);
  report_progress(options.progress, "distance", 0.55);
  const OneSided backward =
      one_sided(reference_samples, given_tree != nullptr ? *given_tree : *own_mesh_tree, options.n_threads);
  r.mesh_to_reference_max = forward.max;
  r.mesh_to_reference_mean = forward.mean;
  r.reference_to_mesh_max = backward.max;
  r.reference_to_mesh_mean = backward.mean;
  r.hausdorff = std::max(forward.max, backward.max);
  r.mean = 0.5 * (forward.mean + backward.mean);
  if (r.reference_diagonal > 0.0) {
    r.hausdorff_relative = r.hausdorff / r.reference_diagonal;
    r.mean_relative = r.mean / r.reference_diagonal;
  }
  if (quality_detail::is_closed_surface(mesh) && quality_detail::is_closed_surface(reference)) {
    const double v_ref = enclosed_volume(reference);
    if (v_ref != 0.0) r.relative_volume_change = (enclosed_volume(mesh) - v_ref) / v_ref;
  }
  report_progress(options.progress, "distance", 1.0);
  return r;
}

}  // namespace nurbsfront
