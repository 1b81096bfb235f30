// Quad filling of n-sided regions: topology only (fill_region(counts)) and the full 3D fill
// (Coons + relaxation + quality), on named inputs and on a sweep of skewed count vectors with
// Σl = 200 for n = 2..10 (the worst shapes for the plan search). Numbers in
// docs/benchmarks.md, "Meshing".

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <string>
#include <vector>

#include "meshing/patch_fill.hpp"

namespace {

using sd::meshing::fill_region;

std::string describe(const std::vector<int>& counts);

// Named inputs, each with Σl <= 200.
const std::vector<std::vector<int>>& cases() {
  static const std::vector<std::vector<int>> all = {
      {5, 6, 3, 6, 4},                   // the paper's pentagon, Σ 24
      {50, 50, 50, 50},                  // grid, Σ 200
      {40, 44, 36, 42, 38},              // fair pentagon, Σ 200
      {26, 24, 24, 26, 24, 26, 24, 26},  // octagon, Σ 200
      {120, 20, 20, 20, 20},             // one very long side, Σ 200
      {60, 8, 60, 8, 60, 4},             // alternating long/short, Σ 200
      {2, 8, 4},                         // Takayama's (2,8,4)
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

// The small skewed pentagons that take a rectilinear layout (a boundary vertex of valence 4),
// scaled up to 2,500 quads, next to a fair pentagon of about that size: the 3D fill.
std::vector<int> scaled(std::vector<int> counts, int factor) {
  for (int& c : counts) c *= factor;
  return counts;
}

const std::vector<std::vector<int>>& rectilinear_cases() {
  static const std::vector<std::vector<int>> all = {
      scaled({1, 2, 3, 1, 3}, 4), scaled({1, 2, 3, 1, 3}, 10), scaled({1, 2, 3, 1, 3}, 25),
      scaled({2, 4, 4, 2, 4}, 2), scaled({2, 4, 4, 2, 4}, 6),  scaled({2, 4, 4, 2, 4}, 14),
      {40, 44, 36, 42, 38},
  };
  return all;
}

void BM_FillGeometrySkewed(benchmark::State& state) {
  const std::vector<int>& counts = rectilinear_cases()[static_cast<size_t>(state.range(0))];
  const auto sides = ellipse_sides(counts);
  const auto filled = fill_region(sides);
  for (auto _ : state) benchmark::DoNotOptimize(fill_region(sides));
  state.SetLabel(describe(counts) + ": " + std::to_string(filled.mesh.faces.rows()) + " quads, " +
                 filled.topology.partition + ", distortion " +
                 std::to_string(filled.quality.distortion));
}

BENCHMARK(BM_FillGeometrySkewed)->DenseRange(0, 6)->Unit(benchmark::kMicrosecond);

// Counts proportional to the weights, each >= 1, summing to `total` (largest remainders).
std::vector<int> counts_from_weights(const std::vector<double>& weights, int total) {
  const double sum = std::accumulate(weights.begin(), weights.end(), 0.0);
  const auto n = static_cast<int>(weights.size());
  std::vector<int> counts(weights.size());
  std::vector<std::pair<double, int>> remainders;
  int used = 0;
  for (int i = 0; i < n; ++i) {
    const double exact = (total - n) * weights[static_cast<size_t>(i)] / sum;
    counts[static_cast<size_t>(i)] = 1 + static_cast<int>(std::floor(exact));
    used += counts[static_cast<size_t>(i)];
    remainders.emplace_back(exact - std::floor(exact), i);
  }
  std::stable_sort(remainders.begin(), remainders.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  for (size_t k = 0; used < total; ++k, ++used)
    ++counts[static_cast<size_t>(remainders[k % remainders.size()].second)];
  return counts;
}

struct SweepCase {
  std::string name;
  std::vector<int> counts;
};

// Skewed shapes with Σl = 200 for every n = 2..10: one very long side (the rest 1-2 edges or
// 4-5), two long sides next to each other or opposite, alternating long/short, a linear ramp,
// a geometric ramp (each side twice the last) and one side of 1 edge among equal ones.
std::vector<SweepCase> skewed_sweep() {
  std::vector<SweepCase> sweep;
  for (int n = 2; n <= 10; ++n) {
    auto add = [&](const std::string& family, auto weight) {
      std::vector<double> weights(static_cast<size_t>(n));
      for (int i = 0; i < n; ++i) weights[static_cast<size_t>(i)] = weight(i);
      sweep.push_back({family + "/n" + std::to_string(n), counts_from_weights(weights, 200)});
    };
    add("one_long", [](int i) { return i == 0 ? 200.0 : 1.0; });
    add("one_long_4", [n](int i) { return i == 0 ? 200.0 - 4 * (n - 1) : 4.0; });
    add("two_adjacent", [](int i) { return i < 2 ? 50.0 : 1.0; });
    add("two_opposite", [n](int i) { return i == 0 || i == n / 2 ? 50.0 : 1.0; });
    add("alternating", [](int i) { return i % 2 == 0 ? 12.0 : 1.0; });
    add("ramp", [](int i) { return i + 1.0; });
    add("geometric", [](int i) { return std::pow(2.0, i); });
    add("one_short", [](int i) { return i == 0 ? 0.0 : 1.0; });
  }
  return sweep;
}

std::string describe(const std::vector<int>& counts) {
  std::string text;
  for (const int c : counts) text += (text.empty() ? "" : ",") + std::to_string(c);
  return text;
}

}  // namespace

// The fixed cases above, then BM_SweepTopology/<shape>/n<N> and BM_SweepGeometry/<shape>/n<N>
// (label: the counts). Take the worst over the sweep, not only the fair cases.
int main(int argc, char** argv) {
  for (const SweepCase& sweep_case : skewed_sweep()) {
    const std::vector<int> counts = sweep_case.counts;
    benchmark::RegisterBenchmark(("BM_SweepTopology/" + sweep_case.name).c_str(),
                                 [counts](benchmark::State& state) {
                                   for (auto _ : state)
                                     benchmark::DoNotOptimize(fill_region(counts));
                                   state.SetLabel(describe(counts));
                                 })
        ->Unit(benchmark::kMicrosecond);
    const auto sides = ellipse_sides(counts);
    benchmark::RegisterBenchmark(("BM_SweepGeometry/" + sweep_case.name).c_str(),
                                 [sides, counts](benchmark::State& state) {
                                   for (auto _ : state)
                                     benchmark::DoNotOptimize(fill_region(sides));
                                   state.SetLabel(describe(counts));
                                 })
        ->Unit(benchmark::kMicrosecond);
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
