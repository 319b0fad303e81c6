// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Patch frames: the source method rotates each patch onto the xy-plane, fits a height
//! field there, meshes, then rotates back. A PatchFrame is that rigid motion.

#include <vector>

#include <Eigen/Core>

namespace nurbsfront {

//! An orthonormal right-handed frame: local = R^T (world - origin), world = origin + R local.
//! The columns of `axes` are the frame's x, y and z axes in world coordinates.
struct PatchFrame {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();    //!< frame origin in world coordinates
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  //!< columns: unit x, y, z axes (det +1)

  [[nodiscard]] Eigen::Vector3d to_local(const Eigen::Vector3d& world) const { return axes.transpose() * (world - origin); }
  [[nodiscard]] Eigen::Vector3d to_world(const Eigen::Vector3d& local) const { return origin + axes * local; }
  [[nodiscard]] Eigen::Vector3d direction_to_local(const Eigen::Vector3d& d) const { return axes.transpose() * d; }
  [[nodiscard]] Eigen::Vector3d direction_to_world(const Eigen::Vector3d& d) const { return axes * d; }
  [[nodiscard]] std::vector<Eigen::Vector3d> to_local(const std::vector<Eigen::Vector3d>& world) const;
  [[nodiscard]] std::vector<Eigen::Vector3d> to_world(const std::vector<Eigen::Vector3d>& local) const;
};

//! The frame of a patch: z = the normalised mean of the (normalised) normals, origin = the
//! centroid of the points, x = the direction of largest spread of the points projected on
//! the plane (so the fitted rectangle is tight), y = z x x.
//! \throw InvalidInput if points is empty, the counts differ, a value is not finite, or the
//!        normals cancel out (no mean direction).
[[nodiscard]] PatchFrame patch_frame(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& normals);

//! A frame from points alone: z = direction of least spread (principal component analysis),
//! oriented so that z . `up` >= 0; x, y as in patch_frame().
//! \throw InvalidInput if there are fewer than 3 points, a value is not finite, or the points
//!        are collinear (no plane).
[[nodiscard]] PatchFrame patch_frame_pca(const std::vector<Eigen::Vector3d>& points,
                                         const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ());

}  // namespace nurbsfront
