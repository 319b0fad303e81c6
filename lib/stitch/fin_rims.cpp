// SPDX-License-Identifier: BSD-3-Clause
// StitchOptions::fin_rim_max_move in every stage of the stitch (docs/stitch.md "Fin rims: every
// stage within the bound"): which nodes are bounded, and holding them within the bound.
#include <cmath>
#include <cstdint>
#include <vector>

#include "nurbsfront/stitch/stitch_internal.h"

namespace nurbsfront::stitch_detail {

std::vector<std::uint8_t> fin_rim_nodes(const SurfaceMesh& surface) {
  std::vector<std::uint8_t> out;
  const std::vector<std::uint8_t>& rim = surface.curve_is_fin_rim;
  if (rim.empty() || surface.curve_nodes.size() != rim.size()) return out;
  out.assign(surface.nodes.size(), 0);
  for (std::size_t c = 0; c < rim.size(); ++c) {
    if (rim[c] == 0) continue;
    for (const int g : surface.curve_nodes[c]) {
      if (g >= 0 && static_cast<std::size_t>(g) < out.size()) out[static_cast<std::size_t>(g)] = 1;
    }
  }
  return out;
}

FinRimBound fin_rim_bound(const SurfaceMesh& surface, const StitchOptions& options) {
  FinRimBound out;
  if (!std::isfinite(options.fin_rim_max_move)) return out;
  out.on_rim = fin_rim_nodes(surface);
  if (out.on_rim.empty()) return out;
  out.radius = options.fin_rim_max_move * surface.input_mean_edge;
  out.origins = &surface.nodes;
  return out;
}

bool FinRimBound::allows(int node, const Eigen::Vector3d& q) const {
  if (!is_bounded(node)) return true;
  return ((q - (*origins)[static_cast<std::size_t>(node)]).norm() <= radius * (1.0 + kSlack));
}

Eigen::Vector3d FinRimBound::clamp(int node, const Eigen::Vector3d& q) const {
  if (!is_bounded(node)) return q;
  return clamp_to_ball(q, (*origins)[static_cast<std::size_t>(node)], radius);
}

std::size_t hold_fin_rim_nodes(TriMesh& mesh, const std::vector<int>& vertex_node, const FinRimBound& bound) {
  if (bound.on_rim.empty()) return 0;
  std::size_t n_held = 0;
  for (auto v : mesh.vertices()) {
    const int node = vertex_node[static_cast<std::size_t>(v.idx())];
    const Eigen::Vector3d p = point(mesh, v);
    if (bound.allows(node, p)) continue;
    mesh.set_point(v, to_openmesh(bound.clamp(node, p)));
    ++n_held;
  }
  return n_held;
}

}  // namespace nurbsfront::stitch_detail
