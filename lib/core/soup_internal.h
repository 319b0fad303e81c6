// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Shared between the modules (not part of the public API).
#include "nurbsfront/core/soup.h"

namespace nurbsfront::core_detail {

//! As to_trimesh(soup, mesh) for a soup the caller has already found ok by
//! check_manifold() (not checked again: the result is undefined otherwise, but every
//! triangle naming three distinct in-range points is read and written safely); the same
//! mesh. Its steps run on n_threads threads: the same mesh for any count.
//! \throw InvalidInput for non-finite coordinates; `mesh` is left empty then.
void to_trimesh_checked(const TriangleSoup& soup, TriMesh& mesh, unsigned n_threads = 1);

//! check_manifold(soup); when it is ok, `mesh` is to_trimesh_checked(soup, mesh)'s mesh,
//! otherwise it is left empty. With n_threads >= 2 and every triangle naming three distinct
//! in-range points, the check runs on a second thread while the mesh is built (the build
//! only stores handles there, so a refused soup costs a discarded mesh, never a bad access).
//! \throw InvalidInput for non-finite coordinates of a soup the check accepts.
ManifoldCheck check_and_build(const TriangleSoup& soup, TriMesh& mesh, unsigned n_threads);

//! mean_edge_length(mesh) with the box and the edge lengths computed on n_threads threads
//! (the lengths are summed in edge order on the calling thread): the same value, bit for
//! bit, for any thread count (for finite points; remesh() checks them first).
[[nodiscard]] double mean_edge_length(const TriMesh& mesh, unsigned n_threads);

}  // namespace nurbsfront::core_detail
