#pragma once
// Structural checks shared by the patch filling tests: what every fill must satisfy.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <set>
#include <span>
#include <string>
#include <utility>
#include <vector>

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
  if (!check.ok())
    return ::testing::AssertionFailure() << describe(counts) << ": " << check.problems.front();
  if (topo.side_vertices.size() != counts.size())
    return ::testing::AssertionFailure() << describe(counts) << ": wrong side count";
  std::vector<int> expected_loop;
  for (size_t i = 0; i < counts.size(); ++i) {
    const auto& side = topo.side_vertices[i];
    if (static_cast<int>(side.size()) != counts[i] + 1)
      return ::testing::AssertionFailure()
             << describe(counts) << ": side " << i << " has " << side.size() - 1 << " edges";
    if (side.back() != topo.side_vertices[(i + 1) % counts.size()].front())
      return ::testing::AssertionFailure() << describe(counts) << ": sides do not meet";
    expected_loop.insert(expected_loop.end(), side.begin(), side.end() - 1);
  }
  std::vector<int> loop = boundary_loop(topo.mesh);
  if (loop.size() != expected_loop.size())
    return ::testing::AssertionFailure()
           << describe(counts) << ": boundary has " << loop.size() << " vertices";
  const auto start = std::find(loop.begin(), loop.end(), expected_loop.front());
  if (start == loop.end()) return ::testing::AssertionFailure() << "corner 0 not on the boundary";
  std::rotate(loop.begin(), start, loop.end());
  if (loop != expected_loop)
    return ::testing::AssertionFailure() << describe(counts) << ": boundary order differs";
  std::set<std::pair<int, int>> edges;
  for (Eigen::Index f = 0; f < topo.mesh.faces.rows(); ++f)
    for (int k = 0; k < 4; ++k)
      edges.insert(std::minmax(topo.mesh.faces(f, k), topo.mesh.faces(f, (k + 1) % 4)));
  const auto euler =
      topo.mesh.vertices.rows() - static_cast<Eigen::Index>(edges.size()) + topo.mesh.faces.rows();
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

// Corner i at `corner_point(i)`, straight sides split evenly (n = 2: two half circles).
template <class CornerPoint>
inline std::vector<Eigen::MatrixX3d> straight_sides(std::span<const int> counts,
                                                    const CornerPoint& corner_point) {
  const auto n = static_cast<int>(counts.size());
  std::vector<Eigen::MatrixX3d> sides;
  for (int i = 0; i < n; ++i) {
    const int count = counts[static_cast<size_t>(i)];
    Eigen::MatrixX3d side(count + 1, 3);
    for (int k = 0; k <= count; ++k) {
      const double t = static_cast<double>(k) / count;
      if (n == 2) {
        const double a = std::numbers::pi * (i + t);
        side.row(k) << std::cos(a), std::sin(a), 0;
      } else {
        side.row(k) = ((1 - t) * corner_point(i) + t * corner_point((i + 1) % n)).transpose();
      }
    }
    sides.push_back(side);
  }
  for (int i = 0; i < n; ++i)
    sides[static_cast<size_t>(i)].bottomRows<1>() =
        sides[static_cast<size_t>((i + 1) % n)].topRows<1>();
  return sides;
}

inline Eigen::Vector3d on_circle(int i, int n, double radius = 1) {
  const double a = 2 * std::numbers::pi * i / n;
  return {radius * std::cos(a), radius * std::sin(a), 0};
}

// A regular n-gon (n >= 4) whose corner 1 is pulled inwards along its ray until the boundary's
// interior angle there is `reflex_deg` (> 180°), every side bowed inwards by kBow of its chord
// (so every side vertex is reflex too, by 0.5-4°).
inline constexpr double kBow = 0.02;
inline std::vector<Eigen::MatrixX3d> notched_sides(std::span<const int> counts, double reflex_deg) {
  const auto n = static_cast<int>(counts.size());
  const double step = 2 * std::numbers::pi / n;
  // Corner 1 at distance r on its ray: the chord of corners 0 and 2 is at cos(step), half of it
  // sin(step) long, so the angle is 180° + 2 atan((cos(step) − r) / sin(step)).
  const double radius =
      std::cos(step) - std::sin(step) * std::tan((reflex_deg - 180) / 2 * std::numbers::pi / 180);
  auto corner = [n, radius](int i) { return i == 1 ? on_circle(1, n, radius) : on_circle(i, n); };
  std::vector<Eigen::MatrixX3d> sides = straight_sides(counts, corner);
  for (int i = 0; i < n; ++i) {
    auto& side = sides[static_cast<size_t>(i)];
    const Eigen::RowVector3d a = side.topRows<1>(), b = side.bottomRows<1>();
    const Eigen::RowVector3d chord = b - a;
    const Eigen::RowVector3d inward(-chord.y(), chord.x(), 0);  // left of a counter-clockwise side
    const Eigen::Index count = side.rows() - 1;
    for (Eigen::Index k = 1; k < count; ++k) {
      const double t = static_cast<double>(k) / static_cast<double>(count);
      side.row(k) += 4 * kBow * t * (1 - t) * inward;
    }
  }
  return sides;
}

}  // namespace sd::meshing::test
