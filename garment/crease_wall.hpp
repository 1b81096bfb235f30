#pragma once
// Cloth in a narrow crease of the body (under the arm, between the legs): which of the crease's
// two walls a panel's vertex lies on, and how far from it (docs/garment.md, "Narrow creases").
// Where two walls face each other closer than twice a panel's offset, the offset surfaces of
// both overlap, and the nearest wall is not always the panel's: the back's first row past an
// armhole drawn along the floor of the armpit lay on the arm's wall, where the sleeve lies. The
// panel's seams say which wall is its own: from a seam the panel goes on along d (SeamSide)
// and reaches the wall that faces back against d.

#include <Eigen/Core>
#include <vector>

#include "garment/body_surface.hpp"

namespace sd::garment {

// A point of a panel's boundary and the direction the panel goes on in from it along the body:
// d = n × t, with t the loop's tangent there (the loop runs counter-clockwise seen from outside,
// so d points into the panel) and n the body's normal at the point's nearest body point; on the
// floor of a narrow crease, where that point lies on either wall, n is the mean of the two
// walls' normals (out of the crease).
struct SeamSide {
  Eigen::Vector3d point;
  Eigen::Vector3d inward;  // unit, or zero where the seam says nothing (below)
};

// Every boundary point of a panel's sides (`side_points`, corner to corner, each side's last
// point the next one's first). The side is zero where the tangent runs along the normal, or
// where the point lies between two nearly parallel walls (their normals more than 150° apart:
// a gap between two limbs with no floor), where either wall may be the panel's.
std::vector<SeamSide> seam_sides(const std::vector<Eigen::MatrixX3d>& side_points,
                                 const BodySurface& body, double offset);

struct CreaseWall {
  SurfacePoint point;  // on the wall the cloth lies on (its normal the wall's)
  double offset = 0;   // m, from that wall
  bool moved = false;  // another wall than the nearest, or less than the full offset
};

// The wall of the body the cloth at `p` lies on and its offset from it, for a panel with
// `seams` at `offset` (m) and edge length `reach` (m); `nearest` is the body's point nearest p
// (or what the caller takes for it). Within two edge lengths of a seam, a nearest wall that faces
// along the seam's side direction (by more than 60°) is the other side's: the cloth goes to the
// wall across from it along d, when that faces back against d within 2.5 offsets plus an edge,
// at the point of its tangent plane nearest p. On whichever wall, when another faces it closer
// than 2.5 offsets, the cloth keeps 0.4 of that width from it instead of the full offset (two
// panels in one crease then leave a fifth of it between them).
CreaseWall crease_wall(const BodySurface& body, const std::vector<SeamSide>& seams,
                       const Eigen::Vector3d& p, const SurfacePoint& nearest, double offset,
                       double reach);

}  // namespace sd::garment
