#pragma once
// Closed body meshes for the contact tests: an icosphere and a box, outward-facing.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "meshing/tri_mesh.hpp"

namespace sd::sim::testing {

// Icosphere of radius r centred at `centre` (meshing::icosphere): every vertex on the sphere,
// so the mesh lies between the sphere and its inscribed sphere (see inscribed_radius).
inline meshing::TriMesh make_sphere(double r, int subdivisions,
                                    const Eigen::Vector3d& centre = Eigen::Vector3d::Zero()) {
  return meshing::icosphere(r, subdivisions, centre);
}

// Smallest distance from `centre` to a face plane: the mesh of a sphere contains the ball of
// this radius.
inline double inscribed_radius(const meshing::TriMesh& mesh, const Eigen::Vector3d& centre) {
  double r = std::numeric_limits<double>::infinity();
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.faces(f, 0)).transpose();
    const Eigen::Vector3d b = mesh.vertices.row(mesh.faces(f, 1)).transpose();
    const Eigen::Vector3d c = mesh.vertices.row(mesh.faces(f, 2)).transpose();
    const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
    r = std::min(r, std::abs((centre - a).dot(n)));
  }
  return r;
}

// Axis-aligned box [lo, hi] as 12 outward-facing triangles.
inline meshing::TriMesh make_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  meshing::TriMesh mesh;
  mesh.vertices.resize(8, 3);
  for (int i = 0; i < 8; ++i)
    mesh.vertices.row(i) << (i & 1 ? hi.x() : lo.x()), (i & 2 ? hi.y() : lo.y()),
        (i & 4 ? hi.z() : lo.z());
  mesh.faces.resize(12, 3);
  mesh.faces << 0, 2, 3, 0, 3, 1,  // z = lo
      4, 5, 7, 4, 7, 6,            // z = hi
      0, 1, 5, 0, 5, 4,            // y = lo
      2, 6, 7, 2, 7, 3,            // y = hi
      0, 4, 6, 0, 6, 2,            // x = lo
      1, 3, 7, 1, 7, 5;            // x = hi
  return mesh;
}

// A cone standing on y = base_y with its apex straight above `centre` (x, z) at base_y + height:
// `segments` triangles around the side meeting at the sharp apex, a fan closing the base.
// Outward-facing. Vertex 0 is the apex.
inline meshing::TriMesh make_cone(double radius, double height, int segments,
                                  const Eigen::Vector3d& base_centre = Eigen::Vector3d::Zero()) {
  meshing::TriMesh mesh;
  mesh.vertices.resize(segments + 2, 3);
  mesh.vertices.row(0) = (base_centre + Eigen::Vector3d(0.0, height, 0.0)).transpose();
  mesh.vertices.row(1) = base_centre.transpose();
  for (int k = 0; k < segments; ++k) {
    const double a = 2.0 * std::numbers::pi * k / segments;
    mesh.vertices.row(2 + k) =
        (base_centre + Eigen::Vector3d(radius * std::cos(a), 0.0, radius * std::sin(a)))
            .transpose();
  }
  mesh.faces.resize(2 * segments, 3);
  for (int k = 0; k < segments; ++k) {
    const int a = 2 + k, b = 2 + (k + 1) % segments;
    mesh.faces.row(k) << 0, b, a;             // side, seen from outside counter-clockwise
    mesh.faces.row(segments + k) << 1, a, b;  // base, facing down
  }
  return mesh;
}

// The same points moved by a rigid rotation about the origin, #V by 3.
inline Eigen::MatrixX3d rotated(const Eigen::MatrixX3d& points, const Eigen::Matrix3d& rotation) {
  return (points * rotation.transpose()).eval();
}

}  // namespace sd::sim::testing
