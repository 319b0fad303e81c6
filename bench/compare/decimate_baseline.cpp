// SPDX-License-Identifier: BSD-3-Clause
#include "decimate_baseline.h"

#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModAspectRatioT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#include <OpenMesh/Tools/Decimater/ModRoundnessT.hh>

namespace nurbsfront::bench {

namespace {
std::size_t count_deleted(const TriMesh& mesh) {
  std::size_t n = 0;
  for (auto v : mesh.all_vertices()) n += mesh.status(v).deleted() ? 1 : 0;
  return n;
}
}  // namespace

DecimateResult decimate(const TriMesh& input, std::size_t target_vertices, const DecimateOptions& options) {
  DecimateResult result{input, options.roundness ? options.roundness_min_angle_deg : 0.0};
  TriMesh& mesh = result.mesh;
  mesh.update_face_normals();
  using Decimater = OpenMesh::Decimater::DecimaterT<TriMesh>;
  Decimater decimater(mesh);
  OpenMesh::Decimater::ModQuadricT<TriMesh>::Handle quadric;
  OpenMesh::Decimater::ModNormalFlippingT<TriMesh>::Handle normal_flipping;
  OpenMesh::Decimater::ModAspectRatioT<TriMesh>::Handle aspect_ratio;
  OpenMesh::Decimater::ModRoundnessT<TriMesh>::Handle roundness;
  decimater.add(quadric);
  decimater.module(quadric).unset_max_err();  // the priority, no error bound
  decimater.add(normal_flipping);
  decimater.module(normal_flipping).set_max_normal_deviation(options.max_normal_deviation_deg);
  decimater.add(aspect_ratio);
  decimater.module(aspect_ratio).set_aspect_ratio(static_cast<float>(options.max_aspect_ratio));
  decimater.module(aspect_ratio).set_binary(true);
  if (options.roundness) {
    decimater.add(roundness);
    decimater.module(roundness).set_min_angle(static_cast<float>(options.roundness_min_angle_deg), true);
  }
  decimater.initialize();
  decimater.decimate_to(target_vertices);
  // On marching-cubes input the roundness guard blocks most collapses long before the
  // target (the input's own slivers surround every candidate): relax it stepwise, keeping
  // the quadrics, until the vertex count is met or the angle is tiny.
  double angle = options.roundness_min_angle_deg;
  while (options.roundness && mesh.n_vertices() - count_deleted(mesh) > target_vertices && angle > 1.0) {
    angle *= 0.5;
    decimater.module(roundness).set_min_angle(static_cast<float>(angle), true);
    // decimate_to() counts deleted vertices as present: aim at the same number of removals.
    const std::size_t alive = mesh.n_vertices() - count_deleted(mesh);
    decimater.decimate_to(mesh.n_vertices() - (alive - target_vertices));
  }
  mesh.garbage_collection();
  if (options.roundness) result.roundness_angle = angle;
  return result;
}

}  // namespace nurbsfront::bench
