// SPDX-License-Identifier: BSD-3-Clause
// The inner nodes of detail-fitted patches stay within their patch's node bound of the input
// after the stitch (PatchFitOptions::detail_node_offset_edges; docs/surfmesh.md "Detail fit:
// the node bound after the stitch").
#include <algorithm>
#include <cstdint>
#include <vector>

#include "nurbsfront/stitch/stitch_internal.h"

namespace nurbsfront::stitch_detail {

std::size_t hold_detail_nodes(TriMesh& mesh, const SurfaceMesh& surface,
                              const std::vector<int>& vertex_node) {
  const std::size_t n_patches = surface.surfaces.size();
  // Per detail-fitted patch, its surface with no offset allowed: its projection lands on the
  // input face straight above or below (on the fit where there is none).
  std::vector<PatchSurface> on_input(n_patches);
  std::vector<std::uint8_t> has_on_input(n_patches, 0);
  std::size_t n_held = 0;
  for (auto v : mesh.vertices()) {
    const int node = vertex_node[static_cast<std::size_t>(v.idx())];
    if (node < 0 || static_cast<std::size_t>(node) >= surface.nodes.size() ||
        surface.node_kind[static_cast<std::size_t>(node)] != NodeKind::Inner)
      continue;
    const auto p = static_cast<std::size_t>(surface.node_owner[static_cast<std::size_t>(node)]);
    if (p >= n_patches || p >= surface.patches.size() || !surface.patches[p].detail_fit) continue;
    const PatchSurface& own = surface.surfaces[p];
    if (!own.input_heights || !(own.max_offset > 0.0)) continue;
    if (has_on_input[p] == 0) {
      on_input[p] = own;
      on_input[p].max_offset = 0.0;
      has_on_input[p] = 1;
    }
    const Eigen::Vector3d q = point(mesh, v);
    Eigen::Vector3d local = own.frame.to_local(q);
    const double z = own.frame.to_local(on_input[p].project(q)).z();
    const double held = std::clamp(local.z(), z - own.max_offset, z + own.max_offset);
    if (held == local.z()) continue;
    local.z() = held;
    mesh.set_point(v, to_openmesh(own.frame.to_world(local)));
    ++n_held;
  }
  return n_held;
}

}  // namespace nurbsfront::stitch_detail
