// SPDX-License-Identifier: BSD-3-Clause
// bench_cgal: nurbsfront remesh against CGAL's isotropic remeshing
// (CGAL::Polygon_mesh_processing::isotropic_remeshing, Botsch-Kobbelt split/collapse/flip/
// smooth rounds) at the same target edge length (issue 5: "at least ten times faster than
// CGAL's isotropic remeshing at the same target edge length, with better quality").
//
// Optional and off by default: CGAL's Polygon Mesh Processing is GPL-3.0-or-later, so this
// program (and only this program) links it when configured with
// -DNURBSFRONT_BUILD_CGAL_BENCH=ON (Debian package libcgal-dev; `scripts/install-deps.sh
// --cgal`). The library and every other target stay free of it.
//
//   bench_cgal [--filter REGEX] [--iterations N] [--md FILE]        table (Markdown)
//   bench_cgal --benchmark [google benchmark flags]                   timings
//
// Both methods get the same welded input; CGAL's time is the remeshing call alone (the
// conversion to its Surface_mesh and back is not counted), nurbsfront's the remesh() call
// with one thread and no distances. The figures of both outputs come from the quality
// module's mesh_report() against the input; for the analytic scenes also the distance to
// the true surface (the scene's signed distance at the vertices and triangle centroids).
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Surface_mesh.h>
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <functional>
#include <iostream>
#include <optional>
#include <regex>
#include <string>
#include <vector>

#include "../compare/inputs.h"
#include "nurbsfront/core/soup.h"
#include "nurbsfront/core/stopwatch.h"
#include "nurbsfront/io/mesh_io.h"
#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/scenes.h"
#include "nurbsfront/pipeline/remesh.h"
#include "nurbsfront/surfmesh/surfmesh.h"
#include "nurbsfront/quality/report.h"

