// SPDX-License-Identifier: BSD-3-Clause
// nurbsfront stats MESH [--json] [--ref REF] [--vtk OUT.vtk] [--no-self-intersections]:
// topology, quality and (with --ref) distance report of a mesh file, read raw (no
// cleaning) so its defects are reported, not repaired; with --clean, of the surface as
// `remesh` reads it (prepare_mesh), after listing the repairs.
#include <iostream>
#include <memory>
#include <string>

#include "cli_util.h"
#include "commands.h"
#include "nurbsfront/io/mesh_io.h"
#include "nurbsfront/quality/report.h"

namespace nurbsfront::cli {

namespace {
struct StatsArgs {
  std::string input;
  std::string reference;
  std::string vtk;
  bool json = false;
  bool no_self_intersections = false;
  bool clean = false;
  bool quiet = false;
  unsigned threads = ReportOptions{}.n_threads;
  double sample_spacing_relative = DistanceOptions{}.sample_spacing_relative;
};
}  // namespace

void add_stats_command(CLI::App& app) {
  auto args = std::make_shared<StatsArgs>();
  auto* cmd = app.add_subcommand("stats", "Report topology, element quality and (with --ref) distances of a mesh");
  cmd->add_option("mesh", args->input, "Mesh file (.obj .ply .stl .off .vtk)")->required();
  cmd->add_flag("--json", args->json, "Print the report as one JSON object");
  cmd->add_option("--ref", args->reference, "Reference mesh: adds Hausdorff/mean distances and volume change");
  cmd->add_option("--vtk", args->vtk, "Write the mesh with per-face alpha and min_angle_deg fields (.vtk/.vtu)");
  cmd->add_flag("--clean", args->clean,
                "Report on the surface as remesh reads it: welded, cleaned, made manifold (the repairs are listed)");
  cmd->add_flag("--no-self-intersections", args->no_self_intersections, "Skip the exact self-intersection check");
  cmd->add_option("--threads", args->threads, "Worker threads")->capture_default_str();
  cmd->add_option("--sample-spacing", args->sample_spacing_relative,
                  "Distance sample spacing relative to the reference's bounding-box diagonal")
      ->capture_default_str();
  cmd->add_flag("--quiet", args->quiet, "No progress on stderr");
  cmd->callback([args] {
    ReportOptions options;
    options.self_intersections = !args->no_self_intersections;
    options.n_threads = args->threads;
    options.distance.n_threads = args->threads;
    options.distance.sample_spacing_relative = args->sample_spacing_relative;
    options.progress = terminal_progress(args->quiet);
    options.validate();
    TriangleSoup soup = read_soup(args->input);
    std::string repairs;
    if (args->clean) {
      const PreparedMesh prepared = prepare_mesh(soup);
      repairs = prepared.report.summary();
      soup = to_soup(prepared.mesh);
    }
    MeshReport report;
    if (args->reference.empty()) {
      report = mesh_report(soup, options);
    } else {
      const TriangleSoup reference = read_soup(args->reference);
      report = mesh_report(soup, reference, options);
    }
    if (!args->vtk.empty()) {
      WriteOptions write_options;
      write_options.face_fields.push_back({"alpha", face_alpha(soup)});
      write_options.face_fields.push_back({"min_angle_deg", face_min_angle_deg(soup)});
      write_soup(soup, args->vtk, write_options);
    }
    if (args->json) {
      std::cout << to_json(report) << '\n';
    } else {
      std::cout << args->input << '\n';
      if (args->clean) std::cout << "input repairs: " << repairs << '\n';
      std::cout << to_text(report);
    }
  });
}

}  // namespace nurbsfront::cli
