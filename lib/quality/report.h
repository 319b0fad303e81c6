// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Mesh quality and validity reports: element quality (Lo's alpha and gamma), angles,
//! edge lengths, topology (components, Euler characteristic, genus, boundary loops,
//! non-manifold elements, orientation), degenerate and duplicate faces, exact
//! self-intersection detection, and two-sided sampled distances between two surfaces.
//!
//! Everything works on a TriangleSoup, so broken inputs (non-manifold, flipped, open,
//! duplicated) can be measured, not only valid meshes.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "nurbsfront/core/progress.h"
#include "nurbsfront/core/soup.h"

namespace nurbsfront {

//! Lo's triangle quality alpha = 4 sqrt(3) A / (l1^2 + l2^2 + l3^2): 1 for an
//! equilateral triangle, 0 for a degenerate one (also when all three points coincide).
[[nodiscard]] double triangle_alpha(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                    const Eigen::Vector3d& c);

//! The interior angles in degrees at a, b and c (in that order), computed with atan2 so
//! they are accurate for needles too. A zero-length edge gives 0 at its end points.
[[nodiscard]] std::array<double, 3> triangle_angles_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                                        const Eigen::Vector3d& c);

//! Lo's tetrahedron quality gamma = 72 sqrt(3) V / (sum of the 6 squared edges)^(3/2):
//! 1 for a regular tetrahedron, 0 for a flat one. Uses |V|, so it ignores orientation.
[[nodiscard]] double tetrahedron_gamma(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                       const Eigen::Vector3d& c, const Eigen::Vector3d& d);

//! alpha of every triangle of the soup, in triangle order.
//! \throw InvalidInput if a triangle has an out-of-range index.
[[nodiscard]] std::vector<double> face_alpha(const TriangleSoup& soup);

//! Minimum interior angle (degrees) of every triangle of the soup, in triangle order.
//! \throw InvalidInput if a triangle has an out-of-range index.
[[nodiscard]] std::vector<double> face_min_angle_deg(const TriangleSoup& soup);

//! Enclosed volume by the divergence theorem, sum over faces of a . (b x c) / 6.
//! Positive for a closed, outward-oriented surface; meaningless for an open one.
//! \throw InvalidInput if a triangle has an out-of-range index.
[[nodiscard]] double enclosed_volume(const TriangleSoup& soup);

//! Topology of one connected component (faces connected through shared vertices).
struct ComponentTopology {
  std::size_t n_vertices = 0;  //!< vertices referenced by the component's faces
  std::size_t n_edges = 0;     //!< distinct undirected edges
  std::size_t n_faces = 0;     //!< faces (those repeating a vertex index included)
  long euler_characteristic = 0;  //!< chi = V - E + F
  bool is_closed = false;      //!< every edge has exactly two faces
  bool is_manifold = false;    //!< no non-manifold edge or vertex
  bool is_oriented = false;    //!< every two-face edge is traversed once in each direction
  //! g = (2 - chi) / 2 when the component is a closed, oriented 2-manifold; else unknown.
  std::optional<long> genus;
};

