#include "garment/body_clefts.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace sd::garment {

std::optional<BodyCleft> cleft_at(const BodySurface& body, const Eigen::Vector3d& p,
                                  const CleftProbe& probe) {
  const SurfacePoint centre = body.closest_point(p);
  const Eigen::Vector3d n = centre.normal;
  // A frame across the normal.
  const Eigen::Vector3d helper =
      std::abs(n.y()) < 0.9 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitX();
  const Eigen::Vector3d t1 = n.cross(helper).normalized();
  const Eigen::Vector3d t2 = n.cross(t1);
  std::vector<SurfacePoint> walls{centre};
  for (int k = 0; k < probe.directions; ++k) {
    const double angle = 2.0 * std::numbers::pi * k / probe.directions;
    walls.push_back(body.closest_point(
        p + probe.radius * (std::cos(angle) * t1 + std::sin(angle) * t2), centre));
  }
  const double reach = centre.distance + probe.radius;
  const double max_tilt = std::sin(probe.max_opening_tilt_deg * std::numbers::pi / 180.0);
  std::optional<BodyCleft> found;
  for (std::size_t a = 0; a < walls.size(); ++a)
    for (std::size_t b = a + 1; b < walls.size(); ++b) {
      const SurfacePoint& wa = walls[a];
      const SurfacePoint& wb = walls[b];
      if (wa.normal.dot(wb.normal) >= 0.0) continue;  // not facing: 90° apart or less
      const Eigen::Vector3d ab = wb.position - wa.position;
      // Concave: each wall's point in front of the other's tangent plane.
      if (ab.dot(wa.normal) <= 0.0 || ab.dot(wb.normal) >= 0.0) continue;
      if ((wa.position - p).norm() > reach || (wb.position - p).norm() > reach) continue;
      const Eigen::Vector3d mean = wa.normal + wb.normal;
      if (!(mean.norm() > 1e-6)) continue;  // opposite walls: a slot, no opening to bridge
      const Eigen::Vector3d opening = mean.normalized();
      if (std::abs(opening.y()) > max_tilt) continue;  // opens downwards (or up)
      // The narrowest pair: the crease where it is closest.
      if (found && ab.norm() >= found->width) continue;
      found = BodyCleft{wa.position, wb.position, wa.normal, wb.normal, opening, ab.norm()};
    }
  // Only where the offset surfaces of the two walls meet: walls closer than twice the offset
  // (and the slack). A wider crease leaves room for the cloth on each wall.
  if (found && found->width >= 2.0 * probe.offset + probe.slack) return std::nullopt;
  return found;
}

std::vector<JunctionInCleft> find_junctions_in_clefts(const Garment& garment,
                                                      const BodySurface& body,
                                                      const CleftProbe& probe) {
  const meshing::QuadMesh& mesh = garment.mesh;
  std::vector<std::vector<int>> panels_at(static_cast<std::size_t>(mesh.vertex_count()));
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f)
    for (int k = 0; k < 4; ++k) {
      std::vector<int>& at = panels_at[static_cast<std::size_t>(mesh.faces(f, k))];
      const int panel = garment.face_panel(f);
      if (std::find(at.begin(), at.end(), panel) == at.end()) at.push_back(panel);
    }
  std::vector<JunctionInCleft> found;
  for (int v = 0; v < mesh.vertex_count(); ++v) {
    std::vector<int>& panels = panels_at[static_cast<std::size_t>(v)];
    if (panels.size() < 3) continue;
    const Eigen::Vector3d p = mesh.vertices.row(v).transpose();
    if (p.x() < -1e-9) {
      // A mirror image of a junction at x > 0 is reported there.
      const Eigen::Vector3d image(-p.x(), p.y(), p.z());
      bool mirrored = false;
      for (int w = 0; w < mesh.vertex_count() && !mirrored; ++w)
        mirrored = panels_at[static_cast<std::size_t>(w)].size() >= 3 &&
                   (mesh.vertices.row(w).transpose() - image).norm() < 1e-6;
      if (mirrored) continue;
    }
    const std::optional<BodyCleft> cleft = cleft_at(body, p, probe);
    if (!cleft) continue;
    // Held by both walls only when nearer than the offset to each: a junction at the offset
    // from one wall (or farther) has room on that side.
    const double a = cleft->clearance_a(p), b = cleft->clearance_b(p);
    if (a >= probe.offset || b >= probe.offset) continue;
    std::sort(panels.begin(), panels.end());
    found.push_back({p, panels, *cleft, a, b});
  }
  return found;
}

}  // namespace sd::garment
