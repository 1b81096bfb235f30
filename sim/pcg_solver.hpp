#pragma once
// Linear solvers for the constrained system of one Newton iteration:
//   find s with  S (A s − b) = 0  and  (I − S) s = z,
// A symmetric positive definite (3n by 3n), S the per-vertex constraint filter, z the
// prescribed correction in the constrained directions.

#include <Eigen/Core>
#include <vector>

#include "sim/cloth_model.hpp"
#include "sim/coarse_correction.hpp"
#include "sim/constraint_filter.hpp"
#include "sim/membrane_pattern.hpp"

namespace sd::sim {

struct LinearSolveStats {
  int iterations = 0;  // PCG iterations (0 for a direct solve)
  // Residual reduction in the norm the solver uses: preconditioned for the PCG, Euclidean
  // |S(b − A s)| / |S(b − A z)| for the direct solver.
  double relative_residual = 0.0;
  bool converged = false;
};

enum class PcgPreconditioner {
  block_jacobi,               // the inverse of each 3x3 diagonal block (Baraff & Witkin)
  block_incomplete_cholesky,  // IC(0) on 3x3 blocks of the filtered matrix, see below
  // IC(0) balanced by an exact solve on vertex aggregates (CoarseCorrection): a two-level
  // preconditioner whose iterations grow far less with the resolution than IC(0)'s. Both levels
  // are made from the matrix's membrane pattern (MembranePattern: the flat bends' second-ring
  // couplings moved to the diagonal): as few iterations, and a factor several times cheaper to
  // make and to apply.
  two_level,
};

// Incomplete Cholesky with no fill, IC(0), on the 3x3 blocks of the filtered matrix
//   B = S A S + (I − S)
// (SPD, with A's block pattern; it is the matrix CHOLMOD factorises exactly). B ≈ L P Lᵀ with
// L unit lower block-triangular on the pattern of A's lower half and P block diagonal, both
// computed from the upper half U = P Lᵀ in vertex order. Because S is block diagonal, the
// factor keeps the constrained directions decoupled, so the preconditioner respects the
// filter. IC(0) can break down (a pivot block that is not positive definite) on matrices that
// are SPD but not diagonally dominant; it is then recomputed for B + α·blockdiag(B) with α
// growing from 1e-4 (Manteuffel's shift), and `shift()` says which α was used.
class BlockIncompleteCholesky {
 public:
  // Returns false only if no shift up to α = 1 gave positive definite pivots.
  bool factorize(const SparseMatrixR& a, const std::vector<int>& diagonal_offsets,
                 const ConstraintFilter& filter);
  // out = (L P Lᵀ)⁻¹ r, 3n.
  void apply(const Eigen::VectorXd& r, Eigen::VectorXd& out) const;
  // out = L P Lᵀ x, 3n: the matrix the factor represents (equal to B + α·blockdiag(B) on the
  // pattern, for tests).
  void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& out) const;
  double shift() const { return shift_; }
  // B's blocks (before the factorisation), for the coarse level of the two-level cycle.
  const std::vector<int>& row_start() const { return row_start_; }
  const std::vector<int>& column() const { return column_; }
  const std::vector<Eigen::Matrix3d>& b_upper() const { return b_upper_; }
  const std::vector<Eigen::Matrix3d>& b_diagonal() const { return b_diagonal_; }

 private:
  bool factorize_shifted(double alpha);

  // Upper half of B, block row by block row: blocks (i, column_[k]) for k in
  // [row_start_[i], row_start_[i+1]), columns increasing and > i.
  std::vector<int> row_start_;
  std::vector<int> column_;
  std::vector<Eigen::Matrix3d> b_upper_, b_diagonal_;   // B's blocks
  std::vector<Eigen::Matrix3d> upper_;                  // the factor's U_ij (i < j)
  std::vector<Eigen::Matrix3d> pivot_, pivot_inverse_;  // P_i, P_i⁻¹
  double shift_ = 0.0;
};

