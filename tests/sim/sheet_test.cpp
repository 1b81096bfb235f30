#include "sim/sheet.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <string>
#include <vector>

namespace sd::sim {
namespace {

TEST(Sheet, GridCountsPinsAndOrientation) {
  SheetSpec spec;
  spec.size = {1.0, 0.5};
  spec.columns = 4;
  spec.rows = 2;
  spec.pins = {"top-left", "top-right", "top-left"};
  const SheetScene scene = build_sheet(spec);
  EXPECT_EQ(scene.input.rest_positions.rows(), 15);
  EXPECT_EQ(scene.input.triangles.rows(), 16);
  ASSERT_EQ(scene.pinned_vertices, (std::vector<int>{0, 4}));
  EXPECT_NEAR(scene.input.rest_positions(0, 0), -0.5, 1e-15);
  EXPECT_NEAR(scene.input.rest_positions(0, 1), 1.25, 1e-15);  // top edge at centre + 0.25
  EXPECT_NEAR(scene.input.rest_positions(14, 1), 0.75, 1e-15);
  // Every triangle faces +Z and has positive area.
  for (Eigen::Index f = 0; f < scene.input.triangles.rows(); ++f) {
    const Eigen::Vector3d a = scene.input.rest_positions.row(scene.input.triangles(f, 0));
    const Eigen::Vector3d b = scene.input.rest_positions.row(scene.input.triangles(f, 1));
    const Eigen::Vector3d c = scene.input.rest_positions.row(scene.input.triangles(f, 2));
    EXPECT_GT((b - a).cross(c - a).z(), 0.0);
  }
  spec.orientation = SheetOrientation::horizontal;
  spec.pins = {"top", "left"};
  const SheetScene flat = build_sheet(spec);
  EXPECT_EQ(flat.pinned_vertices.size(), 5u + 3u - 1u);
  EXPECT_NEAR(flat.input.rest_positions.col(1).maxCoeff(), 1.0, 1e-15);
  EXPECT_NEAR(flat.input.rest_positions.col(1).minCoeff(), 1.0, 1e-15);
  for (Eigen::Index f = 0; f < flat.input.triangles.rows(); ++f) {
    const Eigen::Vector3d a = flat.input.rest_positions.row(flat.input.triangles(f, 0));
    const Eigen::Vector3d b = flat.input.rest_positions.row(flat.input.triangles(f, 1));
    const Eigen::Vector3d c = flat.input.rest_positions.row(flat.input.triangles(f, 2));
    EXPECT_GT((b - a).cross(c - a).y(), 0.0);
  }
}

TEST(Sheet, BadSpecsAreRejected) {
  SheetSpec spec;
  spec.pins = {"middle"};
  EXPECT_THROW(build_sheet(spec), InvalidSheetError);
  spec.pins.clear();
  spec.columns = 0;
  EXPECT_THROW(build_sheet(spec), InvalidSheetError);
  spec.columns = 2;
  spec.size = {-1.0, 1.0};
  EXPECT_THROW(build_sheet(spec), std::invalid_argument);
}

}  // namespace
}  // namespace sd::sim

namespace sd::sim {
namespace {

// A clamp "top:N" holds N lines of vertices from that edge (a cantilever's clamp, where an edge
// alone would be a hinge); bad depths are rejected.
TEST(Sheet, ClampPinsHoldSeveralLines) {
  SheetSpec spec;
  spec.columns = 4;
  spec.rows = 6;
  spec.pins = {"top:2", "right:1"};
  const SheetScene scene = build_sheet(spec);
  std::vector<int> expected;
  for (int r = 0; r <= 1; ++r)
    for (int c = 0; c <= 4; ++c) expected.push_back(scene.vertex(r, c));
  for (int r = 2; r <= 6; ++r) expected.push_back(scene.vertex(r, 4));
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(scene.pinned_vertices, expected);
  spec.pins = {"bottom:7"};
  EXPECT_EQ(build_sheet(spec).pinned_vertices.size(), 35u);  // every vertex
  for (const std::string bad : {"bottom:8", "left:0", "top:x", "top:2x", "middle:2"}) {
    spec.pins = {bad};
    EXPECT_THROW(build_sheet(spec), InvalidSheetError) << bad;
  }
}

}  // namespace
}  // namespace sd::sim
