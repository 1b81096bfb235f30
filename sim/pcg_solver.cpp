#include "sim/pcg_solver.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "sim/parallel.hpp"

namespace sd::sim {

namespace {

// Vertices per chunk of the threaded product: a 32×32 sheet's 1,089 vertices make 4 chunks of
// about 60 µs of work each, well above oneTBB's cost of handing one out.
constexpr int kProductGrain = 256;

}  // namespace

bool VertexBlockMatrix::refill(const SparseMatrixR& a) {
  if (vertices_ == 0 || a.rows() != 3 * vertices_ || a.cols() != a.rows() || !a.isCompressed() ||
      a.nonZeros() != nonzeros_)
    return false;
  const int* outer = a.outerIndexPtr();
  const double* values = a.valuePtr();
  std::vector<char> kept(chunks_.size(), 1);
  parallel_chunks(vertices_, kProductGrain, [&](int c, int low, int high) {
    Chunk& chunk = chunks_[static_cast<std::size_t>(c)];
    const int* column = chunk.column.data();
    double* v = chunk.values.data();
    int b = 0;
    for (int i = low; i < high; ++i) {
      const int begin = outer[3 * i];
      const int width = outer[3 * i + 1] - begin;
      if (3 * (chunk.block_start[i - low + 1] - chunk.block_start[i - low]) != width) {
        kept[static_cast<std::size_t>(c)] = 0;  // not the pattern the caller said it was
        return;
      }
      for (int k = 0; k < width; k += 3, ++b) {
        const double* entries = values + begin + k;
        if (column[b] < 0) {
          if (!is_scaled_identity(entries, width)) {
            kept[static_cast<std::size_t>(c)] = 0;
            return;
          }
          *v++ = entries[0];
        } else {
          // A block that has become c·I stays full: the same sums (its six zeros add nothing).
          for (int r = 0; r < 3; ++r, v += 3) std::copy_n(entries + r * width, 3, v);
        }
      }
    }
  });
  return std::find(kept.begin(), kept.end(), 0) == kept.end();
}

bool VertexBlockMatrix::build(const SparseMatrixR& a, bool same_pattern) {
  if (same_pattern && refill(a)) return true;
  vertices_ = 0;
  if (a.rows() % 3 != 0 || a.cols() != a.rows() || !a.isCompressed()) return false;
  const int n = static_cast<int>(a.rows() / 3);
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  const double* values = a.valuePtr();
  chunks_.resize(static_cast<std::size_t>(chunk_count(n, kProductGrain)));
  std::vector<char> valid(chunks_.size(), 1);
  parallel_chunks(n, kProductGrain, [&](int c, int low, int high) {
    Chunk& chunk = chunks_[static_cast<std::size_t>(c)];
    chunk.block_start.assign(1, 0);
    chunk.column.clear();
    chunk.values.clear();
    for (int i = low; i < high; ++i) {
      // The three rows of a vertex hold the same columns, in runs of three from a multiple of
      // three: the structure the product relies on.
      const int begin = outer[3 * i];
      const int width = outer[3 * i + 1] - begin;
      if (width % 3 != 0 || outer[3 * i + 2] - outer[3 * i + 1] != width ||
          outer[3 * i + 3] - outer[3 * i + 2] != width) {
        valid[static_cast<std::size_t>(c)] = 0;
        return;
      }
      for (int k = 0; k < width; k += 3) {
        const int column = inner[begin + k];
        bool block = column % 3 == 0;
        for (int r = 0; r < 3 && block; ++r)
          for (int d = 0; d < 3; ++d)
            block = block && inner[begin + r * width + k + d] == column + d;
        if (!block) {
          valid[static_cast<std::size_t>(c)] = 0;
          return;
        }
        const double* entries = values + begin + k;
        if (is_scaled_identity(entries, width)) {
          chunk.column.push_back(-column - 1);
          chunk.values.push_back(entries[0]);
        } else {
          chunk.column.push_back(column);
          for (int r = 0; r < 3; ++r)
            chunk.values.insert(chunk.values.end(), entries + r * width, entries + r * width + 3);
        }
      }
      chunk.block_start.push_back(static_cast<int>(chunk.column.size()));
    }
  });
  if (std::find(valid.begin(), valid.end(), 0) != valid.end()) return false;
  vertices_ = n;
  nonzeros_ = a.nonZeros();
  return true;
}

int VertexBlockMatrix::scaled_identity_blocks() const {
  int count = 0;
  for (const Chunk& chunk : chunks_)
    count += static_cast<int>(std::count_if(chunk.column.begin(), chunk.column.end(),
                                            [](int column) { return column < 0; }));
  return count;
}

void VertexBlockMatrix::multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  const double* in = x.data();
  y.resize(3 * vertices_);
  double* out = y.data();
  parallel_chunks(vertices_, kProductGrain, [&](int c, int low, int high) {
    const Chunk& chunk = chunks_[static_cast<std::size_t>(c)];
    const int* column = chunk.column.data();
    const double* v = chunk.values.data();
    for (int i = low; i < high; ++i) {
      double sum0 = 0.0, sum1 = 0.0, sum2 = 0.0;
      for (int b = chunk.block_start[i - low]; b < chunk.block_start[i - low + 1]; ++b) {
        if (column[b] < 0) {
          // c·I: the nine-entry sums below with six exact zeros, so the same numbers.
          const double* xj = in - column[b] - 1;
          const double scale = *v++;
          sum0 += scale * xj[0];
          sum1 += scale * xj[1];
          sum2 += scale * xj[2];
        } else {
          const double* xj = in + column[b];
          const double x0 = xj[0], x1 = xj[1], x2 = xj[2];
          sum0 += v[0] * x0 + v[1] * x1 + v[2] * x2;
          sum1 += v[3] * x0 + v[4] * x1 + v[5] * x2;
          sum2 += v[6] * x0 + v[7] * x1 + v[8] * x2;
          v += 9;
        }
      }
      out[3 * i] = sum0;
      out[3 * i + 1] = sum1;
      out[3 * i + 2] = sum2;
    }
  });
}

