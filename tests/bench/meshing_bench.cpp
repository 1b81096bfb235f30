// Quad filling of n-sided regions: topology only (fill_region(counts)) and the full 3D fill
// (Coons + relaxation + quality). Numbers in docs/benchmarks.md, "Meshing".

#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <numeric>
#include <vector>

#include "meshing/patch_fill.hpp"

namespace {

using sd::meshing::fill_region;

// Named inputs, each with Σl <= 200.
const std::vector<std::vector<int>>& cases() {
  static const std::vector<std::vector<int>> all = {
      {5, 6, 3, 6, 4},                  // the paper's pentagon, Σ 24
      {50, 50, 50, 50},                 // grid, Σ 200
      {40, 44, 36, 42, 38},             // fair pentagon, Σ 200
      {26, 24, 24, 26, 24, 26, 24, 26},  // octagon, Σ 200
      {120, 20, 20, 20, 20},            // one very long side, Σ 200
      {60, 8, 60, 8, 60, 4},            // alternating long/short, Σ 200
      {2, 8, 4},                        // Takayama's (2,8,4)
  };
  return all;
}

void BM_FillTopology(benchmark::State& state) {
  const std::vector<int>& counts = cases()[static_cast<size_t>(state.range(0))];
  for (auto _ : state) benchmark::DoNotOptimize(fill_region(counts));
  state.SetLabel(std::to_string(counts.size()) + " sides, sum " +
                 std::to_string(std::accumulate(counts.begin(), counts.end(), 0)));
}

std::vector<Eigen::MatrixX3d> ellipse_sides(const std::vector<int>& counts) {
  const int total = std::accumulate(counts.begin(), counts.end(), 0);
  std::vector<Eigen::MatrixX3d> sides;
  int start = 0;
  for (const int count : counts) {
    Eigen::MatrixX3d side(count + 1, 3);
    for (int k = 0; k <= count; ++k) {
      const double a = 2 * std::numbers::pi * ((start + k) % total) / total;
      side.row(k) << 1.5 * std::cos(a), std::sin(a), 0.1 * std::sin(3 * a);
    }
    sides.push_back(side);
    start += count;
  }
  return sides;
}

void BM_FillGeometry(benchmark::State& state) {
  const std::vector<int>& counts = cases()[static_cast<size_t>(state.range(0))];
  const auto sides = ellipse_sides(counts);
  for (auto _ : state) benchmark::DoNotOptimize(fill_region(sides));
  state.SetLabel(std::to_string(counts.size()) + " sides, sum " +
                 std::to_string(std::accumulate(counts.begin(), counts.end(), 0)));
}

BENCHMARK(BM_FillTopology)->DenseRange(0, 6)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FillGeometry)->DenseRange(0, 6)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
