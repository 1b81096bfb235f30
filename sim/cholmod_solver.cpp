#include "sim/cholmod_solver.hpp"

#include <Eigen/CholmodSupport>
#include <algorithm>
#include <cmath>

namespace sd::sim {

using ColMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

struct CholmodSolver::Factor {
  Eigen::CholmodDecomposition<ColMatrix, Eigen::Lower> llt;
};

CholmodSolver::CholmodSolver(CholmodMethod method)
    : method_(method), factor_(std::make_unique<Factor>()) {
  factor_->llt.setMode(method == CholmodMethod::supernodal ? Eigen::CholmodSupernodalLLt
                                                           : Eigen::CholmodSimplicialLLt);
}
CholmodSolver::~CholmodSolver() = default;
CholmodSolver::CholmodSolver(CholmodSolver&&) noexcept = default;
CholmodSolver& CholmodSolver::operator=(CholmodSolver&&) noexcept = default;

bool CholmodSolver::factorize(const SparseMatrixR& a, const ConstraintFilter& filter) {
  const int rows = static_cast<int>(a.rows());
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  const bool same_pattern = analyses_ > 0 && static_cast<int>(outer_.size()) == rows + 1 &&
                            static_cast<int>(inner_.size()) == a.nonZeros() &&
                            std::equal(outer_.begin(), outer_.end(), outer) &&
                            std::equal(inner_.begin(), inner_.end(), inner);
  if (!same_pattern) {
    outer_.assign(outer, outer + rows + 1);
    inner_.assign(inner, inner + a.nonZeros());
    // A is structurally symmetric, so its row-major arrays read as column-major are A itself.
    filtered_ = Eigen::Map<const ColMatrix>(rows, rows, static_cast<int>(a.nonZeros()), outer,
                                            inner, a.valuePtr());
  }
  // Values of S A S + (I − S), block by block; blocks between free vertices (S = I) stay A's.
  std::copy(a.valuePtr(), a.valuePtr() + a.nonZeros(), filtered_.valuePtr());
  if (filter.constrained_count() > 0) {
    const int n = rows / 3;
    std::vector<Eigen::Matrix3d> filters(n);
    for (int i = 0; i < n; ++i) filters[i] = filter.filter_matrix(i);
    double* values = filtered_.valuePtr();
    for (int i = 0; i < n; ++i) {
      const int begin = outer[3 * i];
      const int width = outer[3 * i + 1] - begin;  // 3 × number of adjacent vertices
      for (int offset = 0; offset < width; offset += 3) {
        const int j = inner[begin + offset] / 3;
        if (filter.is_free(i) && filter.is_free(j)) continue;
        Eigen::Matrix3d block;
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) block(r, c) = values[outer[3 * i + r] + offset + c];
        block = filters[i] * block * filters[j];
        if (i == j) block += Eigen::Matrix3d::Identity() - filters[i];
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) values[outer[3 * i + r] + offset + c] = block(r, c);
      }
    }
  }
  if (!same_pattern) {
    factor_->llt.analyzePattern(filtered_);
    ++analyses_;
  }
  factor_->llt.factorize(filtered_);
  ++factorizations_;
  factorized_ = factor_->llt.info() == Eigen::Success;
  return factorized_;
}

LinearSolveStats CholmodSolver::solve(const SparseMatrixR& a, const ConstraintFilter& filter,
                                      const Eigen::VectorXd& b, const Eigen::VectorXd& z,
                                      Eigen::VectorXd& s) {
  LinearSolveStats stats;
  if (!factorized_) return stats;
  Eigen::VectorXd rhs = b - a * z;
  filter.apply(rhs);
  Eigen::VectorXd y = factor_->llt.solve(rhs);
  filter.apply(y);
  s = z + y;
  stats.relative_residual = constrained_relative_residual(a, filter, b, z, s);
  stats.converged = s.allFinite() && factor_->llt.info() == Eigen::Success;
  return stats;
}

}  // namespace sd::sim