//! Counts describing the connectivity and validity of a soup.
struct TopologyReport {
  std::size_t n_vertices = 0;          //!< points referenced by at least one face
  std::size_t n_unreferenced_points = 0;  //!< points no face uses
  std::size_t n_faces = 0;             //!< all triangles
  std::size_t n_edges = 0;             //!< distinct undirected edges
  std::size_t n_components = 0;        //!< connected through shared vertices
  std::size_t n_boundary_edges = 0;    //!< edges with exactly one face
  //! Connected pieces of the boundary-edge graph (two holes touching at a vertex count once).
  std::size_t n_boundary_loops = 0;
  std::size_t n_nonmanifold_edges = 0;     //!< edges with more than two faces
  //! Vertices whose faces form several fans (faces linked through edges at the vertex).
  std::size_t n_nonmanifold_vertices = 0;
  //! Two-face edges traversed twice in the same direction (a flipped neighbour).
  std::size_t n_misoriented_edges = 0;
  //! Faces repeating a vertex index, or with area <= kDegenerateAreaRelative * diagonal^2.
  std::size_t n_degenerate_faces = 0;
  //! Faces on the same three vertices as an earlier face (either orientation).
  std::size_t n_duplicate_faces = 0;
  //! Pairs of non-degenerate, non-duplicate faces that intersect beyond the vertices or
  //! edge they share (exact predicates). Unset when the check was switched off.
  std::optional<std::size_t> n_self_intersecting_pairs;
  bool is_closed = false;                  //!< no boundary edges, no non-manifold edges
  bool is_manifold = false;                //!< no non-manifold edges or vertices
  bool is_consistently_oriented = false;   //!< no misoriented edges
  long euler_characteristic = 0;           //!< sum over components
  std::vector<ComponentTopology> components;  //!< in order of their lowest face index
  //! Enclosed volume when every component is closed, manifold and oriented.
  std::optional<double> volume;
};

//! Element quality summary (DESIGN.md "Definitions"). NaN for a soup without faces.
struct QualityReport {
  double alpha_mean = 0.0;   //!< mean of alpha over all faces
  double alpha_min = 0.0;    //!< smallest alpha
  //! 1st percentile of alpha: the value of rank floor(0.01 (n - 1)) in ascending order.
  double alpha_p1 = 0.0;
  double min_angle_deg = 0.0;  //!< smallest interior angle of any face
  double max_angle_deg = 0.0;  //!< largest interior angle of any face
  double obtuse_fraction = 0.0;  //!< share of faces with an angle > 90 deg
  double small_angle_fraction = 0.0;  //!< share of faces with min angle < 30 deg
  double edge_length_mean = 0.0;  //!< over distinct undirected edges
  double edge_length_min = 0.0;
  double edge_length_max = 0.0;
  double edge_length_stddev = 0.0;  //!< population standard deviation
};

//! Two-sided sampled distance between a mesh and a reference surface.
struct DistanceReport {
  double hausdorff = 0.0;       //!< max of the two one-sided maxima
  double mean = 0.0;            //!< average of the two one-sided means
  double mesh_to_reference_max = 0.0;   //!< max over mesh samples of the distance to the reference
  double mesh_to_reference_mean = 0.0;  //!< mean over mesh samples
  double reference_to_mesh_max = 0.0;   //!< max over reference samples of the distance to the mesh
  double reference_to_mesh_mean = 0.0;  //!< mean over reference samples
  double reference_diagonal = 0.0;      //!< bbox diagonal of the reference
  double hausdorff_relative = 0.0;      //!< hausdorff / reference_diagonal
  double mean_relative = 0.0;           //!< mean / reference_diagonal
  std::size_t n_mesh_samples = 0;       //!< points sampled on the mesh
  std::size_t n_reference_samples = 0;  //!< points sampled on the reference
  //! (V_mesh - V_reference) / V_reference when both are closed and V_reference != 0.
  std::optional<double> relative_volume_change;
};

//! Options of mesh_distance().
struct DistanceOptions {
  //! Target spacing of the area samples, as a fraction of the reference's bbox diagonal
  //! (every vertex is sampled too). Default 0.005.
  double sample_spacing_relative = 0.005;
  //! Upper bound on the area samples per surface; the spacing grows to respect it.
  //! Default 4'000'000.
  std::size_t max_samples = 4'000'000;
  //! Worker threads (results do not depend on it). Default 2.
  unsigned n_threads = 2;
  //! Progress and cancellation (stage "distance"). Default none.
  ProgressCallback progress;
  //! \throw InvalidInput for a non-positive spacing, max_samples == 0 or n_threads == 0.
  void validate() const;
};

//! Options of mesh_report().
struct ReportOptions {
  //! Run the exact self-intersection check (the most expensive part). Default true.
  bool self_intersections = true;
  //! Worker threads (results do not depend on it). Default 2.
  unsigned n_threads = 2;
  //! Options of the distance part when a reference is given.
  DistanceOptions distance;
  //! Progress and cancellation (stages "topology", "self-intersections", "distance").
  //! Default none.
  ProgressCallback progress;
  //! \throw InvalidInput for n_threads == 0 or invalid distance options.
  void validate() const;
};

