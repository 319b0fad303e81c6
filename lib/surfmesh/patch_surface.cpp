// SPDX-License-Identifier: BSD-3-Clause
// PatchSurface: vertical projection onto a patch's fitted height field and its normal.
#include "nurbsfront/surfmesh/surfmesh.h"

namespace nurbsfront {

Eigen::Vector3d PatchSurface::project(const Eigen::Vector3d& world) const {
  const Eigen::Vector3d local = frame.to_local(world);
  return frame.to_world(field.lift(local.x(), local.y()));
}

Eigen::Vector3d PatchSurface::normal(const Eigen::Vector3d& world) const {
  const Eigen::Vector3d local = frame.to_local(world);
  return frame.direction_to_world(field.normal(local.x(), local.y()));
}

}  // namespace nurbsfront
