#pragma once
// The diamonds of the 4-8 mesh and the map that moves a diamond's centre, for the membrane only,
// to where a smooth bend would put it (docs/simulator.md, "The diamond membrane"). The membrane
// of a diamond's four triangles is evaluated with the centre at x_c + g(x), g = (f − f̄)·n:
// n the unit normal of the two diagonals (x₃ − x₁) × (x₄ − x₂), h₁ = n·((x₁ + x₃)/2 − x_c) and
// h₂ = n·((x₂ + x₄)/2 − x_c) the heights of the corner pairs' midpoints above the centre, and
// f = h₁·h₂·(h₁ + h₂) / (h₁² + h₂² + ε²). f·n does not depend on n's sign; f and its first two
// derivatives vanish on a flat diamond (h₁ = h₂ = 0), so in-plane deformation costs what it did.

#include <Eigen/Core>
#include <array>
#include <vector>

namespace sd::sim {

struct TriangleElement;

// A diamond: an interior vertex whose four triangles close a fan around it, the centre lying in
// its rest shape near the midpoint of both diagonals (every interior triangle of either 4-8
// level belongs to one). Its triangles' membrane is evaluated through the centre's map.
struct DiamondElement {
  std::array<int, 5> vertices{};   // the centre, then the corners in fan order (1, 3 and 2, 4
                                   // opposite)
  std::array<int, 4> triangles{};  // rows of ClothModel::triangles
  double regularisation = 0.0;     // ε² = (0.01·a)², a the mean rest half-diagonal; m²
  double rest_offset = 0.0;        // f̄: f at the rest positions (0 on a flat rest), m
  std::array<int, 25> blocks{};    // offset of block (k, l) of the 5 vertices, see BlockPattern
};

// The diamonds of a mesh (each triangle in at most one, vertices in increasing order of their
// centre) and their regularisation; `flat_rest` (the membrane's rest is a flat layout, rest_uv)
// sets f̄ = 0, otherwise f̄ is read from `rest`. Blocks are left for the pattern.
std::vector<DiamondElement> make_diamonds(const Eigen::MatrixX3d& rest,
                                          const std::vector<TriangleElement>& triangles,
                                          bool flat_rest);

// The centre's offset g(x) (3), its Jacobian G = ∂g/∂x (3 × 15, the diamond's vertices in
// DiamondElement order) and, when asked, the Hessians ∇²g_i (15 × 15 each).
struct DiamondMap {
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 3, 15> jacobian = Eigen::Matrix<double, 3, 15>::Zero();
  std::array<Eigen::Matrix<double, 15, 15>, 3> hessian{};
};

// x: 15 coordinates of the diamond's vertices. A diamond whose diagonals are (nearly) parallel
// has no normal: its map is zero there.
void diamond_centre_map(const DiamondElement& diamond, const Eigen::Matrix<double, 15, 1>& x,
                        bool with_hessian, DiamondMap& out);

}  // namespace sd::sim