//! Full report on one mesh, optionally against a reference.
struct MeshReport {
  TopologyReport topology;
  QualityReport quality;
  std::optional<DistanceReport> distance;  //!< set by the overload with a reference
};

//! Topology and quality of a soup.
//! Algorithm: sorted edge list -> edge multiplicities, orientation and boundary;
//! union-find over vertices -> components, chi and genus per component; per-vertex
//! face fans -> non-manifold vertices; sorted face keys -> duplicates; an AABB tree
//! over the faces and a self-traversal -> candidate pairs, decided with exact
//! orientation predicates (static filter, expansion arithmetic fallback).
//! \throw InvalidInput for out-of-range indices, non-finite points or bad options.
//! \throw Cancelled if the progress callback asks to stop.
[[nodiscard]] MeshReport mesh_report(const TriangleSoup& soup, const ReportOptions& options = {});

//! As above, plus the distance to a reference surface (MeshReport::distance).
[[nodiscard]] MeshReport mesh_report(const TriangleSoup& soup, const TriangleSoup& reference,
                                     const ReportOptions& options);

//! Number of intersecting face pairs (see TopologyReport::n_self_intersecting_pairs).
//! \throw InvalidInput for out-of-range indices or non-finite points.
[[nodiscard]] std::size_t count_self_intersections(const TriangleSoup& soup, unsigned n_threads = 2);

//! The intersecting face pairs themselves (the ones count_self_intersections() counts), as
//! (smaller, larger) face indices in ascending order; the result does not depend on n_threads.
//! \throw InvalidInput for out-of-range indices, non-finite points or n_threads == 0.
[[nodiscard]] std::vector<std::array<std::uint32_t, 2>> self_intersecting_pairs(const TriangleSoup& soup,
                                                                                unsigned n_threads = 2);

//! The intersecting face pairs of self_intersecting_pairs() that involve at least one of
//! `faces` (any order, repeats allowed), in the same form: (smaller, larger) face indices,
//! ascending, each pair once. For re-checking a few changed faces of a large soup: a uniform
//! grid is built over the boxes of `faces` only (quality_detail::BoxGrid) and every face of
//! the soup is looked up in it, so the cost is linear in the soup plus the candidates near
//! `faces`. The soup's faces are taken on
//! n_threads workers; the result does not depend on n_threads.
//! \throw InvalidInput for out-of-range indices (in the soup or in `faces`), non-finite points
//! or n_threads == 0.
[[nodiscard]] std::vector<std::array<std::uint32_t, 2>> intersecting_pairs_of(const TriangleSoup& soup,
                                                                              const std::vector<std::uint32_t>& faces,
                                                                              unsigned n_threads = 1);

//! Two-sided distance by dense sampling: every vertex plus area-proportional samples
//! (spacing sample_spacing_relative * reference diagonal) on both surfaces, exact
//! closest points on the other surface through an AABB tree. Deterministic.
//! \pre both soups have at least one face.
//! \throw InvalidInput for empty or invalid soups or bad options.
[[nodiscard]] DistanceReport mesh_distance(const TriangleSoup& mesh, const TriangleSoup& reference,
                                           const DistanceOptions& options = {});

//! JSON object: {"topology": {...}, "alpha": {"mean", "min", "p1"},
//! "angles": {"min", "max", "obtuse_fraction", "small_angle_fraction"},
//! "edge_length": {...}, "distance": {...} or null}. Non-finite numbers become null.
[[nodiscard]] std::string to_json(const MeshReport& report);
//! JSON object with the fields of DistanceReport.
[[nodiscard]] std::string to_json(const DistanceReport& report);
//! A human-readable multi-line table.
[[nodiscard]] std::string to_text(const MeshReport& report);

}  // namespace nurbsfront
