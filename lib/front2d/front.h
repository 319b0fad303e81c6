// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! 2D advancing front triangulation of a planar straight-line graph.
//!
//! Algorithm (Lo 1985; Peraire et al. 1987), as used by the source method in each patch:
//!  1. Validate the PSLG (finite, distinct points, no crossing segments, holes inside).
//!  2. Find the domain: the faces of the segment arrangement (optionally closed by the
//!     convex hull, whose edges that the input follows closer than h / 200 are left out)
//!     minus the faces that contain a hole point.
//!  3. Split every segment by the sizing field (unless split_segments is false: then the
//!     segments are final mesh edges, as the surface mesher hands in its borders).
//!  4. The front: every segment side facing the domain is a directed edge with the domain on
//!     its left. Repeatedly take the shortest edge (a binary heap with lazy deletion), place
//!     the ideal point at the apex of the triangle of side h (in the metric), gather nearby
//!     front nodes from a uniform grid and accept the first candidate that gives a positively
//!     oriented triangle whose new edges cross no front edge and that contains no front node
//!     (exact predicates). A new point must also keep a clearance from the front.
//!  5. Repair: if no candidate is valid, the edge is closed by the constrained-Delaunay-like
//!     choice among all visible front nodes (growing search); such a node always exists, so
//!     the front always closes. After a work budget no new points are created, which bounds
//!     the work.
//!  6. Optimise: Delaunay edge swaps (never across an input segment), smoothing of the new
//!     points (accepted only if every triangle stays valid and the worst quality does not
//!     drop), swaps again.
//!  7. Min-angle relocation: new points and segment split points (along their segment) of
//!     triangles with an angle below 30 deg move by a compass search that maximises the
//!     smallest angle of their star (a move is kept only if every triangle stays valid),
//!     then swaps again.
//!  8. Min-angle refinement (without a metric, with split_segments): Delaunay refinement
//!     (Ruppert; Shewchuk) of the triangles still below 30 deg: circumcentres inserted,
//!     encroached segment pieces split (concentric shells at small input angles), triangles
//!     at input angles below 60 deg excused; capped. Then smoothing that keeps good
//!     triangles good.
//!
//! Output: counter-clockwise triangles, every input segment a chain of mesh edges, every
//! input point kept at its input index.

#include <array>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "nurbsfront/core/progress.h"
#include "nurbsfront/front2d/pslg.h"
#include "nurbsfront/front2d/sizing.h"

namespace nurbsfront {

//! Options of the 2D mesher.
struct FrontOptions {
  //! Target edge length field (metric lengths). Default: uniform, automatic size.
  SizingField sizing;
  //! Optional metric; null means the identity (Euclidean lengths). Default null.
  std::shared_ptr<const Metric> metric;
  //! Split the input segments by the sizing field. false: every segment is a final mesh
  //! edge (already discretised borders). Default true.
  bool split_segments = true;
  //! Add the convex hull of the points as segments (as Triangle's -c), so that open
  //! polylines are meshed inside their hull. A PSLG without segments (a .node file) always
  //! gets its hull. Default false.
  bool enclose_convex_hull = false;
  //! With enclose_convex_hull: a convex hull edge ab is left out when the input segments
  //! join a to b through points all closer to ab than hull_gap_fraction x h (Euclidean
  //! distance, h the sizing at the point), every input point that close to ab being on such
  //! a path. The input is then the boundary there, and the strip between it and the edge,
  //! which no mesh of size h can fill with good triangles, is not part of the domain (area
  //! in FrontReport::hull_gap_area). 0 = the exact hull (Triangle's -c). Must be in [0, 1).
  //! Default 0.005 (h / 200, the refinement's smallest resolved gap).
  double hull_gap_fraction = 0.005;
  //! Smoothing passes over the new points after the front; 0 also turns off the min-angle
  //! relocation. Default 3.
  int smoothing_passes = 3;
  //! Edge swaps after the front (Delaunay criterion, input segments kept). Default true.
  bool swap_edges = true;
  //! Delaunay refinement of the triangles with an angle below 30 deg after the optimisation
  //! (circumcentres inserted, encroached segment pieces split; triangles at input angles
  //! below 60 deg excused). Runs only with split_segments and without a metric. Default true.
  bool refine_min_angle = true;
  //! A front corner at an input point (its two neighbours may be new points) whose inner
  //! angle (in the metric) exceeds this many degrees is not closed by one triangle joining
  //! its two neighbours (that triangle has this angle at the corner, and input points never
  //! move):
  //! a new node on the corner's bisector makes two triangles instead, when it passes the
  //! front's usual tests and the loop has at least 6 nodes (otherwise the old closure).
  //! In (0, 180]; 180 = off. Default 180 (off): on the planar test domains it did not lower
  //! the obtuse share (docs/front2d.md "Corner rule"); the surface mesher turns it on.
  double corner_split_angle_deg = 180.0;
  //! The front may create at most this many times the expected number of points before it
  //! stops creating new ones and closes with existing nodes only. Must be >= 1. Default 4.
  double work_budget_factor = 4.0;
  //! Progress and cancellation; stage names "front2d: front", "front2d: optimise". Default none.
  ProgressCallback progress;

