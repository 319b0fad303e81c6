// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Files for the nurbs module: NURBS surfaces in a text format that round-trips exactly,
//! IGES 5.3 rational B-spline surfaces (entity 128) for CAD tools, and .xyz point lists.
//!
//! Text format (".nurbs"), whitespace-separated tokens, '#' starts a comment line:
//! \code
//!   nurbsfront_surface 1
//!   degrees <p> <q>
//!   counts <n_u> <n_v>
//!   knots_u <n_u + p + 1 numbers>
//!   knots_v <n_v + q + 1 numbers>
//!   points
//!   <x y z w>   (n_u * n_v lines, u index fastest)
//!   end
//! \endcode
//! Numbers are written in the shortest form that reads back to the same double
//! (std::to_chars), so write -> read reproduces every bit.

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "nurbsfront/nurbs/nurbs_surface.h"

namespace nurbsfront {

//! The surface in the text format. \throw InvalidInput if surface.validate() fails.
[[nodiscard]] std::string surface_to_text(const NurbsSurface& surface);
//! Parses the text format. \throw IoError naming the problem for malformed text;
//! InvalidInput if the parsed surface fails validate().
[[nodiscard]] NurbsSurface surface_from_text(std::string_view text);

//! Writes the text format. \throw IoError if the file cannot be written.
void write_surface(const std::filesystem::path& path, const NurbsSurface& surface);
//! Reads the text format. \throw IoError, InvalidInput as surface_from_text().
[[nodiscard]] NurbsSurface read_surface(const std::filesystem::path& path);

//! An IGES 5.3 file (fixed 80-column ASCII) with one rational B-spline surface entity
//! (type 128, form 0) per surface, in the order given; reals with 17 significant digits.
//! \throw InvalidInput for no surfaces or a surface failing validate().
[[nodiscard]] std::string surfaces_to_iges(const std::vector<NurbsSurface>& surfaces);
//! Writes surfaces_to_iges() to a file. \throw IoError if it cannot be written.
void write_iges(const std::filesystem::path& path, const std::vector<NurbsSurface>& surfaces);

//! Reads points "x y z" (one a line; blanks, commas or tabs separate; further columns and
//! lines starting with '#' are ignored). \throw IoError for an unreadable file or a line
//! with fewer than three numbers (the message names the line).
[[nodiscard]] std::vector<Eigen::Vector3d> read_xyz(const std::filesystem::path& path);
//! Writes points one a line, exact (shortest round-trip form). \throw IoError.
void write_xyz(const std::filesystem::path& path, const std::vector<Eigen::Vector3d>& points);

}  // namespace nurbsfront
