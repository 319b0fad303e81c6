// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Mesh files: strict, fast readers into a raw TriangleSoup (OBJ, PLY ASCII/binary,
//! STL ASCII/binary, OFF, legacy VTK POLYDATA), clean() (weld, drop degenerate,
//! duplicate and unreferenced elements), and writers (OBJ, PLY, STL, OFF, legacy VTK,
//! XML VTU with per-face scalar fields for ParaView).
//!
//! The readers are our own, not OpenMesh's: OpenMesh builds a TriMesh directly (dropping
//! non-manifold faces, which the quality report must see) and prints to std::cerr.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "nurbsfront/core/mesh_types.h"
#include "nurbsfront/core/soup.h"
#include "nurbsfront/core/tolerances.h"

namespace nurbsfront {

//! Supported mesh file formats.
enum class MeshFormat {
  Obj,  //!< Wavefront OBJ (v / f records; read and write)
  Ply,  //!< Stanford PLY, ASCII and binary little/big endian (read and write)
  Stl,  //!< STL, ASCII and binary (read and write)
  Off,  //!< Object File Format (read and write)
  Vtk,  //!< legacy VTK POLYDATA, ASCII and binary (read and write)
  Vtu   //!< VTK XML UnstructuredGrid of triangles (write only)
};

//! The format named by the path's extension (.obj .ply .stl .off .vtk .vtu, case-insensitive).
//! \throw IoError if the extension is missing or unsupported.
[[nodiscard]] MeshFormat mesh_format_from_path(const std::filesystem::path& path);

//! Reads any supported format into a raw soup: nothing is welded or dropped (so a
//! non-manifold or broken file can still be reported on). Polygons with more than three
//! vertices are fan-triangulated; VTK triangle strips are split into triangles with
//! alternating orientation (strip triangles with a repeated index are kept as they are,
//! clean() drops them).
//! \param path file to read; the format is chosen by its extension.
//! \throw IoError (missing, empty, truncated, malformed, unsupported, out-of-range
//! indices, non-finite coordinates, counts the file cannot hold) with a message naming the
//! file and the problem.
[[nodiscard]] TriangleSoup read_soup(const std::filesystem::path& path);

//! Options of clean().
struct CleanOptions {
  //! Points closer than this times the bbox diagonal are welded into one (0 welds only
  //! exactly equal points). Default tolerance::kWeldRelative.
  double weld_tolerance_relative = tolerance::kWeldRelative;
  //! Drop triangles that name a vertex twice after welding (collapsed to an edge or a
  //! point) or whose area is exactly zero. Default true.
  bool drop_degenerate = true;
  //! Drop triangles with the same three vertices as an earlier one (any order or
  //! orientation); the first is kept. Default true.
  bool drop_duplicate_faces = true;
  //! Drop points no triangle references, renumbering the others. Default true.
  bool drop_unreferenced = true;
  //! Threads for clean()'s per-point and per-triangle passes (the weld's grid cells, the
  //! remapping, the sorted triples; the hash tables are filled in order on one thread) and
  //! for building the halfedge mesh in read_mesh() and prepare_mesh() (with 2+ the manifold
  //! check runs beside the build); 0 = all hardware threads. The result does not depend on
  //! it (>= 0). Default 1.
  int threads = 1;
  //! \throw InvalidInput if weld_tolerance_relative is negative, not finite or >= 1, or
  //! threads is negative.
  void validate() const;
};

//! What clean() did.
struct CleanReport {
  std::size_t n_welded_vertices = 0;        //!< points merged into an earlier point
  std::size_t n_degenerate_faces = 0;       //!< triangles dropped as degenerate
  std::size_t n_duplicate_faces = 0;        //!< triangles dropped as duplicates
  std::size_t n_unreferenced_vertices = 0;  //!< points dropped as unreferenced (after welding)
  //! Triangles kept although their area is exactly zero (three distinct but collinear
  //! corners): dropping them would open a hole in a closed surface.
  std::size_t n_collinear_faces = 0;
};

//! Result of clean(): the cleaned soup and the counts.
struct CleanResult {
  TriangleSoup soup;
  CleanReport report;
};

//! Welds duplicate vertices (strip-based writers such as VTK's duplicate them), drops
//! degenerate triangles (collapsing to an edge or point after welding: marching cubes'
//! exactly zero-area triangles come from such coincident points), duplicate faces and
//! unreferenced vertices. Deterministic. Triangles with three distinct collinear corners
//! are kept and counted (CleanReport::n_collinear_faces).
//!
//! Algorithm: points are hashed into a grid of cells 8 x tolerance wide (open addressing);
//! each point is compared with the earlier representatives in its own cell and in the
//! neighbours across the faces it is within the tolerance of, and merged into the first
//! (lowest index) one within the tolerance, so the output order follows the input order
//! and no point moves further than the tolerance. Faces are then remapped, those naming a
//! vertex twice dropped, duplicates found by hashing the sorted index triples (the first
//! is kept), unreferenced points dropped. Expected O(n).
//! \param soup input; its indices must be in range.
//! \throw InvalidInput for out-of-range indices, non-finite coordinates or bad options.
[[nodiscard]] CleanResult clean(const TriangleSoup& soup, const CleanOptions& options = {});

//! What make_manifold() changed.
struct ManifoldRepairReport {
  std::size_t n_flipped_faces = 0;        //!< faces reversed to agree with their component
  std::size_t n_paired_edges = 0;         //!< edges with more than two faces, split into pairs of faces
  std::size_t n_cut_edges = 0;            //!< edges with more than two faces that could not be paired (cut open)
  std::size_t n_nonorientable_edges = 0;  //!< edges cut because their band cannot be oriented
  std::size_t n_split_vertices = 0;       //!< vertex copies added, one per extra face fan
  //! Sum of the counts: 0 when the soup was already an oriented 2-manifold.
  [[nodiscard]] std::size_t n_changes() const;
};

//! Result of make_manifold(): the repaired soup and the counts.
struct ManifoldRepair {
  TriangleSoup soup;
  ManifoldRepairReport report;
};

//! Makes a cleaned soup an oriented 2-manifold (with boundary where it must be cut) that
//! keeps every triangle and every point position:
//! 1. orientation: each connected component (faces joined across edges with two faces)
//!    takes the orientation of the majority of its faces; an edge where that is impossible
//!    (a non-orientable band) is cut;
//! 2. edges with more than two faces (solids touching along an edge, fins): the faces are
//!    sorted by angle around the edge and each is paired with the neighbour that bounds the
//!    same solid, which needs their directions to alternate around the edge; otherwise
//!    all of them are cut off the edge (each keeps its own copy: boundary edges);
//! 3. vertices where several fans of faces meet (solids touching at a point, and the ends
//!    of the edges split above) get one copy of the point per extra fan.
//! Triangle i of the result is triangle i of the input (possibly reversed); points keep
//! their indices and copies are appended. An input that is already an oriented 2-manifold
//! comes back unchanged (report.n_changes() == 0). The result passes check_manifold()
//! except around non-orientable bands whose cut edges still meet at one fan.
//! \pre clean() has run: no triangle repeats a vertex.
//! \throw InvalidInput for out-of-range indices or a triangle repeating a vertex.
[[nodiscard]] ManifoldRepair make_manifold(const TriangleSoup& soup);

//! What prepare_mesh() did.
struct PrepareReport {
  CleanReport clean;                    //!< clean()'s counts
  ManifoldRepairReport manifold;        //!< make_manifold()'s counts
  std::size_t n_zero_area_flipped = 0;  //!< zero-area triangles removed by flipping their long edge
  std::size_t n_zero_area_dropped = 0;  //!< zero-area triangles on the boundary dropped
  std::size_t n_zero_area_left = 0;     //!< zero-area triangles that could be neither flipped nor dropped
  //! One line naming every non-zero count ("nothing to repair" when all are zero).
  [[nodiscard]] std::string summary() const;
};

//! A surface ready for remesh() and what was done to get it.
struct PreparedMesh {
  TriMesh mesh;
  PrepareReport report;
};

//! Makes any triangle soup that describes a surface a valid remesh() input:
//! clean() (weld, drop collapsed and duplicate triangles), make_manifold() (orientation,
//! non-manifold edges and vertices), then removes triangles of exactly zero area (three
//! distinct collinear corners) by flipping their long edge, or dropping them where that
//! edge is on the boundary (the boundary curve stays the same). Positions never move.
//! \throw InvalidInput for non-finite points, bad options, no triangle left, or a soup
//! that is still not an oriented 2-manifold (non-orientable); the message names the problem.
[[nodiscard]] PreparedMesh prepare_mesh(const TriangleSoup& soup, const CleanOptions& options = {});

//! read_soup + clean + to_trimesh.
//! \throw IoError if the file cannot be read, TopologyError if the cleaned soup is not an
//! oriented 2-manifold (the message names the problems).
[[nodiscard]] TriMesh read_mesh(const std::filesystem::path& path, const CleanOptions& options = {});

//! A scalar field with one value per face (e.g. quality, patch id).
struct FaceField {
  std::string name;            //!< field name (no whitespace); shown in ParaView
  std::vector<double> values;  //!< one value per triangle
};

//! Options of write_soup() / write_mesh().
struct WriteOptions {
  //! Binary output where the format has it (PLY, STL, VTK, VTU appended raw data).
  //! Default true. OBJ and OFF are always ASCII.
  bool binary = true;
  //! Per-face scalar fields, written to VTK/VTU (CELL_DATA) and PLY (face properties);
  //! other formats ignore them. Each must have one value per triangle. Default none.
  std::vector<FaceField> face_fields;
  //! \throw InvalidInput for an empty or whitespace-containing field name or a repeated name.
  void validate() const;
};

//! Writes the soup in the format named by the extension (coordinates written so that
//! they read back exactly: 17 significant digits in ASCII, doubles in binary except STL
//! which is single precision by definition).
//! \throw InvalidInput for out-of-range indices or face fields of the wrong size,
//! IoError if the format is unsupported or the file cannot be written.
void write_soup(const TriangleSoup& soup, const std::filesystem::path& path,
                const WriteOptions& options = {});

//! to_soup + write_soup.
void write_mesh(const TriMesh& mesh, const std::filesystem::path& path,
                const WriteOptions& options = {});

}  // namespace nurbsfront