// A's 3×3 vertex blocks as the PCG's products read them. The three rows of a vertex hold the
// same block columns, so one column index and one load of x's three entries serve the three
// rows; and a block that is c·I (on a sheet, the flat bends' couplings of a vertex with the
// second ring of its neighbours: about two thirds of the blocks) is kept as the one number c.
// The product is then the same numbers as the scalar rows' (the six zeros add nothing) from
// about a third of the bytes (docs/benchmarks.md, "Eleventh round"). Rows are cut into chunks
// on the threads, each row summed the same way on any thread count.
class VertexBlockMatrix {
 public:
  // False when `a` is not made of vertex blocks (then multiply must not be called).
  // `same_pattern`: the caller knows that `a` has the pattern of the last build (the same row
  // starts and column indices: every solve of a fixed mesh); its values are then gathered into
  // the kept layout without checking the blocks' structure again (that check and the appends
  // were 6–8 % of a pinned 32×32 sheet's drape). A block kept as c·I that no longer is one makes
  // it a full build.
  bool build(const SparseMatrixR& a, bool same_pattern = false);
  // y = A x, 3n.
  void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const;
  // Blocks kept as one number (for tests and benchmarks).
  int scaled_identity_blocks() const;

 private:
  // One chunk of the product's rows (parallel_chunks' chunks): vertex low + r's blocks are
  // [block_start[r], block_start[r+1]); column 3j for a full block (nine values, row by row),
  // −3j − 1 for c·I (one value), values in block order.
  struct Chunk {
    std::vector<int> block_start, column;
    std::vector<double> values;
  };
  // Gathers the values of `a`, which has the last build's pattern, into its layout; false if a
  // block kept as c·I is no longer one.
  bool refill(const SparseMatrixR& a);

  std::vector<Chunk> chunks_;
  int vertices_ = 0;
  Eigen::Index nonzeros_ = 0;  // of the last build's A
};

// Baraff & Witkin's modified preconditioned conjugate gradient: the iterates stay in the
// filtered subspace, so constrained directions never change. Stops when the preconditioned
// residual norm has dropped by `tolerance` relative to the start, or after `max_iterations`.
class PcgSolver {
 public:
  explicit PcgSolver(PcgPreconditioner preconditioner = PcgPreconditioner::block_jacobi)
      : preconditioner_(preconditioner) {}
  void set_preconditioner(PcgPreconditioner preconditioner) { preconditioner_ = preconditioner; }
  PcgPreconditioner preconditioner() const { return preconditioner_; }

  // `refresh_preconditioner` false reuses the preconditioner of the last solve (same A and
  // filter, e.g. the later iterations of a simplified Newton method). `same_pattern`: `a` has
  // the pattern of the last solve's matrix, only its values changed (VertexBlockMatrix::build).
  LinearSolveStats solve(const SparseMatrixR& a, const std::vector<int>& diagonal_offsets,
                         const ConstraintFilter& filter, const Eigen::VectorXd& b,
                         const Eigen::VectorXd& z, Eigen::VectorXd& s, double tolerance,
                         int max_iterations, bool refresh_preconditioner = true,
                         bool same_pattern = false);

 private:
  void build_block_jacobi(const SparseMatrixR& a, const std::vector<int>& diagonal_offsets);

  PcgPreconditioner preconditioner_;
  bool incomplete_ready_ = false;  // incomplete_ holds the factor of the last refresh
  int prepared_vertices_ = -1;     // vertices of the last refresh's preconditioner
  bool coarse_ready_ = false;
  bool warm_start_ = false;
  Eigen::VectorXd warm_guess_;  // coarse_ holds Ac's factor of the last refresh
  Eigen::VectorXd r_, c_, q_, t_;
  Eigen::VectorXd cycle_residual_, cycle_product_, cycle_coarse_;  // the two-level cycle's
  std::vector<Eigen::Matrix3d> inverse_blocks_;
  VertexBlockMatrix product_;
  MembranePattern membrane_;
  BlockIncompleteCholesky incomplete_;
  CoarseCorrection coarse_;
};

// |S(b − A s)| / |S(b − A z)|: how well s solves the constrained system (for reports and tests).
double constrained_relative_residual(const SparseMatrixR& a, const ConstraintFilter& filter,
                                     const Eigen::VectorXd& b, const Eigen::VectorXd& z,
                                     const Eigen::VectorXd& s);

}  // namespace sd::sim
