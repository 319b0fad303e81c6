// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Each subcommand lives in cmd_<name>.cpp and registers itself on the app here.
// Add one line per command; keep the order of the pipeline.
#include <CLI/CLI.hpp>

namespace nurbsfront::cli {

void add_version_command(CLI::App& app);
void add_convert_command(CLI::App& app);
void add_stats_command(CLI::App& app);
void add_mc_command(CLI::App& app);
void add_mesh2d_command(CLI::App& app);
void add_fit_command(CLI::App& app);
void add_remesh_command(CLI::App& app);
void add_patch_command(CLI::App& app);

//! Registers every subcommand (called once by main).
inline void add_all_commands(CLI::App& app) {
  add_version_command(app);
  add_convert_command(app);
  add_stats_command(app);
  add_mc_command(app);
  add_mesh2d_command(app);
  add_fit_command(app);
  add_remesh_command(app);
  add_patch_command(app);
}

}  // namespace nurbsfront::cli
