#include "sim/sheet.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <string>
#include <utility>
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

namespace sd::sim {
namespace {

// The Cusick test's disc: a closed disc (Euler characteristic 1, every edge in one or two
// triangles), all triangles facing up, its rim on the circle, its area that of the inscribed
// polygon, and the clamp "centre:R" holding exactly the vertices within R, a ring of them at R.
TEST(Sheet, DiscIsAClosedDiscWithItsClampRingAtTheRadius) {
  SheetSpec spec;
  spec.shape = SheetShape::disc;
  spec.size = {0.3, 0.3};
  spec.orientation = SheetOrientation::horizontal;
  spec.centre = {0.1, 1.0, -0.2};
  spec.pins = {"centre:0.09"};
  for (const int cells : {8, 20, 30}) {
    spec.columns = spec.rows = cells;
    const SheetScene scene = build_sheet(spec);
    const Eigen::MatrixX3d& x = scene.input.rest_positions;
    const Eigen::MatrixX3i& t = scene.input.triangles;
    ASSERT_EQ(t.rows(), 2 * scene.quads.rows());
    double area = 0.0, smallest = 1.0;
    std::map<std::pair<int, int>, int> edges;
    for (Eigen::Index f = 0; f < t.rows(); ++f) {
      const Eigen::Vector3d a = x.row(t(f, 0)), b = x.row(t(f, 1)), c = x.row(t(f, 2));
      const Eigen::Vector3d n = (b - a).cross(c - a);
      EXPECT_GT(n.y(), 0.0) << f;
      area += 0.5 * n.norm();
      smallest = std::min(smallest, 0.5 * n.norm());
      for (int k = 0; k < 3; ++k) {
        const int u = t(f, k), v = t(f, (k + 1) % 3);
        ++edges[{std::min(u, v), std::max(u, v)}];
      }
    }
    int rim = 0;
    double rim_radius = 0.0;
    for (const auto& [edge, count] : edges) {
      EXPECT_LE(count, 2);
      if (count == 1) {
        ++rim;
        for (const int v : {edge.first, edge.second})
          rim_radius = std::max(rim_radius, (x.row(v).transpose() - spec.centre).norm());
      }
    }
    EXPECT_EQ(x.rows() - static_cast<Eigen::Index>(edges.size()) + t.rows(), 1) << cells;
    EXPECT_NEAR(rim_radius, 0.15, 1e-12);
    // The rim is a regular polygon of `rim` sides inscribed in the circle.
    const double polygon = 0.5 * rim * 0.15 * 0.15 * std::sin(2 * std::numbers::pi / rim);
    EXPECT_NEAR(area, polygon, 1e-12) << cells;
    const double h = 0.3 / cells;
    EXPECT_GT(smallest, 0.05 * h * h) << cells;  // no sliver
    int at_clamp = 0;
    for (Eigen::Index v = 0; v < x.rows(); ++v) {
      const double r = (x.row(v).transpose() - spec.centre).norm();
      const bool held =
          std::binary_search(scene.pinned_vertices.begin(), scene.pinned_vertices.end(), v);
      EXPECT_EQ(held, r <= 0.09 + 1e-9) << v;
      at_clamp += std::abs(r - 0.09) < 1e-12;
    }
    EXPECT_GE(at_clamp, 8) << cells;
  }
  spec.pins = {"top"};
  EXPECT_THROW(build_sheet(spec), InvalidSheetError);
  spec.pins = {"centre:-1"};
  EXPECT_THROW(build_sheet(spec), InvalidSheetError);
  spec.pins = {};
  spec.size = {0.3, 0.2};
  EXPECT_THROW(build_sheet(spec), InvalidSheetError);
}

}  // namespace
}  // namespace sd::sim

namespace sd::sim {
namespace {

// A corner clamp "top-left:R" holds exactly the grid points within R of that corner: on a
// 1 m sheet of 10 cm cells, "top-left:0.15" holds the corner, its two neighbours along the
// edges (10 cm) and the diagonal one (14.1 cm), not those 20 cm away; a radius landing on a grid
// point (0.1) holds it; the other corners are mirrored; a bad radius is refused.
TEST(Sheet, CornerClampHoldsTheVerticesWithinItsRadius) {
  SheetSpec spec;
  spec.size = {1.0, 1.0};
  spec.columns = spec.rows = 10;
  spec.orientation = SheetOrientation::horizontal;
  spec.centre = {0.3, 1.2, -0.1};
  spec.pins = {"top-left:0.15"};
  SheetScene scene = build_sheet(spec);
  EXPECT_EQ(scene.pinned_vertices, (std::vector<int>{scene.vertex(0, 0), scene.vertex(0, 1),
                                                     scene.vertex(1, 0), scene.vertex(1, 1)}));
  spec.pins = {"bottom-right:0.1", "top-right:0.05"};
  scene = build_sheet(spec);
  EXPECT_EQ(scene.pinned_vertices, (std::vector<int>{scene.vertex(0, 10), scene.vertex(9, 10),
                                                     scene.vertex(10, 9), scene.vertex(10, 10)}));
  // Every held vertex is within R of its corner, and every vertex within R is held (a finer
  // grid, with points at every distance).
  spec.columns = spec.rows = 64;
  spec.pins = {"bottom-left:0.05"};
  scene = build_sheet(spec);
  const Eigen::Vector3d corner = scene.input.rest_positions.row(scene.vertex(64, 0));
  int held = 0;
  for (Eigen::Index v = 0; v < scene.input.rest_positions.rows(); ++v) {
    const double r = (scene.input.rest_positions.row(v).transpose() - corner).norm();
    const bool pinned =
        std::binary_search(scene.pinned_vertices.begin(), scene.pinned_vertices.end(), v);
    EXPECT_EQ(pinned, r <= 0.05 + 1e-9) << v;
    held += pinned;
  }
  // The grid points (i, j) with i² + j² ≤ 3.2² cells²: rows of 4, 4, 3 and 2.
  EXPECT_EQ(held, 13);
  for (const std::string bad : {"top-left:0", "top-left:-0.1", "top-left:x",
                                "top-left:", "top-left:0.1m", "top-middle:0.1"}) {
    spec.pins = {bad};
    EXPECT_THROW(build_sheet(spec), InvalidSheetError) << bad;
  }
  spec.shape = SheetShape::disc;
  spec.columns = spec.rows = 10;
  spec.pins = {"top-left:0.1"};
  EXPECT_THROW(build_sheet(spec), InvalidSheetError);
}

}  // namespace
}  // namespace sd::sim
