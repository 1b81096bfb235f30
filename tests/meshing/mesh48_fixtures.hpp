#pragma once
// Small meshes for the 4-8 mesh tests and benchmarks: quad grids (flat or rolled into a
// cylinder), triangulated sheets and a subdivided icosahedron.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

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

// Icosahedron subdivided `levels` times (4 triangles per step) on a sphere of the given radius
// (meshing::icosphere); closed, outward counter-clockwise.
inline TriMesh icosphere(int levels, double radius = 1.0) {
  return meshing::icosphere(radius, levels, Eigen::Vector3d::Zero());
}

}  // namespace sd::meshing::testing
