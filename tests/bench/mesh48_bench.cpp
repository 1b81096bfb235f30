// Kernels of the 4-8 mesh: one split (alone and with the forced splits of a quad edge), one
// merge, conversion of a 64x64 quad grid and of its triangulated twin (√3), export, compaction
// and validation. Numbers are recorded in docs/benchmarks.md ("4-8 mesh").

#include <benchmark/benchmark.h>

#include <random>

#include "meshing/mesh48.hpp"
#include "tests/meshing/mesh48_fixtures.hpp"

namespace {

using sd::meshing::BlockId;
using sd::meshing::Mesh48;
using sd::meshing::VertexId;
namespace fixtures = sd::meshing::testing;

constexpr int kGrid = 64;  // 64x64 quads: 4,225 vertices, 8,192 triangles

Mesh48 grid_mesh() {
  const auto g = fixtures::quad_grid(kGrid, kGrid, 1.0 / kGrid);
  return Mesh48::from_quads(g.vertices, g.quads);
}

void BM_ConvertQuadGrid64(benchmark::State& state) {
  const auto g = fixtures::quad_grid(kGrid, kGrid, 1.0 / kGrid);
  for (auto _ : state) benchmark::DoNotOptimize(Mesh48::from_quads(g.vertices, g.quads));
  state.counters["quads"] = static_cast<double>(g.quads.rows());
}
BENCHMARK(BM_ConvertQuadGrid64)->Unit(benchmark::kMillisecond);

void BM_ConvertSqrt3TriangleGrid64(benchmark::State& state) {
  const auto sheet = fixtures::triangle_sheet(kGrid, kGrid, 1.0 / kGrid);
  for (auto _ : state) benchmark::DoNotOptimize(Mesh48::from_triangles_sqrt3(sheet));
  state.counters["input_faces"] = static_cast<double>(sheet.face_count());
}
BENCHMARK(BM_ConvertSqrt3TriangleGrid64)->Unit(benchmark::kMillisecond);

// The operation benchmarks run on a grid whose slot arrays have already grown (everything split
// once and merged back), as in a simulation past its first steps; undoing a round of operations
// between rounds is not timed.

// Splits every level-0 block of the grid in turn (no forced split is needed for those).
void BM_SplitOneBlock(benchmark::State& state) {
  Mesh48 mesh = grid_mesh();
  const auto merge_all = [&] {
    for (int k = 0; k < kGrid * kGrid; ++k) (void)mesh.merge(BlockId(k));
  };
  for (int k = 0; k < kGrid * kGrid; ++k) (void)mesh.split(BlockId(k));
  merge_all();
  int next = 0;
  for (auto _ : state) {
    if (next == kGrid * kGrid) {
      state.PauseTiming();
      merge_all();
      next = 0;
      state.ResumeTiming();
    }
    benchmark::DoNotOptimize(mesh.split(BlockId(next++)));
  }
}
BENCHMARK(BM_SplitOneBlock);

// Splits interior vertical quad edges, each between two unsplit quads: every call makes two
// forced splits (the quads) and the requested one.
void BM_SplitEdgeWithTwoForcedSplits(benchmark::State& state) {
  std::vector<std::pair<VertexId, VertexId>> edges;
  for (int j = 0; j < kGrid; ++j)
    for (int i = 1; i < kGrid; i += 2) {
      const int v = j * (kGrid + 1) + i;
      edges.emplace_back(VertexId(v), VertexId(v + kGrid + 1));
    }
  Mesh48 mesh = grid_mesh();
  std::vector<BlockId> done;  // split blocks in order, to undo a round
  const auto run_round = [&] {
    for (const auto& [u, v] : edges)
      for (const auto& change : mesh.split_edge(u, v)) done.push_back(change.block);
  };
  const auto undo_round = [&] {
    for (auto it = done.rbegin(); it != done.rend(); ++it) (void)mesh.merge(*it);
    done.clear();
  };
  run_round();
  undo_round();
  std::size_t next = 0, splits = 0, calls = 0;
  for (auto _ : state) {
    if (next == edges.size()) {
      state.PauseTiming();
      undo_round();
      next = 0;
      state.ResumeTiming();
    }
    const auto changes = mesh.split_edge(edges[next].first, edges[next].second);
    ++next;
    for (const auto& change : changes) done.push_back(change.block);
    splits += changes.size();
    ++calls;
  }
  state.counters["splits_per_call"] = static_cast<double>(splits) / static_cast<double>(calls);
}
BENCHMARK(BM_SplitEdgeWithTwoForcedSplits);

// Merges the level-0 blocks of a fully split grid back, one per iteration.
void BM_MergeOneBlock(benchmark::State& state) {
  Mesh48 mesh = grid_mesh();
  const auto split_all = [&] {
    for (int k = 0; k < kGrid * kGrid; ++k) (void)mesh.split(BlockId(k));
  };
  split_all();
  int next = 0;
  for (auto _ : state) {
    if (next == kGrid * kGrid) {
      state.PauseTiming();
      split_all();
      next = 0;
      state.ResumeTiming();
    }
    benchmark::DoNotOptimize(mesh.merge(BlockId(next++)));
  }
}
BENCHMARK(BM_MergeOneBlock);

// An adapted grid: random splits until about 20k triangles, then the per-step queries the
// simulator makes after a batch of topology changes.
Mesh48 adapted_mesh() {
  Mesh48 mesh = grid_mesh();
  std::mt19937 rng(1);
  while (mesh.triangle_count() < 20000) {
    const auto leaves = mesh.leaf_blocks();
    (void)mesh.split(leaves[rng() % leaves.size()]);
  }
  return mesh;
}

void BM_ExportArrays20k(benchmark::State& state) {
  const Mesh48 mesh = adapted_mesh();
  for (auto _ : state) benchmark::DoNotOptimize(mesh.arrays());
  state.counters["triangles"] = mesh.triangle_count();
}
BENCHMARK(BM_ExportArrays20k)->Unit(benchmark::kMicrosecond);

void BM_MergeableBlocks20k(benchmark::State& state) {
  const Mesh48 mesh = adapted_mesh();
  for (auto _ : state) benchmark::DoNotOptimize(mesh.mergeable_blocks());
}
BENCHMARK(BM_MergeableBlocks20k)->Unit(benchmark::kMicrosecond);

void BM_Compact20k(benchmark::State& state) {
  Mesh48 base = adapted_mesh();
  for (const BlockId k : base.mergeable_blocks())
    if (base.can_merge(k)) (void)base.merge(k);  // leave free slots behind
  for (auto _ : state) {
    state.PauseTiming();
    Mesh48 mesh = base;
    state.ResumeTiming();
    benchmark::DoNotOptimize(mesh.compact());
  }
}
BENCHMARK(BM_Compact20k)->Unit(benchmark::kMicrosecond);

void BM_Validate20k(benchmark::State& state) {
  const Mesh48 mesh = adapted_mesh();
  for (auto _ : state) benchmark::DoNotOptimize(mesh.validate());
}
BENCHMARK(BM_Validate20k)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
