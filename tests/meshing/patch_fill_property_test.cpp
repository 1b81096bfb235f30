// Exhaustive property test of fill_region(side_counts): every n in 2..8, every count vector
// with entries 1..6 and an even total (n >= 6: a deterministic subsample).

#include <gtest/gtest.h>

#include <cstdint>
#include <map>
#include <numeric>

#include "meshing/patch_fill.hpp"
#include "tests/meshing/patch_fill_checks.hpp"

namespace sd::meshing {
namespace {

class PatchFillProperty : public ::testing::TestWithParam<int> {};

TEST_P(PatchFillProperty, EveryCountVectorGivesAValidMeshWithinTheBound) {
  const int n = GetParam();
  std::map<int, int> distortion_histogram;
  std::int64_t filled = 0;
  test::for_each_count_vector(n, [&](const std::vector<int>& counts) {
    if (std::accumulate(counts.begin(), counts.end(), 0) == 2) {
      // (1, 1): no quad mesh has a boundary of two edges
      EXPECT_THROW(fill_region(counts), FillError);
      return;
    }
    const PatchTopology topo = fill_region(counts);
    ASSERT_TRUE(test::well_formed(topo, counts));
    ASSERT_TRUE(test::within_bounds(topo, counts));
    ++distortion_histogram[topo.distortion - std::abs(n - 4)];
    ++filled;
  });
  EXPECT_GT(filled, 0);
  std::string summary;
  for (const auto& [excess, count] : distortion_histogram)
    summary += " +" + std::to_string(excess) + ": " + std::to_string(count);
  std::cout << "n = " << n << ", " << filled << " fills, distortion above |n-4|:" << summary
            << "\n";
}

INSTANTIATE_TEST_SUITE_P(AllSideCounts, PatchFillProperty, ::testing::Range(2, 9));

}  // namespace
}  // namespace sd::meshing
