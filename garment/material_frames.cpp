#include "garment/material_frames.hpp"

#include <Eigen/Geometry>
#include <numbers>
#include <stdexcept>

#include "garment/garment_mesh.hpp"

namespace sd::garment {

MaterialFrames material_frames(const meshing::QuadMesh& mesh) {
  const Eigen::Index q = mesh.face_count();
  MaterialFrames frames;
  frames.warp.resize(q, 3);
  frames.weft.resize(q, 3);
  frames.normal.resize(q, 3);
  for (Eigen::Index f = 0; f < q; ++f) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.faces(f, 0)).transpose();
    const Eigen::Vector3d b = mesh.vertices.row(mesh.faces(f, 1)).transpose();
    const Eigen::Vector3d c = mesh.vertices.row(mesh.faces(f, 2)).transpose();
    const Eigen::Vector3d d = mesh.vertices.row(mesh.faces(f, 3)).transpose();
    const Eigen::Vector3d n = (c - a).cross(d - b).normalized();
    Eigen::Vector3d warp = Eigen::Vector3d::UnitY() - n.y() * n;
    if (warp.norm() < 1e-6) warp = Eigen::Vector3d::UnitZ() - n.z() * n;
    warp.normalize();
    frames.normal.row(f) = n.transpose();
    frames.warp.row(f) = warp.transpose();
    frames.weft.row(f) = n.cross(warp).transpose();
  }
  return frames;
}

MaterialFrames material_frames(const Garment& garment) {
  MaterialFrames frames = material_frames(garment.mesh);
  for (Eigen::Index f = 0; f < frames.warp.rows(); ++f) {
    const GarmentPanel& panel = garment.panels[static_cast<size_t>(garment.face_panel(f))];
    const Eigen::Vector3d n = frames.normal.row(f).transpose();
    Eigen::Vector3d warp = panel.grain_axis - panel.grain_axis.dot(n) * n;
    if (warp.norm() < 1e-6) warp = frames.warp.row(f).transpose();
    warp.normalize();
    if (panel.grain_turn_deg != 0.0) {
      const double turn = panel.grain_turn_deg * std::numbers::pi / 180.0;
      warp = std::cos(turn) * warp + std::sin(turn) * n.cross(warp);
    }
    frames.warp.row(f) = warp.transpose();
    frames.weft.row(f) = n.cross(warp).transpose();
  }
  return frames;
}

Eigen::MatrixXd triangle_rest_coordinates(const meshing::TriMesh& triangles,
                                          const Eigen::VectorXi& triangle_quad,
                                          const MaterialFrames& frames,
                                          const Eigen::VectorXd& quad_ease) {
  const Eigen::Index t = triangles.face_count();
  if (triangle_quad.size() != t)
    throw std::invalid_argument("triangle_rest_coordinates: one quad index per triangle needed");
  Eigen::MatrixXd rest(t, 6);
  for (Eigen::Index f = 0; f < t; ++f) {
    const int q = triangle_quad(f);
    if (q < 0 || q >= frames.warp.rows() || q >= quad_ease.size())
      throw std::invalid_argument("triangle_rest_coordinates: quad index out of range");
    // Express the triangle in its own plane: unit normal of the triangle, the quad's warp
    // projected into it, and weft = normal × warp, so the in-plane shape is exact.
    const Eigen::Vector3d p0 = triangles.vertices.row(triangles.faces(f, 0)).transpose();
    const Eigen::Vector3d p1 = triangles.vertices.row(triangles.faces(f, 1)).transpose();
    const Eigen::Vector3d p2 = triangles.vertices.row(triangles.faces(f, 2)).transpose();
    const Eigen::Vector3d n = (p1 - p0).cross(p2 - p0).normalized();
    Eigen::Vector3d warp = frames.warp.row(q).transpose();
    warp = (warp - warp.dot(n) * n).normalized();
    const Eigen::Vector3d weft = n.cross(warp);
    const double s = quad_ease(q);
    const Eigen::Vector3d e1 = p1 - p0, e2 = p2 - p0;
    rest.row(f) << 0, 0, s * e1.dot(warp), s * e1.dot(weft), s * e2.dot(warp), s * e2.dot(weft);
  }
  return rest;
}

}  // namespace sd::garment
