#include "garment/crease_wall.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <optional>

namespace sd::garment {
namespace {

// Two body surfaces face each other across a crease when their normals are more than 120°
// apart...
constexpr double kFacingWalls = -0.5;
// ... and the crease is narrow when they are less than this many offsets apart (along the
// normal): cloth there cannot be a full offset from both, and keeps kCreaseShare of the width.
constexpr double kNarrowCrease = 2.5;
constexpr double kCreaseShare = 0.4;
// A crease has a floor when its walls' normals sum to at least this (less than 150° apart).
constexpr double kCreaseFloor = 0.5;
// The seams decide which wall is the panel's within this many edge lengths of its boundary...
constexpr double kSeamReach = 2.0;
// ... a wall is the other side's when its normal faces along the seam's side direction d by
// more than this (60°), and the panel's own across from it faces back against d as much...
constexpr double kSideFacing = 0.5;
// ... within this many offsets plus an edge length along d.
constexpr double kCreaseReach = 2.5;
// m: rays start this far out of the wall they leave, so as not to hit it again.
constexpr double kRayStart = 1e-6;

// The wall facing `s` across a crease narrower than kNarrowCrease offsets, if any.
std::optional<SurfacePoint> wall_across(const BodySurface& body, const SurfacePoint& s,
                                        double offset) {
  auto across = body.first_hit(s.position + kRayStart * s.normal, s.normal);
  if (across && across->normal.dot(s.normal) < kFacingWalls &&
      across->distance < kNarrowCrease * offset)
    return across;
  return std::nullopt;
}

}  // namespace

std::vector<SeamSide> seam_sides(const std::vector<Eigen::MatrixX3d>& side_points,
                                 const BodySurface& body, double offset) {
  std::vector<Eigen::Vector3d> loop;
  for (const auto& side : side_points)
    for (Eigen::Index r = 0; r + 1 < side.rows(); ++r) loop.emplace_back(side.row(r).transpose());
  std::vector<SeamSide> seams;
  seams.reserve(loop.size());
  const size_t n = loop.size();
  for (size_t k = 0; k < n; ++k) {
    const Eigen::Vector3d t = loop[(k + 1) % n] - loop[(k + n - 1) % n];
    const SurfacePoint s = body.closest_point(loop[k]);
    Eigen::Vector3d normal = s.normal;
    if (offset > 0)
      if (const auto across = wall_across(body, s, offset)) normal = s.normal + across->normal;
    const Eigen::Vector3d d = normal.cross(t);
    const bool known = normal.norm() > kCreaseFloor && d.norm() > 0.5 * normal.norm() * t.norm();
    seams.push_back({loop[k], known ? Eigen::Vector3d(d.normalized()) : Eigen::Vector3d::Zero()});
  }
  return seams;
}

CreaseWall crease_wall(const BodySurface& body, const std::vector<SeamSide>& seams,
                       const Eigen::Vector3d& p, const SurfacePoint& nearest, double offset,
                       double reach) {
  CreaseWall w{nearest, offset, false};
  if (offset <= 0) return w;
  const SeamSide* seam = nullptr;
  double closest = kSeamReach * reach;
  for (const SeamSide& side : seams)
    if (const double d = (side.point - p).norm(); d < closest) {
      closest = d;
      seam = &side;
    }
  SurfacePoint& s = w.point;
  if (seam != nullptr && s.normal.dot(seam->inward) > kSideFacing) {
    const Eigen::Vector3d& d = seam->inward;
    if (const auto own = body.first_hit(s.position + kRayStart * s.normal, d);
        own && own->normal.dot(d) < -kSideFacing && own->distance < kCreaseReach * offset + reach) {
      // Along the own wall's normal (its tangent plane's point nearest p), so that neighbours
      // stay apart.
      s = *own;
      s.position = p - (p - own->position).dot(own->normal) * own->normal;
      w.moved = true;
    }
  }
  if (const auto across = wall_across(body, s, offset)) {
    w.offset = std::min(offset, kCreaseShare * across->distance);
    w.moved = w.moved || w.offset < offset;
  }
  return w;
}

}  // namespace sd::garment
