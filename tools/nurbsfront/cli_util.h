// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Small helpers shared by the subcommands: progress display on stderr.
#include <filesystem>
#include <string>
#include <string_view>

#include "nurbsfront/core/mesh_types.h"
#include "nurbsfront/core/progress.h"

namespace nurbsfront::cli {

//! A ProgressCallback that draws "stage: 42%" on stderr when it is a terminal,
//! or prints one line per stage otherwise. Never cancels.
ProgressCallback terminal_progress(bool quiet = false);

//! The path's extension in lower case, with its dot (".ply"), or "".
std::string lower_extension(const std::filesystem::path& path);

//! "" when the surface has no self-intersecting triangle pairs; otherwise a sentence naming
//! their number and how many join different connected components, for an output whose
//! self-intersections come from its input.
std::string input_self_intersections(const TriMesh& input, unsigned threads);

//! Prints "nurbsfront: error: <message>" on stderr (a leading "nurbsfront: " of the message,
//! as the library's exceptions often have, dropped: the prefix once).
void print_error(std::string_view message);

}  // namespace nurbsfront::cli
