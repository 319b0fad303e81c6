// SPDX-License-Identifier: BSD-3-Clause
// nurbsfront fit POINTS -o SURFACE: multilevel B-spline fit of a height field to points
// (.xyz text, or the vertices of a mesh file), written as a NURBS surface (.igs/.iges: IGES
// entity 128; .nurbs: the exact text format of docs/nurbs.md), with the residual report.
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "cli_util.h"
#include "commands.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/io/mesh_io.h"
#include "nurbsfront/nurbs/frame.h"
#include "nurbsfront/nurbs/mba.h"
#include "nurbsfront/nurbs/surface_io.h"

namespace nurbsfront::cli {

namespace {
struct FitArgs {
  std::string input;
  std::string output;
  std::string frame = "xy";
  FitOptions options;
  bool no_linear = false;
  bool quiet = false;
};

}  // namespace

void add_fit_command(CLI::App& app) {
  auto args = std::make_shared<FitArgs>();
  auto* cmd = app.add_subcommand(
      "fit", "Fit a NURBS surface (multilevel B-spline height field) to points (.xyz or a mesh's vertices)");
  cmd->add_option("input", args->input, "Points: .xyz/.txt (x y z a line) or a mesh file (its vertices)")->required();
  cmd->add_option("-o,--output", args->output, "Surface file: .igs/.iges (IGES 128) or .nurbs (exact text)")->required();
  cmd->add_option("--frame", args->frame,
                  "Plane of the height field: 'xy' (z = f(x, y)) or 'auto' (best-fit plane of the points)")
      ->check(CLI::IsMember({"xy", "auto"}))
      ->capture_default_str();
  cmd->add_option("--tolerance", args->options.tolerance,
                  "Stop at this max residual (unit of z); 0 = relative tolerance x rectangle diagonal")
      ->capture_default_str();
  cmd->add_option("--relative-tolerance", args->options.relative_tolerance, "Tolerance relative to the rectangle diagonal")
      ->capture_default_str();
  cmd->add_option("--max-levels", args->options.max_levels, "Most lattice levels")->capture_default_str();
  cmd->add_option("--min-spacing", args->options.min_spacing,
                  "Smallest lattice spacing (e.g. 3 voxels for terraced input); 0 = no limit")
      ->capture_default_str();
  cmd->add_option("--base-cells", args->options.base_cells, "Level-0 cells along the shorter side")->capture_default_str();
  cmd->add_option("--final-passes", args->options.final_passes, "Extra passes on the finest lattice when a limit stops")
      ->capture_default_str();
  cmd->add_flag("--no-linear", args->no_linear, "Plain MBA: no least-squares bilinear start");
  cmd->add_flag("-q,--quiet", args->quiet, "No progress display");
  cmd->callback([args] {
    const std::filesystem::path in(args->input);
    const std::filesystem::path out(args->output);
    const std::string out_ext = lower_extension(out);
    if (out_ext != ".igs" && out_ext != ".iges" && out_ext != ".nurbs") {
      throw InvalidInput("fit: output must end in .igs, .iges or .nurbs, not '" + out.string() + "'");
    }
    const std::string in_ext = lower_extension(in);
    std::vector<Eigen::Vector3d> points =
        (in_ext == ".xyz" || in_ext == ".txt" || in_ext == ".pts") ? read_xyz(in) : read_soup(in).points;

    FitOptions options = args->options;
    options.linear_precision = !args->no_linear;
    options.progress = terminal_progress(args->quiet);
    options.validate();
    PatchFrame frame;  // identity for --frame xy
    if (args->frame == "auto") frame = patch_frame_pca(points);
    const FitResult fit = fit_height_field(frame.to_local(points), options);
    const NurbsSurface surface = fit.field.to_nurbs().transformed(frame.axes, frame.origin);
    if (out_ext == ".nurbs") {
      write_surface(out, surface);
    } else {
      write_iges(out, {surface});
    }

    const Rectangle& r = fit.field.domain();
    std::printf("%zu points (%zu outside the rectangle), rectangle [%g, %g] x [%g, %g], tolerance %g\n", fit.n_points,
                fit.n_outside, r.min.x(), r.max.x(), r.min.y(), r.max.y(), fit.tolerance);
    std::printf("bilinear start: max residual %g\n", fit.base_max_residual);
    std::printf("%5s %11s %11s %13s %13s\n", "level", "cells", "spacing", "max residual", "rms residual");
    for (const FitLevel& l : fit.levels) {
      const std::string cells = std::to_string(l.n_cells_x) + "x" + std::to_string(l.n_cells_y);
      std::printf("%5d %11s %11.4g %13.4g %13.4g\n", l.level, cells.c_str(), std::min(l.spacing_x, l.spacing_y),
                  l.max_residual, l.rms_residual);
    }
    if (!fit.final_pass_max_residual.empty()) {
      std::printf("%zu final passes: max residual %g\n", fit.final_pass_max_residual.size(), fit.max_residual());
    }
    std::printf("stopped: %s; wrote %s (bicubic NURBS, %zu x %zu control points)\n", to_string(fit.stop),
                out.string().c_str(), surface.n_u, surface.n_v);
  });
}

}  // namespace nurbsfront::cli
