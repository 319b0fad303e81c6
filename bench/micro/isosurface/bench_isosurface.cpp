// SPDX-License-Identifier: BSD-3-Clause
// Marching cubes and scene sampling. Run a Release build:
//   bench_isosurface --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/scenes.h"

namespace {

using namespace nurbsfront;

// Marching cubes on the DRAM level-set grid with `resolution` cells along its longest side (the
// grid is sampled once, outside the timed loop). Items = grid cells (voxels) processed.
void BM_MarchingCubesDram(benchmark::State& state) {
  const int resolution = static_cast<int>(state.range(0));
  const ScalarGrid grid = sample_scene(DramScene{}, resolution, SampleMode::LevelSet);
  const MarchingCubesOptions options = scene_marching_cubes_options(SampleMode::LevelSet);
  std::size_t n_triangles = 0;
  for (auto _ : state) {
    const TriangleSoup soup = marching_cubes(grid, options);
    n_triangles = soup.triangles.size();
    benchmark::DoNotOptimize(soup.triangles.data());
  }
  const auto cells = static_cast<std::int64_t>(grid.dims[0] - 1) * (grid.dims[1] - 1) * (grid.dims[2] - 1);
  state.SetItemsProcessed(state.iterations() * cells);
  state.counters["voxels"] = static_cast<double>(cells);
  state.counters["triangles"] = static_cast<double>(n_triangles);
}
BENCHMARK(BM_MarchingCubesDram)->Arg(128)->Arg(256)->Unit(benchmark::kMillisecond)->UseRealTime();

// A cubic grid with dims = resolution of the occupancy sphere (a 0/1 input, the terraced case).
void BM_MarchingCubesSphereOccupancy(benchmark::State& state) {
  const int resolution = static_cast<int>(state.range(0));
  const ScalarGrid grid = sample_scene(SphereScene{}, resolution, SampleMode::Occupancy);
  const MarchingCubesOptions options = scene_marching_cubes_options(SampleMode::Occupancy);
  for (auto _ : state) {
    const TriangleSoup soup = marching_cubes(grid, options);
    benchmark::DoNotOptimize(soup.triangles.data());
  }
  const auto cells = static_cast<std::int64_t>(grid.dims[0] - 1) * (grid.dims[1] - 1) * (grid.dims[2] - 1);
  state.SetItemsProcessed(state.iterations() * cells);
}
BENCHMARK(BM_MarchingCubesSphereOccupancy)->Arg(256)->Unit(benchmark::kMillisecond)->UseRealTime();

// Sampling the DRAM scene (signed distance at every grid point, all hardware threads).
void BM_SampleDram(benchmark::State& state) {
  const int resolution = static_cast<int>(state.range(0));
  std::size_t n = 0;
  for (auto _ : state) {
    const ScalarGrid grid = sample_scene(DramScene{}, resolution, SampleMode::LevelSet);
    n = grid.values.size();
    benchmark::DoNotOptimize(grid.values.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(n));
}
BENCHMARK(BM_SampleDram)->Arg(256)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
