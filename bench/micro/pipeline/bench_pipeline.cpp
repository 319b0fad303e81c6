// SPDX-License-Identifier: BSD-3-Clause
// remesh() end to end on the DRAM scene's marching-cubes surface (res 256: about 780k
// faces; res 128 for quick profiles) and on the liver volume's surface
// (/work/shared/data/volumes, skipped when absent), with 1 and 2 threads.
// Arguments: threads, distances (1: RemeshOptions::compute_distances, the default; 0: off,
// as in the comparison with CGAL's isotropic remeshing, which reports no distances), files
// (1: the timing also reads the input from a binary PLY file and writes the output to
// one, in the system's temporary directory; 0: the input is built once outside the
// timing). The stitch stage's verification (exact self-intersections) is always on.
// Counter peak_rss_MB is the process's peak resident set (getrusage maxrss) after the run.

#include <benchmark/benchmark.h>

#include <sys/resource.h>
#include <unistd.h>

#include <filesystem>
#include <map>
#include <string>

#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/scenes.h"
#include "nurbsfront/io/mesh_io.h"
#include "nurbsfront/isosurface/volume_io.h"
#include "nurbsfront/pipeline/remesh.h"

namespace {

using namespace nurbsfront;

const char* const kLiver = "/work/shared/data/volumes/cgal_images/liver.inr.gz";

// Inputs are cached: building the 256 DRAM surface takes seconds.
const TriMesh& input(const std::string& name) {
  static std::map<std::string, TriMesh> cache;  // benchmark-program state, not library state
  auto it = cache.find(name);
  if (it != cache.end()) return it->second;
  TriangleSoup soup;
  if (name == "liver") {
    MarchingCubesOptions options;
    options.iso = 127.5;
    options.inside_above = true;
    soup = marching_cubes(read_volume(kLiver), options);
  } else {
    const int resolution = name == "dram128" ? 128 : 256;
    const ScalarGrid grid = sample_scene(scene_by_name("dram"), resolution, SampleMode::LevelSet);
    soup = marching_cubes(grid, scene_marching_cubes_options(SampleMode::LevelSet));
  }
  return cache.emplace(name, to_trimesh(soup)).first->second;
}

double peak_rss_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

// User + system CPU time of the whole process so far (all threads).
double process_cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

void run(benchmark::State& state, const std::string& name) {
  if (name == "liver" && !std::filesystem::exists(kLiver)) {
    state.SkipWithError("liver volume absent (/work/shared/data/volumes/cgal_images/liver.inr.gz)");
    return;
  }
  const TriMesh& mesh = input(name);
  RemeshOptions options;
  options.set_threads(static_cast<unsigned>(state.range(0)));
  options.compute_distances = state.range(1) != 0;
  const bool files = state.range(2) != 0;
  // The process id in the names: two benchmark processes at once do not share files.
  const std::string stem = "nurbsfront_bench_" + std::to_string(::getpid()) + "_" + name;
  const std::filesystem::path in_path = std::filesystem::temp_directory_path() / (stem + "_in.ply");
  const std::filesystem::path out_path = std::filesystem::temp_directory_path() / (stem + "_out.ply");
  if (files) write_mesh(mesh, in_path);
  CleanOptions read_options;  // the input's mesh built with the run's threads
  read_options.threads = static_cast<int>(state.range(0));
  RemeshReport report;
  const double cpu_start = process_cpu_seconds();
  for (auto _ : state) {
    if (files) {
      const TriMesh read = read_mesh(in_path, read_options);
      RemeshResult result = remesh(read, options);
      write_mesh(result.mesh, out_path);
      report = std::move(result.report);
    } else {
      RemeshResult result = remesh(mesh, options);
      benchmark::DoNotOptimize(result.mesh.n_faces());
      report = std::move(result.report);
    }
  }
  const double cpu_seconds = process_cpu_seconds() - cpu_start;
  if (files) {
    std::filesystem::remove(in_path);
    std::filesystem::remove(out_path);
  }
  state.counters["in_faces"] = static_cast<double>(mesh.n_faces());
  state.counters["out_faces"] = static_cast<double>(report.n_triangles);
  state.counters["patches"] = static_cast<double>(report.n_patches);
  state.counters["errors"] = static_cast<double>(report.errors.size());
  state.counters["alpha_mean"] = report.output.quality.alpha_mean;
  state.counters["s_segment"] = report.seconds_segment;
  state.counters["s_surfmesh"] = report.seconds_surfmesh;
  state.counters["s_stitch"] = report.seconds_stitch;
  state.counters["s_distance"] = report.seconds_distance;
  state.counters["s_remesh"] = report.seconds_total;
  state.counters["s_stitch_optimise"] = report.stitch.seconds_optimise;
  state.counters["s_stitch_verify"] = report.stitch.seconds_verify;
  if (report.output.distance) {
    state.counters["samples"] = static_cast<double>(report.output.distance->n_mesh_samples + report.output.distance->n_reference_samples);
    state.counters["hausdorff"] = report.output.distance->hausdorff;
  }
  state.counters["reverted"] = static_cast<double>(report.stitch.n_reverted_moves + report.stitch.n_reverted_flips);
  state.counters["opt_undone"] = report.stitch.optimisation_undone ? 1.0 : 0.0;
  state.counters["cpu_s"] = cpu_seconds;  // CPU time of all threads during the timed run
  state.counters["peak_rss_MB"] = peak_rss_mb();
}

// {threads, distances, files}
void cases(benchmark::internal::Benchmark* b) {
  b->ArgNames({"threads", "distances", "files"});
  for (int threads : {1, 2}) {
    b->Args({threads, 1, 0});
    b->Args({threads, 0, 0});
    b->Args({threads, 0, 1});
  }
  b->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();
}

void BM_RemeshDram256(benchmark::State& state) { run(state, "dram"); }
BENCHMARK(BM_RemeshDram256)->Apply(cases);

void BM_RemeshDram128(benchmark::State& state) { run(state, "dram128"); }
BENCHMARK(BM_RemeshDram128)->Apply(cases);

void BM_RemeshLiver(benchmark::State& state) { run(state, "liver"); }
BENCHMARK(BM_RemeshLiver)->Apply(cases);

}  // namespace

BENCHMARK_MAIN();
