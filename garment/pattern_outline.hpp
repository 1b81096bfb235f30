#pragma once
// A piece's sewing line as a smooth curve through its outline points: the mesh's boundary
// vertices lie an edge length apart (~30 mm), and a polyline through them shows an angle at each
// one at true scale. Between corners (seam junctions, the points where the outline passes from
// one sketch curve to the next, and sharp turns) the curve is a centripetal Catmull-Rom spline,
// written as cubic Béziers (SVG paths) and densified into a polyline within a chord tolerance
// (the cutting line's offset, DXF polylines, lengths).

#include <Eigen/Core>
#include <vector>

namespace sd::garment {

// One Bézier span from outline point k to k + 1: control points b1, b2 (the ends are the
// points themselves).
struct BezierSpan {
  Eigen::Vector2d b1 = Eigen::Vector2d::Zero(), b2 = Eigen::Vector2d::Zero();
};

struct SmoothOutline {
  std::vector<BezierSpan> spans;  // span k: point k → point k + 1 (cyclically)
  Eigen::MatrixX2d points;        // densified, closed, first point not repeated
  std::vector<Eigen::Index> at;   // row of `points` that is outline point k
  std::vector<bool> corner;       // outline point k is a corner (the curve turns there)
};

// The outline points where the turn from the incoming to the outgoing edge exceeds `max_turn`
// (radians) are marked in `corner` (sized to the outline).
void mark_sharp_turns(const Eigen::MatrixX2d& outline, double max_turn, std::vector<bool>& corner);

// The smooth closed curve through `outline` (closed, first point not repeated): a corner point
// ends the spline on each side (its spans leave along their chords' thirds), elsewhere the
// tangent is centripetal Catmull-Rom's. Each span is densified so that the polyline lies within
// `tolerance` (m) of the Bézier (the bound (3/4)·max|Δ²b| / n² on n chords).
SmoothOutline smooth_outline(const Eigen::MatrixX2d& outline, const std::vector<bool>& corner,
                             double tolerance);

// A point at fraction t (0..1) of the densified curve's length between outline points k and
// k + 1, and the curve's outward normal there (counter-clockwise outline: out is right).
std::pair<Eigen::Vector2d, Eigen::Vector2d> point_on_span(const SmoothOutline& curve, int k,
                                                          double t);

}  // namespace sd::garment
