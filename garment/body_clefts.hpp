#pragma once
// Clefts of the body: concave creases where two body surfaces face each other a few centimetres
// apart and open sideways (the seat's cleft, the gap between the thighs), so that the offset
// surfaces of the two sides meet along a ridge in front of the crease. Cloth laid on that ridge
// is held by both walls at once; a seam junction there (several panels pulling on one point)
// keeps the drape from resting (docs/garment.md, "Junctions in a cleft"). Found from the body's
// geometry alone, not from one body's coordinates.

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "garment/body_surface.hpp"
#include "garment/garment_mesh.hpp"

namespace sd::garment {

struct CleftProbe {
  // m: the circle around the point, in the plane across the body's normal, on which the body's
  // closest points are looked up (the walls of a crease narrower than about twice this are found).
  double radius = 0.02;
  int directions = 12;
  // A crease opening downwards (the armpit's apex, the crotch) lets hanging cloth fall out of it;
  // only openings within this angle of the horizontal count (degrees).
  double max_opening_tilt_deg = 45.0;
  // m: the offset of the garment's curves from the body. A crease is a cleft where its walls are
  // closer than twice the offset plus `slack`: there the offset surfaces of the two walls meet
  // and the cloth cannot lie at the offset from both. Measured: the Collada human's seat, at
  // the strapless dress's junction, 1.42 cm (offset 1 cm; 2.05 cm on the mesh of 28 November); the
  // built-in body's front armpit under the cropped jacket's underarm junction, 3.03 cm (offset 1.2
  // cm: a crease with room for it).
  double offset = 0.01;
  double slack = 0.005;
};

struct BodyCleft {
  Eigen::Vector3d wall_a = Eigen::Vector3d::Zero();  // the two facing walls' points, m
  Eigen::Vector3d wall_b = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal_a = Eigen::Vector3d::Zero();  // unit, the walls' outward normals there
  Eigen::Vector3d normal_b = Eigen::Vector3d::Zero();
  Eigen::Vector3d opening = Eigen::Vector3d::Zero();  // unit: the way out of the crease
  double width = 0.0;                                 // m, between the two walls' points

  // m: how far `p` lies out from each wall's tangent plane (negative behind it).
  double clearance_a(const Eigen::Vector3d& p) const { return (p - wall_a).dot(normal_a); }
  double clearance_b(const Eigen::Vector3d& p) const { return (p - wall_b).dot(normal_b); }
};

// The cleft `p` (a point on or a little off the body) lies in, if any: two closest points of
// the body, seen from the probe circle round p, on walls whose normals are more than 90° apart,
// each in front of the other's tangent plane (concave: at a convex edge each lies behind), both
// within p's distance from the body plus the probe radius, and the crease opening (their
// normals' mean) within the probe's tilt of the horizontal, and the walls closer than twice the
// offset (plus the slack).
std::optional<BodyCleft> cleft_at(const BodySurface& body, const Eigen::Vector3d& p,
                                  const CleftProbe& probe = {});

// A seam junction of three or more panels lying in a cleft and held by both its walls.
struct JunctionInCleft {
  Eigen::Vector3d where = Eigen::Vector3d::Zero();  // the junction's mesh vertex, m
  std::vector<int> panels;                          // indices into garment.panels, ascending
  BodyCleft cleft;
  double clearance_a = 0.0;  // m, from each wall's tangent plane (both below the offset)
  double clearance_b = 0.0;
};

// Every mesh vertex shared by three or more panels that lies in a cleft and nearer than the
// offset to both its walls: the cloth there bridges the cleft, held by both sides (the strapless
// dress's junction in the seat: 0.1 and 0.2 cm from the cheeks, offset 1 cm). A junction at
// its offset or more from one wall lies on the other wall's side: its panels follow the crease,
// each on its own wall (garment/crease_wall.hpp; the cropped jacket's underarm: 1.13 and 1.53 cm
// from torso and arm, offset 1.2 cm), and is not returned. Of a junction and its mirror image
// (x → −x) only the one with x ≥ 0.
std::vector<JunctionInCleft> find_junctions_in_clefts(const Garment& garment,
                                                      const BodySurface& body,
                                                      const CleftProbe& probe = {});

}  // namespace sd::garment
