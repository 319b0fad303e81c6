// SPDX-License-Identifier: BSD-3-Clause
// Fin rims (SurfMeshOptions::fin_rim_width): crease curves along a fin's narrow strip that
// stitch may cross and move (docs/stitch.md "Fin rims").
#include <cstdint>
#include <vector>

#include "nurbsfront/segment/segment.h"
#include "nurbsfront/surfmesh/surfmesh_internal.h"

namespace nurbsfront::surfmesh_detail {

std::vector<int> fin_rim_curves(const TriMesh& mesh, const Segmentation& segmentation,
                                const SurfaceMesh& surface, const std::vector<double>& angles, double max_width,
                                double max_angle_deg, double max_gap, unsigned threads) {
  const std::vector<std::uint8_t>& is_feature = surface.curve_is_feature;
  std::vector<int> out;
  if (!(max_width > 0.0)) return out;
  std::vector<std::uint8_t> narrow(segmentation.patches.size(), 0);
  for (const int p : segment_detail::narrow_patches(mesh, segmentation, max_width, threads)) narrow[static_cast<std::size_t>(p)] = 1;
  for (std::size_t c = 0; c < segmentation.curves.size(); ++c) {
    const BorderCurve& curve = segmentation.curves[c];
    // The input's boundary is its geometry: always a feature.
    if (is_feature[c] == 0 || curve.patch_right < 0 || angles[c] > max_angle_deg) continue;
    if (narrow[static_cast<std::size_t>(curve.patch_left)] == 0 && narrow[static_cast<std::size_t>(curve.patch_right)] == 0)
      continue;
    // Stitch moves a node of a curve that is no feature onto the mean of its projections
    // onto both fits: only where the two fits agree at every node of the curve (a narrow
    // strip's fit can leave its strip quickly; headsq@1150: nodes moved 2 mean edges off).
    // A patch that failed has no fit to move the nodes on.
    if (surface.patches[static_cast<std::size_t>(curve.patch_left)].status != PatchStatus::Ok ||
        surface.patches[static_cast<std::size_t>(curve.patch_right)].status != PatchStatus::Ok)
      continue;
    const PatchSurface& left = surface.surfaces[static_cast<std::size_t>(curve.patch_left)];
    const PatchSurface& right = surface.surfaces[static_cast<std::size_t>(curve.patch_right)];
    bool agree = true;
    for (const int g : surface.curve_nodes[c]) {
      const Eigen::Vector3d& x = surface.nodes[static_cast<std::size_t>(g)];
      const Eigen::Vector3d a = left.project(x), b = right.project(x);
      if (!((a - b).norm() <= max_gap && (0.5 * (a + b) - x).norm() <= max_gap)) {
        agree = false;
        break;
      }
    }
    if (agree) out.push_back(static_cast<int>(c));
  }
  return out;
}

}  // namespace nurbsfront::surfmesh_detail
