#pragma once
// The coarse level of the two-level PCG preconditioner (PcgPreconditioner::two_level): the
// cloth's vertices grouped into aggregates (a vertex and its neighbours in the matrix, the mesh's
// second ring through the bending hinges, plus leftovers: tens of vertices each), one translation
// per aggregate, and the filtered system B = S A S + (I − S) restricted to those translations, Ac =
// Pᵀ B P (P: 3n by 3m, an identity block from each vertex to its aggregate). Solved exactly (sparse
// Cholesky), it removes the smooth error that IC(0) alone reduces only a few vertices per
// iteration: that error is why the IC(0) PCG's iterations grow with the resolution
// (docs/benchmarks.md, "Scaling").
//
// The aggregates depend on the matrix pattern only and are kept while it stays the same (a fixed
// mesh keeps them for the whole run; an adaptive one rebuilds them after a topology change).

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <vector>

namespace sd::sim {

class CoarseCorrection {
 public:
  // B's blocks in the layout of BlockIncompleteCholesky: the upper half block row by block row
  // (blocks (i, column[k]) for k in [row_start[i], row_start[i+1]), columns > i), and the
  // diagonal blocks. Returns false if Ac is not positive definite (the caller then preconditions
  // without the coarse level).
  bool build(const std::vector<int>& row_start, const std::vector<int>& column,
             const std::vector<Eigen::Matrix3d>& upper,
             const std::vector<Eigen::Matrix3d>& diagonal);
  // out += P Ac⁻¹ Pᵀ r (3n vectors).
  void add_correction(const Eigen::VectorXd& r, Eigen::VectorXd& out) const;
  int aggregate_count() const { return aggregate_count_; }
  // The aggregate of each vertex (for tests).
  const std::vector<int>& aggregate() const { return aggregate_; }

 private:
  void aggregate_vertices(const std::vector<int>& row_start, const std::vector<int>& column);

  // The pattern the aggregates and Ac's pattern were made for.
  std::vector<int> row_start_, column_;
  std::vector<int> aggregate_;  // per vertex
  int aggregate_count_ = 0;
  // Ac, column-major, full symmetric pattern in 3x3 blocks; for each of B's upper blocks k the
  // value index of its (a, b) = (0, 0) entry in block (I, J) and in block (J, I) (I = aggregate
  // of the row vertex, J of the column vertex), and for each vertex the one of block (I, I).
  Eigen::SparseMatrix<double> coarse_;
  std::vector<int> upper_target_, lower_target_, diagonal_target_;
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> factor_;
  bool analysed_ = false;
  mutable Eigen::VectorXd coarse_rhs_, coarse_solution_;
};

}  // namespace sd::sim
