#pragma once
// Where a meshed garment passes through itself: pairs of its triangles (each quad split along
// one diagonal) that intersect, grouped by the pair of panels they belong to. The simulator
// separates such a start by smoothing and stops before that stretches the cloth past twice its
// strain limit (docs/collision.md, "An untangled start"), and crossings it cannot separate stay
// through each other for the whole drape: the quality gate names them.

#include <Eigen/Core>
#include <vector>

#include "garment/garment_mesh.hpp"

namespace sd::garment {

struct PanelCrossing {
  int panel_a = -1, panel_b = -1;  // indices into Garment::panels, a ≤ b (a == b: itself)
  int pairs = 0;                   // intersecting triangle pairs between them
  Eigen::Vector3d where = Eigen::Vector3d::Zero();  // m, the centre of the first pair
};

// Crossing panel pairs of `garment`, ordered by (panel_a, panel_b). Triangles that share a
// vertex are tested too (CGAL's self-intersection test reports them only when they overlap).
std::vector<PanelCrossing> find_panel_crossings(const Garment& garment);

}  // namespace sd::garment
