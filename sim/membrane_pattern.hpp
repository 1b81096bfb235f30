#pragma once
// The system matrix without the couplings that only the flat bends make: the preconditioner's
// pattern for IC(0) (PcgPreconditioner's *_membrane kinds).
//
// On a sheet with flat-rest bending a vertex couples with the second ring of its neighbours
// through the bends' constant operator K ⊗ I: blocks c·I, about two thirds of A's off-diagonal
// blocks. IC(0)'s factorisation grows with the square of a row's blocks and its sweeps with
// their number, so on those blocks it costs about four times what it costs on the triangles'
// pattern (the first ring), for a preconditioner whose iterations the bends' weak couplings
// change little. Each dropped c·I block (i, j) adds c to the diagonal block (i, i): the rows keep
// their sums, so the reduced matrix acts on a uniform translation of the cloth as A does (the
// smooth error IC(0) reduces worst; a modified incomplete factorisation's rule).

#include <vector>

#include "sim/cloth_model.hpp"

namespace sd::sim {

// Whether the 3×3 block whose rows start at `values`, `stride` apart, is c·I (off-diagonals
// exactly zero, the diagonal three equal numbers): the flat bends' blocks and the mass. Inline:
// it is asked of every block of every solve.
inline bool is_scaled_identity(const double* values, int stride) {
  const double* r1 = values + stride;
  const double* r2 = r1 + stride;
  return values[1] == 0.0 && values[2] == 0.0 && r1[0] == 0.0 && r1[2] == 0.0 && r2[0] == 0.0 &&
         r2[1] == 0.0 && r1[1] == values[0] && r2[2] == values[0];
}

class MembranePattern {
 public:
  // From A (3n by 3n, made of vertex blocks; diagonal_offsets as in ClothModel's pattern).
  // Returns false when A is not made of vertex blocks (then matrix() must not be used).
  bool build(const SparseMatrixR& a, const std::vector<int>& diagonal_offsets);
  const SparseMatrixR& matrix() const { return matrix_; }
  const std::vector<int>& diagonal_offsets() const { return diagonal_offsets_; }
  // Off-diagonal blocks left out by the last build (for tests and the report).
  int dropped_blocks() const { return dropped_; }

 private:
  SparseMatrixR matrix_;
  std::vector<int> diagonal_offsets_;
  std::vector<int> outer_, inner_;
  std::vector<double> values_;
  int dropped_ = 0;
};

}  // namespace sd::sim
