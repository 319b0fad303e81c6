// SPDX-License-Identifier: BSD-3-Clause
// remesh() end to end on the DRAM scene's marching-cubes surface (res 256: about 780k
// faces) and on the liver volume's surface (/work/shared/data/volumes, skipped when
// absent), with 1 and 2 threads. The input is built once, outside the timing; the timing
// includes the output's quality report and distances (RemeshOptions defaults), not files.
// Counter peak_rss_MB is the process's peak resident set (getrusage maxrss) after the run.

#include <benchmark/benchmark.h>

#include <sys/resource.h>

#include <filesystem>
#include <map>
#include <string>

#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/scenes.h"
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
    const ScalarGrid grid = sample_scene(scene_by_name("dram"), 256, SampleMode::LevelSet);
    soup = marching_cubes(grid, scene_marching_cubes_options(SampleMode::LevelSet));
  }
  return cache.emplace(name, to_trimesh(soup)).first->second;
}

double peak_rss_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

void run(benchmark::State& state, const std::string& name) {
  if (name == "liver" && !std::filesystem::exists(kLiver)) {
    state.SkipWithError("liver volume absent (/work/shared/data/volumes/cgal_images/liver.inr.gz)");
    return;
  }
  const TriMesh& mesh = input(name);
  RemeshOptions options;
  options.set_threads(static_cast<unsigned>(state.range(0)));
  RemeshReport report;
  for (auto _ : state) {
    RemeshResult result = remesh(mesh, options);
    benchmark::DoNotOptimize(result.mesh.n_faces());
    report = std::move(result.report);
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
  state.counters["peak_rss_MB"] = peak_rss_mb();
}

void BM_RemeshDram256(benchmark::State& state) { run(state, "dram"); }
BENCHMARK(BM_RemeshDram256)->Arg(1)->Arg(2)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

void BM_RemeshLiver(benchmark::State& state) { run(state, "liver"); }
BENCHMARK(BM_RemeshLiver)->Arg(1)->Arg(2)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
