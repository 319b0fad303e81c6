// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! The one place where OpenMesh traits are chosen: every module uses TriMesh.

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include <Eigen/Core>

namespace nurbsfront {

//! OpenMesh traits: double-precision points and normals, status flags for deletion.
struct MeshTraits : public OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
  using Normal = OpenMesh::Vec3d;
  VertexAttributes(OpenMesh::Attributes::Status);
  EdgeAttributes(OpenMesh::Attributes::Status);
  HalfedgeAttributes(OpenMesh::Attributes::PrevHalfedge);
  FaceAttributes(OpenMesh::Attributes::Status | OpenMesh::Attributes::Normal);
};

//! The halfedge triangle mesh of the library (always 2-manifold by construction).
using TriMesh = OpenMesh::TriMesh_ArrayKernelT<MeshTraits>;
using Point3 = OpenMesh::Vec3d;

//! Eigen view of an OpenMesh point (no copy semantics implied: returns a value).
inline Eigen::Vector3d to_eigen(const OpenMesh::Vec3d& p) { return {p[0], p[1], p[2]}; }
inline OpenMesh::Vec3d to_openmesh(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }

}  // namespace nurbsfront
