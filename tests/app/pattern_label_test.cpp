#include "src/app/pipeline/pattern_label.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

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
    for (const double y : {y0, y1}) {
      // SVG's rotate(−turn) about the anchor.
      const double a = at.turn_deg * std::numbers::pi / 180;
      out.emplace_back(at.anchor.x() + x * std::cos(a) + y * std::sin(a),
                       at.anchor.y() - x * std::sin(a) + y * std::cos(a));
    }
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
  EXPECT_EQ(at.turn_deg, 0);
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
  EXPECT_EQ(at.turn_deg, 90);
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

TEST(PatternLabel, ASlantedStrapGetsItsLabelAlongIt) {
  // A strap 30 mm wide and 500 mm long laid at 50° across the sheet (SVG frame, y down: running
  // down to the right), its grain line vertical, as trial 39's shortalls strap lay: neither
  // across nor a quarter turned does a 5 mm label fit (the old placements gave it 2 mm text at
  // the centroid); turned along the strap it does, every corner inside the strap.
  const double a = 50 * std::numbers::pi / 180, length = 500, half = 15;
  const Eigen::Vector2d d(std::cos(a), std::sin(a)), n(-std::sin(a), std::cos(a));
  Eigen::MatrixX2d strap(4, 2);
  strap.row(0) = -half * n;
  strap.row(1) = length * d - half * n;
  strap.row(2) = length * d + half * n;
  strap.row(3) = half * n;
  const LabelText text{"strap",
                       {"30 × 500 mm · denim",
                        "cut 2 (mirror pair) · strap and strap.mirror · ease 1 · stretch 1.2 % "
                        "(95th pct)"}};
  const Eigen::Vector2d mid = 0.5 * length * d;
  const LabelPlacement at = place_label(strap, {mid.x(), 0}, {mid.x(), length * d.y()}, text);
  ASSERT_TRUE(at.fits);
  EXPECT_GE(at.size, 5.0);
  EXPECT_NEAR(at.turn_deg, -50, 1.0);  // reads along the strap, left to right
  for (const Eigen::Vector2d& c : corners(at, text)) {
    EXPECT_LT(std::abs(c.dot(n)), half) << c.transpose();
    EXPECT_GT(c.dot(d), 0) << c.transpose();
    EXPECT_LT(c.dot(d), length) << c.transpose();
  }
}

TEST(PatternLabel, APieceTooSmallForAnyLabelSaysSo) {
  const LabelPlacement at = place_label(rectangle(8, 8), {4, 1}, {4, 7}, typical());
  EXPECT_FALSE(at.fits);
  EXPECT_DOUBLE_EQ(at.size, 2.0);
}

}  // namespace
}  // namespace sd::app
