// Self-collision kernels (sim/self_collision.hpp): the proximity query and the continuous query
// of a folded strip, with and without curvature culling, and of a flat one (what culling saves on
// a still, smooth cloth). Figures in docs/collision.md, "Self-collision".

#include <benchmark/benchmark.h>

#include "sim/parallel.hpp"
#include "sim/self_collision.hpp"
#include "tests/sim/self_contact_helpers.hpp"

namespace {

using sd::sim::SelfCollider;

// n: quads across the strip (2n × n quads in all); fold: layers 1 mm apart, or flat.
void BM_SelfProximity(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const bool fold = state.range(1) != 0;
  const bool culling = state.range(2) != 0;
  const auto sheet = sd::sim::testing::folded_sheet(n, 0.5, fold ? 0.001 : -1.0);
  SelfCollider collider(sheet.triangles, sheet.x);
  collider.set_culling(culling);
  sd::sim::SelfQueryStats stats;
  for (auto _ : state) benchmark::DoNotOptimize(collider.find_proximities(sheet.x, 0.002, &stats));
  state.counters["triangles"] = stats.triangles;
  state.counters["culled_share"] = static_cast<double>(stats.culled_triangles) / stats.triangles;
  state.counters["pairs"] = stats.pairs_found;
}
BENCHMARK(BM_SelfProximity)
    ->Args({32, 1, 1})
    ->Args({32, 1, 0})
    ->Args({32, 0, 1})
    ->Args({32, 0, 0})
    ->Unit(benchmark::kMicrosecond);

// The continuous query over a step in which the upper layer moves 1 cm towards the lower one
// (stopping 1 mm short of it: no collision, every pair near).
void BM_SelfContinuous(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const bool culling = state.range(1) != 0;
  const auto sheet = sd::sim::testing::folded_sheet(n, 0.5, 0.011);
  Eigen::VectorXd x1 = sheet.x;
  for (int i = 0; i < static_cast<int>(sheet.upper.size()); ++i)
    if (sheet.upper[i]) x1[3 * i + 1] -= 0.01;
  SelfCollider collider(sheet.triangles, sheet.x);
  collider.set_culling(culling);
  sd::sim::SelfQueryStats stats;
  for (auto _ : state)
    benchmark::DoNotOptimize(collider.find_collisions(sheet.x, x1, 1e-5, &stats));
  state.counters["triangles"] = stats.triangles;
  state.counters["element_tests"] = static_cast<double>(stats.element_tests);
  state.counters["culled_share"] = static_cast<double>(stats.culled_triangles) / stats.triangles;
}
BENCHMARK(BM_SelfContinuous)->Args({32, 1})->Args({32, 0})->Unit(benchmark::kMicrosecond);

// Building the tree (after a topology change).
void BM_SelfBuild(benchmark::State& state) {
  const auto sheet = sd::sim::testing::folded_sheet(static_cast<int>(state.range(0)), 0.5, 0.001);
  for (auto _ : state) benchmark::DoNotOptimize(SelfCollider(sheet.triangles, sheet.x));
  state.counters["triangles"] = static_cast<double>(sheet.triangles.size());
}
BENCHMARK(BM_SelfBuild)->Arg(32)->Unit(benchmark::kMicrosecond);

// A step's two queries and a refit on `threads` threads (sketchdrape --threads): a folded strip
// of 32 (4,096 triangles, a garment's size), culling on. The tree's refit and walk and the pair
// tests run on the threads (docs/simulator.md, "Threads"); wall time, since the point is
// what a second core takes off it.
void BM_SelfStepQueries(benchmark::State& state) {
  sd::sim::set_thread_count(static_cast<int>(state.range(0)));
  const auto sheet = sd::sim::testing::folded_sheet(32, 0.5, 0.002);
  Eigen::VectorXd x1 = sheet.x;
  for (int i = 0; i < static_cast<int>(sheet.upper.size()); ++i)
    if (sheet.upper[i]) x1[3 * i + 1] -= 0.001;
  SelfCollider collider(sheet.triangles, sheet.x);
  for (auto _ : state) {
    benchmark::DoNotOptimize(collider.find_proximities(sheet.x, 0.004));
    benchmark::DoNotOptimize(collider.find_collisions(sheet.x, x1, 1e-5));
  }
  sd::sim::set_thread_count(0);
}
BENCHMARK(BM_SelfStepQueries)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMicrosecond);

// Building the tree after a topology change, on `threads` threads.
void BM_SelfBuildThreads(benchmark::State& state) {
  sd::sim::set_thread_count(static_cast<int>(state.range(0)));
  const auto sheet = sd::sim::testing::folded_sheet(32, 0.5, 0.001);
  for (auto _ : state) benchmark::DoNotOptimize(SelfCollider(sheet.triangles, sheet.x));
  sd::sim::set_thread_count(0);
}
BENCHMARK(BM_SelfBuildThreads)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
