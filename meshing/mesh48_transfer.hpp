#pragma once
// Moving lumped masses and velocities through a 4-8 split or merge so that total mass and
// linear momentum are conserved (DESIGN.md, "Adaptive level of detail"; Birra & Santos 2008).
// Pure arithmetic on arrays indexed by VertexId value; the simulator owns the arrays.

#include <Eigen/Core>
#include <vector>

#include "meshing/mesh48.hpp"

namespace sd::meshing {

// Area densities (kg/m², or any unit: masses come out in that unit times area) of the block's
// two parent triangles A1 = (A, B, C) and A2 = (D, C, B); children inherit their parent's.
// density_a2 is ignored for a boundary block.
struct BlockDensities {
  double a1 = 1.0;
  double a2 = 1.0;
};

// Split: with A1, A2 and the children's rest areas from the change record,
//   m_E  = (ρ1 A1 + ρ2 A2) / 3
//   m_B += (ρ1 (A11 − A1) + ρ2 (A20 − A2)) / 3,  m_C += (ρ1 (A10 − A1) + ρ2 (A21 − A2)) / 3
//   v_E  = (v_C (ρ1 A11 + ρ2 A20) + v_B (ρ1 A10 + ρ2 A21)) / (ρ1 A1 + ρ2 A2)
// (DESIGN.md's formulas with one density per triangle; m_A, m_D unchanged).
// Merge: E's mass and momentum go to B and C in the proportions the split took from them,
// so a merge right after a split restores the masses exactly and momentum is conserved.
// masses (#slots) and velocities (#slots by 3) are grown with zero rows to hold E if needed;
// a merged-away E is left with zero mass and velocity.
void transfer_mass_and_velocity(const BlockChange& change, const BlockDensities& densities,
                                Eigen::VectorXd& masses, Eigen::MatrixX3d& velocities);

// Current (deformed) position of a split's new vertex: the midpoint of B and C, matching its
// rest position. positions (#slots by 3) grows to hold E. A merge needs nothing.
void place_split_vertex(const BlockChange& change, Eigen::MatrixX3d& positions);

// Carries per-vertex (or per-triangle, per-block) rows through compact(): row old moves to row
// old_to_new[old]; rows mapped to -1 are dropped. Returns new_count rows.
Eigen::MatrixXd remap_rows(const Eigen::MatrixXd& rows, const std::vector<int>& old_to_new,
                           int new_count);

}  // namespace sd::meshing
