// SPDX-License-Identifier: BSD-3-Clause
// nurbsfront mc: marching cubes on a volume file or on a built-in analytic scene.
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "cli_util.h"
#include "commands.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/core/stopwatch.h"
#include "nurbsfront/io/mesh_io.h"
#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/scenes.h"
#include "nurbsfront/isosurface/volume_io.h"

namespace nurbsfront::cli {

namespace {

struct McArgs {
  std::string volume;
  std::string scene;
  int resolution = 128;
  std::optional<double> iso;
  bool occupancy = false;
  bool inside_above = false;
  bool inside_below = false;
  bool pad = false;
  bool quiet = false;
  std::string output;
};

void run_mc(const McArgs& args) {
  if (args.volume.empty() == args.scene.empty()) {
    throw InvalidInput("mc: give either a VOLUME_FILE or --scene NAME (exactly one)");
  }
  Stopwatch watch;
  ScalarGrid grid;
  MarchingCubesOptions options;
  if (!args.scene.empty()) {
    const SampleMode mode = args.occupancy ? SampleMode::Occupancy : SampleMode::LevelSet;
    grid = sample_scene(scene_by_name(args.scene), args.resolution, mode);
    options = scene_marching_cubes_options(mode);
  } else {
    if (args.occupancy) throw InvalidInput("mc: --occupancy applies to --scene only");
    grid = read_volume(args.volume);
    options.inside_above = true;  // CT-like data by default
    const auto range = grid.value_range();
    options.iso = 0.5 * (double(range[0]) + double(range[1]));  // replaced by --iso when given
  }
  const double t_input = watch.seconds();
  if (args.iso) options.iso = *args.iso;
  if (args.inside_above) options.inside_above = true;
  if (args.inside_below) options.inside_above = false;
  options.pad = args.pad;
  options.progress = terminal_progress(args.quiet);
  std::cout << "grid " << grid.dims[0] << " x " << grid.dims[1] << " x " << grid.dims[2] << ", origin "
            << grid.origin.transpose() << ", spacing " << grid.spacing.transpose() << ", iso " << options.iso << " (inside "
            << (options.inside_above ? "above" : "below") << ")" << (args.iso ? "" : " [default]") << '\n';
  watch.restart();
  const TriangleSoup soup = marching_cubes(grid, options);
  const double t_mc = watch.seconds();
  watch.restart();
  write_soup(soup, args.output);
  const double t_write = watch.seconds();
  std::cout << "vertices " << soup.points.size() << ", faces " << soup.triangles.size() << '\n'
            << "time: " << (args.scene.empty() ? "read " : "sample ") << t_input << " s, marching cubes " << t_mc
            << " s, write " << t_write << " s\n"
            << "wrote " << args.output << '\n';
}

}  // namespace

void add_mc_command(CLI::App& app) {
  auto args = std::make_shared<McArgs>();
  auto* cmd = app.add_subcommand("mc", "Marching cubes on a volume file (.mha/.mhd/.vtk/.inr/.inr.gz) or a built-in scene");
  cmd->add_option("volume", args->volume, "Volume file (MetaImage, legacy VTK STRUCTURED_POINTS, INRIA .inr[.gz])");
  cmd->add_option("--scene", args->scene, "Built-in scene instead of a file: sphere, torus, trench, dram");
  cmd->add_option("--res", args->resolution, "Scene cells along the longest side (default 128)");
  cmd->add_option("--iso", args->iso,
                  "Iso-value (default: 0 for level-set scenes, 0.5 for --occupancy, mid-range for volume files)");
  cmd->add_flag("--occupancy", args->occupancy, "Sample the scene as 0/1 cell occupancy instead of a signed distance");
  auto* above = cmd->add_flag("--inside-above", args->inside_above,
                              "Inside where value > iso (default for volume files and --occupancy)");
  auto* below = cmd->add_flag("--inside-below", args->inside_below,
                              "Inside where value < iso (default for level-set scenes)");
  above->excludes(below);
  cmd->add_flag("--pad", args->pad, "Pad the grid with outside values so the surface is closed");
  cmd->add_flag("-q,--quiet", args->quiet, "No progress display");
  cmd->add_option("-o,--output", args->output, "Output mesh (.ply, .obj, .stl, .off, .vtk, ...)")->required();
  cmd->callback([args] { run_mc(*args); });
}

}  // namespace nurbsfront::cli
