// SPDX-License-Identifier: BSD-3-Clause
#pragma once
//! \file
//! Helpers shared by the quality module's sources (not part of the public API).

#include "nurbsfront/core/soup.h"

namespace nurbsfront::quality_detail {

//! \throw InvalidInput naming `what` for out-of-range indices or non-finite points.
void validate_soup(const TriangleSoup& soup, const char* what);

//! Every edge has exactly two faces and no face repeats a vertex (orientation ignored).
bool is_closed_surface(const TriangleSoup& soup);

}  // namespace nurbsfront::quality_detail
