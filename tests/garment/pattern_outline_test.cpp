// Tests of garment/pattern_outline: the smooth sewing line through a piece's outline points.
#include "garment/pattern_outline.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace sd::garment {
namespace {

double turn_at(const Eigen::MatrixX2d& p, Eigen::Index i) {
  const Eigen::Index n = p.rows();
  const Eigen::Vector2d a = p.row(i) - p.row((i + n - 1) % n);
  const Eigen::Vector2d b = p.row((i + 1) % n) - p.row(i);
  return std::abs(std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b)));
}

// Twelve points on a circle of 100 mm radius (30° apart, the polyline turns 30° at each): the
// curve passes through them, stays within 0.2 mm of the circle (a centripetal Catmull-Rom of
// equal chords is the uniform one, whose error on a 30° arc is about 0.1 % of the radius),
// turns by less than 6° between consecutive chords (chords within 0.1 mm of an arc turn by about
// 2·√(8·0.1/100) rad ≈ 10° at most), and is densified between the points.
TEST(PatternOutline, CircleBecomesSmooth) {
  const int n = 12;
  const double r = 0.1;
  Eigen::MatrixX2d points(n, 2);
  for (int k = 0; k < n; ++k)
    points.row(k) << r * std::cos(2 * std::numbers::pi * k / n),
        r * std::sin(2 * std::numbers::pi * k / n);
  std::vector<bool> corner;
  mark_sharp_turns(points, 40 * std::numbers::pi / 180, corner);
  for (const bool c : corner) EXPECT_FALSE(c);
  const SmoothOutline curve = smooth_outline(points, corner, 1e-4);
  ASSERT_EQ(curve.at.size(), static_cast<size_t>(n));
  for (int k = 0; k < n; ++k)
    EXPECT_EQ((curve.points.row(curve.at[static_cast<size_t>(k)]) - points.row(k)).norm(), 0.0);
  double worst_radius = 0, worst_turn = 0;
  for (Eigen::Index i = 0; i < curve.points.rows(); ++i) {
    worst_radius = std::max(worst_radius, std::abs(curve.points.row(i).norm() - r));
    worst_turn = std::max(worst_turn, turn_at(curve.points, i));
  }
  EXPECT_LT(worst_radius, 2e-4);
  EXPECT_LT(worst_turn, 6 * std::numbers::pi / 180);
  EXPECT_GT(curve.points.rows(), 2 * n);  // densified between the points
  // The curve is longer than the 12-gon, as the circle is (2π r against 12 · 2r sin 15°: 1.1 %
  // longer), and within 0.2 % of the circle, as its radius is (measured 0.11 % short: the
  // chords of the densification cut the arcs).
  double length = 0;
  for (Eigen::Index i = 0; i < curve.points.rows(); ++i)
    length += (curve.points.row((i + 1) % curve.points.rows()) - curve.points.row(i)).norm();
  EXPECT_GT(length, 12 * 2 * r * std::sin(std::numbers::pi / 12));
  EXPECT_NEAR(length, 2 * std::numbers::pi * r, 2e-3 * 2 * std::numbers::pi * r);
  // A point a third of the way along span 0 is on the curve, its normal pointing out.
  const auto [p, normal] = point_on_span(curve, 0, 1.0 / 3);
  EXPECT_NEAR(p.norm(), r, 2e-4);
  EXPECT_GT(normal.dot(p.normalized()), 0.99);
}

// A square sampled with four points a side: its corners turn 90° and are found as corners;
// the curve keeps them (turns 90° there) and its sides stay straight (every point on a side).
TEST(PatternOutline, CornersStayCornersAndStraightSidesStayStraight) {
  const std::vector<Eigen::Vector2d> corners = {{0, 0}, {0.2, 0}, {0.2, 0.2}, {0, 0.2}};
  Eigen::MatrixX2d points(16, 2);
  for (int c = 0; c < 4; ++c)
    for (int k = 0; k < 4; ++k)
      points.row(4 * c + k) =
          (corners[static_cast<size_t>(c)] +
           (corners[static_cast<size_t>((c + 1) % 4)] - corners[static_cast<size_t>(c)]) * k / 4.0)
              .transpose();
  std::vector<bool> corner;
  mark_sharp_turns(points, 40 * std::numbers::pi / 180, corner);
  for (int i = 0; i < 16; ++i) EXPECT_EQ(corner[static_cast<size_t>(i)], i % 4 == 0) << i;
  const SmoothOutline curve = smooth_outline(points, corner, 1e-4);
  for (int c = 0; c < 4; ++c)
    EXPECT_NEAR(turn_at(curve.points, curve.at[static_cast<size_t>(4 * c)]), std::numbers::pi / 2,
                1e-9);
  for (Eigen::Index i = 0; i < curve.points.rows(); ++i) {
    const double x = curve.points(i, 0), y = curve.points(i, 1);
    const double off = std::min({std::abs(x), std::abs(y), std::abs(x - 0.2), std::abs(y - 0.2)});
    EXPECT_LT(off, 1e-12) << i;
  }
}

}  // namespace
}  // namespace sd::garment
