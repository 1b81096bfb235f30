#pragma once
// The curve network: projected curves cut into edges between junction nodes. Endpoints closer
// than the junction tolerance become one node; an endpoint on the interior of another curve
// splits that curve there (a T-junction). Curves of mirrored panels get mirror copies across
// x = 0 ("<id>.mirror"); a curve lying on the plane is its own mirror.

#include <Eigen/Core>
#include <set>
#include <string>
#include <vector>

#include "garment/garment_request.hpp"
#include "garment/stroke_projection.hpp"

namespace sd::garment {

// A curve of a mirrored panel within this fraction of the junction tolerance of x = 0 all along
// (3.75 mm at the default 1.5 cm) lies on the plane: it is snapped onto it and is its own mirror.
inline constexpr double kOnPlaneFraction = 0.25;

struct NetworkEdge {
  int curve = -1;           // NetworkCurve index
  int from = -1, to = -1;   // node indices
  Eigen::MatrixX3d points;  // #P by 3 polyline from node `from` to node `to` (exact ends)
  double length = 0;        // metres
  int orbit = -1;           // the original edge of a mirror copy; itself for originals
};

struct NetworkCurve {
  std::string id;  // "side_l", or "side_l.mirror" for a copy
  int spec = -1;   // index into Sketch::curves
  bool mirror_copy = false;
  bool closed = false;
  std::vector<int> edges;  // in curve order
  std::vector<int> nodes;  // edges.size() + 1 nodes along the curve (closed: first == last)
};

// A junction of mirrored curves moved onto the mirror plane x = 0 from farther than half the
// junction tolerance: there it joins its mirror copy, although the two were farther apart than
// the tolerance. Kept to explain a seam that then meets only at that point.
struct PlaneSnap {
  Eigen::Vector3d at = Eigen::Vector3d::Zero();  // m, on x = 0
  double from_plane = 0;                         // m, |x| before the move
  std::vector<std::string> ends;                 // "the end of 'hem_f'", ...
};

// Curve ends joined to the interior of another curve (a T-junction) because they lay within
// the junction tolerance of it. Kept to explain an error at that junction by its cause (trial
// 44, P1: a sleeve hem ending 1.9 cm from a side seam split it, and the errors spoke of a 2.4 cm
// 'side' and of two curves along one seam).
struct TJoin {
  int node = -1;                                   // the junction in CurveNetwork::nodes
  Eigen::Vector3d from = Eigen::Vector3d::Zero();  // m, where the ends were before the move
  double distance = 0;                             // m, from there to the curve
  std::string curve;                               // the curve split there
  std::vector<std::string> ends;                   // "the end of 'underarm'", ...
};

struct CurveNetwork {
  std::vector<Eigen::Vector3d> nodes;
  std::vector<NetworkEdge> edges;
  std::vector<NetworkCurve> curves;
  std::vector<PlaneSnap> plane_snaps;
  std::vector<TJoin> t_joins;

  // Curve by id ("x.mirror" for a copy; the copy of an on-plane curve is the curve itself);
  // -1 when unknown.
  int find_curve(const std::string& id) const;
};

// Builds the network. `mirrored` holds the ids of the curves that need mirror copies.
// Curves within `tolerance` of x = 0 at an end (or entirely) are snapped onto the plane when
// mirrored, so their copies meet them there exactly.
CurveNetwork build_network(const GarmentRequest& sketch, const std::vector<ProjectedCurve>& curves,
                           const std::set<std::string>& mirrored);

// Polyline length, metres.
double polyline_length(const Eigen::MatrixX3d& points);

// Metres of curve used to estimate a tangent at a junction.
inline constexpr double kJunctionTangentArc = 0.02;

// Unit direction of a polyline (#P by 3, at least 2 points) leaving its first point (at_start)
// or arriving at its last, measured over `reach` metres of it (a third of its length when
// shorter), so a tangent at a junction is not thrown off by the last few millimetres.
Eigen::Vector3d polyline_end_tangent(const Eigen::MatrixX3d& points, bool at_start, double reach);

// Mirror image across x = 0.
inline Eigen::Vector3d mirror_point(const Eigen::Vector3d& p) {
  return {-p.x(), p.y(), p.z()};
}

}  // namespace sd::garment
