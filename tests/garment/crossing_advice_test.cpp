#include "garment/crossing_advice.hpp"

#include <gtest/gtest.h>

#include "garment/body.hpp"
#include "garment/body_surface.hpp"

namespace sd::garment {
namespace {

// Trial 37's bolero crossed at (0.176, 1.227, -0.015) m, under the built-in body's left arm:
// the crease between the arm and the torso is 2.6 cm across there (measured, 26 November: the
// warning's "2.6 cm"), so with a reach of 2.5 offsets of 1.5 cm it is a crease and with 1 cm
// (2.5 cm reach) it is not. In front of the chest, where nothing faces the torso, there is none.
TEST(CrossingAdvice, TheCreaseUnderTheArmIsMeasuredAndTheChestHasNone) {
  const BodySurface body(load_body("builtin").mesh);
  const auto under_arm = crease_width(body, {0.176, 1.227, -0.015}, 2.5 * 0.015);
  ASSERT_TRUE(under_arm.has_value());
  EXPECT_GT(*under_arm, 0.02);
  EXPECT_LT(*under_arm, 0.03);
  EXPECT_FALSE(crease_width(body, {0.176, 1.227, -0.015}, 0.02).has_value());
  EXPECT_FALSE(crease_width(body, {0.0, 1.2, 0.15}, 0.5).has_value());
}

// Every curve's offset is capped, and the file's, but none is raised.
TEST(CrossingAdvice, ASmallerOffsetCapsEveryCurve) {
  GarmentRequest sketch;
  sketch.offset = 0.015;
  sketch.curves.resize(2);
  sketch.curves[0].offset = 0.02;
  sketch.curves[1].offset = 0.005;
  const GarmentRequest trial = with_offset_at_most(sketch, 0.012);
  EXPECT_EQ(trial.offset, 0.012);
  EXPECT_EQ(trial.curves[0].offset, 0.012);
  EXPECT_EQ(trial.curves[1].offset, 0.005);
}

}  // namespace
}  // namespace sd::garment
