#pragma once
// Quad grids on a plane and a sphere for the tests of smoothing and unfolding on a surface.

#include "meshing/quad_mesh.hpp"
#include "tests/meshing/quad_grid.hpp"

namespace sd::test {

// An n × n grid of unit-spaced quads in the plane z = 0, counter-clockwise seen from +z.
inline meshing::QuadMesh plane_grid(int n) {
  return quad_grid(n, n);
}

// The same grid spanning `span` across, centred on +z and pushed radially onto the sphere of
// radius r around the origin (facing out).
inline meshing::QuadMesh sphere_grid(int n, double r, double span) {
  meshing::QuadMesh mesh = plane_grid(n);
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v) {
    const Eigen::Vector3d p(span * (mesh.vertices(v, 0) - n / 2.0) / n,
                            span * (mesh.vertices(v, 1) - n / 2.0) / n, r);
    mesh.vertices.row(v) = (r * p.normalized()).transpose();
  }
  return mesh;
}

// Flags (nonzero) for the boundary vertices of plane_grid(n) or sphere_grid(n, ...).
inline std::vector<char> grid_boundary(int n) {
  std::vector<char> fixed(static_cast<std::size_t>((n + 1) * (n + 1)), 0);
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j)
      if (i == 0 || j == 0 || i == n || j == n)
        fixed[static_cast<std::size_t>(i * (n + 1) + j)] = 1;
  return fixed;
}

}  // namespace sd::test
