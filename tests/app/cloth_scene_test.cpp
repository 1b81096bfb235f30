// The simulator's model of a sketch's garment takes each panel's `ease` into account: a panel
// cut smaller than drawn has shorter rest lengths (its gradient operators grow by 1/ease) and
// less cloth (rest area and mass by ease²); a panel with ease 1 is exactly build_cloth_model.

#include <gtest/gtest.h>

#include <string>

#include "garment/sketch_file.hpp"
#include "sim/cloth_model.hpp"
#include "src/app/cloth_scene.hpp"

namespace sd::app {
namespace {

// Two panels on the front of the built-in body's torso, sewn along x = 0.1: "left" with the
// given ease, "right" as drawn.
std::string two_patches(double ease) {
  return R"({
    "curves": [
      { "id": "top_l",   "view": "front", "points": [[-0.1, 1.3], [0.1, 1.3]] },
      { "id": "seam",    "view": "front", "points": [[0.1, 1.3], [0.1, 1.1]] },
      { "id": "bottom_l","view": "front", "points": [[0.1, 1.1], [-0.1, 1.1]] },
      { "id": "side_l",  "view": "front", "points": [[-0.1, 1.1], [-0.1, 1.3]] },
      { "id": "top_r",   "view": "front", "points": [[0.1, 1.3], [0.14, 1.3]] },
      { "id": "side_r",  "view": "front", "points": [[0.14, 1.3], [0.14, 1.1]] },
      { "id": "bottom_r","view": "front", "points": [[0.14, 1.1], [0.1, 1.1]] }
    ],
    "panels": [
      { "id": "left", "boundary": ["top_l", "seam", "bottom_l", "side_l"], "ease": )" +
         std::to_string(ease) + R"( },
      { "id": "right", "boundary": ["top_r", "side_r", "bottom_r", "seam"] }
    ]
  })";
}

TEST(ClothScene, PanelEaseScalesRestShapeAndMass) {
  constexpr double kEase = 0.9;
  const ClothScene eased = build_cloth_scene(garment::parse_sketch(two_patches(kEase), "eased.json"));
  const ClothScene plain = build_cloth_scene(garment::parse_sketch(two_patches(1.0), "plain.json"));
  ASSERT_EQ(eased.input.triangles.rows(), plain.input.triangles.rows());
  ASSERT_EQ(eased.triangle_ease.size(), eased.input.triangles.rows());
  EXPECT_EQ(plain.triangle_ease.size(), 0) << "no ease recorded when every panel is as drawn";

  const sim::ClothModel a = build_scene_model(eased);
  const sim::ClothModel b = build_scene_model(plain);
  // ease 1 everywhere: exactly the plain model.
  const sim::ClothModel reference = sim::build_cloth_model(plain.input, plain.fabric);
  EXPECT_EQ(b.mass, reference.mass);

  int eased_triangles = 0;
  double left_area = 0.0, right_area = 0.0;
  for (size_t t = 0; t < a.triangles.size(); ++t) {
    const double e = eased.triangle_ease(static_cast<Eigen::Index>(t));
    ASSERT_TRUE(e == kEase || e == 1.0) << e;
    const sim::TriangleElement& x = a.triangles[t];
    const sim::TriangleElement& y = b.triangles[t];
    ASSERT_EQ(x.vertices, y.vertices);
    EXPECT_NEAR(x.rest_area, e * e * y.rest_area, 1e-15);
    EXPECT_TRUE(x.du.isApprox(y.du / e, 1e-12));
    EXPECT_TRUE(x.dv.isApprox(y.dv / e, 1e-12));
    if (e == kEase) {
      ++eased_triangles;
      left_area += y.rest_area;
    } else {
      right_area += y.rest_area;
    }
  }
  EXPECT_GT(eased_triangles, 0);
  EXPECT_LT(eased_triangles, static_cast<int>(a.triangles.size()));
  // Lumped masses follow the rest areas: the eased panel weighs ease² of its drawn area.
  const double density = plain.fabric.area_density;
  EXPECT_NEAR(a.mass.sum(), density * (kEase * kEase * left_area + right_area), 1e-12);
  EXPECT_NEAR(b.mass.sum(), density * (left_area + right_area), 1e-12);
  // Bending is scale-free: hinge rest angles and weights do not change.
  ASSERT_EQ(a.hinges.size(), b.hinges.size());
  for (size_t h = 0; h < a.hinges.size(); ++h) EXPECT_EQ(a.hinges[h].rest_angle, b.hinges[h].rest_angle);
}

// A sheet with "layers": copies stacked by layer_offset and turned by layer_turn about the
// vertical through the centre, one group each; self-collision is off for sheets unless asked and
// on for garments.
TEST(ClothScene, SheetLayersAndTheSelfCollisionDefault) {
  const std::string sheet = R"({
    "body": { "mesh": "none" },
    "sheet": { "size": [0.4, 0.4], "resolution": [4, 4], "orientation": "horizontal",
               "centre": [0, 1, 0], "layers": 3, "layer_offset": [0.01, 0.05, 0],
               "layer_turn": 90 }
  })";
  const garment::Sketch sketch = garment::parse_sketch(sheet, "layers.json");
  const ClothScene scene = build_cloth_scene(sketch);
  ASSERT_EQ(scene.input.rest_positions.rows(), 3 * 25);
  ASSERT_EQ(scene.input.triangles.rows(), 3 * 32);
  EXPECT_EQ(scene.group_names.size(), 3u);
  EXPECT_EQ(scene.triangle_group(32), 1);
  EXPECT_EQ(scene.input.triangles(32, 0), scene.input.triangles(0, 0) + 25);
  for (int i = 0; i < 25; ++i) {
    const Eigen::Vector3d p = scene.start.row(i).transpose() - Eigen::Vector3d(0, 1, 0);
    // Layer 2: turned 180° about y and moved by twice the offset.
    const Eigen::Vector3d q = scene.start.row(50 + i).transpose() - Eigen::Vector3d(0, 1, 0);
    EXPECT_TRUE(q.isApprox(Eigen::Vector3d(-p.x() + 0.02, p.y() + 0.1, -p.z()), 1e-12)) << i;
  }
  EXPECT_FALSE(simulation_settings(sketch).self_contact.enabled);
  const std::string asked = R"({
    "body": { "mesh": "none" }, "sheet": {}, "simulate": { "self_collision": true } })";
  EXPECT_TRUE(simulation_settings(garment::parse_sketch(asked, "asked.json")).self_contact.enabled);
  EXPECT_TRUE(simulation_settings(garment::parse_sketch(two_patches(1.0), "garment.json"))
                  .self_contact.enabled);
}

}  // namespace
}  // namespace sd::app