  //! \throw InvalidInput on nonsense (bad sizing, budget < 1, negative passes).
  void validate() const;
};

//! Outcome of the mesher.
enum class FrontStatus {
  Ok,          //!< the front closed; the mesh covers the domain
  Incomplete,  //!< some front edges could not be closed (a bug; the mesh has a gap)
};

//! Counts and timings of one run.
struct FrontReport {
  FrontStatus status = FrontStatus::Ok;
  std::string message;                //!< empty when Ok
  std::size_t n_boundary_nodes = 0;   //!< nodes on the initial front
  std::size_t n_new_points = 0;       //!< points created by the front
  std::size_t n_repairs = 0;          //!< front edges closed by the fallback search
  std::size_t n_corner_points = 0;    //!< new points on the bisector of an obtuse corner (corner_split_angle_deg)
  std::size_t n_open_edges = 0;       //!< front edges left open (0 when Ok)
  std::size_t n_swaps = 0;            //!< edge swaps in the optimisation
  std::size_t n_refinement_points = 0;  //!< points inserted by the min-angle refinement (segment splits included)
  std::size_t n_dropped_points = 0;   //!< input points outside the domain (left unreferenced)
  std::size_t n_hull_edges_followed = 0;  //!< convex hull edges left out: the input follows them (hull_gap_fraction)
  double hull_gap_area = 0.0;         //!< area between those edges and the input (not in domain_area)
  double domain_area = 0.0;           //!< area enclosed by the initial front
  double seconds_front = 0.0;         //!< wall time of the front
  double seconds_optimise = 0.0;      //!< wall time of swaps and smoothing
};

//! The mesh of a PSLG.
struct Mesh2d {
  //! Points: the input points first (same indices), then segment splits, then new points.
  std::vector<Eigen::Vector2d> points;
  //! Counter-clockwise triangles.
  std::vector<std::array<int, 3>> triangles;
  //! Region marker per triangle (Region::marker, 0 where no region point is given).
  std::vector<int> triangle_regions;
  //! Per input segment, its mesh nodes from the first endpoint to the second.
  std::vector<std::vector<int>> segment_chains;
  //! Per convex hull edge added as a segment (enclose_convex_hull) and not an input segment,
  //! its mesh nodes from one hull vertex to the next, counter-clockwise around the domain.
  std::vector<std::vector<int>> hull_chains;
  FrontReport report;
};

//! Meshes the domain of a PSLG with the advancing front.
//! \param pslg    points, segments, holes and regions (see Pslg)
//! \param options sizing, metric, optimisation; FrontOptions::validate() is called
//! \return the mesh and its report (status Ok unless a bug left the front open)
//! \throw InvalidInput for an empty PSLG, NaN/inf coordinates, duplicate points, bad
//!        indices, crossing or overlapping segments, a point inside a segment, a hole
//!        point outside the domain, an empty domain, per-vertex sizes of the wrong count.
//! \throw Cancelled if the progress callback returns false.
[[nodiscard]] Mesh2d mesh_pslg(const Pslg& pslg, const FrontOptions& options = {});

//! Quality of a triangle (Lo): alpha = 4 sqrt(3) A / (l1^2 + l2^2 + l3^2), signed by A.
[[nodiscard]] double triangle_alpha_2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                       const Eigen::Vector2d& c);

//! Quality (Lo) of triangle abc measured in the constant metric M (SPD): alpha of the image
//! of abc under M^{1/2}, i.e. lengths sqrt(e^T M e) and area sqrt(det M) A; signed by A.
//! With M = identity this is triangle_alpha_2d. The optimiser of mesh_pslg uses it with
//! M = triangle_metric(...), so a surface mesher can report the same figure.
[[nodiscard]] double triangle_alpha_in_metric(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                              const Eigen::Vector2d& c, const Eigen::Matrix2d& M);

//! Smallest angle of triangle abc in degrees, angles measured in the constant metric M
//! (cos = u^T M w / (|u|_M |w|_M)). For a non-degenerate triangle in [0, 60].
[[nodiscard]] double triangle_min_angle_in_metric_deg(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                                      const Eigen::Vector2d& c, const Eigen::Matrix2d& M);

//! The tensor the optimiser uses for a triangle: the mean of the metric at its vertices.
[[nodiscard]] Eigen::Matrix2d triangle_metric(const Metric& metric, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                              const Eigen::Vector2d& c);

//! Writes Triangle's .node and .ele files (0-based, the .ele with one region attribute).
//! `stem` is the path without extension.
//! \throw IoError if a file cannot be written.
void write_triangle_files(const Mesh2d& mesh, const std::filesystem::path& stem);

}  // namespace nurbsfront