namespace nurbsfront::bench {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using CgalMesh = CGAL::Surface_mesh<Kernel::Point_3>;

CgalMesh to_cgal(const TriangleSoup& soup) {
  CgalMesh mesh;
  std::vector<CgalMesh::Vertex_index> v;
  v.reserve(soup.points.size());
  for (const auto& p : soup.points) v.push_back(mesh.add_vertex(Kernel::Point_3(p.x(), p.y(), p.z())));
  for (const auto& t : soup.triangles) mesh.add_face(v[t[0]], v[t[1]], v[t[2]]);
  return mesh;
}

TriangleSoup from_cgal(const CgalMesh& mesh) {
  TriangleSoup soup;
  std::vector<std::uint32_t> index(mesh.number_of_vertices() + mesh.number_of_removed_vertices(), 0);
  for (const auto v : mesh.vertices()) {
    index[v.idx()] = static_cast<std::uint32_t>(soup.points.size());
    const auto& p = mesh.point(v);
    soup.points.emplace_back(p.x(), p.y(), p.z());
  }
  for (const auto f : mesh.faces()) {
    std::array<std::uint32_t, 3> t{};
    int k = 0;
    for (const auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) {
      if (k < 3) t[static_cast<std::size_t>(k)] = index[v.idx()];
      ++k;
    }
    if (k == 3) soup.triangles.push_back(t);
  }
  return soup;
}

struct Input {
  std::string name;
  std::string description;
  std::function<TriMesh()> load;
  std::optional<Scene> scene;  // analytic truth, when there is one
  CellGrid cells;              // occupancy scenes: the band fit's cells (enabled)
  double voxel = 0.0;          // distances in voxels when > 0
};

TriMesh scene_surface(const std::string& scene, int resolution, SampleMode mode) {
  const ScalarGrid grid = sample_scene(scene_by_name(scene), resolution, mode);
  return to_trimesh(clean(marching_cubes(grid, scene_marching_cubes_options(mode))).soup);
}

std::vector<Input> inputs() {
  std::vector<Input> list;
  for (const auto& [scene, res, mode] : std::vector<std::tuple<std::string, int, SampleMode>>{
           {"sphere", 96, SampleMode::Occupancy}, {"dram", 128, SampleMode::LevelSet}, {"dram", 256, SampleMode::LevelSet}}) {
    const bool occupancy = mode == SampleMode::Occupancy;
    Input in;
    in.name = scene + "/" + std::to_string(res) + (occupancy ? " occupancy" : "");
    in.description = "marching cubes of the built-in " + scene + " scene (" + (occupancy ? "0/1 occupancy" : "signed distance") +
                     "), " + std::to_string(res) + " cells";
    in.load = [scene = scene, res = res, mode = mode] { return scene_surface(scene, res, mode); };
    in.scene = scene_by_name(scene);
    const BoundingBox box = bounding_box(*in.scene);
    in.voxel = (box.max - box.min).maxCoeff() / res;  // sample_scene's spacing
    if (occupancy) {  // as `nurbsfront remesh --scene S --occupancy` does: the band fit
      const ScalarGrid grid = sample_scene(*in.scene, res, mode);
      in.cells = {true, grid.origin, grid.spacing};
    }
    list.push_back(in);
  }
  std::vector<std::string> skipped;
  for (const CompareInput& c : comparison_inputs(skipped)) {
    if (c.name == "liver@127.5") list.push_back({c.name, c.description, c.load, std::nullopt, {}, 0.0});
  }
  return list;
}

// |signed distance| to the scene's surface at the vertices and triangle centroids.
DistanceSummary truth_distance(const TriangleSoup& soup, const Scene& scene) {
  const SceneDistance d = distance_to_scene(soup, scene);
  return d.vertices.merged(d.centroids);
}

double cpu_seconds() { return double(std::clock()) / CLOCKS_PER_SEC; }

struct Row {
  std::string method;
  double seconds = 0.0;
  double cpu = 0.0;
  TriangleSoup soup;
  MeshReport report;
  std::optional<DistanceSummary> truth;
};

// `input` null: the input's own row (no distance to itself).
Row measure(std::string method, double seconds, double cpu, TriangleSoup soup, const TriangleSoup* input, const Input& in) {
  Row row;
  row.method = std::move(method);
  row.seconds = seconds;
  row.cpu = cpu;
  ReportOptions options;
  options.n_threads = 2;
  options.distance.n_threads = 2;
  row.report = input == nullptr ? mesh_report(soup, options) : mesh_report(soup, *input, options);
  if (in.scene) row.truth = truth_distance(soup, *in.scene);
  row.soup = std::move(soup);
  return row;
}

RemeshOptions nurbsfront_options(const Input& in) {
  RemeshOptions options;  // library defaults: target edge 1.5 x the input's mean edge
  options.surfmesh.cell_grid = in.cells;
  options.set_threads(1);
  options.compute_distances = false;
  return options;
}

// CGAL's isotropic remeshing of the whole surface at `target` edge length, `iterations`
// rounds (CGAL's default is 1; its examples use 3). Returns the remeshing's wall seconds.
double cgal_remesh(CgalMesh& mesh, double target, unsigned iterations) {
  Stopwatch watch;
  CGAL::Polygon_mesh_processing::isotropic_remeshing(faces(mesh), target, mesh,
                                                      CGAL::parameters::number_of_iterations(iterations));
  return watch.seconds();
}

std::string fmt(const char* format, double x) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, x);
  return buffer;
}

std::string table_row(const std::string& input, const Row& r, const Input& in) {
  const QualityReport& q = r.report.quality;
  const TopologyReport& t = r.report.topology;
  std::string s = "| " + input + " | " + r.method + " | " + fmt("%.2f", r.seconds) + " | " + fmt("%.2f", r.cpu) + " | " +
                  std::to_string(r.soup.triangles.size()) + " | " + fmt("%.3f", q.alpha_mean) + " | " +
                  fmt("%.3f", q.alpha_min) + " | " + fmt("%.1f", q.min_angle_deg) + " | " + fmt("%.1f", q.max_angle_deg) +
                  " | " + fmt("%.2f", 100.0 * q.obtuse_fraction) + " | ";
  const double unit = in.voxel > 0.0 ? in.voxel : 1.0;
  if (r.report.distance) {
    s += fmt("%.3g", r.report.distance->hausdorff / unit) + " | " + fmt("%.3g", r.report.distance->mean / unit) + " | ";
  } else {
    s += "- | - | ";
  }
  if (r.truth) {
    s += fmt("%.3f", r.truth->mean / unit) + " / " + fmt("%.3f", r.truth->max / unit) + " | ";
  } else {
    s += "- | ";
  }
  s += (t.n_self_intersecting_pairs ? std::to_string(*t.n_self_intersecting_pairs) : std::string("-")) + " | ";
  s += std::string(t.is_manifold && t.is_consistently_oriented ? "yes" : "no") + ", chi " +
       std::to_string(t.euler_characteristic) + " |";
  return s;
}

