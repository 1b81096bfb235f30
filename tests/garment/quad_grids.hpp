#pragma once
// Quad grids on a plane and a sphere for the tests of smoothing and unfolding on a surface.

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

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

// k rhombi of side 2 around a centre c at the origin (angle 2π/k at c), each cut 2 × 2: 4k quads
// of side 1 around c of valence k, counter-clockwise seen from +z. `fixed` flags the outline;
// the interior is c, the k spoke midpoints and the k rhombus centres.
struct RhombusTiling {
  meshing::QuadMesh mesh;
  std::vector<char> fixed;
};
inline RhombusTiling rhombus_tiling(int k) {
  // Vertices s A_i + t A_{i+1} for the spokes A_i (length 2 at 90° + 360° i / k), s, t in
  // {0, 1/2, 1}, numbered as they are first met.
  std::vector<Eigen::Vector3d> points;
  RhombusTiling tiling;
  const auto id = [&](const Eigen::Vector3d& p, bool interior) {
    for (size_t v = 0; v < points.size(); ++v)
      if ((points[v] - p).norm() < 1e-12) return static_cast<int>(v);
    points.push_back(p);
    tiling.fixed.push_back(interior ? 0 : 1);
    return static_cast<int>(points.size()) - 1;
  };
  std::vector<std::array<int, 4>> quads;
  for (int i = 0; i < k; ++i) {
    const auto spoke = [k](int j) {
      const double a = std::numbers::pi / 2 + 2 * std::numbers::pi / k * j;
      return Eigen::Vector3d(2 * std::cos(a), 2 * std::sin(a), 0);
    };
    const Eigen::Vector3d a = spoke(i), b = spoke(i + 1);
    for (int s = 0; s < 2; ++s)
      for (int t = 0; t < 2; ++t) {
        const auto at = [&](int u, int w) { return id(0.5 * u * a + 0.5 * w * b, u < 2 && w < 2); };
        quads.push_back({at(s, t), at(s + 1, t), at(s + 1, t + 1), at(s, t + 1)});
      }
  }
  meshing::QuadMesh& mesh = tiling.mesh;
  mesh.vertices.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t v = 0; v < points.size(); ++v)
    mesh.vertices.row(static_cast<Eigen::Index>(v)) = points[v].transpose();
  mesh.faces.resize(static_cast<Eigen::Index>(quads.size()), 4);
  for (size_t f = 0; f < quads.size(); ++f)
    for (int c = 0; c < 4; ++c)
      mesh.faces(static_cast<Eigen::Index>(f), c) = quads[f][static_cast<size_t>(c)];
  return tiling;
}

}  // namespace sd::test
