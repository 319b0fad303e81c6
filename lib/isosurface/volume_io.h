// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Readers for scalar volumes (CT images, label images, density grids).

#include <filesystem>

#include "nurbsfront/isosurface/scalar_grid.h"

namespace nurbsfront {

//! Reads a 3D scalar volume; the format is chosen by the file name's extension:
//! - MetaImage `.mha` (header and data in one file) and `.mhd` (header; data in the file named
//!   by ElementDataFile, relative to the header): ElementType MET_UCHAR, MET_CHAR, MET_USHORT,
//!   MET_SHORT, MET_UINT, MET_INT, MET_FLOAT, MET_DOUBLE; BinaryDataByteOrderMSB /
//!   ElementByteOrderMSB; CompressedData (zlib); ElementSpacing (or ElementSize); Offset (or
//!   Position / Origin); HeaderSize for .raw files; ASCII data (BinaryData = False).
//!   TransformMatrix is ignored (the grid is axis-aligned).
//! - legacy VTK `.vtk` DATASET STRUCTURED_POINTS with one scalar component, ASCII or BINARY
//!   (big-endian), SPACING or ASPECT_RATIO, ORIGIN.
//! - INRIA `.inr` and gzipped `.inr.gz`: INRIMAGE-4 header (blocks of 256 bytes), TYPE
//!   unsigned fixed / signed fixed / float, PIXSIZE 8/16/32/64 bits, CPU (byte order), VX VY VZ,
//!   VDIM = 1.
//! Values are converted to float. Sizes given by a header are checked against the data
//! actually present before anything is allocated for them.
//! \param path the volume file
//! \return the grid (validated)
//! \throw IoError for a missing, empty or unreadable file, an unknown extension, a malformed
//!        header, an unsupported element type or layout, truncated data, data whose length does
//!        not match the header's sizes, or a corrupt compressed stream.
[[nodiscard]] ScalarGrid read_volume(const std::filesystem::path& path);

}  // namespace nurbsfront
