// SPDX-License-Identifier: BSD-3-Clause
// nurbsfront convert IN OUT [--ascii] [--no-clean | --repair]: mesh format conversion (by
// extension), welding and cleaning, optionally the repair remesh applies on reading.
#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "nurbsfront/io/mesh_io.h"

namespace nurbsfront::cli {

namespace {
struct ConvertArgs {
  std::string input;
  std::string output;
  bool ascii = false;
  bool no_clean = false;
  bool repair = false;
  double weld_tolerance_relative = CleanOptions{}.weld_tolerance_relative;
};
}  // namespace

void add_convert_command(CLI::App& app) {
  auto args = std::make_shared<ConvertArgs>();
  auto* cmd = app.add_subcommand("convert", "Convert a mesh file (format by extension: obj ply stl off vtk vtu)");
  cmd->add_option("input", args->input, "Input mesh (.obj .ply .stl .off .vtk)")->required();
  cmd->add_option("output", args->output, "Output mesh (.obj .ply .stl .off .vtk .vtu)")->required();
  cmd->add_flag("--ascii", args->ascii, "Write ASCII instead of binary (PLY, STL, VTK, VTU)");
  cmd->add_flag("--no-clean", args->no_clean, "Do not weld duplicate points nor drop degenerate/duplicate faces");
  auto* repair = cmd->add_flag("--repair", args->repair,
                               "Also make the mesh a valid remesh input: orient every component, split non-manifold "
                               "edges and vertices, flip away zero-area triangles (what remesh does on reading)");
  repair->excludes(cmd->get_option("--no-clean"));
  cmd->add_option("--weld-tolerance", args->weld_tolerance_relative,
                  "Welding distance relative to the bounding-box diagonal")
      ->capture_default_str();
  cmd->callback([args] {
    CleanOptions clean_options;
    clean_options.weld_tolerance_relative = args->weld_tolerance_relative;
    clean_options.validate();
    WriteOptions write_options;
    write_options.binary = !args->ascii;
    TriangleSoup soup = read_soup(args->input);
    const std::size_t n_points_in = soup.points.size();
    const std::size_t n_triangles_in = soup.triangles.size();
    std::string cleaned = "not cleaned";
    if (args->repair) {
      const PreparedMesh prepared = prepare_mesh(soup, clean_options);
      soup = to_soup(prepared.mesh);
      cleaned = "repair: " + prepared.report.summary();
    } else if (!args->no_clean) {
      CleanResult result = clean(soup, clean_options);
      soup = std::move(result.soup);
      const CleanReport& r = result.report;
      cleaned = "clean: " + std::to_string(r.n_welded_vertices) + " welded, " +
                std::to_string(r.n_unreferenced_vertices) + " unreferenced vertices, " +
                std::to_string(r.n_degenerate_faces) + " degenerate, " + std::to_string(r.n_duplicate_faces) +
                " duplicate faces dropped";
      if (r.n_collinear_faces > 0) cleaned += ", " + std::to_string(r.n_collinear_faces) + " zero-area faces kept";
    }
    write_soup(soup, args->output, write_options);
    std::cout << args->output << ": " << soup.points.size() << " vertices, " << soup.triangles.size()
              << " triangles (read " << n_points_in << " points, " << n_triangles_in << " triangles; " << cleaned
              << ")\n";
  });
}

}  // namespace nurbsfront::cli
