#pragma once
// Small meshes for the 4-8 mesh tests and benchmarks: quad grids (flat or rolled into a
// cylinder), triangulated sheets and a subdivided icosahedron.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <utility>

#include "meshing/tri_mesh.hpp"

namespace sd::meshing::testing {

struct QuadArrays {
  Eigen::MatrixX3d vertices;  // #V by 3
  Eigen::MatrixX4i quads;     // #Q by 4, counter-clockwise seen from +z (flat grid)
};

// nx by ny quads over [0, nx*h] x [0, ny*h] in the z = 0 plane; with `roll` the sheet is bent
// around the y axis onto a cylinder of radius nx*h/roll (roll in radians of arc).
inline QuadArrays quad_grid(int nx, int ny, double h = 1.0, double roll = 0.0) {
  QuadArrays g;
  g.vertices.resize((nx + 1) * (ny + 1), 3);
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const double x = i * h, y = j * h;
      if (roll == 0.0) {
        g.vertices.row(j * (nx + 1) + i) << x, y, 0.0;
      } else {
        const double radius = nx * h / roll, angle = x / radius;
        g.vertices.row(j * (nx + 1) + i) << radius * std::sin(angle), y,
            radius * (1 - std::cos(angle));
      }
    }
  g.quads.resize(nx * ny, 4);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int v = j * (nx + 1) + i;
      g.quads.row(j * nx + i) << v, v + 1, v + nx + 2, v + nx + 1;
    }
  return g;
}

// nx by ny squares each cut into two triangles along alternating diagonals, z = 0.
inline TriMesh triangle_sheet(int nx, int ny, double h = 1.0) {
  const QuadArrays g = quad_grid(nx, ny, h);
  TriMesh m;
  m.vertices = g.vertices;
  m.faces.resize(2 * nx * ny, 3);
  for (int q = 0; q < nx * ny; ++q) {
    const Eigen::Vector4i c = g.quads.row(q);
    if ((q + q / nx) % 2 == 0) {
      m.faces.row(2 * q) << c(0), c(1), c(2);
      m.faces.row(2 * q + 1) << c(0), c(2), c(3);
    } else {
      m.faces.row(2 * q) << c(0), c(1), c(3);
      m.faces.row(2 * q + 1) << c(1), c(2), c(3);
    }
  }
  return m;
}

// Icosahedron subdivided `levels` times (4 triangles per step), projected to a sphere of the
// given radius; closed, outward counter-clockwise.
inline TriMesh icosphere(int levels, double radius = 1.0) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                    {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                    {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<Eigen::Vector3i> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                    {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                    {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                    {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    const auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(0.5 * (v[a] + v[b]));
      return mid[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<Eigen::Vector3i> next;
    for (const Eigen::Vector3i& tri : f) {
      const int ab = midpoint(tri(0), tri(1)), bc = midpoint(tri(1), tri(2)),
                ca = midpoint(tri(2), tri(0));
      next.push_back({tri(0), ab, ca});
      next.push_back({tri(1), bc, ab});
      next.push_back({tri(2), ca, bc});
      next.push_back({ab, bc, ca});
    }
    f = std::move(next);
  }
  TriMesh m;
  m.vertices.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i)
    m.vertices.row(static_cast<Eigen::Index>(i)) = radius * v[i].normalized().transpose();
  m.faces.resize(static_cast<Eigen::Index>(f.size()), 3);
  for (std::size_t i = 0; i < f.size(); ++i) m.faces.row(static_cast<Eigen::Index>(i)) = f[i];
  return m;
}

}  // namespace sd::meshing::testing
