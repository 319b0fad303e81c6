// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Shared between the stitch sources (not part of the public API).
#include <vector>

#include "nurbsfront/stitch/stitch.h"

namespace nurbsfront::stitch_detail {

//! alpha of every face, in face order.
std::vector<double> face_alphas(const TriMesh& mesh);

//! Edge flips and constrained smoothing (StitchOptions::optimisation_passes rounds) on
//! result.mesh; result.face_patch stays valid (flips keep face handles).
void optimise(const SurfaceMesh& surface, const StitchOptions& options, StitchResult& result, StitchReport& report);

}  // namespace nurbsfront::stitch_detail
