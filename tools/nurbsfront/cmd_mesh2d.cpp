// SPDX-License-Identifier: BSD-3-Clause
// nurbsfront mesh2d DOMAIN (.poly/.node/.edg) [--size H] [-o OUT] [--json]: 2D advancing
// front mesh of a planar straight-line graph; output format by extension (.node/.ele via
// .node or .ele, otherwise any mesh format of the io module, lifted to z = 0), followed by
// the quality report.
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "cli_util.h"
#include "commands.h"
#include "nurbsfront/core/error.h"
#include "nurbsfront/front2d/front.h"
#include "nurbsfront/io/mesh_io.h"
#include "nurbsfront/quality/report.h"

namespace nurbsfront::cli {

namespace {
struct Mesh2dArgs {
  std::string input;
  std::string output;
  double size = 0.0;
  double gradation = SizingField{}.gradation;
  bool vertex_sizes = false;
  bool convex_hull = false;
  double hull_gap = FrontOptions{}.hull_gap_fraction;
  bool keep_segments = false;
  int smoothing_passes = FrontOptions{}.smoothing_passes;
  bool no_swaps = false;
  bool no_refine = false;
  double corner_angle = FrontOptions{}.corner_split_angle_deg;
  bool json = false;
  bool quiet = false;
};

TriangleSoup lift(const Mesh2d& mesh) {
  TriangleSoup soup;
  soup.points.reserve(mesh.points.size());
  for (const auto& p : mesh.points) soup.points.emplace_back(p.x(), p.y(), 0.0);
  soup.triangles.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles)
    soup.triangles.push_back({static_cast<std::uint32_t>(t[0]), static_cast<std::uint32_t>(t[1]), static_cast<std::uint32_t>(t[2])});
  return soup;
}
}  // namespace

void add_mesh2d_command(CLI::App& app) {
  auto args = std::make_shared<Mesh2dArgs>();
  auto* cmd = app.add_subcommand("mesh2d", "Triangulate a planar straight-line graph with the advancing front");
  cmd->add_option("domain", args->input, "PSLG file (.poly .node .edg)")->required();
  cmd->add_option("-o,--output", args->output, "Output mesh (.node/.ele, .obj, .vtk, .ply, ...)");
  cmd->add_option("--size", args->size, "Uniform target edge length (0 = bounding-box diagonal / 40)")->capture_default_str();
  cmd->add_flag("--vertex-sizes", args->vertex_sizes, "Use the first vertex attribute of the .poly/.node as the size at each vertex");
  cmd->add_option("--gradation", args->gradation, "Maximum size growth: |grad h| <= gradation - 1")->capture_default_str();
  cmd->add_flag("--convex-hull", args->convex_hull, "Enclose the convex hull with segments (as Triangle -c)");
  cmd->add_option("--hull-gap", args->hull_gap,
                  "With --convex-hull: a hull edge the input follows closer than this times the size is left out (0 = exact hull)")
      ->capture_default_str();
  cmd->add_flag("--keep-segments", args->keep_segments, "Do not split the input segments (already discretised)");
  cmd->add_option("--smooth", args->smoothing_passes, "Smoothing passes")->capture_default_str();
  cmd->add_flag("--no-swaps", args->no_swaps, "No edge swaps after the front");
  cmd->add_flag("--no-refine", args->no_refine, "No Delaunay refinement of the triangles below 30 deg");
  cmd->add_option("--corner-angle", args->corner_angle,
                  "A front corner wider than this (deg) gets a node on its bisector instead of one closing triangle (180 = off)")
      ->check(CLI::Range(1e-9, 180.0))
      ->capture_default_str();
  cmd->add_flag("--json", args->json, "Print the quality report as JSON");
  cmd->add_flag("--quiet", args->quiet, "No progress on stderr");
  cmd->callback([args] {
    const Pslg pslg = read_pslg(args->input);
    FrontOptions options;
    if (args->vertex_sizes) {
      if (pslg.point_sizes.size() != pslg.points.size())
        throw InvalidInput("--vertex-sizes: '" + args->input + "' has no size attribute on every vertex");
      options.sizing = SizingField::per_vertex(pslg.point_sizes);
    } else {
      options.sizing = SizingField::uniform(args->size);
    }
    options.sizing.gradation = args->gradation;
    options.enclose_convex_hull = args->convex_hull;
    options.hull_gap_fraction = args->hull_gap;
    options.split_segments = !args->keep_segments;
    options.smoothing_passes = args->smoothing_passes;
    options.swap_edges = !args->no_swaps;
    options.refine_min_angle = !args->no_refine;
    options.corner_split_angle_deg = args->corner_angle;
    options.progress = terminal_progress(args->quiet);
    Mesh2d mesh;
    try {
      mesh = mesh_pslg(pslg, options);
    } catch (const InvalidInput& e) {
      const std::string what = e.what();
      if (args->convex_hull || what.find("domain is empty") == std::string::npos) throw;
      throw InvalidInput(what + "; the segments enclose no region: --convex-hull meshes the convex hull (Triangle -c)");
    }
    if (mesh.report.status != FrontStatus::Ok) std::cerr << "nurbsfront: warning: " << mesh.report.message << "\n";
    const TriangleSoup soup = lift(mesh);
    if (!args->output.empty()) {
      std::filesystem::path out(args->output);
      const std::string ext = lower_extension(out);
      if (ext == ".node" || ext == ".ele") {
        write_triangle_files(mesh, out.replace_extension());
      } else {
        write_soup(soup, out);
      }
    }
    ReportOptions report_options;
    report_options.self_intersections = soup.triangles.size() <= 2'000'000;
    report_options.progress = terminal_progress(args->quiet);
    const MeshReport report = mesh_report(soup, report_options);
    if (args->json) {
      std::cout << to_json(report) << "\n";
    } else {
      std::cout << "triangles " << mesh.triangles.size() << ", points " << mesh.points.size() << " (new "
                << mesh.report.n_new_points << ", corner " << mesh.report.n_corner_points << ", refinement " << mesh.report.n_refinement_points << "), hull edges followed by the input " << mesh.report.n_hull_edges_followed
                << " (area left out " << mesh.report.hull_gap_area << "), repairs " << mesh.report.n_repairs << ", swaps " << mesh.report.n_swaps
                << ", domain area " << mesh.report.domain_area << ", front " << mesh.report.seconds_front << " s, optimise "
                << mesh.report.seconds_optimise << " s\n"
                << to_text(report);
    }
  });
}

}  // namespace nurbsfront::cli
