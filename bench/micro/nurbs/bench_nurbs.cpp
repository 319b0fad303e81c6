// SPDX-License-Identifier: BSD-3-Clause
// Benchmarks of the nurbs module: height-field and NURBS evaluation, multilevel fitting.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "nurbsfront/nurbs/height_field.h"
#include "nurbsfront/nurbs/mba.h"

namespace {

using namespace nurbsfront;

BicubicHeightField random_field(int cells) {
  BicubicHeightField f(Rectangle{{0.0, 0.0}, {1.0, 1.0}}, cells, cells);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> c(-1.0, 1.0);
  for (auto& x : f.mutable_coefficients()) x = c(rng);
  return f;
}

std::vector<Eigen::Vector2d> random_queries(std::size_t n) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Eigen::Vector2d> q(n);
  for (auto& p : q) p = {u(rng), u(rng)};
  return q;
}

// Bicubic height field f(x, y): direct uniform weights (target: >= 20 M evaluations/s/core).
void BM_HeightFieldValue(benchmark::State& state) {
  const BicubicHeightField f = random_field(static_cast<int>(state.range(0)));
  const auto q = random_queries(1 << 16);
  for (auto _ : state) {
    double sum = 0.0;
    for (const auto& p : q) sum += f.value(p.x(), p.y());
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(q.size()));
}
BENCHMARK(BM_HeightFieldValue)->Arg(16)->Arg(256);

// f with first and second derivatives.
void BM_HeightFieldJet(benchmark::State& state) {
  const BicubicHeightField f = random_field(static_cast<int>(state.range(0)));
  const auto q = random_queries(1 << 16);
  for (auto _ : state) {
    double sum = 0.0;
    for (const auto& p : q) sum += f.jet(p.x(), p.y()).zxy;
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(q.size()));
}
BENCHMARK(BM_HeightFieldJet)->Arg(256);

// The same bicubic surface as a general NURBS S(u, v) (span search, Cox-de Boor).
void BM_NurbsSurfaceEvaluate(benchmark::State& state) {
  const NurbsSurface s = random_field(static_cast<int>(state.range(0))).to_nurbs();
  const auto q = random_queries(1 << 16);
  for (auto _ : state) {
    double sum = 0.0;
    for (const auto& p : q) sum += s.evaluate(p.x(), p.y()).z();
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(q.size()));
}
BENCHMARK(BM_NurbsSurfaceEvaluate)->Arg(16)->Arg(256);

void BM_NurbsSurfaceDerivatives(benchmark::State& state) {
  const NurbsSurface s = random_field(64).to_nurbs();
  const auto q = random_queries(1 << 14);
  for (auto _ : state) {
    double sum = 0.0;
    for (const auto& p : q) sum += s.derivatives(p.x(), p.y()).suv.z();
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(q.size()));
}
BENCHMARK(BM_NurbsSurfaceDerivatives);

// Multilevel fit of N scattered samples of a sine bump, levels up to a 512 x 512 lattice
// (target: >= 2 M points/s over the whole fit for N = 1 M).
void BM_MbaFit(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Eigen::Vector3d> pts(n);
  for (auto& p : pts) {
    const double x = u(rng);
    const double y = u(rng);
    p = {x, y, 0.2 * std::sin(6.0 * x) * std::cos(4.0 * y)};
  }
  FitOptions o;
  o.max_levels = static_cast<int>(state.range(1));
  o.tolerance = 1e-12;  // run every level
  o.final_passes = 0;
  std::size_t levels = 0;
  for (auto _ : state) {
    const FitResult fit = fit_height_field(pts, o);
    levels = fit.levels.size();
    benchmark::DoNotOptimize(fit.field.coefficients().data());
  }
  state.counters["levels"] = static_cast<double>(levels);
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(n));
}
BENCHMARK(BM_MbaFit)->Args({100000, 8})->Args({1000000, 10})->Unit(benchmark::kMillisecond);

}  // namespace
BENCHMARK_MAIN();
