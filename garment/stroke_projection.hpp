#pragma once
// Strokes to 3D polylines on the body. A stroke drawn in a view is cast along the view's rays
// onto the body and pushed out along the surface normal by its offset; a ray that misses takes
// its depth from the neighbouring hits. points3d curves are used as given, snapped to the
// offset surface when on_body is true.

#include <Eigen/Core>
#include <optional>
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
  // points3d curves on the body: per written point, how far (m) the snap onto the body moved
  // it, not counting the curve's own "offset" (no more than the point's distance to the skin);
  // -1 for a point given relative to a landmark. Empty for other curves.
  std::vector<double> written_moves;
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

// All curves of the sketch, in file order. Warns (once per file and sentence) when written
// points moved far onto the body (moved_points_warning).
std::vector<ProjectedCurve> project_curves(const GarmentRequest& sketch, const BodySurface& body);

// m: a written [x, y, z] point that the snap onto the body moves farther than this was likely
// written for another body (or another size of it). Measured with `validate`, each design on the
// body it was written for (the 37 designs, 6 examples, 18 files of repro/ and the cleft tests'
// two): the largest move of any written point is 5.35 cm (the cotton shift dress's back
// neckline, written out in the air behind the nape; 53 of the 63 files under 3.2 cm); the
// designs moved to the other body that get as far as joining their curves: 7.7 cm (the Collada
// pencil skirt on the built-in body) to 12.7 cm (trial 36's halter), and the rest fail earlier
// with a curve folded by the snap, whose error names its farthest move (7.5-13.7 cm).
inline constexpr double kWrittenPointMoveLimit = 0.06;

// The sentence (with the file, the curve's JSON path, the point, how far it moved and its nearest
// landmark) when the largest move of a written point of `curves` is above `limit`; "" when none.
std::string moved_points_warning(const GarmentRequest& sketch,
                                 const std::vector<ProjectedCurve>& curves, const BodySurface& body,
                                 double limit = kWrittenPointMoveLimit);

// Index pair (i, j) of the first two non-adjacent segments of a polyline that cross (2D) or come
// closer than `tolerance` (3D); {-1, -1} when none do.
std::pair<int, int> find_self_intersection(const std::vector<Eigen::Vector2d>& polyline,
                                           bool closed);
std::pair<int, int> find_self_intersection(const Eigen::MatrixX3d& polyline, bool closed,
                                           double tolerance);

// The written point of `curve` nearest to `where` (m, world; a point of its projected polyline):
// its index in "points3d" or "points" and its coordinates as written ("(0.165, 1.170, -0.010)",
// or "(0.100, 1.300) in the front view"), for an error to point the designer at. A view point is
// compared in its view's plane; none for a perspective camera's.
struct WrittenPoint {
  int index = 0;
  std::string text;
};
std::optional<WrittenPoint> nearest_written_point(const CurveSpec& curve,
                                                  const Eigen::Vector3d& where);

// Where segments (a, b) and (c, d) cross seen from outside the body: `outward_ab` and
// `outward_cd` (each the sum of the body's nearest normals at the segment's ends; zero means no
// direction) agree within 60°, and the two segments cross properly (neither touching the other's
// line at an end) in the plane across their mean outward direction. The crossing's parameters
// (s along a→b, t along c→d, both in [0, 1]), or nullopt. Shared by a curve crossing itself
// (find_crossing_seen_from_outside) and a panel's outline crossing itself (panel_loop.cpp).
std::optional<Eigen::Vector2d> crossing_seen_from_outside(
    const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
    const Eigen::Vector3d& d, const Eigen::Vector3d& outward_ab, const Eigen::Vector3d& outward_cd);

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
