// The extent of report.json's slice dent (trial 34: a blouse's "dent" of 8.6 cm was the gap
// between a sleeve and the torso).

#include "src/app/pipeline/run_report.hpp"

#include <gtest/gtest.h>

namespace sd::app {
namespace {

TEST(SliceDentTop, StopsAtTheCrotchAndLeavesOutTops) {
  // Without a body: the fixed 60 % of the garment's height.
  EXPECT_DOUBLE_EQ(*slice_dent_top(0.4, 1.1, std::nullopt), 0.6);
  // A skirt from 0.9 m to a hem at 0.4 m, crotch 0.77 m: the slices end at the crotch,
  // (0.77 − 0.4) / 0.5 = 74 % of its height, so the 60 % stands.
  EXPECT_DOUBLE_EQ(*slice_dent_top(0.4, 0.9, 0.77), 0.6);
  // A dress from 1.47 m to 0.4 m: 60 % would be 1.04 m, beside the arms; the crotch is at
  // (0.77 − 0.4) / 1.07 of its height.
  EXPECT_NEAR(*slice_dent_top(0.4, 1.47, 0.77), 0.37 / 1.07, 1e-12);
  // A blouse ending at the hips (0.86 m) or 4 cm below the crotch: no slice dent.
  EXPECT_FALSE(slice_dent_top(0.86, 1.47, 0.77).has_value());
  EXPECT_FALSE(slice_dent_top(0.73, 1.47, 0.77).has_value());
  EXPECT_TRUE(slice_dent_top(0.71, 1.47, 0.77).has_value());
}

}  // namespace
}  // namespace sd::app
