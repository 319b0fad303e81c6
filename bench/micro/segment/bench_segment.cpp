// SPDX-License-Identifier: BSD-3-Clause
// segment() on a smooth procedural torus and on terraced marching-cubes spheres.

#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <numbers>

#include "nurbsfront/core/soup.h"
#include "nurbsfront/segment/segment.h"
#ifdef NURBSFRONT_BENCH_HAVE_ISOSURFACE
#include "nurbsfront/isosurface/marching_cubes.h"
#include "nurbsfront/isosurface/scenes.h"
#include "nurbsfront/isosurface/volume_io.h"
#endif

namespace {

using nurbsfront::TriMesh;

// A torus with 2 * n * n / 2 = n^2 triangles (n around, n / 2 across).
TriMesh torus(int n) {
  nurbsfront::TriangleSoup s;
  const int n_minor = n / 2;
  const double two_pi = 2.0 * std::numbers::pi;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n_minor; ++j) {
      const double u = two_pi * i / n, v = two_pi * j / n_minor;
      const double r = 1.0 + 0.35 * std::cos(v);
      s.points.emplace_back(r * std::cos(u), r * std::sin(u), 0.35 * std::sin(v));
    }
  }
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>((i % n) * n_minor + j % n_minor); };
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n_minor; ++j) {
      s.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      s.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  return nurbsfront::to_trimesh(s);
}

void run(benchmark::State& state, const TriMesh& mesh) {
  std::size_t n_patches = 0;
  for (auto _ : state) {
    const nurbsfront::Segmentation seg = nurbsfront::segment(mesh);
    n_patches = seg.patches.size();
    benchmark::DoNotOptimize(n_patches);
  }
  state.counters["faces"] = static_cast<double>(mesh.n_faces());
  state.counters["patches"] = static_cast<double>(n_patches);
  state.counters["faces/s"] = benchmark::Counter(static_cast<double>(mesh.n_faces()) * static_cast<double>(state.iterations()),
                                                 benchmark::Counter::kIsRate);
}

void BM_SegmentTorus(benchmark::State& state) { run(state, torus(static_cast<int>(state.range(0)))); }
BENCHMARK(BM_SegmentTorus)->Arg(100)->Arg(316)->Arg(1000)->Unit(benchmark::kMillisecond);

#ifdef NURBSFRONT_BENCH_HAVE_ISOSURFACE
void BM_SegmentOccupancySphere(benchmark::State& state) {
  const auto mode = nurbsfront::SampleMode::Occupancy;
  const auto grid = nurbsfront::sample_scene(nurbsfront::scene_by_name("sphere"), static_cast<int>(state.range(0)), mode);
  run(state, nurbsfront::to_trimesh(nurbsfront::marching_cubes(grid, nurbsfront::scene_marching_cubes_options(mode))));
}
BENCHMARK(BM_SegmentOccupancySphere)->Arg(96)->Arg(192)->Arg(320)->Unit(benchmark::kMillisecond);

// The liver volume's surface (marching cubes at iso 127.5 of a 0/255 label volume: about
// 440k terraced faces, some 2000 patches). Reads /work/shared/data; skipped when absent.
void BM_SegmentLiver(benchmark::State& state) {
  const char* const path = "/work/shared/data/volumes/cgal_images/liver.inr.gz";
  if (!std::filesystem::exists(path)) {
    state.SkipWithError("liver volume absent (/work/shared/data/volumes/cgal_images/liver.inr.gz)");
    return;
  }
  nurbsfront::MarchingCubesOptions options;
  options.iso = 127.5;
  options.inside_above = true;
  run(state, nurbsfront::to_trimesh(nurbsfront::marching_cubes(nurbsfront::read_volume(path), options)));
}
BENCHMARK(BM_SegmentLiver)->Unit(benchmark::kMillisecond);
#endif

}  // namespace

BENCHMARK_MAIN();
