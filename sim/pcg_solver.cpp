#include "sim/pcg_solver.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/LU>

namespace sd::sim {

LinearSolveStats PcgSolver::solve(const SparseMatrixR& a, const std::vector<int>& diagonal_offsets,
                                  const ConstraintFilter& filter, const Eigen::VectorXd& b,
                                  const Eigen::VectorXd& z, Eigen::VectorXd& s, double tolerance,
                                  int max_iterations) {
  const int n = filter.vertex_count();
  inverse_blocks_.resize(n);
  const double* values = a.valuePtr();
  for (int i = 0; i < n; ++i) {
    Eigen::Matrix3d block;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        block(r, c) = values[block_value_index(a, i, diagonal_offsets[i], r, c)];
    // A diagonal block of an SPD matrix is SPD; fall back to the diagonal if it is not.
    Eigen::Matrix3d inverse;
    bool invertible = false;
    block.computeInverseWithCheck(inverse, invertible);
    if (!invertible || !inverse.allFinite()) {
      inverse = Eigen::Matrix3d::Zero();
      for (int r = 0; r < 3; ++r) inverse(r, r) = block(r, r) > 0.0 ? 1.0 / block(r, r) : 1.0;
    }
    inverse_blocks_[i] = inverse;
  }
  const auto precondition = [&](const Eigen::VectorXd& in, Eigen::VectorXd& out) {
    out.resize(in.size());
    for (int i = 0; i < n; ++i) out.segment<3>(3 * i) = inverse_blocks_[i] * in.segment<3>(3 * i);
    filter.apply(out);
  };

  LinearSolveStats stats;
  s = z;
  r_.noalias() = b - a * s;
  filter.apply(r_);
  precondition(r_, c_);
  double delta = r_.dot(c_);
  const double delta0 = delta;
  const double threshold = tolerance * tolerance * delta0;
  if (!(delta > threshold) || delta0 <= 0.0) {
    stats.converged = std::isfinite(delta);
    return stats;
  }
  while (stats.iterations < max_iterations) {
    q_.noalias() = a * c_;
    filter.apply(q_);
    const double curvature = c_.dot(q_);
    if (!(curvature > 0.0)) break;  // A is not positive definite on the filtered subspace
    const double alpha = delta / curvature;
    s += alpha * c_;
    r_ -= alpha * q_;
    precondition(r_, t_);
    const double delta_old = delta;
    delta = r_.dot(t_);
    ++stats.iterations;
    if (!std::isfinite(delta)) break;
    if (delta <= threshold) {
      stats.converged = true;
      break;
    }
    c_ = t_ + (delta / delta_old) * c_;
  }
  stats.relative_residual = std::sqrt(std::max(delta, 0.0) / delta0);
  return stats;
}

double constrained_relative_residual(const SparseMatrixR& a, const ConstraintFilter& filter,
                                     const Eigen::VectorXd& b, const Eigen::VectorXd& z,
                                     const Eigen::VectorXd& s) {
  Eigen::VectorXd r = b - a * s;
  filter.apply(r);
  Eigen::VectorXd r0 = b - a * z;
  filter.apply(r0);
  const double scale = r0.norm();
  return scale > 0.0 ? r.norm() / scale : r.norm();
}

}  // namespace sd::sim
