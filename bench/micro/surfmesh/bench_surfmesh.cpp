// SPDX-License-Identifier: BSD-3-Clause
// mesh_surface() (border discretisation, per-patch fit and 2D front) on the DRAM cell's
// marching-cubes surface at 256 cells, level-set and occupancy, on 1 and 2 threads. The
// input and its segmentation are built once, outside the timed loop. Built-in scene only:
// no files needed.

#include <benchmark/benchmark.h>

#include <map>
#include <utility>

#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/scenes.h"
#include "nurbsfront/surfmesh/surfmesh.h"

namespace {

using namespace nurbsfront;

struct Input {
  TriMesh mesh;
  Segmentation seg;
};

const Input& dram(SampleMode mode) {
  static std::map<int, Input> cache;  // benchmark-local: built once per mode
  auto it = cache.find(static_cast<int>(mode));
  if (it == cache.end()) {
    Input input;
    const ScalarGrid grid = sample_scene(scene_by_name("dram"), 256, mode);
    input.mesh = to_trimesh(marching_cubes(grid, scene_marching_cubes_options(mode)));
    input.seg = segment(input.mesh);
    it = cache.emplace(static_cast<int>(mode), std::move(input)).first;
  }
  return it->second;
}

void BM_MeshSurfaceDram256(benchmark::State& state) {
  const SampleMode mode = state.range(0) == 0 ? SampleMode::LevelSet : SampleMode::Occupancy;
  const Input& input = dram(mode);
  SurfMeshOptions options;
  options.threads = static_cast<int>(state.range(1));
  std::size_t n_triangles = 0, n_failed = 0;
  for (auto _ : state) {
    const SurfaceMesh sm = mesh_surface(input.mesh, input.seg, options);
    n_triangles = sm.triangles.size();
    n_failed = 0;
    for (const auto& p : sm.patches) n_failed += p.status == PatchStatus::Ok ? 0 : 1;
    benchmark::DoNotOptimize(n_triangles);
  }
  state.SetLabel(mode == SampleMode::LevelSet ? "level-set" : "occupancy");
  state.counters["input_faces"] = static_cast<double>(input.mesh.n_faces());
  state.counters["patches"] = static_cast<double>(input.seg.patches.size());
  state.counters["failed"] = static_cast<double>(n_failed);
  state.counters["triangles"] = static_cast<double>(n_triangles);
}
// Args: mode (0 level-set, 1 occupancy), threads. CPU time is summed over all threads
// (Google Benchmark's default measures the main thread only), so report both.
BENCHMARK(BM_MeshSurfaceDram256)
    ->Args({0, 1})->Args({0, 2})->Args({1, 1})->Args({1, 2})
    ->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime()->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
