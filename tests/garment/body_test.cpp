#include "garment/body.hpp"

#include <gtest/gtest.h>

namespace sd::garment {
namespace {

TEST(Body, BuiltinIsNormalisedToYUpAndGivenHeight) {
  const Body body = load_body("builtin");
  const meshing::BoundingBox box = meshing::bounding_box(body.mesh);
  EXPECT_NEAR(box.extent().y(), 1.75, 1e-9);
  EXPECT_NEAR(box.min.y(), 0.0, 1e-12);
  EXPECT_NEAR(box.centre().x(), 0.0, 1e-12);
  EXPECT_EQ(body.raw.up.name(), "+z");
  EXPECT_NEAR(body.raw.height, 10.72, 0.01);
  EXPECT_EQ(body.mesh.face_count(), 8560);
  EXPECT_TRUE(meshing::analyse_topology(body.mesh).closed());
}

TEST(Body, BuiltinFacesPlusZ) {
  // The nose and toes point forward: the front half (z > centre) holds the body's frontmost
  // points near head height and near the floor.
  const Body body = load_body("builtin");
  const meshing::BoundingBox box = meshing::bounding_box(body.mesh);
  double toe_z = -1e9, heel_z = 1e9;
  for (Eigen::Index v = 0; v < body.mesh.vertex_count(); ++v) {
    if (body.mesh.vertices(v, 1) > 0.03) continue;
    toe_z = std::max(toe_z, body.mesh.vertices(v, 2));
    heel_z = std::min(heel_z, body.mesh.vertices(v, 2));
  }
  // Feet stick out forward of the ankle much more than the heel sticks back.
  EXPECT_GT(toe_z - box.centre().z(), box.centre().z() - heel_z);
}

TEST(Body, HeightOptionWins) {
  BodyOptions options;
  options.height = 1.60;
  EXPECT_NEAR(meshing::bounding_box(load_body("builtin", options).mesh).extent().y(), 1.60, 1e-9);
}

TEST(Body, MissingFileIsABodyError) {
  EXPECT_THROW(load_body("/nonexistent/body.obj"), BodyError);
}

TEST(Body, AxisParsing) {
  EXPECT_EQ(AxisDirection::parse("-Z").name(), "-z");
  EXPECT_EQ(AxisDirection::parse("y").name(), "+y");
  EXPECT_THROW(AxisDirection::parse("w"), BodyError);
}

}  // namespace
}  // namespace sd::garment
