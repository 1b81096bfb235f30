#pragma once
// CHOLMOD (SuiteSparse) as the direct alternative to the PCG on the same constrained system.
// Constraints enter as in the filtered subspace: with s = z + S y,
//   (S A S + (I − S)) y = S (b − A z),
// whose matrix is SPD and has the block pattern of A (S is block diagonal), so the symbolic
// analysis is reused while the mesh topology, hence the pattern, does not change.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <stdexcept>
#include <vector>

#include "sim/cloth_model.hpp"
#include "sim/constraint_filter.hpp"
#include "sim/factor_size.hpp"
#include "sim/pcg_solver.hpp"

namespace sd::sim {

// CHOLMOD's two factorisations of the same LLᵀ: supernodal (dense BLAS kernels on groups of
// columns) or simplicial (column by column, no BLAS).
enum class CholmodMethod { supernodal, simplicial };

// CHOLMOD could not allocate the factor: the machine's memory, not the cloth, is the cause.
class CholmodOutOfMemoryError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class CholmodSolver {
 public:
  explicit CholmodSolver(CholmodMethod method = CholmodMethod::supernodal);
  ~CholmodSolver();
  CholmodSolver(CholmodSolver&&) noexcept;
  CholmodSolver& operator=(CholmodSolver&&) noexcept;

  // Factorises S A S + (I − S). Analyses the pattern only when it differs from the last one.
  // Returns false if the factorisation failed (matrix not positive definite). Throws
  // CholmodOutOfMemoryError when CHOLMOD runs out of memory (analysis or factorisation).
  bool factorize(const SparseMatrixR& a, const ConstraintFilter& filter);
  // Solves with the last factorisation; needs the same A and filter as factorize().
  LinearSolveStats solve(const SparseMatrixR& a, const ConstraintFilter& filter,
                         const Eigen::VectorXd& b, const Eigen::VectorXd& z, Eigen::VectorXd& s);

  // The number of rows of the last successful numeric factorisation; 0 before any or after a
  // failed one.
  int factor_rows() const { return factorized_ ? static_cast<int>(upper_.rows()) : 0; }
  // Solves the same constrained system as solve() by the modified PCG (iterates kept in the
  // filtered subspace), preconditioned by the last factorisation, which may be of an earlier
  // matrix of the same size (an earlier step's, with other contacts and pair springs): while the
  // cloth changes little from step to step it is a near-exact preconditioner, and a few
  // iterations (a triangular solve pair and a product with A each) cost less than factorising
  // again. Stops when the Euclidean residual |S(b − A s)| has dropped by `tolerance` relative to
  // |S(b − A z)|; not converged after `max_iterations` (s then holds the last iterate). Needs
  // factor_rows() == a.rows().
  LinearSolveStats solve_preconditioned(const SparseMatrixR& a, const ConstraintFilter& filter,
                                        const Eigen::VectorXd& b, const Eigen::VectorXd& z,
                                        Eigen::VectorXd& s, double tolerance, int max_iterations);

  int symbolic_analyses() const { return analyses_; }
  // The factor of the last symbolic analysis, as predict_factor_size() reports it (for tests
  // and the memory estimate's check).
  const FactorSize& analysed_size() const { return analysed_size_; }
  int numeric_factorizations() const { return factorizations_; }
  CholmodMethod method() const { return method_; }

 private:
  // A fill-reducing ordering of the 3n rows that keeps each vertex's three together: AMD on
  // the vertex graph of A's pattern (row-major arrays). Empty if CHOLMOD's AMD failed.
  std::vector<int> block_ordering(const int* outer, const int* inner, int rows);
  // Throws CholmodOutOfMemoryError when CHOLMOD's last call ran out of memory.
  void throw_if_out_of_memory(int rows, const char* stage);
  void record_analysed_size();
  // lower_ and lower_source_ from upper_, upper_source_ and permutation_.
  void make_permuted_lower();
  // (L Lᵀ)⁻¹ r with the last factorisation, its permutation applied (3n).
  Eigen::VectorXd apply_factor(const Eigen::VectorXd& r) const;

  struct Factor;
  CholmodMethod method_;
  std::unique_ptr<Factor> factor_;
  // The values of S A S + (I − S), in A's pattern (outer_, inner_).
  std::vector<double> filtered_;
  // The upper triangle of S A S + (I − S), what CHOLMOD is given, and where each of its values
  // sits in filtered_.
  Eigen::SparseMatrix<double, Eigen::ColMajor, int> upper_;
  std::vector<int> upper_source_;
  // Supernodal: the fill-reducing permutation P taken out of the factor (row k of the factored
  // matrix is row permutation_[k] of A), tril(P A Pᵀ) that is factorised, and where each of its
  // values sits in filtered_'s value array. Empty permutation_: upper_ is factorised.
  std::vector<int> permutation_;
  Eigen::SparseMatrix<double, Eigen::ColMajor, int> lower_;
  std::vector<int> lower_source_;
  int pattern_factorizations_ = 0;  // numeric factorisations since the last analysis
  std::vector<int> outer_;
  std::vector<int> inner_;
  bool factorized_ = false;
  int analyses_ = 0;
  int factorizations_ = 0;
  FactorSize analysed_size_;
};

}  // namespace sd::sim
