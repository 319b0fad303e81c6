// SPDX-License-Identifier: BSD-3-Clause
// Read/write throughput of the mesh formats, clean() and prepare_mesh() on a generated torus
// of 2 * n * n/2 triangles (argument n = 1000: 1M triangles, 500k vertices); read_mesh()
// (read, clean, manifold check, halfedge mesh) and its two core steps alone.
#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>

#include "nurbsfront/io/mesh_io.h"

namespace {

using nurbsfront::TriangleSoup;

TriangleSoup torus(int n_major, int n_minor) {
  TriangleSoup s;
  const double two_pi = 2.0 * std::numbers::pi;
  for (int i = 0; i < n_major; ++i) {
    for (int j = 0; j < n_minor; ++j) {
      const double u = two_pi * i / n_major, v = two_pi * j / n_minor;
      s.points.emplace_back((1.0 + 0.3 * std::cos(v)) * std::cos(u), (1.0 + 0.3 * std::cos(v)) * std::sin(u),
                            0.3 * std::sin(v));
    }
  }
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>((i % n_major) * n_minor + (j % n_minor)); };
  for (int i = 0; i < n_major; ++i) {
    for (int j = 0; j < n_minor; ++j) {
      s.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      s.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  return s;
}

std::filesystem::path bench_file(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / "nurbsfront_bench_io";
  std::filesystem::create_directories(dir);
  return dir / name;
}

const TriangleSoup& shared_torus(int n) {
  static const TriangleSoup soup = torus(n, n / 2);  // benchmark fixture, not library state
  return soup;
}

void set_counters(benchmark::State& state, const TriangleSoup& s, const std::filesystem::path& path) {
  state.counters["triangles"] = static_cast<double>(s.triangles.size());
  state.counters["tri/s"] = benchmark::Counter(static_cast<double>(s.triangles.size()) * state.iterations(),
                                               benchmark::Counter::kIsRate);
  state.SetBytesProcessed(static_cast<std::int64_t>(std::filesystem::file_size(path)) * state.iterations());
}

void BM_Write(benchmark::State& state, const char* name, bool binary) {
  const TriangleSoup& s = shared_torus(static_cast<int>(state.range(0)));
  const auto path = bench_file(name);
  nurbsfront::WriteOptions options;
  options.binary = binary;
  for (auto _ : state) {
    std::filesystem::remove(path);  // a fresh file: rewriting in place makes ext4 flush it
    nurbsfront::write_soup(s, path, options);
  }
  set_counters(state, s, path);
}

void BM_Read(benchmark::State& state, const char* name, bool binary) {
  const TriangleSoup& s = shared_torus(static_cast<int>(state.range(0)));
  const auto path = bench_file(std::string("r_") + name);
  nurbsfront::WriteOptions options;
  options.binary = binary;
  nurbsfront::write_soup(s, path, options);
  for (auto _ : state) {
    TriangleSoup back = nurbsfront::read_soup(path);
    benchmark::DoNotOptimize(back.points.data());
  }
  set_counters(state, s, path);
}

void BM_CleanStl(benchmark::State& state) {
  // STL's three points per facet: clean() welds 3M points back to 500k.
  const TriangleSoup& s = shared_torus(static_cast<int>(state.range(0)));
  const auto path = bench_file("clean.stl");
  nurbsfront::write_soup(s, path);
  const TriangleSoup raw = nurbsfront::read_soup(path);
  for (auto _ : state) {
    nurbsfront::CleanResult r = nurbsfront::clean(raw);
    benchmark::DoNotOptimize(r.soup.points.data());
  }
  state.counters["points_in"] = static_cast<double>(raw.points.size());
  state.counters["tri/s"] = benchmark::Counter(static_cast<double>(raw.triangles.size()) * state.iterations(),
                                               benchmark::Counter::kIsRate);
}

void BM_ReadMesh(benchmark::State& state) {
  // What the remesh tool and the pipeline benchmark's files case do with a binary PLY.
  const TriangleSoup& s = shared_torus(static_cast<int>(state.range(0)));
  const auto path = bench_file("read_mesh.ply");
  nurbsfront::write_soup(s, path);
  for (auto _ : state) {
    const nurbsfront::TriMesh mesh = nurbsfront::read_mesh(path);
    benchmark::DoNotOptimize(mesh.n_faces());
  }
  set_counters(state, s, path);
}

void BM_CheckManifold(benchmark::State& state) {
  const TriangleSoup& s = shared_torus(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    const nurbsfront::ManifoldCheck check = nurbsfront::check_manifold(s);
    benchmark::DoNotOptimize(check.n_nonmanifold_vertices);
  }
  state.counters["tri/s"] = benchmark::Counter(static_cast<double>(s.triangles.size()) * state.iterations(),
                                               benchmark::Counter::kIsRate);
}

// prepare_mesh() on a valid oriented manifold (argument 0: the fast path, clean + to_trimesh
// + the zero-area scan, what remesh's reading costs) and with every 7th triangle reversed
// (argument 1: make_manifold's orientation pass and a second to_trimesh).
void BM_PrepareMesh(benchmark::State& state) {
  TriangleSoup s = shared_torus(static_cast<int>(state.range(0)));
  std::size_t n_reversed = 0;
  if (state.range(1) == 1) {
    for (std::size_t f = 0; f < s.triangles.size(); f += 7, ++n_reversed) std::swap(s.triangles[f][1], s.triangles[f][2]);
  }
  for (auto _ : state) {
    nurbsfront::PreparedMesh p = nurbsfront::prepare_mesh(s);
    benchmark::DoNotOptimize(p.mesh.n_faces());
  }
  state.counters["reversed"] = static_cast<double>(n_reversed);
  state.counters["tri/s"] = benchmark::Counter(static_cast<double>(s.triangles.size()) * state.iterations(),
                                               benchmark::Counter::kIsRate);
}

void BM_ToTriMesh(benchmark::State& state) {
  const TriangleSoup& s = shared_torus(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    const nurbsfront::TriMesh mesh = nurbsfront::to_trimesh(s);
    benchmark::DoNotOptimize(mesh.n_faces());
  }
  state.counters["tri/s"] = benchmark::Counter(static_cast<double>(s.triangles.size()) * state.iterations(),
                                               benchmark::Counter::kIsRate);
}

// What reading cost before prepare_mesh(): clean + to_trimesh (the baseline of BM_PrepareMesh/n/0).
void BM_CleanToTriMesh(benchmark::State& state) {
  const TriangleSoup& s = shared_torus(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    nurbsfront::TriMesh mesh = nurbsfront::to_trimesh(nurbsfront::clean(s).soup);
    benchmark::DoNotOptimize(mesh.n_faces());
  }
  state.counters["tri/s"] = benchmark::Counter(static_cast<double>(s.triangles.size()) * state.iterations(),
                                               benchmark::Counter::kIsRate);
}

}  // namespace

BENCHMARK(BM_CleanToTriMesh)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_PrepareMesh)->Args({1000, 0})->Args({1000, 1})->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Write, ply_binary, "m.ply", true)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Read, ply_binary, "m.ply", true)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Write, stl_binary, "m.stl", true)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Read, stl_binary, "m.stl", true)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Write, obj, "m.obj", false)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Read, obj, "m.obj", false)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Write, vtk_binary, "m.vtk", true)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Read, vtk_binary, "m.vtk", true)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CleanStl)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReadMesh)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CheckManifold)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ToTriMesh)->Arg(1000)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
