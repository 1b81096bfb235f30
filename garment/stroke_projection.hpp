#pragma once
// Strokes to 3D polylines on the body. A stroke drawn in a view is cast along the view's rays
// onto the body and pushed out along the surface normal by its offset; a ray that misses takes
// its depth from the neighbouring hits. points3d curves are used as given, snapped to the
// offset surface when on_body is true.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "garment/body_surface.hpp"
#include "garment/garment_request.hpp"

namespace sd::garment {

// Dense sampling of projected curves: about one point per this many metres.
inline constexpr double kCurveSampleSpacing = 0.005;

// How a view maps its 2D plane points (metres) to rays in the world.
struct ViewFrame {
  Eigen::Vector3d right;         // world direction of the plane's +x
  Eigen::Vector3d up;            // world direction of the plane's +y
  Eigen::Vector3d direction;     // viewing direction (into the scene), unit
  Eigen::Vector3d plane_origin;  // world point of plane coordinates (0, 0)
  bool perspective = false;
  Eigen::Vector3d eye;  // perspective only

  // The world point of plane coordinates (u, v).
  Eigen::Vector3d plane_point(const Eigen::Vector2d& uv) const;
  // Ray through (u, v): origin outside the scene (`far` metres back for orthographic views).
  void ray(const Eigen::Vector2d& uv, double far, Eigen::Vector3d& origin,
           Eigen::Vector3d& unit_direction) const;
};

// front: camera at +z looking -z (plane x right, y up); back: at -z looking +z (x = -u);
// left: the body's left side, camera at +x looking -x (z = -u); right: camera at -x (z = u).
// Orthographic planes pass through the body's vertical axis (x = 0 or z = 0).
ViewFrame view_frame(const ViewSpec& view);

struct ProjectedCurve {
  std::string id;
  std::string json_path;    // of the curve spec
  Eigen::MatrixX3d points;  // #P by 3 world metres, spacing ~kCurveSampleSpacing
  bool closed = false;      // points wrap around (the last point is not repeated)
  double offset = 0;
  bool on_body = true;
  int misses = 0;  // samples whose ray missed the body (depth interpolated)
};

// Samples a Catmull-Rom spline (centripetal) through `points` (or the polyline when !smooth) at
// about `spacing`. #P by D.
template <int D>
std::vector<Eigen::Matrix<double, D, 1>> sample_stroke(
    const std::vector<Eigen::Matrix<double, D, 1>>& points, bool closed, bool smooth,
    double spacing);

// Projects one curve (body may be null only for points3d curves with on_body false).
// Throws SketchError when the curve crosses itself or misses the body entirely.
ProjectedCurve project_curve(const GarmentRequest& sketch, const CurveSpec& curve,
                             const BodySurface* body);

// All curves of the sketch, in file order.
std::vector<ProjectedCurve> project_curves(const GarmentRequest& sketch, const BodySurface& body);

// Index pair (i, j) of the first two non-adjacent segments of a polyline that cross (2D) or come
// closer than `tolerance` (3D); {-1, -1} when none do.
std::pair<int, int> find_self_intersection(const std::vector<Eigen::Vector2d>& polyline,
                                           bool closed);
std::pair<int, int> find_self_intersection(const Eigen::MatrixX3d& polyline, bool closed,
                                           double tolerance);

// Index pair (i, j) of the first two non-adjacent segments of a 3D polyline (#P by 3) that cross
// seen from outside the body: segments less than `reach` metres apart whose outward directions
// (`outward`: #P unit vectors, the body's normal nearest each point) agree within 60°, and that
// cross in the plane across their mean outward direction. A curve that loops back over itself
// off the body (a figure-of-eight hem with its strands a few centimetres apart in depth) passes
// the 3D test above, but a panel bounded by it folds over itself. {-1, -1} when none do.
std::pair<int, int> find_crossing_seen_from_outside(const Eigen::MatrixX3d& polyline, bool closed,
                                                    const std::vector<Eigen::Vector3d>& outward,
                                                    double reach);

}  // namespace sd::garment
