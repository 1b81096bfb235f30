#include "src/render/camera.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace sd::render {
namespace {

constexpr std::array kViews{ViewName::kFront, ViewName::kBack,         ViewName::kLeft,
                            ViewName::kRight, ViewName::kThreeQuarter, ViewName::kTop};

double radians(double degrees) {
  return degrees * std::numbers::pi / 180.0;
}

std::array<Eigen::Vector3d, 8> corners(const meshing::BoundingBox& box) {
  std::array<Eigen::Vector3d, 8> out;
  for (int i = 0; i < 8; ++i)
    out[i] = {(i & 1) ? box.max.x() : box.min.x(), (i & 2) ? box.max.y() : box.min.y(),
              (i & 4) ? box.max.z() : box.min.z()};
  return out;
}

}  // namespace

ViewName parse_view_name(std::string_view text) {
  std::string t(text);
  std::replace(t.begin(), t.end(), '_', '-');
  for (ViewName v : kViews)
    if (view_name(v) == t) return v;
  throw ViewError(
      fmt::format("unknown view '{}': use front, back, left, right, three-quarter or top", text));
}

std::string view_name(ViewName view) {
  switch (view) {
    case ViewName::kFront:
      return "front";
    case ViewName::kBack:
      return "back";
    case ViewName::kLeft:
      return "left";
    case ViewName::kRight:
      return "right";
    case ViewName::kThreeQuarter:
      return "three-quarter";
    case ViewName::kTop:
      return "top";
  }
  return "front";
}

std::span<const ViewName> all_views() {
  return kViews;
}

void validate_camera(const Camera& camera) {
  if (!camera.eye.allFinite() || !camera.target.allFinite() || !camera.up.allFinite())
    throw ViewError("the camera has a non-finite eye, target or up vector");
  const Eigen::Vector3d forward = camera.target - camera.eye;
  if (forward.norm() < 1e-9) throw ViewError("the camera's eye and target are the same point");
  if (camera.up.norm() < 1e-12 || forward.normalized().cross(camera.up.normalized()).norm() < 1e-6)
    throw ViewError("the camera's up vector is parallel to its viewing direction");
  if (!(camera.fov_y_deg > 0 && camera.fov_y_deg < 180))
    throw ViewError(fmt::format("field of view {} degrees is outside (0, 180)", camera.fov_y_deg));
}

Camera frame_view(ViewName view, const meshing::BoundingBox& box, double aspect, double margin) {
  const double elevation = radians(kViewElevationDeg);
  if (view == ViewName::kTop) return frame_direction({0, -1, 0}, {0, 0, -1}, box, aspect, margin);
  // Horizontal direction from the figure toward the camera.
  const Eigen::Vector3d side = view == ViewName::kFront   ? Eigen::Vector3d(0, 0, 1)
                               : view == ViewName::kBack  ? Eigen::Vector3d(0, 0, -1)
                               : view == ViewName::kLeft  ? Eigen::Vector3d(1, 0, 0)
                               : view == ViewName::kRight ? Eigen::Vector3d(-1, 0, 0)
                                                          : Eigen::Vector3d(1, 0, 1).normalized();
  const Eigen::Vector3d toward_camera =
      std::cos(elevation) * side + std::sin(elevation) * Eigen::Vector3d::UnitY();
  return frame_direction(-toward_camera, Eigen::Vector3d::UnitY(), box, aspect, margin);
}

Camera frame_direction(const Eigen::Vector3d& forward_in, const Eigen::Vector3d& up_in,
                       const meshing::BoundingBox& box, double aspect, double margin,
                       double fov_y_deg) {
  const Eigen::Vector3d forward = forward_in.normalized();
  const Eigen::Vector3d right = forward.cross(up_in).normalized();
  const Eigen::Vector3d up = right.cross(forward);
  const double ty = std::tan(radians(fov_y_deg) / 2) * (1 - margin);
  const double tx = ty * aspect;
  // Guard against a degenerate (point or flat) box: frame at least a millimetre.
  const double radius = std::max(0.5 * box.extent().norm(), 1e-3);

  Eigen::Vector3d target = box.centre();
  double distance = radius;
  // Two passes: fit the distance for the current target, then centre the projected box and
  // refit (the second pass changes the distance by a few percent at most for oblique views).
  for (int pass = 0; pass < 2; ++pass) {
    distance = 0;
    for (const Eigen::Vector3d& c : corners(box)) {
      const Eigen::Vector3d d = c - target;
      const double depth = d.dot(forward);  // toward the far side is positive
      // Corner inside the frustum when |x| <= tx (distance + depth), likewise y.
      distance = std::max(
          {distance, std::abs(d.dot(right)) / tx - depth, std::abs(d.dot(up)) / ty - depth});
    }
    distance = std::max(distance, 0.05 * radius);
    if (pass == 1) break;
    // Projected extents at this distance, in tangent units; shift the target so they centre.
    double lo_x = 1e300, hi_x = -1e300, lo_y = 1e300, hi_y = -1e300;
    for (const Eigen::Vector3d& c : corners(box)) {
      const Eigen::Vector3d d = c - target;
      const double z = distance + d.dot(forward);
      lo_x = std::min(lo_x, d.dot(right) / z);
      hi_x = std::max(hi_x, d.dot(right) / z);
      lo_y = std::min(lo_y, d.dot(up) / z);
      hi_y = std::max(hi_y, d.dot(up) / z);
    }
    target += distance * (0.5 * (lo_x + hi_x) * right + 0.5 * (lo_y + hi_y) * up);
  }
  Camera camera;
  camera.target = target;
  camera.eye = target - distance * forward;
  camera.up = up;
  camera.fov_y_deg = fov_y_deg;
  return camera;
}

Eigen::Matrix4d view_matrix(const Camera& camera) {
  const Eigen::Vector3d f = (camera.target - camera.eye).normalized();
  const Eigen::Vector3d s = f.cross(camera.up).normalized();
  const Eigen::Vector3d u = s.cross(f);
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -s.dot(camera.eye);
  m(1, 3) = -u.dot(camera.eye);
  m(2, 3) = f.dot(camera.eye);
  return m;
}

Eigen::Matrix4d perspective_matrix(double fov_y_deg, double aspect, double near, double far) {
  const double f = 1.0 / std::tan(radians(fov_y_deg) / 2);
  Eigen::Matrix4d m = Eigen::Matrix4d::Zero();
  m(0, 0) = f / aspect;
  m(1, 1) = f;
  m(2, 2) = (far + near) / (near - far);
  m(2, 3) = 2 * far * near / (near - far);
  m(3, 2) = -1;
  return m;
}

Eigen::Matrix4d orthographic_matrix(double left, double right, double bottom, double top,
                                    double near, double far) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m(0, 0) = 2 / (right - left);
  m(1, 1) = 2 / (top - bottom);
  m(2, 2) = -2 / (far - near);
  m(0, 3) = -(right + left) / (right - left);
  m(1, 3) = -(top + bottom) / (top - bottom);
  m(2, 3) = -(far + near) / (far - near);
  return m;
}

}  // namespace sd::render
