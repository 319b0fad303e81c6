// SPDX-License-Identifier: BSD-3-Clause
// Quality module benchmarks: alpha per face, the full report (topology, quality,
// exact self-intersections) and two-sided distances on generated meshes of ~N faces.
#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <numbers>

#include "nurbsfront/quality/report.h"

namespace {

using nurbsfront::TriangleSoup;
using Tri = std::array<std::uint32_t, 3>;

// Torus with 2 * n_major * n_minor faces (bench-local generator, no test fixtures).
TriangleSoup make_torus(int n_major, int n_minor, double major_radius, double minor_radius, double phase) {
  TriangleSoup s;
  const double two_pi = 2.0 * std::numbers::pi;
  s.points.reserve(static_cast<std::size_t>(n_major) * n_minor);
  for (int i = 0; i < n_major; ++i) {
    const double u = two_pi * (i + phase) / n_major;
    for (int j = 0; j < n_minor; ++j) {
      const double v = two_pi * (j + phase) / n_minor;
      const double r = major_radius + minor_radius * std::cos(v);
      s.points.emplace_back(r * std::cos(u), r * std::sin(u), minor_radius * std::sin(v));
    }
  }
  auto id = [&](int i, int j) {
    return static_cast<std::uint32_t>(((i + n_major) % n_major) * n_minor + (j + n_minor) % n_minor);
  };
  for (int i = 0; i < n_major; ++i) {
    for (int j = 0; j < n_minor; ++j) {
      s.triangles.push_back(Tri{id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      s.triangles.push_back(Tri{id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  return s;
}

// Torus of about `faces` triangles with a 3:1 aspect of the parameter grid.
TriangleSoup torus_with_faces(std::int64_t faces, double phase) {
  const int n_minor = static_cast<int>(std::sqrt(static_cast<double>(faces) / 6.0));
  const int n_major = 3 * n_minor;
  return make_torus(n_major, n_minor, 1.0, 0.33, phase);
}

void BM_FaceAlpha(benchmark::State& state) {
  const TriangleSoup mesh = torus_with_faces(state.range(0), 0.0);
  for (auto _ : state) benchmark::DoNotOptimize(nurbsfront::face_alpha(mesh));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(mesh.triangles.size()));
}
BENCHMARK(BM_FaceAlpha)->Arg(1'000'000)->Unit(benchmark::kMillisecond);

void BM_ReportTopologyQuality(benchmark::State& state) {
  const TriangleSoup mesh = torus_with_faces(state.range(0), 0.0);
  nurbsfront::ReportOptions options;
  options.self_intersections = false;
  for (auto _ : state) benchmark::DoNotOptimize(nurbsfront::mesh_report(mesh, options));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(mesh.triangles.size()));
}
BENCHMARK(BM_ReportTopologyQuality)->Arg(1'000'000)->Unit(benchmark::kMillisecond);

void BM_SelfIntersections(benchmark::State& state) {
  const TriangleSoup mesh = torus_with_faces(state.range(0), 0.0);
  const auto threads = static_cast<unsigned>(state.range(1));
  for (auto _ : state) benchmark::DoNotOptimize(nurbsfront::count_self_intersections(mesh, threads));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(mesh.triangles.size()));
}
BENCHMARK(BM_SelfIntersections)->Args({1'000'000, 1})->Args({1'000'000, 2})->Unit(benchmark::kMillisecond);

void BM_Distance(benchmark::State& state) {
  const TriangleSoup mesh = torus_with_faces(state.range(0), 0.0);
  const TriangleSoup reference = torus_with_faces(state.range(0) / 4, 0.37);
  nurbsfront::DistanceOptions options;
  options.n_threads = static_cast<unsigned>(state.range(1));
  for (auto _ : state) benchmark::DoNotOptimize(nurbsfront::mesh_distance(mesh, reference, options));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(mesh.triangles.size()));
}
BENCHMARK(BM_Distance)->Args({1'000'000, 1})->Args({1'000'000, 2})->Unit(benchmark::kMillisecond);

// The whole report as `nurbsfront stats --ref` computes it.
void BM_FullReport(benchmark::State& state) {
  const TriangleSoup mesh = torus_with_faces(state.range(0), 0.0);
  const TriangleSoup reference = torus_with_faces(state.range(0) / 4, 0.37);
  nurbsfront::ReportOptions options;
  options.n_threads = static_cast<unsigned>(state.range(1));
  options.distance.n_threads = options.n_threads;
  for (auto _ : state) benchmark::DoNotOptimize(nurbsfront::mesh_report(mesh, reference, options));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(mesh.triangles.size()));
}
BENCHMARK(BM_FullReport)->Args({1'000'000, 1})->Args({1'000'000, 2})->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
