// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Property checks of marching-cubes output shared by the isosurface tests.
#include <string>

#include "nurbsfront/core/soup.h"

namespace nurbsfront::test {

struct SurfaceFacts {
  bool manifold = false;          //!< check_manifold().ok()
  std::string manifold_message;   //!< why not
  std::size_t n_boundary_edges = 0;
  int euler = 0;                  //!< V - E + F (of the halfedge mesh)
  double signed_volume = 0.0;     //!< sum of signed tetrahedra volumes (> 0 for outward)
  std::size_t n_degenerate = 0;   //!< triangles with area <= kDegenerateAreaRelative * diag^2
  std::size_t n_duplicate_points = 0;  //!< points equal to another point
  std::size_t n_unused_points = 0;     //!< points no triangle uses
};

//! Measures the facts above (the halfedge mesh only when the soup is manifold).
SurfaceFacts surface_facts(const TriangleSoup& soup);

//! Asserts manifold, no degenerate triangles, no duplicate or unused points, and (if closed) no
//! boundary edge and a positive volume. Returns the facts for further checks.
SurfaceFacts expect_clean_surface(const TriangleSoup& soup, bool closed, const std::string& what);

}  // namespace nurbsfront::test
