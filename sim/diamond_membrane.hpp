#pragma once
// The diamonds of the 4-8 mesh and the map that moves a diamond's centre, for the membrane only,
// to where a smooth bend would put it (docs/simulator.md, "The diamond membrane"). The membrane
// of a diamond's four triangles is evaluated with the centre at x_c + g(x), g = (f − f̄)·n:
// n the unit normal of the two diagonals (x₃ − x₁) × (x₄ − x₂), p = Σ w_s·x_s the centre a smooth
// surface through the corners and their neighbours predicts (the corners' own second differences,
// never the centre), h₁ = n·((x₁ + x₃)/2 − p) and h₂ = n·((x₂ + x₄)/2 − p) the heights of the
// corner pairs' midpoints above it, and f = h₁·h₂·(h₁ + h₂) / (h₁² + h₂² + ε²). The centre enters
// only through x_c itself, so the membrane holds its normal position as it holds any vertex's
// (a dent of the centre moves the mapped centre by as much), while a smooth bend, where x_c = p,
// is unlocked. f·n does not depend on n's sign; f and its first two derivatives vanish on a flat
// diamond (h₁ = h₂ = 0), so in-plane deformation costs what it did.

#include <Eigen/Core>
#include <array>
#include <vector>

namespace sd::sim {

struct TriangleElement;

// A diamond: an interior vertex whose four triangles close a fan around it, the centre lying in
// its rest shape near the midpoint of both diagonals (every interior triangle of either 4-8
// level belongs to one). Its triangles' membrane is evaluated through the centre's map.
struct DiamondElement {
  static constexpr int kVertices = 13;
  // The centre, the corners in fan order (1, 3 and 2, 4 opposite), then the corners' neighbours
  // o(k, j) = the vertex beyond corner k on the line from its fellow corner j (j = k − 1, k + 1),
  // in the order (1,4), (1,2), (2,1), (2,3), (3,2), (3,4), (4,3), (4,1). A neighbour the mesh
  // lacks (at a border) is the centre again, with weight 0.
  std::array<int, kVertices> vertices{};
  std::array<double, kVertices> weights{};  // w_s of the predicted centre p (Σ w_s = 1, w_0 = 0)
  // Rows of ClothModel::triangles, (c, b_k, b_k+1) in fan order; -1 for a sector an adaptive
  // split has replaced (a partial diamond: its other triangles keep the centre's map).
  std::array<int, 4> triangles{};
  double regularisation = 0.0;  // ε² = (0.01·a)², a the mean rest half-diagonal; m²
  double rest_offset = 0.0;     // f̄: f at the rest positions (0 on a flat rest), m
  std::array<int, kVertices * kVertices> blocks{};  // offset of block (k, l), see BlockPattern
};

// The diamonds of a mesh (each triangle in at most one; the whole ones in increasing order of
// their centre, then the partial ones, likewise), their corners' neighbours, the predictor's
// weights and their regularisation; `flat_rest` (the membrane's rest is a flat layout, rest_uv)
// sets f̄ = 0, otherwise f̄ is read from `rest`. Then the partial diamonds of an adaptive 4-8 mesh: a
// centre whose fan a split has broken keeps its map on the triangles it still has (exact right
// isosceles triangles with the right angle at the centre, the four corners present as vertices).
// Blocks are left for the pattern.
std::vector<DiamondElement> make_diamonds(const Eigen::MatrixX3d& rest,
                                          const std::vector<TriangleElement>& triangles,
                                          bool flat_rest);

using DiamondVector = Eigen::Matrix<double, 3 * DiamondElement::kVertices, 1>;
using DiamondMatrix =
    Eigen::Matrix<double, 3 * DiamondElement::kVertices, 3 * DiamondElement::kVertices>;

// The map depends on the 13 vertices only through six points, z = (x_c, x₁, …, x₄, p), 18
// coordinates; z = L·x with L (18 × 39) the identity on the first five and p's weights.
// The centre's offset g (3), its Jacobian G = ∂g/∂x (3 × 39, the diamond's vertices in
// DiamondElement order) and, when asked, the Hessians of g in the six points' coordinates
// (∇²g_i = Lᵀ·H_i·L, H_i 18 × 18 each) and the map L.
struct DiamondMap {
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 3, 3 * DiamondElement::kVertices> jacobian =
      Eigen::Matrix<double, 3, 3 * DiamondElement::kVertices>::Zero();
  std::array<Eigen::Matrix<double, 18, 18>, 3> point_hessian{};
  Eigen::Matrix<double, 18, 3 * DiamondElement::kVertices> points =
      Eigen::Matrix<double, 18, 3 * DiamondElement::kVertices>::Zero();  // L
};

// x: the 39 coordinates of the diamond's vertices. A diamond whose diagonals are (nearly)
// parallel has no normal: its map is zero there.
void diamond_centre_map(const DiamondElement& diamond, const DiamondVector& x, bool with_hessian,
                        DiamondMap& out);

// ∇²g_i = Lᵀ·H_i·L (39 × 39) from a map evaluated with its Hessians.
DiamondMatrix diamond_map_hessian(const DiamondMap& map, int i);

}  // namespace sd::sim
