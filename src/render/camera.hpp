#pragma once
// Cameras for previews: named views around a figure and explicit eye/target/fov cameras.
// Conventions (the project frame): metres, +Y up, the mannequin faces +Z, so its left side is
// at +X. Images have their origin at the top-left.

#include <Eigen/Core>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

#include "meshing/tri_mesh.hpp"

namespace sd::render {

// A view name the renderer does not know. Bad user input (exit code 2 in the CLI).
class ViewError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// Named views. The camera sits on the named side of the figure and looks at it:
//   front          on +Z looking toward -Z (sees the face and chest)
//   back           on -Z
//   left           on +X: the figure's left side
//   right          on -X: the figure's right side
//   three-quarter  between front and left, 45° from each (azimuth 45° toward +X)
//   top            above, looking down -Y with -Z up in the image (for flat patches in XZ)
// All but `top` look slightly down (kViewElevationDeg) so the ground and shadow show.
enum class ViewName { kFront, kBack, kLeft, kRight, kThreeQuarter, kTop };

inline constexpr double kViewElevationDeg = 8.0;
inline constexpr double kDefaultFovYDeg = 30.0;
// Fraction of the image (per side, of the half-extent) kept free around the framed box.
inline constexpr double kDefaultFramingMargin = 0.06;

// "front", "back", "left", "right", "three-quarter" (also "three_quarter"), "top".
// Throws ViewError with the list of valid names.
ViewName parse_view_name(std::string_view text);
std::string view_name(ViewName view);  // the canonical spelling, used for file names
std::span<const ViewName> all_views();

// A pinhole camera. `up` need not be orthogonal to the view direction, only not parallel.
struct Camera {
  Eigen::Vector3d eye{0, 1, 5};
  Eigen::Vector3d target{0, 1, 0};
  Eigen::Vector3d up{0, 1, 0};
  double fov_y_deg = kDefaultFovYDeg;  // vertical field of view, in (0, 180)
};

// Checks that the camera is usable (finite, eye != target, up not parallel to the view, fov in
// (0, 180)). Throws ViewError naming the problem.
void validate_camera(const Camera& camera);

// The camera for `view` that fits `box` into an image of width/height `aspect`, leaving
// `margin` of the image free on the tightest side. The direction is fixed by the view; the
// distance is the smallest at which all eight box corners project inside the margin, and the
// target is shifted so the projected box is centred.
Camera frame_view(ViewName view, const meshing::BoundingBox& box, double aspect,
                  double margin = kDefaultFramingMargin);

// The same for an arbitrary viewing direction `forward` (from the eye toward the box) and `up`.
Camera frame_direction(const Eigen::Vector3d& forward, const Eigen::Vector3d& up,
                       const meshing::BoundingBox& box, double aspect,
                       double margin = kDefaultFramingMargin, double fov_y_deg = kDefaultFovYDeg);

// World → camera (OpenGL convention: the camera looks down its -Z).
Eigen::Matrix4d view_matrix(const Camera& camera);
// Camera → clip space, OpenGL depth range [-1, 1]; near/far in metres, 0 < near < far.
Eigen::Matrix4d perspective_matrix(double fov_y_deg, double aspect, double near, double far);
// Camera → clip space for an orthographic box (used for the shadow map).
Eigen::Matrix4d orthographic_matrix(double left, double right, double bottom, double top,
                                    double near, double far);

}  // namespace sd::render
