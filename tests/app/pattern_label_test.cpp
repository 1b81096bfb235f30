#include "src/app/pipeline/pattern_label.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace sd::app {
namespace {

Eigen::MatrixX2d rectangle(double w, double h) {
  Eigen::MatrixX2d p(4, 2);
  p << 0, 0, w, 0, w, h, 0, h;
  return p;
}

LabelText typical() {
  return {"skirt-front-gore",
          {"43 × 612 mm · cotton", "cut 1 · ease 1 · stretch 0.4 % (95th pct)"}};
}

// The block's corners in the sheet frame, from the placement (the SVG transform it becomes).
std::vector<Eigen::Vector2d> corners(const LabelPlacement& at, const LabelText& text) {
  double w = text_width(text.title, at.size, true);
  for (const std::string& line : text.lines)
    w = std::max(w, text_width(line, 0.75 * at.size, false));
  const double x0 = at.centred ? -0.5 * w : 0.0, x1 = x0 + w;
  const double y0 = -0.8 * at.size, y1 = at.size * (1 + 0.9 * double(text.lines.size() - 1));
  std::vector<Eigen::Vector2d> out;
  for (const double x : {x0, x1})
    for (const double y : {y0, y1})
      out.push_back(at.along ? Eigen::Vector2d(at.anchor.x() + y, at.anchor.y() - x)
                             : Eigen::Vector2d(at.anchor.x() + x, at.anchor.y() + y));
  return out;
}

TEST(PatternLabel, TextWidthCountsCharactersNotBytes) {
  EXPECT_DOUBLE_EQ(text_width("ab", 10, false), 2 * 0.56 * 10);
  EXPECT_DOUBLE_EQ(text_width("a×b", 10, false), 3 * 0.56 * 10);  // × is two bytes
  EXPECT_GT(text_width("ab", 10, true), text_width("ab", 10, false));
}

TEST(PatternLabel, AWidePieceGetsTheLargestTypeBesideItsGrainLine) {
  const LabelPlacement at = place_label(rectangle(600, 700), {300, 50}, {300, 650}, typical());
  EXPECT_TRUE(at.fits);
  EXPECT_FALSE(at.along);
  EXPECT_DOUBLE_EQ(at.size, 9.0);
  EXPECT_GT(at.anchor.x(), 300);  // right of the grain line
  EXPECT_NEAR(at.anchor.y(), 350, 1e-9);
}

TEST(PatternLabel, ANarrowGoreGetsItsLabelAlongItsLength) {
  // 45 mm × 600 mm: the figure line is ~110 mm long at the smallest size across, so only the
  // turned label fits; every corner of its block lies inside the strip.
  const Eigen::MatrixX2d strip = rectangle(45, 600);
  const LabelText text = typical();
  const LabelPlacement at = place_label(strip, {22.5, 20}, {22.5, 580}, text);
  ASSERT_TRUE(at.fits);
  EXPECT_TRUE(at.along);
  EXPECT_GE(at.size, 4.0);
  for (const Eigen::Vector2d& c : corners(at, text)) {
    EXPECT_GT(c.x(), 0);
    EXPECT_LT(c.x(), 45);
    EXPECT_GT(c.y(), 0);
    EXPECT_LT(c.y(), 600);
  }
}

TEST(PatternLabel, ATriangleKeepsTheBlockOffItsSlantedSide) {
  // A right triangle whose hypotenuse passes right of the grain line's middle: the block is
  // placed where the slanted side leaves room, inside the outline.
  Eigen::MatrixX2d tri(3, 2);
  tri << 0, 0, 400, 400, 0, 400;  // SVG frame: the wide end at the bottom
  const LabelText text = typical();
  const LabelPlacement at = place_label(tri, {60, 120}, {60, 380}, text);
  ASSERT_TRUE(at.fits);
  for (const Eigen::Vector2d& c : corners(at, text)) {
    EXPECT_GT(c.x(), 0);
    EXPECT_LT(c.y(), 400);
    EXPECT_LT(c.x(), c.y());  // left of the hypotenuse y = x
  }
}

TEST(PatternLabel, APieceTooSmallForAnyLabelSaysSo) {
  const LabelPlacement at = place_label(rectangle(8, 8), {4, 1}, {4, 7}, typical());
  EXPECT_FALSE(at.fits);
  EXPECT_DOUBLE_EQ(at.size, 2.0);
}

}  // namespace
}  // namespace sd::app
