// SPDX-License-Identifier: BSD-3-Clause
#include "nurbsfront/nurbs/frame.h"

#include <cmath>
#include <string>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "nurbsfront/core/error.h"
#include "nurbsfront/core/tolerances.h"

namespace nurbsfront {
namespace {

void check_finite(const std::vector<Eigen::Vector3d>& values, const char* what) {
  for (std::size_t k = 0; k < values.size(); ++k) {
    if (!values[k].allFinite()) throw InvalidInput(std::string("patch frame: ") + what + " " + std::to_string(k) + " is not finite");
  }
}

Eigen::Vector3d centroid(const std::vector<Eigen::Vector3d>& points) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& p : points) c += p;
  return c / static_cast<double>(points.size());
}

// Completes z to a right-handed frame whose x axis is the main in-plane spread of the points.
PatchFrame frame_with_z(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& origin, const Eigen::Vector3d& z) {
  // Any unit vector perpendicular to z, then the in-plane principal direction.
  const Eigen::Vector3d seed = std::abs(z.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d a = (seed - seed.dot(z) * z).normalized();
  const Eigen::Vector3d b = z.cross(a);
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const auto& p : points) {
    const Eigen::Vector2d q((p - origin).dot(a), (p - origin).dot(b));
    cov.noalias() += q * q.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
  Eigen::Vector2d main = eig.eigenvectors().col(1);
  if (!(eig.eigenvalues()[1] > eig.eigenvalues()[0])) main = Eigen::Vector2d::UnitX();  // isotropic: keep a
  const Eigen::Vector3d x = (main.x() * a + main.y() * b).normalized();
  PatchFrame f;
  f.origin = origin;
  f.axes.col(0) = x;
  f.axes.col(1) = z.cross(x);
  f.axes.col(2) = z;
  return f;
}

}  // namespace

std::vector<Eigen::Vector3d> PatchFrame::to_local(const std::vector<Eigen::Vector3d>& world) const {
  std::vector<Eigen::Vector3d> out;
  out.reserve(world.size());
  for (const auto& p : world) out.push_back(to_local(p));
  return out;
}

std::vector<Eigen::Vector3d> PatchFrame::to_world(const std::vector<Eigen::Vector3d>& local) const {
  std::vector<Eigen::Vector3d> out;
  out.reserve(local.size());
  for (const auto& p : local) out.push_back(to_world(p));
  return out;
}

PatchFrame patch_frame(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& normals) {
  if (points.empty()) throw InvalidInput("patch frame: no points");
  if (normals.size() != points.size()) {
    throw InvalidInput("patch frame: " + std::to_string(normals.size()) + " normals for " + std::to_string(points.size()) + " points");
  }
  check_finite(points, "point");
  check_finite(normals, "normal");
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  std::size_t n_used = 0;
  for (const auto& n : normals) {
    const double len = n.norm();
    if (len > 0.0) {
      sum += n / len;
      ++n_used;
    }
  }
  if (n_used == 0 || !(sum.norm() > tolerance::kMinMeanNormalLength * static_cast<double>(n_used))) {
    throw InvalidInput("patch frame: the normals cancel out (no mean direction)");
  }
  return frame_with_z(points, centroid(points), sum.normalized());
}

PatchFrame patch_frame_pca(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& up) {
  if (points.size() < 3) throw InvalidInput("patch frame: at least 3 points are needed for a plane");
  check_finite(points, "point");
  if (!up.allFinite()) throw InvalidInput("patch frame: the up direction is not finite");
  const Eigen::Vector3d origin = centroid(points);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : points) cov.noalias() += (p - origin) * (p - origin).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const Eigen::Vector3d ev = eig.eigenvalues().cwiseMax(0.0);
  if (!(ev[2] > 0.0) || std::sqrt(ev[1]) <= tolerance::kCollinearRelative * std::sqrt(ev[2])) {
    throw InvalidInput("patch frame: the points are collinear or coincide (no plane)");
  }
  Eigen::Vector3d z = eig.eigenvectors().col(0).normalized();
  if (z.dot(up) < 0.0) z = -z;
  return frame_with_z(points, origin, z);
}

}  // namespace nurbsfront
