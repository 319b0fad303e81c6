// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The stitch tests' hand-made SurfaceMeshes: one height-field fit per patch.
#include <cstddef>
#include <cstdint>
#include <set>
#include <vector>

#include <Eigen/Geometry>

#include "nurbsfront/core/soup.h"
#include "nurbsfront/nurbs/frame.h"
#include "nurbsfront/nurbs/mba.h"
#include "nurbsfront/surfmesh/surfmesh.h"

namespace nurbsfront::test {

//! One PatchSurface per patch 0 .. n_patches - 1 of face_patch (one per soup triangle): the
//! frame of its faces' centroids and unit normals (patch_frame) and a height field of at most
//! max_levels lattice levels over its faces' vertices; a patch without faces gets a default
//! PatchSurface.
inline std::vector<PatchSurface> fit_patches(const TriangleSoup& soup, const std::vector<int>& face_patch,
                                             int n_patches, int max_levels) {
  std::vector<PatchSurface> surfaces;
  for (int p = 0; p < n_patches; ++p) {
    std::vector<Eigen::Vector3d> points, centroids, normals;
    std::set<std::uint32_t> vertices;
    for (std::size_t t = 0; t < soup.triangles.size(); ++t) {
      if (face_patch[t] != p) continue;
      const auto& tri = soup.triangles[t];
      const auto& q = soup.points;
      normals.push_back((q[tri[1]] - q[tri[0]]).cross(q[tri[2]] - q[tri[0]]).normalized());
      centroids.push_back((q[tri[0]] + q[tri[1]] + q[tri[2]]) / 3.0);
      for (const auto v : tri) vertices.insert(v);
    }
    PatchSurface surface;
    if (!vertices.empty()) {
      for (const auto v : vertices) points.push_back(soup.points[v]);
      surface.frame = patch_frame(centroids, normals);
      FitOptions fit;
      fit.max_levels = max_levels;
      surface.field = fit_height_field(surface.frame.to_local(points), fit).field;
    }
    surfaces.push_back(surface);
  }
  return surfaces;
}

}  // namespace nurbsfront::test