bool BlockIncompleteCholesky::factorize(const SparseMatrixR& a,
                                        const std::vector<int>& diagonal_offsets,
                                        const ConstraintFilter& filter) {
  const int n = filter.vertex_count();
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  const double* values = a.valuePtr();
  std::vector<Eigen::Matrix3d> filters;
  if (filter.constrained_count() > 0) {
    filters.resize(n);
    for (int i = 0; i < n; ++i) filters[i] = filter.filter_matrix(i);
  }
  const auto read_block = [&](int i, int offset) {
    Eigen::Matrix3d block;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) block(r, c) = values[outer[3 * i + r] + offset + c];
    return block;
  };
  row_start_.assign(1, 0);
  column_.clear();
  b_upper_.clear();
  b_diagonal_.resize(n);
  for (int i = 0; i < n; ++i) {
    const bool free_i = filters.empty() || filter.is_free(i);
    const int width = outer[3 * i + 1] - outer[3 * i];
    for (int offset = diagonal_offsets[i] + 3; offset < width; offset += 3) {
      const int j = inner[outer[3 * i] + offset] / 3;
      Eigen::Matrix3d block = read_block(i, offset);
      if (!free_i || !(filters.empty() || filter.is_free(j)))
        block = filters[i] * block * filters[j];
      column_.push_back(j);
      b_upper_.push_back(block);
    }
    row_start_.push_back(static_cast<int>(column_.size()));
    Eigen::Matrix3d diagonal = read_block(i, diagonal_offsets[i]);
    if (!free_i)
      diagonal = filters[i] * diagonal * filters[i] + (Eigen::Matrix3d::Identity() - filters[i]);
    b_diagonal_[i] = 0.5 * (diagonal + diagonal.transpose());
  }
  for (double alpha : {0.0, 1e-4, 1e-3, 1e-2, 1e-1, 1.0})
    if (factorize_shifted(alpha)) {
      shift_ = alpha;
      return true;
    }
  return false;
}

