#pragma once
// Structural checks shared by the patch filling tests: what every fill must satisfy.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <set>
#include <span>
#include <string>
#include <utility>

#include "meshing/patch_fill.hpp"

namespace sd::meshing::test {

inline std::string describe(std::span<const int> counts) {
  std::string s = "(";
  for (size_t i = 0; i < counts.size(); ++i) s += (i ? "," : "") + std::to_string(counts[i]);
  return s + ")";
}

// Valid mesh, sides exactly as asked, boundary = the sides in order, Euler characteristic 1,
// and the reported figures equal the measured ones.
inline ::testing::AssertionResult well_formed(const PatchTopology& topo,
                                              std::span<const int> counts) {
  const MeshCheck check = validate(topo.mesh);
  if (!check.ok()) return ::testing::AssertionFailure() << describe(counts) << ": " << check.problems.front();
  if (topo.side_vertices.size() != counts.size())
    return ::testing::AssertionFailure() << describe(counts) << ": wrong side count";
  std::vector<int> expected_loop;
  for (size_t i = 0; i < counts.size(); ++i) {
    const auto& side = topo.side_vertices[i];
    if (static_cast<int>(side.size()) != counts[i] + 1)
      return ::testing::AssertionFailure() << describe(counts) << ": side " << i << " has "
                                           << side.size() - 1 << " edges";
    if (side.back() != topo.side_vertices[(i + 1) % counts.size()].front())
      return ::testing::AssertionFailure() << describe(counts) << ": sides do not meet";
    expected_loop.insert(expected_loop.end(), side.begin(), side.end() - 1);
  }
  std::vector<int> loop = boundary_loop(topo.mesh);
  if (loop.size() != expected_loop.size())
    return ::testing::AssertionFailure() << describe(counts) << ": boundary has " << loop.size()
                                         << " vertices";
  const auto start = std::find(loop.begin(), loop.end(), expected_loop.front());
  if (start == loop.end()) return ::testing::AssertionFailure() << "corner 0 not on the boundary";
  std::rotate(loop.begin(), start, loop.end());
  if (loop != expected_loop)
    return ::testing::AssertionFailure() << describe(counts) << ": boundary order differs";
  std::set<std::pair<int, int>> edges;
  for (Eigen::Index f = 0; f < topo.mesh.faces.rows(); ++f)
    for (int k = 0; k < 4; ++k)
      edges.insert(std::minmax(topo.mesh.faces(f, k), topo.mesh.faces(f, (k + 1) % 4)));
  const auto euler = topo.mesh.vertices.rows() - static_cast<Eigen::Index>(edges.size()) +
                     topo.mesh.faces.rows();
  if (euler != 1) return ::testing::AssertionFailure() << describe(counts) << ": Euler " << euler;
  const QuadQuality q = measure_valence(topo.mesh, topo.corner_vertices());
  if (q.distortion != topo.distortion || q.irregular_vertices != topo.irregular_vertices)
    return ::testing::AssertionFailure() << describe(counts) << ": reported figures differ";
  return ::testing::AssertionSuccess();
}

// Proven limits (docs/meshing.md): the signed deviations sum to 4 − n, so the distortion is at
// least |n − 4| and has the parity of n; the fallback triangle keeps it at most n + 2.
inline ::testing::AssertionResult within_bounds(const PatchTopology& topo,
                                                std::span<const int> counts) {
  const int n = static_cast<int>(counts.size());
  if (topo.distortion < std::abs(n - 4) || (topo.distortion - n) % 2 != 0 ||
      topo.distortion > n + 2)
    return ::testing::AssertionFailure() << describe(counts) << ": distortion " << topo.distortion;
  return ::testing::AssertionSuccess();
}

// Every count vector of n sides with entries 1..6 and an even total, in a fixed order; for
// 6^n above kMaxCasesPerN a deterministic subsample: vector indices 0, s, 2s, ... with s prime
// to 6, so that every side still takes every value. Calls visit(counts) for each.
template <class Visit>
void for_each_count_vector(int n, Visit&& visit) {
  constexpr int kMaxCount = 6;
  constexpr std::int64_t kMaxCasesPerN = 6000;
  std::int64_t total_vectors = 1;
  for (int i = 0; i < n; ++i) total_vectors *= kMaxCount;
  std::int64_t stride = std::max<std::int64_t>(1, total_vectors / kMaxCasesPerN);
  while (stride % 2 == 0 || stride % 3 == 0) ++stride;
  if (total_vectors <= kMaxCasesPerN) stride = 1;
  for (std::int64_t index = 0; index < total_vectors; index += stride) {
    std::vector<int> counts(static_cast<size_t>(n));
    std::int64_t rest = index;
    int sum = 0;
    for (int& c : counts) {
      c = 1 + static_cast<int>(rest % kMaxCount);
      rest /= kMaxCount;
      sum += c;
    }
    if (sum % 2 == 0) visit(counts);
  }
}

}  // namespace sd::meshing::test
