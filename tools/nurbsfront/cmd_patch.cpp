// SPDX-License-Identifier: BSD-3-Clause
// nurbsfront patch IN -o OUT: the source method's single-polygon path. An ordered 3D
// polygon with node densities at its vertices plus scattered points (text format of
// docs/surfmesh.md, or --example for the built-in curved surface) is rotated onto its
// plane, fitted, meshed by the advancing front with the surface metric, lifted and
// rotated back; prints the quality report.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "cli_util.h"
#include "commands.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/core/stopwatch.h"
#include "nurbsfront/io/mesh_io.h"
#include "nurbsfront/nurbs/surface_io.h"
#include "nurbsfront/quality/report.h"
#include "nurbsfront/surfmesh/polygon_patch.h"

namespace nurbsfront::cli {

namespace {
struct PatchArgs {
  std::string input;
  std::string output;
  std::string surface;
  bool example = false;
  bool json = false;
  bool quiet = false;
  PolygonPatchOptions options;
};
}  // namespace

void add_patch_command(CLI::App& app) {
  auto args = std::make_shared<PatchArgs>();
  auto* cmd = app.add_subcommand(
      "patch", "Mesh one polygonal surface patch (polygon with node densities + scattered points), as the source method");
  cmd->add_option("input", args->input, "Polygon patch text file ('polygon N' x y z density lines, 'points M' x y z lines)");
  cmd->add_flag("--example", args->example, "Use the built-in curved example (about 500 nodes) instead of a file");
  cmd->add_option("-o,--output", args->output, "Output mesh (.ply .obj .stl .off .vtk .vtu; VTK gets per-face alpha)");
  cmd->add_option("--surface", args->surface, "Also write the fitted surface (.igs/.iges or .nurbs)");
  cmd->add_option("--gradation", args->options.gradation, "Sizing gradation (> 1)")->capture_default_str();
  cmd->add_option("--smoothing-passes", args->options.smoothing_passes, "Smoothing passes after the front")
      ->capture_default_str();
  cmd->add_flag("--keep-polygon-vertices", args->options.keep_polygon_vertices,
                "Keep the polygon's vertices where they are instead of moving them onto the fitted surface");
  cmd->add_flag("--json", args->json, "Print the quality report as JSON");
  cmd->add_flag("-q,--quiet", args->quiet, "No progress display");
  cmd->callback([args] {
    if (args->example == !args->input.empty()) throw InvalidInput("patch: give either an input file or --example");
    const PolygonPatch patch = args->example ? example_polygon_patch() : read_polygon_patch(args->input);
    PolygonPatchOptions options = args->options;
    options.progress = terminal_progress(args->quiet);
    Stopwatch clock;
    const PolygonPatchMesh mesh = mesh_polygon_patch(patch, options);
    const double seconds = clock.seconds();

    TriangleSoup soup;
    soup.points = mesh.nodes;
    for (const auto& t : mesh.triangles) {
      soup.triangles.push_back({static_cast<std::uint32_t>(t[0]), static_cast<std::uint32_t>(t[1]), static_cast<std::uint32_t>(t[2])});
    }
    if (!args->output.empty()) {
      WriteOptions write_options;
      write_options.face_fields.push_back({"alpha", face_alpha(soup)});
      write_soup(soup, args->output, write_options);
    }
    if (!args->surface.empty()) {
      const std::string ext = lower_extension(args->surface);
      const NurbsSurface surface = mesh.surface.field.to_nurbs().transformed(mesh.surface.frame.axes, mesh.surface.frame.origin);
      if (ext == ".nurbs") {
        write_surface(args->surface, surface);
      } else if (ext == ".igs" || ext == ".iges") {
        write_iges(args->surface, {surface});
      } else {
        throw InvalidInput("patch: --surface must end in .igs, .iges or .nurbs");
      }
    }
    const MeshReport report = mesh_report(soup);
    if (args->json) {
      std::cout << to_json(report) << "\n";
    } else {
      std::cout << "polygon of " << patch.polygon.size() << " vertices, " << patch.points.size()
                << " scattered points; fit max residual " << mesh.fit.max_residual() << "; " << mesh.nodes.size()
                << " nodes, " << mesh.triangles.size() << " triangles in " << seconds << " s\n"
                << to_text(report);
    }
  });
}

}  // namespace nurbsfront::cli
