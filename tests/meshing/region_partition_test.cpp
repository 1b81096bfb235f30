#include "meshing/region_partition.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>
#include <vector>

namespace sd::meshing::detail {
namespace {

int at(const std::vector<int>& v, int i) {
  const int n = static_cast<int>(v.size());
  return v[static_cast<std::size_t>(((i % n) + n) % n)];
}

// The Nasri system arcs_j = d_{j-1} + d_{j+1} with every d_j >= 1, checked on random polygons
// of 3 to 8 sides; whenever a solution exists for an odd n (unique), it is the closed form.
TEST(RegionPartition, NasriSpokesSolveTheSystemWithPositiveLengths) {
  std::mt19937 random(7);
  int solved = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const int n = 3 + trial % 6;
    std::vector<int> arcs(static_cast<std::size_t>(n));
    for (int& a : arcs) a = 1 + static_cast<int>(random() % 9);
    const auto spokes = nasri_spokes(arcs);
    if (!spokes) continue;
    ++solved;
    ASSERT_EQ(spokes->size(), arcs.size());
    for (int j = 0; j < n; ++j) {
      EXPECT_GE(at(*spokes, j), 1);
      EXPECT_EQ(at(arcs, j), at(*spokes, j - 1) + at(*spokes, j + 1)) << "n " << n << " j " << j;
    }
    if (n % 2 == 1) {
      const std::vector<int> doubled = nasri_distances_doubled(arcs);
      for (int j = 0; j < n; ++j) EXPECT_EQ(2 * at(*spokes, j), at(doubled, j));
    }
  }
  EXPECT_GT(solved, 200);  // 248 of the 4000 random polygons have a solution: not vacuous
}

// For n = 4 the system needs opposite sides equal; its free parameter is chosen to make the
// smallest spoke as large as possible.
TEST(RegionPartition, FourSidedSystemIsSingularAndBalanced) {
  EXPECT_FALSE(nasri_spokes(std::vector<int>{4, 6, 5, 6}).has_value());
  const auto spokes = nasri_spokes(std::vector<int>{4, 6, 4, 6});
  ASSERT_TRUE(spokes.has_value());
  // d1 + d3 = 4 and d0 + d2 = 6: the balanced choice is (3, 2, 3, 2).
  EXPECT_EQ(*std::min_element(spokes->begin(), spokes->end()), 2);
  EXPECT_EQ(at(*spokes, 0) + at(*spokes, 2), 6);
  EXPECT_EQ(at(*spokes, 1) + at(*spokes, 3), 4);
}

// The closed form of DESIGN.md for a triangle: 2 d_i = l_{i+1} + l_{i+2} − l_i; it satisfies
// 2 l_i = 2 d_{i-1} + 2 d_{i+1} for every odd n and for n = 6 (n/2 odd), half-integers included.
TEST(RegionPartition, ClosedFormDistancesSatisfyTheSystem) {
  const std::vector<int> triangle{3, 5, 6};
  const std::vector<int> d3 = nasri_distances_doubled(triangle);
  for (int i = 0; i < 3; ++i)
    EXPECT_EQ(at(d3, i), at(triangle, i + 1) + at(triangle, i + 2) - at(triangle, i));
  std::mt19937 random(11);
  for (int trial = 0; trial < 600; ++trial) {
    const int n = std::vector<int>{3, 5, 6, 7, 9, 10}[static_cast<std::size_t>(trial % 6)];
    std::vector<int> lengths(static_cast<std::size_t>(n));
    for (int& l : lengths) l = 1 + static_cast<int>(random() % 12);
    const std::vector<int> doubled = nasri_distances_doubled(lengths);
    ASSERT_EQ(doubled.size(), lengths.size());
    for (int i = 0; i < n; ++i)
      EXPECT_EQ(2 * at(lengths, i), at(doubled, i - 1) + at(doubled, i + 1)) << "n " << n;
  }
}

// The layout search on a region's own boundary: a plain grid costs nothing, a centre of valence
// n costs |n − 4|, and the search never goes below its own lower bound.
TEST(RegionPartition, BestLayoutCostsAndLowerBound) {
  EXPECT_EQ(best_layout(region_costs(std::vector<int>{3, 2, 3, 2}), 2000).cost, 0);
  EXPECT_EQ(best_layout(region_costs(std::vector<int>{2, 2, 2}), 2000).cost, 1);
  EXPECT_EQ(best_layout(region_costs(std::vector<int>{2, 2, 2, 2, 2}), 2000).cost, 1);
  EXPECT_EQ(best_layout(region_costs(std::vector<int>{2, 2, 2, 2, 2, 2}), 2000).cost, 2);
  std::mt19937 random(3);
  for (int trial = 0; trial < 300; ++trial) {
    const int n = 3 + trial % 4;
    std::vector<int> sides(static_cast<std::size_t>(n));
    for (int& s : sides) s = 1 + static_cast<int>(random() % 6);
    if (std::accumulate(sides.begin(), sides.end(), 0) % 2 != 0) ++sides[0];
    const PositionCosts costs = region_costs(sides);
    const PolygonLayout layout = best_layout(costs, 2000);
    EXPECT_GE(layout.cost, layout_cost_lower_bound(costs));
    EXPECT_GE(layout.corners.size(), 3u);
    EXPECT_TRUE(std::is_sorted(layout.corners.begin(), layout.corners.end()));
  }
}

}  // namespace
}  // namespace sd::meshing::detail
