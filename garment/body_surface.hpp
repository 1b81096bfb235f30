#pragma once
// Geometric queries on the body mesh (closest point, first ray hit, smooth normal), behind a
// header without CGAL: the AABB tree lives in body_surface.cpp only.

#include <Eigen/Core>
#include <memory>
#include <optional>

#include "garment/body_landmarks.hpp"
#include "meshing/tri_mesh.hpp"

namespace sd::garment {

struct SurfacePoint {
  Eigen::Vector3d position;  // on the body surface
  Eigen::Vector3d normal;    // unit, outward: vertex normals interpolated barycentrically
  int face = -1;             // body triangle
  double distance = 0;       // from the query point (closest point) or the ray origin (hit)
  // closest_point only: another triangle is as near (within 1e-10 m): the point lies on an
  // edge or corner they share, or another surface point is as near (a point on a symmetric
  // body's mirror plane); the face (and the point, in the second case) is the tree's choice.
  bool tied = false;
};

class BodySurface {
 public:
  // Builds the AABB tree (a few ms for 10k triangles). The mesh is copied.
  explicit BodySurface(const meshing::TriMesh& mesh);
  ~BodySurface();
  BodySurface(BodySurface&&) noexcept;
  BodySurface& operator=(BodySurface&&) noexcept;

  // Closest point of the surface to `p`.
  SurfacePoint closest_point(const Eigen::Vector3d& p) const;
  // The same point, searched from `near`, a surface point close to the answer (the previous
  // query's, when queries move in small steps): it bounds the search from the start instead of
  // a nearest-neighbour lookup among the triangles (the t-shirt's fill: 30 % less time). The
  // result does not depend on `near`; a `near` without a face (default) is no hint.
  SurfacePoint closest_point(const Eigen::Vector3d& p, const SurfacePoint& near) const;

  // First intersection of the ray origin + t·direction, t > 0; empty when the ray misses.
  std::optional<SurfacePoint> first_hit(const Eigen::Vector3d& origin,
                                        const Eigen::Vector3d& direction) const;

  // Signed distance of `p` from the surface: positive on the side the normal points to.
  double signed_distance(const Eigen::Vector3d& p) const;

  // The point on the offset surface (`offset` metres out along the normal) nearest to `p`.
  Eigen::Vector3d snap_to_offset(const Eigen::Vector3d& p, double offset) const;

  // Whether `p` lies in a gap between two parts of the body (between a hanging arm and the
  // torso, between the legs) rather than near one of them: more than 5 mm outside the offset
  // surface, with the body across the gap (along the way out from the nearest point) at most
  // a few times as far as the nearest point, both measured to the offset surface
  // (body_surface.cpp). A seam written there bridges the gap (stroke_projection.cpp).
  bool in_gap(const Eigen::Vector3d& p, double offset) const;

  const meshing::TriMesh& mesh() const;
  const meshing::BoundingBox& box() const;
  // The body's landmarks (body_landmarks.hpp), found on the first call (about 20 ms for the
  // built-in body) and kept: every garment built on this surface (the quality gate's trials
  // rebuild it) asks again. nullptr when the body is not a standing figure.
  const BodyLandmarks* landmarks() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sd::garment