bool BlockIncompleteCholesky::factorize_shifted(double alpha) {
  const int n = static_cast<int>(b_diagonal_.size());
  upper_ = b_upper_;
  std::vector<Eigen::Matrix3d>& pivot = pivot_;
  pivot.resize(n);
  for (int i = 0; i < n; ++i) pivot[i] = (1.0 + alpha) * b_diagonal_[i];
  pivot_inverse_.resize(n);
  for (int i = 0; i < n; ++i) {
    pivot[i] = 0.5 * (pivot[i] + pivot[i].transpose());
    // Positive definite by Sylvester's criterion (the leading minors), then the inverse from the
    // cofactors: what a 3x3 LLT and its solve decide and give, without their general loops.
    const Eigen::Matrix3d& p = pivot[i];
    const double minor2 = p(0, 0) * p(1, 1) - p(0, 1) * p(1, 0);
    if (!(p(0, 0) > 0.0) || !(minor2 > 0.0) || !(p.determinant() > 0.0)) return false;
    pivot_inverse_[i] = p.inverse();
    if (!pivot_inverse_[i].allFinite()) return false;
    // Schur complement restricted to the pattern: for k < j both above-diagonal neighbours of
    // i, U_kj −= U_ikᵀ P_i⁻¹ U_ij (no fill: dropped if (k, j) is not in the pattern).
    const int begin = row_start_[i];
    const int end = row_start_[i + 1];
    for (int p_index = begin; p_index < end; ++p_index) {
      const int k = column_[p_index];
      const Eigen::Matrix3d w = upper_[p_index].transpose() * pivot_inverse_[i];
      pivot[k].noalias() -= w * upper_[p_index];
      int cursor = row_start_[k];
      const int row_end = row_start_[k + 1];
      for (int q_index = p_index + 1; q_index < end; ++q_index) {
        const int j = column_[q_index];
        while (cursor < row_end && column_[cursor] < j) ++cursor;
        if (cursor == row_end) break;
        if (column_[cursor] == j) upper_[cursor].noalias() -= w * upper_[q_index];
      }
    }
  }
  return true;
}

void BlockIncompleteCholesky::apply(const Eigen::VectorXd& r, Eigen::VectorXd& out) const {
  const int n = static_cast<int>(pivot_inverse_.size());
  // Forward: (P Lᵀ)ᵀ y = Uᵀ y = r, column by column.
  out = r;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d y = pivot_inverse_[i] * out.segment<3>(3 * i);
    out.segment<3>(3 * i) = y;
    for (int k = row_start_[i]; k < row_start_[i + 1]; ++k)
      out.segment<3>(3 * column_[k]).noalias() -= upper_[k].transpose() * y;
  }
  // Backward: Lᵀ x = y, i.e. x_i = y_i − P_i⁻¹ Σ_{j>i} U_ij x_j.
  for (int i = n - 1; i >= 0; --i) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int k = row_start_[i]; k < row_start_[i + 1]; ++k)
      sum.noalias() += upper_[k] * out.segment<3>(3 * column_[k]);
    out.segment<3>(3 * i) -= pivot_inverse_[i] * sum;
  }
}

void BlockIncompleteCholesky::multiply(const Eigen::VectorXd& x, Eigen::VectorXd& out) const {
  const int n = static_cast<int>(pivot_.size());
  // t = Lᵀ x = P⁻¹ U x, then out = L (P t) with L = Uᵀ P⁻¹: out_i = P_i t_i + Σ_{k<i} U_kiᵀ t_k.
  Eigen::VectorXd t(3 * n);
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d sum = pivot_[i] * x.segment<3>(3 * i);
    for (int k = row_start_[i]; k < row_start_[i + 1]; ++k)
      sum.noalias() += upper_[k] * x.segment<3>(3 * column_[k]);
    t.segment<3>(3 * i) = pivot_inverse_[i] * sum;
  }
  out.resize(3 * n);
  for (int i = 0; i < n; ++i) out.segment<3>(3 * i) = pivot_[i] * t.segment<3>(3 * i);
  for (int i = 0; i < n; ++i)
    for (int k = row_start_[i]; k < row_start_[i + 1]; ++k)
      out.segment<3>(3 * column_[k]).noalias() += upper_[k].transpose() * t.segment<3>(3 * i);
}

void PcgSolver::build_block_jacobi(const SparseMatrixR& a,
                                   const std::vector<int>& diagonal_offsets) {
  const int n = static_cast<int>(diagonal_offsets.size());
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
}

