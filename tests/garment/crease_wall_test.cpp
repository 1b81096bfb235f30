#include "garment/crease_wall.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace sd::garment {
namespace {

// Two vertical tubes side by side, like a torso and a hanging arm: the torso of radius 0.1 m
// round the y axis, the arm of radius 0.04 m round x = kArmX, kGap apart where they are nearest
// (z = 0); y from 0.8 to 1.2 m, 192 vertices round each ring, rings every 1 cm, open ends.
constexpr double kTorsoR = 0.1, kArmR = 0.04, kGap = 0.015, kArmX = kTorsoR + kGap + kArmR;
constexpr double kOffset = 0.012, kEdge = 0.02;  // m: twice the offset is more than the gap

const BodySurface& torso_and_arm() {
  static const BodySurface surface = [] {
    constexpr int around = 192, rings = 41;
    meshing::TriMesh m;
    m.vertices.resize(2 * around * rings, 3);
    m.faces.resize(2 * 2 * around * (rings - 1), 3);
    Eigen::Index f = 0;
    for (int tube = 0; tube < 2; ++tube) {
      const double r = tube == 0 ? kTorsoR : kArmR, cx = tube == 0 ? 0 : kArmX;
      const int base = tube * around * rings;
      for (int j = 0; j < rings; ++j)
        for (int k = 0; k < around; ++k) {
          const double a = 2 * std::numbers::pi * k / around;
          m.vertices.row(base + j * around + k) << cx + r * std::cos(a), 0.8 + 0.01 * j,
              r * std::sin(a);
        }
      for (int j = 0; j + 1 < rings; ++j)
        for (int k = 0; k < around; ++k) {
          const int a = base + j * around + k, b = base + j * around + (k + 1) % around;
          m.faces.row(f++) << a, a + around, b;  // outward
          m.faces.row(f++) << b, a + around, b + around;
        }
    }
    return BodySurface(m);
  }();
  return surface;
}

double from_torso(const Eigen::Vector3d& p) {
  return std::hypot(p.x(), p.z()) - kTorsoR;
}
double from_arm(const Eigen::Vector3d& p) {
  return std::hypot(p.x() - kArmX, p.z()) - kArmR;
}

// Where the cloth goes: the wall's point plus the offset along its normal.
Eigen::Vector3d cloth(const CreaseWall& w) {
  return w.point.position + w.offset * w.point.normal;
}

// A seam on the floor of the gap, 2 mm behind its narrowest place, with the side its panel goes
// on to: -x for a panel on the torso, +x for one on the arm.
std::vector<SeamSide> seam_towards(double side) {
  return {{Eigen::Vector3d(kTorsoR + 0.5 * kGap, 1.0, -0.002), Eigen::Vector3d(side, 0, 0)}};
}

// A point of the gap 1 cm from the seam, nearer the arm (its nearest wall the arm's, normal -x).
const Eigen::Vector3d kNearArm(kTorsoR + 0.6 * kGap, 1.01, -0.004);

// The torso's panel (its seam's side -x) lies on the torso even where the arm is nearer, at 0.4
// of the gap's width (the gap measured along the wall's normal: 1.5-1.6 cm), so that the arm's
// panel fits beside it.
TEST(CreaseWall, ThePanelOfTheTorsoLiesOnTheTorsoWhereTheArmIsNearer) {
  const BodySurface& body = torso_and_arm();
  const SurfacePoint nearest = body.closest_point(kNearArm);
  ASSERT_LT(nearest.normal.x(), -0.9);  // the case meant: the arm's wall is nearest
  const CreaseWall w = crease_wall(body, seam_towards(-1), kNearArm, nearest, kOffset, kEdge);
  EXPECT_TRUE(w.moved);
  EXPECT_GT(w.point.normal.x(), 0.9);  // the torso's wall
  EXPECT_NEAR(from_torso(w.point.position), 0, 1e-3);
  EXPECT_NEAR(w.offset, 0.4 * kGap, 0.05 * kGap);
  const Eigen::Vector3d c = cloth(w);
  EXPECT_LT(from_torso(c), from_arm(c));
  EXPECT_GT(from_arm(c), 0.5 * kGap);
}

// The arm's panel (side +x) at the same point stays on the arm, at the narrowed offset too.
TEST(CreaseWall, ThePanelOfTheArmStaysOnTheArmAtANarrowedOffset) {
  const BodySurface& body = torso_and_arm();
  const SurfacePoint nearest = body.closest_point(kNearArm);
  const CreaseWall w = crease_wall(body, seam_towards(1), kNearArm, nearest, kOffset, kEdge);
  EXPECT_TRUE(w.moved);
  EXPECT_EQ(w.point.face, nearest.face);
  EXPECT_NEAR(w.offset, 0.4 * kGap, 0.05 * kGap);
  const Eigen::Vector3d c = cloth(w);
  EXPECT_LT(from_arm(c), from_torso(c));
  EXPECT_GT(from_torso(c), 0.5 * kGap);
}

// Far from any seam the nearest wall is kept; the offset still narrows in the gap. Where no
// other wall is near (the torso's far side), nothing changes.
TEST(CreaseWall, AwayFromSeamsOnlyTheOffsetNarrows) {
  const BodySurface& body = torso_and_arm();
  const SurfacePoint nearest = body.closest_point(kNearArm);
  const CreaseWall gap = crease_wall(body, {}, kNearArm, nearest, kOffset, kEdge);
  EXPECT_EQ(gap.point.face, nearest.face);
  EXPECT_LT(gap.offset, kOffset);
  const Eigen::Vector3d far(-kTorsoR - kOffset, 1.0, 0.0);
  const CreaseWall open =
      crease_wall(body, seam_towards(-1), far, body.closest_point(far), kOffset, kEdge);
  EXPECT_FALSE(open.moved);
  EXPECT_EQ(open.offset, kOffset);
}

// A seam down the middle of the gap, where the walls are parallel (no floor), says nothing of
// its side; one down the torso's back does, pointing into its panel.
TEST(CreaseWall, ASeamBetweenParallelWallsHasNoSide) {
  const BodySurface& body = torso_and_arm();
  // A loop: down the gap, then back up behind the torso (counter-clockwise seen from -z).
  Eigen::MatrixX3d down(5, 3), up(5, 3);
  for (int i = 0; i < 5; ++i) {
    down.row(i) << kTorsoR + 0.5 * kGap, 1.1 - 0.05 * i, 0.0;
    up.row(i) << 0.0, 0.9 + 0.05 * i, -kTorsoR - kOffset;
  }
  // Closing the loop: the last point of each side is the next side's first.
  Eigen::MatrixX3d across_bottom(2, 3), across_top(2, 3);
  across_bottom << down.row(4), up.row(0);
  across_top << up.row(4), down.row(0);
  const std::vector<SeamSide> sides =
      seam_sides({down, across_bottom, up, across_top}, body, kOffset);
  ASSERT_EQ(sides.size(), 10u);  // each side's points but its last
  for (int i = 1; i < 4; ++i) EXPECT_EQ(sides[static_cast<size_t>(i)].inward.norm(), 0) << i;
  // On the back, going up (+y) with the body's normal -z: d = n × t = -z × +y = +x.
  for (int i = 6; i < 9; ++i) EXPECT_GT(sides[static_cast<size_t>(i)].inward.x(), 0.99) << i;
}

}  // namespace
}  // namespace sd::garment
