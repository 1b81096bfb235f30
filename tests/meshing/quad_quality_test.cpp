#include "meshing/quad_quality.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace sd::meshing {
namespace {

QuadMesh single_quad(const Eigen::Matrix<double, 4, 3>& corners) {
  QuadMesh mesh;
  mesh.vertices = corners;
  mesh.faces.resize(1, 4);
  mesh.faces << 0, 1, 2, 3;
  return mesh;
}

TEST(QuadQuality, UnitSquareIsPerfect) {
  Eigen::Matrix<double, 4, 3> c;
  c << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0;
  const std::vector<int> corners{0, 1, 2, 3};
  const QuadQuality q = measure_quality(single_quad(c), corners);
  EXPECT_EQ(q.distortion, 0);
  EXPECT_EQ(q.irregular_vertices, 0);
  EXPECT_NEAR(q.min_angle_deg, 90, 1e-12);
  EXPECT_NEAR(q.max_angle_deg, 90, 1e-12);
  EXPECT_NEAR(q.scaled_jacobian_min, 1, 1e-12);
  EXPECT_NEAR(q.max_aspect_ratio, 1, 1e-12);
  EXPECT_EQ(q.inverted_quads, 0);
}

TEST(QuadQuality, ParallelogramAnglesAndJacobian) {
  // Sheared by 45°: angles 45° and 135°, scaled Jacobian sin 45°, edges 1 and √2.
  Eigen::Matrix<double, 4, 3> c;
  c << 0, 0, 0, 1, 0, 0, 2, 1, 0, 1, 1, 0;
  const std::vector<int> corners{0, 1, 2, 3};
  const QuadQuality q = measure_quality(single_quad(c), corners);
  EXPECT_NEAR(q.min_angle_deg, 45, 1e-9);
  EXPECT_NEAR(q.max_angle_deg, 135, 1e-9);
  EXPECT_NEAR(q.scaled_jacobian_min, std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(q.max_aspect_ratio, std::sqrt(2.0), 1e-12);
}

TEST(QuadQuality, DartQuadIsInverted) {
  // A reflex corner at vertex 2: its scaled Jacobian is negative, its angle above 180°.
  Eigen::Matrix<double, 4, 3> c;
  c << 0, 0, 0, 2, 0, 0, 0.5, 0.5, 0, 0, 2, 0;
  const std::vector<int> corners{0, 1, 2, 3};
  const QuadQuality q = measure_quality(single_quad(c), corners);
  EXPECT_EQ(q.inverted_quads, 1);
  EXPECT_LT(q.scaled_jacobian_min, 0);
  EXPECT_GT(q.max_angle_deg, 180);
}

TEST(QuadQuality, TriangleOfThreeQuadsHasDistortionOne) {
  // Three quads around a centre of valence 3: the only irregular vertex.
  QuadMesh mesh;
  mesh.vertices.resize(7, 3);
  mesh.vertices << 0, 0, 0, 1, 0, 0, 2, 0, 0, 1.5, 0.8, 0, 1, 1.7, 0, 0.5, 0.8, 0, 1, 0.5, 0;
  mesh.faces.resize(3, 4);
  mesh.faces << 0, 1, 6, 5, 1, 2, 3, 6, 3, 4, 5, 6;
  const std::vector<int> corners{0, 2, 4};
  const QuadQuality q = measure_valence(mesh, corners);
  EXPECT_EQ(q.distortion, 1);
  EXPECT_EQ(q.irregular_vertices, 1);
  // Calling every boundary vertex a side vertex makes the three corners irregular as well.
  EXPECT_EQ(measure_valence(mesh, {}).distortion, 4);
}

}  // namespace
}  // namespace sd::meshing
