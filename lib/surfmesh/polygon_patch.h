// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! The single-polygon path of the source method (its Fig. 2): an ordered 3D polygon with a
//! node density (target edge length) at each vertex and scattered points on the surface is
//! rotated onto the xy-plane, a height field is fitted to the points, the polygon is meshed
//! by the 2D advancing front with the surface metric, and every node is lifted onto the
//! fitted surface and rotated back.

#include <array>
#include <filesystem>
#include <vector>

#include <Eigen/Core>

#include "nurbsfront/core/progress.h"
#include "nurbsfront/front2d/front.h"
#include "nurbsfront/nurbs/mba.h"
#include "nurbsfront/surfmesh/surfmesh.h"

namespace nurbsfront {

//! The input of mesh_polygon_patch().
struct PolygonPatch {
  //! The polygon's vertices in order, counter-clockwise seen from the side its normal points
  //! to (the source method orders them "according to the normal direction"); the first
  //! vertex is not repeated. At least 3, distinct, simple in projection on its plane.
  std::vector<Eigen::Vector3d> polygon;
  //! Node density at each polygon vertex: the target edge length there (length units, > 0),
  //! interpolated inside (front2d per-vertex sizing, graded).
  std::vector<double> densities;
  //! Scattered points on the surface (the source method's "control points set on the
  //! surface"). May be empty: the polygon's own vertices are always fitted too.
  std::vector<Eigen::Vector3d> points;
};

//! Options of mesh_polygon_patch().
struct PolygonPatchOptions {
  //! Fit tolerance relative to the polygon's bounding-box diagonal. Default 1e-4.
  double relative_tolerance = 1e-4;
  //! Most lattice levels of the fit. Default 8.
  int max_levels = 8;
  //! Gradation of the sizing field (> 1). Default 1.5.
  double gradation = 1.5;
  //! Smoothing passes after the front (front2d). Default 3.
  int smoothing_passes = 3;
  //! Keep the polygon's vertices at their input positions (true) or move them onto the
  //! fitted surface like every other node (false, as the source method). Default false.
  bool keep_polygon_vertices = false;
  //! Progress and cancellation (stages of fit and front2d). Default none.
  ProgressCallback progress;
  //! \throw InvalidInput on nonsense.
  void validate() const;
};

//! The meshed polygon.
struct PolygonPatchMesh {
  std::vector<Eigen::Vector3d> nodes;          //!< polygon vertices first (same order), then the rest
  std::vector<std::array<int, 3>> triangles;   //!< oriented like the polygon
  PatchSurface surface;                        //!< the fitted surface (world via its frame)
  FitResult fit;                               //!< the fit's residual report (frame coordinates)
  FrontReport front;                           //!< the 2D front's report
};

//! Meshes one polygonal surface patch.
//! \throw InvalidInput for fewer than 3 vertices, a density count that differs from the
//!        vertex count, non-positive or non-finite values, a polygon without area (its
//!        vertices collinear), a polygon that is not simple in its plane, or invalid options.
//! \throw SolverError if the front could not close (a bug).
//! \throw Cancelled if the progress callback returns false.
[[nodiscard]] PolygonPatchMesh mesh_polygon_patch(const PolygonPatch& patch, const PolygonPatchOptions& options = {});

//! Reads the text format of a polygon patch (documented in docs/surfmesh.md):
//! `polygon N` then N lines `x y z density`, then optionally `points M` and M lines
//! `x y z`; '#' starts a comment.
//! \throw IoError if the file cannot be read or is malformed.
[[nodiscard]] PolygonPatch read_polygon_patch(const std::filesystem::path& path);

//! The built-in example: a curved surface like the source method's Fig. 2 (an irregular
//! hexagon over a smooth bump, node densities 0.35 to 0.6, 400 scattered points), which
//! meshes to about 500 nodes.
[[nodiscard]] PolygonPatch example_polygon_patch();

}  // namespace nurbsfront
