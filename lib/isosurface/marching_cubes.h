// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Marching cubes: the iso-surface of a ScalarGrid as a welded, oriented, manifold triangle soup.

#include <array>
#include <cstdint>
#include <vector>

#include "nurbsfront/core/progress.h"
#include "nurbsfront/core/soup.h"
#include "nurbsfront/isosurface/scalar_grid.h"

namespace nurbsfront {

//! Options of marching_cubes().
struct MarchingCubesOptions {
  //! The iso-value separating inside from outside (same unit as the grid's values). Default 0.
  double iso = 0.0;
  //! true for CT-like data (inside where value > iso), false for signed distances (inside where
  //! value < iso). A value exactly equal to iso always counts as outside. Default false.
  bool inside_above = false;
  //! Pad the grid by one layer of "outside" values so the surface closes at the grid border.
  //! Default false (the surface is open where it leaves the grid).
  bool pad = false;
  //! Progress / cancel callback (stage "marching cubes"). Default empty = none.
  ProgressCallback progress;
  //! \throw InvalidInput if iso is not finite.
  void validate() const;
};

//! Extracts the iso-surface of a grid by marching cubes.
//!
//! Algorithm: every grid corner is classified inside / outside (values equal to iso count as
//! outside). Each cube's surface comes from a 256-case table derived from one per-face rule:
//! on a face whose inside corners are diagonal (the ambiguous case) the inside corners are
//! separated, i.e. each cube face's segments depend on its 4 corner signs only, so neighbouring
//! cubes always agree. The segments on the cube's faces are traced into loops and each loop is
//! triangulated without any diagonal between two vertices of one cube face. The grid is swept
//! slice by slice with two slices of edge-vertex caches; one vertex is made per cut grid edge,
//! placed by linear interpolation with the parameter kept in [e, 1 - e] (e =
//! kMarchingCubesEdgeClamp) so no two vertices coincide and no triangle has zero area.
//!
//! Guarantees: the output is edge- and vertex-manifold and consistently oriented, triangles are
//! counter-clockwise seen from outside (normals point from inside to outside), there are no
//! duplicate vertices and no unused vertices; it is closed when the surface does not reach the
//! grid border, or when options.pad is set.
//!
//! \param grid the sampled field; must have at least 2 samples along each axis (1 with pad)
//! \param options iso-value, inside side, padding, progress
//! \return the surface (empty if no grid edge crosses the iso-value)
//! \throw InvalidInput for an invalid grid (see ScalarGrid::validate), too few samples or bad options
//! \throw Cancelled if the progress callback asks to stop
[[nodiscard]] TriangleSoup marching_cubes(const ScalarGrid& grid, const MarchingCubesOptions& options = {});

//! A parameter of an edge vertex is kept at least this far (relative to the edge length) from
//! the edge's end points, so that vertices on edges meeting at a grid point never coincide.
inline constexpr double kMarchingCubesEdgeClamp = 1e-3;

//! One entry of the marching-cubes case table (exposed for tests and documentation).
//! Corner c of a cube is at offset (c & 1, (c >> 1) & 1, (c >> 2) & 1). Edges 0-3 run along x
//! (index = dy + 2 dz), 4-7 along y (4 + dx + 2 dz), 8-11 along z (8 + dx + 2 dy).
struct MarchingCubesCase {
  std::uint8_t n_triangles = 0;                             //!< number of triangles
  std::array<std::array<std::uint8_t, 3>, 12> triangles{};  //!< cube edges of each triangle, CCW from outside
};

//! The case for a cube whose corner c is inside iff bit c of `inside_mask` is set.
[[nodiscard]] const MarchingCubesCase& marching_cubes_case(std::uint8_t inside_mask);

}  // namespace nurbsfront
