#include "src/render/camera.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "tests/render/test_scenes.hpp"

namespace sd::render {
namespace {

meshing::BoundingBox figure_box() {
  meshing::BoundingBox box;
  box.min = {-0.35, 0.0, -0.15};
  box.max = {0.35, 1.75, 0.18};
  return box;
}

TEST(Camera, ParsesEveryViewNameAndRejectsOthers) {
  for (ViewName v : all_views()) EXPECT_EQ(parse_view_name(view_name(v)), v);
  EXPECT_EQ(parse_view_name("three_quarter"), ViewName::kThreeQuarter);
  EXPECT_THROW(parse_view_name("sideways"), ViewError);
  EXPECT_THROW(parse_view_name(""), std::invalid_argument);  // ViewError is bad user input
  try {
    parse_view_name("frnt");
  } catch (const ViewError& e) {
    EXPECT_NE(std::string(e.what()).find("three-quarter"), std::string::npos) << e.what();
  }
}

TEST(Camera, NamedViewsSitOnTheNamedSideOfTheFigure) {
  const meshing::BoundingBox box = figure_box();
  const auto eye_offset = [&](ViewName v) {
    const Camera c = frame_view(v, box, 0.75);
    return Eigen::Vector3d(c.eye - c.target);
  };
  // Front on +Z (the figure faces +Z), back on -Z, left on +X (the figure's left), right -X.
  EXPECT_GT(eye_offset(ViewName::kFront).z(), 0);
  EXPECT_NEAR(eye_offset(ViewName::kFront).x(), 0, 1e-9);
  EXPECT_LT(eye_offset(ViewName::kBack).z(), 0);
  EXPECT_GT(eye_offset(ViewName::kLeft).x(), 0);
  EXPECT_NEAR(eye_offset(ViewName::kLeft).z(), 0, 1e-9);
  EXPECT_LT(eye_offset(ViewName::kRight).x(), 0);
  const Eigen::Vector3d q = eye_offset(ViewName::kThreeQuarter);
  EXPECT_NEAR(q.x(), q.z(), 1e-9);
  EXPECT_GT(q.x(), 0);
  const Eigen::Vector3d top = eye_offset(ViewName::kTop);
  EXPECT_NEAR(top.normalized().y(), 1.0, 1e-12);
  // The side views look slightly down, by kViewElevationDeg.
  const Eigen::Vector3d f = eye_offset(ViewName::kFront).normalized();
  EXPECT_NEAR(std::asin(f.y()) * 180 / std::numbers::pi, kViewElevationDeg, 1e-9);
}

// Framing: every corner of the box projects inside the image minus the margin, and the fit is
// tight (some corner touches the margin), for every view and several aspect ratios.
TEST(Camera, FramingFitsTheBoxWithTheMargin) {
  const meshing::BoundingBox box = figure_box();
  for (double aspect : {0.5, 0.75, 1.0, 1.6}) {
    for (ViewName v : all_views()) {
      const Camera c = frame_view(v, box, aspect, 0.1);
      const ImageSize size{static_cast<int>(1000 * aspect), 1000};
      double worst = 0;  // largest |NDC| coordinate over the corners
      double lo_x = 1e9, hi_x = -1e9, lo_y = 1e9, hi_y = -1e9;
      for (int i = 0; i < 8; ++i) {
        const Eigen::Vector3d p((i & 1) ? box.max.x() : box.min.x(),
                                (i & 2) ? box.max.y() : box.min.y(),
                                (i & 4) ? box.max.z() : box.min.z());
        Eigen::Vector2d px = Eigen::Vector2d::Zero();
        ASSERT_TRUE(test::project(c, p, size, px));
        const double nx = px.x() / size.width * 2 - 1, ny = 1 - px.y() / size.height * 2;
        worst = std::max({worst, std::abs(nx), std::abs(ny)});
        lo_x = std::min(lo_x, nx), hi_x = std::max(hi_x, nx);
        lo_y = std::min(lo_y, ny), hi_y = std::max(hi_y, ny);
      }
      SCOPED_TRACE(view_name(v) + " aspect " + std::to_string(aspect));
      EXPECT_LE(worst, 0.9 + 0.01);
      EXPECT_GE(worst, 0.9 - 0.05);  // tight up to the centring pass
      // Centred: the projected box is symmetric about the image centre on its tight axis.
      EXPECT_NEAR(lo_x + hi_x, 0, 0.05);
      EXPECT_NEAR(lo_y + hi_y, 0, 0.05);
    }
  }
}

TEST(Camera, ViewMatrixPutsTheEyeAtTheOriginLookingDownMinusZ) {
  Camera c;
  c.eye = {1, 2, 3};
  c.target = {0, 1, -1};
  c.up = {0, 1, 0};
  const Eigen::Matrix4d m = view_matrix(c);
  EXPECT_LT((m * c.eye.homogeneous()).head<3>().norm(), 1e-12);
  const Eigen::Vector3d t = (m * c.target.homogeneous()).head<3>();
  EXPECT_NEAR(t.x(), 0, 1e-12);
  EXPECT_NEAR(t.y(), 0, 1e-12);
  EXPECT_NEAR(t.z(), -(c.target - c.eye).norm(), 1e-12);
  const Eigen::Matrix3d rotation = m.topLeftCorner<3, 3>();
  EXPECT_NEAR(rotation.determinant(), 1.0, 1e-12);
}

TEST(Camera, PerspectiveMapsNearAndFarToTheDepthRange) {
  const Eigen::Matrix4d p = perspective_matrix(40, 1.5, 0.5, 20);
  const auto ndc_z = [&](double depth) {
    const Eigen::Vector4d clip = p * Eigen::Vector4d(0.3, -0.2, -depth, 1);
    return clip.z() / clip.w();
  };
  EXPECT_NEAR(ndc_z(0.5), -1, 1e-12);
  EXPECT_NEAR(ndc_z(20), 1, 1e-12);
  // A point on the top edge of the field of view lands on y = 1.
  const double depth = 3, y = depth * std::tan(20 * std::numbers::pi / 180);
  const Eigen::Vector4d clip = p * Eigen::Vector4d(0, y, -depth, 1);
  EXPECT_NEAR(clip.y() / clip.w(), 1, 1e-12);
}

TEST(Camera, ValidationRejectsUnusableCameras) {
  Camera c;
  EXPECT_NO_THROW(validate_camera(c));
  Camera same = c;
  same.target = same.eye;
  EXPECT_THROW(validate_camera(same), ViewError);
  Camera parallel = c;
  parallel.up = parallel.target - parallel.eye;
  EXPECT_THROW(validate_camera(parallel), ViewError);
  Camera wide = c;
  wide.fov_y_deg = 180;
  EXPECT_THROW(validate_camera(wide), ViewError);
  Camera nan = c;
  nan.eye.x() = std::nan("");
  EXPECT_THROW(validate_camera(nan), ViewError);
}

}  // namespace
}  // namespace sd::render
