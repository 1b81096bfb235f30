#pragma once
// Linear solvers for the constrained system of one Newton iteration:
//   find s with  S (A s − b) = 0  and  (I − S) s = z,
// A symmetric positive definite (3n by 3n), S the per-vertex constraint filter, z the
// prescribed correction in the constrained directions.

#include <Eigen/Core>

#include "sim/cloth_model.hpp"
#include "sim/constraint_filter.hpp"

namespace sd::sim {

struct LinearSolveStats {
  int iterations = 0;              // PCG iterations (0 for a direct solve)
  // Residual reduction in the norm the solver uses: preconditioned for the PCG, Euclidean
  // |S(b − A s)| / |S(b − A z)| for the direct solver.
  double relative_residual = 0.0;
  bool converged = false;
};

// Baraff & Witkin's modified preconditioned conjugate gradient: the iterates stay in the
// filtered subspace, so constrained directions never change. Preconditioner: the inverse of
// each 3x3 diagonal block of A (block Jacobi). Stops when the preconditioned residual norm has
// dropped by `tolerance` relative to the start, or after `max_iterations`.
class PcgSolver {
 public:
  LinearSolveStats solve(const SparseMatrixR& a, const std::vector<int>& diagonal_offsets,
                         const ConstraintFilter& filter, const Eigen::VectorXd& b,
                         const Eigen::VectorXd& z, Eigen::VectorXd& s, double tolerance,
                         int max_iterations);

 private:
  Eigen::VectorXd r_, c_, q_, t_;
  std::vector<Eigen::Matrix3d> inverse_blocks_;
};

// |S(b − A s)| / |S(b − A z)|: how well s solves the constrained system (for reports and tests).
double constrained_relative_residual(const SparseMatrixR& a, const ConstraintFilter& filter,
                                     const Eigen::VectorXd& b, const Eigen::VectorXd& z,
                                     const Eigen::VectorXd& s);

}  // namespace sd::sim