LinearSolveStats PcgSolver::solve(const SparseMatrixR& a, const std::vector<int>& diagonal_offsets,
                                  const ConstraintFilter& filter, const Eigen::VectorXd& b,
                                  const Eigen::VectorXd& z, Eigen::VectorXd& s, double tolerance,
                                  int max_iterations, bool refresh_preconditioner,
                                  bool same_pattern) {
  const int n = filter.vertex_count();
  const bool reuse = !refresh_preconditioner && prepared_vertices_ == n;
  if (!reuse) {
    // The two-level cycle's IC(0) (and the coarse matrix from its B) on the membrane pattern:
    // the coarse level carries the smooth error the bends' weak second-ring couplings hold, and
    // the factor and its sweeps get several times cheaper (pinned 128x128 sheet: 7.0 iterations
    // a solve against 7.9, stepping CPU 0.68x; docs/benchmarks.md, "Twelfth round").
    const bool reduced =
        preconditioner_ == PcgPreconditioner::two_level && membrane_.build(a, diagonal_offsets);
    incomplete_ready_ =
        preconditioner_ != PcgPreconditioner::block_jacobi &&
        incomplete_.factorize(reduced ? membrane_.matrix() : a,
                              reduced ? membrane_.diagonal_offsets() : diagonal_offsets, filter);
    coarse_ready_ = incomplete_ready_ && preconditioner_ == PcgPreconditioner::two_level &&
                    coarse_.build(incomplete_.row_start(), incomplete_.column(),
                                  incomplete_.b_upper(), incomplete_.b_diagonal());
    // Block Jacobi: the preconditioner asked for, or the fallback if IC(0) broke down even with
    // a shift (built only then: 0.5 % of a pinned sheet's run).
    if (!incomplete_ready_) build_block_jacobi(a, diagonal_offsets);
    prepared_vertices_ = n;
  }
  const bool incomplete = incomplete_ready_;
  const bool coarse = coarse_ready_;
  const bool blocks = product_.build(a, same_pattern);
  const auto multiply = [&](const Eigen::VectorXd& x, Eigen::VectorXd& y) {
    if (blocks)
      product_.multiply(x, y);
    else
      y.noalias() = a * x;
  };
  const auto precondition = [&](const Eigen::VectorXd& in, Eigen::VectorXd& out) {
    if (coarse) {
      // Balancing two-grid cycle on B, with Q = P Ac⁻¹ Pᵀ (exact on the coarse space, so
      // Q B Q = Q) and IC(0) between (Mandel's balancing Neumann-Neumann form):
      //   out = Q in + (I − Q B) IC⁻¹ (I − B Q) in,
      // symmetric positive definite whenever IC(0) is, unlike a V-cycle with IC(0) as smoother
      // (measured: that one lost definiteness on a swinging sheet, and the cheaper A-DEF2 form
      // took more iterations than IC(0) alone). B x = S A x for filtered x.
      const auto multiply_b = [&](const Eigen::VectorXd& x, Eigen::VectorXd& y) {
        multiply(x, y);
        filter.apply(y);
      };
      cycle_coarse_.setZero(in.size());
      coarse_.add_correction(in, cycle_coarse_);
      filter.apply(cycle_coarse_);
      multiply_b(cycle_coarse_, cycle_product_);
      cycle_residual_ = in - cycle_product_;
      incomplete_.apply(cycle_residual_, out);
      filter.apply(out);
      multiply_b(out, cycle_product_);
      out += cycle_coarse_;
      cycle_coarse_.setZero(in.size());
      coarse_.add_correction(cycle_product_, cycle_coarse_);
      out -= cycle_coarse_;
    } else if (incomplete) {
      incomplete_.apply(in, out);
    } else {
      out.resize(in.size());
      for (int i = 0; i < n; ++i) out.segment<3>(3 * i) = inverse_blocks_[i] * in.segment<3>(3 * i);
    }
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
  if (!(delta0 > 0.0)) {
    // r·M⁻¹r is zero only for a zero residual (z solves the system); negative or NaN, the
    // preconditioner is not positive definite and there is no step: never report s = z as one.
    stats.converged = r_.squaredNorm() == 0.0;
    return stats;
  }
  if (!(delta > threshold)) {
    stats.converged = true;
    return stats;
  }
  while (stats.iterations < max_iterations) {
    multiply(c_, q_);
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
