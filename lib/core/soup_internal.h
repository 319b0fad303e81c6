// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Shared between the modules (not part of the public API).
#include "nurbsfront/core/soup.h"

namespace nurbsfront::core_detail {

//! As to_trimesh(soup, mesh) for a soup the caller has already found ok by
//! check_manifold() (not checked again: the result is undefined otherwise); the same mesh.
//! \throw InvalidInput for non-finite coordinates; `mesh` is left empty then.
void to_trimesh_checked(const TriangleSoup& soup, TriMesh& mesh);

}  // namespace nurbsfront::core_detail