int report(const std::string& filter, unsigned iterations, const std::string& md_path) {
  std::string md;
  md += "| input | method | wall s | CPU s | faces | alpha mean | alpha min | min angle | max angle | obtuse % | "
        "Hausdorff | mean dist | truth mean / max | self-int. | manifold, Euler |\n";
  md += "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  const std::regex re(filter.empty() ? std::string(".*") : filter);
  for (const Input& in : inputs()) {
    if (!std::regex_search(in.name, re)) continue;
    std::cerr << in.name << ": input\n";
    const TriMesh input = in.load();
    const TriangleSoup input_soup = to_soup(input);
    std::vector<Row> rows;
    rows.push_back(measure("input", 0.0, 0.0, input_soup, nullptr, in));

    std::cerr << in.name << ": nurbsfront\n";
    Stopwatch watch;
    double cpu = cpu_seconds();
    const RemeshResult ours = remesh(input, nurbsfront_options(in));
    const double ours_seconds = watch.seconds();
    const double ours_cpu = cpu_seconds() - cpu;
    rows.push_back(measure("nurbsfront remesh (1 thread)", ours_seconds, ours_cpu, to_soup(ours.mesh), &input_soup, in));

    std::cerr << in.name << ": CGAL, target " << ours.report.target_size << "\n";
    CgalMesh mesh = to_cgal(input_soup);
    cpu = cpu_seconds();
    const double cgal_seconds = cgal_remesh(mesh, ours.report.target_size, iterations);
    const double cgal_cpu = cpu_seconds() - cpu;
    rows.push_back(measure("CGAL isotropic_remeshing (" + std::to_string(iterations) + " it.)", cgal_seconds, cgal_cpu,
                           from_cgal(mesh), &input_soup, in));
    for (const Row& r : rows) md += table_row(in.name, r, in) + "\n";
    std::cout << md << std::flush;
    md.clear();
    if (!md_path.empty()) {
      std::ofstream out(md_path, std::ios::app);
      for (const Row& r : rows) out << table_row(in.name, r, in) << "\n";
    }
  }
  return 0;
}

void BM_Nurbsfront(benchmark::State& state, const Input* in) {
  const TriMesh input = in->load();
  for (auto _ : state) benchmark::DoNotOptimize(remesh(input, nurbsfront_options(*in)));
  state.counters["faces"] = static_cast<double>(input.n_faces());
}

void BM_Cgal(benchmark::State& state, const Input* in) {
  const TriMesh input = in->load();
  const double target = remesh(input, nurbsfront_options(*in)).report.target_size;
  const TriangleSoup soup = to_soup(input);
  for (auto _ : state) {
    state.PauseTiming();
    CgalMesh mesh = to_cgal(soup);
    state.ResumeTiming();
    cgal_remesh(mesh, target, static_cast<unsigned>(state.range(0)));
  }
  state.counters["faces"] = static_cast<double>(input.n_faces());
}

}  // namespace
}  // namespace nurbsfront::bench

int main(int argc, char** argv) {
  using namespace nurbsfront::bench;
  std::string filter, md;
  unsigned iterations = 3;
  bool google = false;
  std::vector<char*> rest{argv[0]};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--filter" && i + 1 < argc) {
      filter = argv[++i];
    } else if (a == "--iterations" && i + 1 < argc) {
      iterations = static_cast<unsigned>(std::stoul(argv[++i]));
    } else if (a == "--md" && i + 1 < argc) {
      md = argv[++i];
    } else if (a == "--benchmark") {
      google = true;
    } else {
      rest.push_back(argv[i]);
    }
  }
  if (!google) {
    try {
      return report(filter, iterations, md);
    } catch (const std::exception& e) {
      std::cerr << "bench_cgal: " << e.what() << "\n";
      return 1;
    }
  }
  static const std::vector<Input> all = inputs();
  for (const Input& in : all) {
    benchmark::RegisterBenchmark(("BM_Nurbsfront/" + in.name).c_str(), BM_Nurbsfront, &in)
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
    benchmark::RegisterBenchmark(("BM_CgalIsotropic/" + in.name).c_str(), BM_Cgal, &in)
        ->Arg(1)
        ->Arg(3)
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
  }
  int n = static_cast<int>(rest.size());
  benchmark::Initialize(&n, rest.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
