// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! TriangleSoup: an indexed triangle list that can hold anything a file holds
//! (non-manifold edges, duplicate faces, unreferenced points), and its conversion
//! to and from the halfedge TriMesh, which only holds oriented 2-manifolds.

#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "nurbsfront/core/mesh_types.h"

namespace nurbsfront {

//! Points and triangles by index. Triangles are counter-clockwise seen from outside.
struct TriangleSoup {
  std::vector<Eigen::Vector3d> points;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

//! Axis-aligned box.
struct BoundingBox {
  Eigen::Vector3d min = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d max = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
  void extend(const Eigen::Vector3d& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  [[nodiscard]] bool is_empty() const { return !(min.array() <= max.array()).all(); }
  //! Length of the diagonal; 0 for an empty box.
  [[nodiscard]] double diagonal() const { return is_empty() ? 0.0 : (max - min).norm(); }
};

[[nodiscard]] BoundingBox bounding_box(const TriangleSoup& soup);
[[nodiscard]] BoundingBox bounding_box(const TriMesh& mesh);
//! Mean length of the mesh's non-deleted edges longer than tolerance::kZeroLengthRelative
//! x its bbox diagonal (0 when there are none).
[[nodiscard]] double mean_edge_length(const TriMesh& mesh);

//! Why a soup cannot become a TriMesh; empty when it can.
struct ManifoldCheck {
  std::size_t n_bad_indices = 0;          //!< triangles with an index out of range
  std::size_t n_repeated_index = 0;       //!< triangles naming one vertex twice
  std::size_t n_nonmanifold_edges = 0;    //!< undirected edges with more than two triangles
  std::size_t n_misoriented_edges = 0;    //!< edges traversed twice in the same direction
  std::size_t n_nonmanifold_vertices = 0; //!< vertices whose triangles form several fans
  [[nodiscard]] bool ok() const {
    return n_bad_indices + n_repeated_index + n_nonmanifold_edges + n_misoriented_edges +
               n_nonmanifold_vertices == 0;
  }
  //! A human-readable reason naming each problem and its count.
  [[nodiscard]] std::string message() const;
};

//! Checks that the soup is an oriented 2-manifold (with or without boundary).
[[nodiscard]] ManifoldCheck check_manifold(const TriangleSoup& soup);

//! Builds the halfedge mesh. Every point becomes a vertex (same index), every triangle
//! a face (same index).
//! \throw InvalidInput for non-finite coordinates.
//! \throw TopologyError if check_manifold() fails; the message names the problems.
[[nodiscard]] TriMesh to_trimesh(const TriangleSoup& soup);

//! As to_trimesh(soup), built in `mesh` (its content is replaced): OpenMesh meshes have no
//! move operations, so assigning a returned mesh to one that lives elsewhere copies it.
//! \throw as to_trimesh(soup); `mesh` is left empty then.
void to_trimesh(const TriangleSoup& soup, TriMesh& mesh);

//! As to_trimesh(soup, mesh); with n_threads >= 2 check_manifold() runs beside the build
//! (the build of a soup the check refuses is thrown away). The same mesh and the same
//! errors for any thread count.
void to_trimesh(const TriangleSoup& soup, TriMesh& mesh, unsigned n_threads);

//! The mesh's vertices and faces as a soup (deleted elements skipped, garbage ignored).
[[nodiscard]] TriangleSoup to_soup(const TriMesh& mesh);

}  // namespace nurbsfront
