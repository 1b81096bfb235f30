#include "meshing/slice_dent.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace sd::meshing {
namespace {

// A vertical tube of height 1 whose cross-section is the outline r(θ) (Y up), n around, m up.
template <typename Outline>
TriMesh tube(Outline outline, int n, int m) {
  TriMesh mesh;
  mesh.vertices.resize(n * (m + 1), 3);
  for (int j = 0; j <= m; ++j)
    for (int i = 0; i < n; ++i) {
      const double theta = 2 * std::numbers::pi * i / n;
      const Eigen::Vector2d xz = outline(theta);
      mesh.vertices.row(j * n + i) << xz.x(), static_cast<double>(j) / m, xz.y();
    }
  mesh.faces.resize(2 * n * m, 3);
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * n + i, b = j * n + (i + 1) % n, c = a + n, d = b + n;
      mesh.faces.row(2 * (j * n + i)) << a, b, d;
      mesh.faces.row(2 * (j * n + i) + 1) << a, d, c;
    }
  return mesh;
}

TEST(SliceDent, ConvexTubeHasNoDent) {
  const TriMesh cylinder =
      tube([](double t) { return Eigen::Vector2d(0.2 * std::cos(t), 0.2 * std::sin(t)); }, 64, 10);
  EXPECT_LT(slice_dent(cylinder).depth, 1e-12);
  EXPECT_EQ(slice_dent(cylinder).slices, 51);
}

TEST(SliceDent, NotchedOutlineGivesTheNotchDepth) {
  // A circle of radius 0.2 with the front (θ within 0.25 rad of π/2, +z) pushed in by up to
  // 5 cm in a V: steep enough that the hull closes over the notch with the chord between its
  // two ends, at z = 0.2 cos 0.25; the notch's bottom is at z = 0.15.
  const auto notched = [](double t) {
    const double bump = std::max(0.0, 1.0 - std::abs(t - std::numbers::pi / 2) / 0.25);
    const double r = 0.2 - 0.05 * bump;
    return Eigen::Vector2d(r * std::cos(t), r * std::sin(t));
  };
  const SliceDent dent = slice_dent(tube(notched, 256, 4), 0.1, 0.6, 5);
  const double chord = 0.2 * std::cos(0.25);
  EXPECT_NEAR(dent.depth, chord - 0.15, 2e-3);
  EXPECT_NEAR(dent.where.z(), 0.15, 1e-3);
}

TEST(SliceDent, TwoTouchingCirclesDentAnalytically) {
  // Points of two circles of radius r centred at (±d, 0): the hull's top edge is z = r, and the
  // deepest point is where the circles cross, at x = 0, z = sqrt(r² − d²).
  const double r = 0.1, d = 0.06;
  Eigen::MatrixX2d points(400, 2);
  for (int i = 0; i < 200; ++i) {
    const double t = 2 * std::numbers::pi * i / 200;
    const Eigen::Vector2d p(r * std::cos(t), r * std::sin(t));
    points.row(i) << p.x() - d, p.y();
    points.row(200 + i) << p.x() + d, p.y();
  }
  // Keep only the outer outline: points not inside the other circle.
  std::vector<Eigen::Vector2d> outer;
  for (int i = 0; i < 400; ++i) {
    const Eigen::Vector2d p = points.row(i);
    const double other = i < 200 ? d : -d;
    if ((p - Eigen::Vector2d(other, 0)).norm() >= r) outer.push_back(p);
  }
  outer.emplace_back(0.0, std::sqrt(r * r - d * d));
  Eigen::MatrixX2d outline(static_cast<Eigen::Index>(outer.size()), 2);
  for (size_t i = 0; i < outer.size(); ++i)
    outline.row(static_cast<Eigen::Index>(i)) = outer[i].transpose();
  EXPECT_NEAR(hull_dent(outline), r - std::sqrt(r * r - d * d), 1e-4);
}

TEST(SliceDent, FewPointsHaveNoDent) {
  EXPECT_EQ(hull_dent(Eigen::MatrixX2d(2, 2)), 0.0);
  EXPECT_EQ(slice_dent(TriMesh{}).depth, 0.0);
}

}  // namespace
}  // namespace sd::meshing
