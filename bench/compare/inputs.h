// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The inputs of the comparison: built-in scenes' marching-cubes surfaces, the real volumes'
// surfaces and meshes from ../shared/data (skipped, with a note, when absent).
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "nurbsfront/core/mesh_types.h"

namespace nurbsfront::bench {

struct CompareInput {
  std::string name;         //!< e.g. "dram/128", "headsq@500", "bunny"
  std::string description;  //!< how it is made (for the tables)
  bool quick = false;       //!< part of --quick
  std::function<TriMesh()> load;  //!< welded, cleaned, 2-manifold
};

//! The inputs in table order. `skipped` receives one line per input that needs files
//! which are absent.
[[nodiscard]] std::vector<CompareInput> comparison_inputs(std::vector<std::string>& skipped);

//! $NURBSFRONT_SHARED_DATA, else the nearest <ancestor of the repository>/shared/data.
[[nodiscard]] std::filesystem::path shared_data_dir();

}  // namespace nurbsfront::bench
