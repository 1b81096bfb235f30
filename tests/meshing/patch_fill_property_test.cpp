// Exhaustive property test of fill_region(side_counts): every n in 2..8, every count vector
// with entries 1..6 and an even total (n >= 6: a deterministic subsample).

#include <gtest/gtest.h>

#include <cstdint>
#include <map>

#include "meshing/patch_fill.hpp"
#include "tests/meshing/patch_fill_checks.hpp"

namespace sd::meshing {
namespace {

constexpr int kMaxCount = 6;
constexpr std::int64_t kMaxCasesPerN = 6000;

class PatchFillProperty : public ::testing::TestWithParam<int> {};

TEST_P(PatchFillProperty, EveryCountVectorGivesAValidMeshWithinTheBound) {
  const int n = GetParam();
  std::int64_t total_vectors = 1;
  for (int i = 0; i < n; ++i) total_vectors *= kMaxCount;
  // Visit vector indices 0, s, 2s, ... with s odd and not a multiple of 3, so that every
  // "digit" (count) still takes every value (a stride sharing no factor with 6^n).
  std::int64_t stride = std::max<std::int64_t>(1, total_vectors / kMaxCasesPerN);
  while (stride % 2 == 0 || stride % 3 == 0) ++stride;
  if (total_vectors <= kMaxCasesPerN) stride = 1;
  std::map<int, int> distortion_histogram;
  std::int64_t filled = 0;
  for (std::int64_t index = 0; index < total_vectors; index += stride) {
    std::vector<int> counts(static_cast<size_t>(n));
    std::int64_t rest = index;
    int sum = 0;
    for (int& c : counts) {
      c = 1 + static_cast<int>(rest % kMaxCount);
      rest /= kMaxCount;
      sum += c;
    }
    if (sum % 2 != 0) continue;
    if (sum == 2) {  // (1, 1): no quad mesh has a boundary of two edges
      EXPECT_THROW(fill_region(counts), FillError);
      continue;
    }
    const PatchTopology topo = fill_region(counts);
    ASSERT_TRUE(test::well_formed(topo, counts));
    ASSERT_TRUE(test::within_bounds(topo, counts));
    ++distortion_histogram[topo.distortion - std::abs(n - 4)];
    ++filled;
  }
  EXPECT_GT(filled, 0);
  std::string summary;
  for (const auto& [excess, count] : distortion_histogram)
    summary += " +" + std::to_string(excess) + ": " + std::to_string(count);
  std::cout << "n = " << n << ", " << filled << " fills, distortion above |n-4|:" << summary << "\n";
}

INSTANTIATE_TEST_SUITE_P(AllSideCounts, PatchFillProperty, ::testing::Range(2, 9));

}  // namespace
}  // namespace sd::meshing
