// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Planar straight-line graphs (PSLG) and their file formats.

#include <array>
#include <filesystem>
#include <vector>

#include <Eigen/Core>

namespace nurbsfront {

//! A region marker: every triangle of the face of the PSLG that contains `point` gets
//! `marker` (as Triangle's regional attributes).
struct Region {
  Eigen::Vector2d point = Eigen::Vector2d::Zero();  //!< a point strictly inside the region
  int marker = 0;                                   //!< the marker given to its triangles
};

//! A planar straight-line graph: the input of the 2D mesher.
//!
//! The domain is the union of the bounded faces of the arrangement of `segments` (plus
//! the convex hull edges when FrontOptions::enclose_convex_hull is set, except those the
//! segments follow within FrontOptions::hull_gap_fraction), minus every face containing a
//! hole point. Segments must not cross or overlap, no point may lie inside a
//! segment, and points must be distinct. Points that are on no segment are kept as mesh
//! vertices when they lie inside the domain.
struct Pslg {
  std::vector<Eigen::Vector2d> points;        //!< input vertices (0-based)
  std::vector<std::array<int, 2>> segments;   //!< pairs of point indices
  std::vector<Eigen::Vector2d> holes;         //!< one point inside each face to leave empty
  std::vector<Region> regions;                //!< optional region markers
  std::vector<double> point_sizes;            //!< optional target size per point (.node attribute), empty if none
};

//! Reads Triangle's .poly format (comments with '#', 0- or 1-based indices, attributes
//! and boundary markers allowed and ignored except that the first attribute of each
//! vertex is stored in point_sizes; a .poly with zero vertices reads the sibling .node).
//! \throw IoError if the file cannot be read or is malformed.
[[nodiscard]] Pslg read_poly(const std::filesystem::path& path);

//! Reads Triangle's .node format: points only, no segments. Meshed with
//! FrontOptions::enclose_convex_hull, this gives the convex hull with every point kept.
//! \throw IoError if the file cannot be read or is malformed.
[[nodiscard]] Pslg read_node(const std::filesystem::path& path);

//! Reads CGAL's .edg format: a count N, then N lines `x1 y1 x2 y2`. Points are shared
//! between segments when their coordinates are equal exactly; zero-length segments are
//! skipped.
//! \throw IoError if the file cannot be read or is malformed.
[[nodiscard]] Pslg read_edg(const std::filesystem::path& path);

//! Dispatches on the extension (.poly, .node, .edg).
//! \throw IoError for an unknown extension or an unreadable file.
[[nodiscard]] Pslg read_pslg(const std::filesystem::path& path);

}  // namespace nurbsfront
