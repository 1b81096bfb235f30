#pragma once
// Closed body meshes for the contact tests: an icosphere and a box, outward-facing.

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "meshing/tri_mesh.hpp"

namespace sd::sim::testing {

// Icosphere of radius r centred at `centre`: every vertex on the sphere, so the mesh lies
// between the sphere and its inscribed sphere (see inscribed_radius).
inline meshing::TriMesh make_sphere(double r, int subdivisions,
                                    const Eigen::Vector3d& centre = Eigen::Vector3d::Zero()) {
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0},
                                    {0, -1, g}, {0, 1, g}, {0, -1, -g}, {0, 1, -g},
                                    {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  std::vector<Eigen::Vector3i> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                    {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                    {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                    {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& p : v) p.normalize();
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> midpoint;
    const auto mid = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      midpoint[key] = static_cast<int>(v.size()) - 1;
      return static_cast<int>(v.size()) - 1;
    };
    std::vector<Eigen::Vector3i> next;
    for (const auto& t : f) {
      const int a = mid(t[0], t[1]), b = mid(t[1], t[2]), c = mid(t[2], t[0]);
      next.push_back({t[0], a, c});
      next.push_back({t[1], b, a});
      next.push_back({t[2], c, b});
      next.push_back({a, b, c});
    }
    f = next;
  }
  meshing::TriMesh mesh;
  mesh.vertices.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i) mesh.vertices.row(i) = (centre + r * v[i]).transpose();
  mesh.faces.resize(static_cast<Eigen::Index>(f.size()), 3);
  for (std::size_t i = 0; i < f.size(); ++i) mesh.faces.row(i) = f[i].transpose();
  return mesh;
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
        (base_centre + Eigen::Vector3d(radius * std::cos(a), 0.0, radius * std::sin(a))).transpose();
  }
  mesh.faces.resize(2 * segments, 3);
  for (int k = 0; k < segments; ++k) {
    const int a = 2 + k, b = 2 + (k + 1) % segments;
    mesh.faces.row(k) << 0, b, a;                // side, seen from outside counter-clockwise
    mesh.faces.row(segments + k) << 1, a, b;     // base, facing down
  }
  return mesh;
}

// The same points moved by a rigid rotation about the origin, #V by 3.
inline Eigen::MatrixX3d rotated(const Eigen::MatrixX3d& points, const Eigen::Matrix3d& rotation) {
  return (points * rotation.transpose()).eval();
}

}  // namespace sd::sim::testing
