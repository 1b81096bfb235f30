#include "sim/coarse_correction.hpp"

#include <algorithm>

namespace sd::sim {

void CoarseCorrection::aggregate_vertices(const std::vector<int>& row_start,
                                          const std::vector<int>& column) {
  const int n = static_cast<int>(row_start.size()) - 1;
  // Symmetric adjacency of B's pattern: the stretch and shear springs along the mesh's edges
  // and the bending couplings across each hinge, so an aggregate holds a vertex and its second
  // ring, and the vertices left over join one (tens of vertices each). Keeping only the strong
  // couplings (|B_ij|² ≥ θ² |B_ii| |B_jj|, θ = 0.08, smoothed aggregation's rule), i.e. the mesh's
  // edges, made aggregates of 5–9 vertices: about as many iterations but a coarse system 3× larger,
  // and the pinned 64x64 sheet's run 1.24× dearer (1.54 against 1.24 s CPU).
  std::vector<int> degree(n + 1, 0);
  for (int i = 0; i < n; ++i)
    for (int k = row_start[i]; k < row_start[i + 1]; ++k) {
      ++degree[i + 1];
      ++degree[column[k] + 1];
    }
  for (int i = 0; i < n; ++i) degree[i + 1] += degree[i];
  std::vector<int> neighbours(degree[n]);
  std::vector<int> fill(degree.begin(), degree.end() - 1);
  for (int i = 0; i < n; ++i)
    for (int k = row_start[i]; k < row_start[i + 1]; ++k) {
      neighbours[fill[i]++] = column[k];
      neighbours[fill[column[k]]++] = i;
    }
  // Greedy distance-1 aggregation in vertex order (deterministic): a vertex none of whose
  // neighbours is taken starts an aggregate with all of them; then each vertex left joins the
  // aggregate of its first aggregated neighbour (or makes its own if it has none).
  aggregate_.assign(n, -1);
  aggregate_count_ = 0;
  for (int i = 0; i < n; ++i) {
    if (aggregate_[i] >= 0) continue;
    bool free_neighbourhood = true;
    for (int k = degree[i]; k < degree[i + 1] && free_neighbourhood; ++k)
      free_neighbourhood = aggregate_[neighbours[k]] < 0;
    if (!free_neighbourhood) continue;
    aggregate_[i] = aggregate_count_;
    for (int k = degree[i]; k < degree[i + 1]; ++k) aggregate_[neighbours[k]] = aggregate_count_;
    ++aggregate_count_;
  }
  const std::vector<int> first_pass = aggregate_;
  for (int i = 0; i < n; ++i) {
    if (aggregate_[i] >= 0) continue;
    for (int k = degree[i]; k < degree[i + 1] && aggregate_[i] < 0; ++k)
      if (first_pass[neighbours[k]] >= 0) aggregate_[i] = first_pass[neighbours[k]];
    if (aggregate_[i] < 0) aggregate_[i] = aggregate_count_++;
  }
}

bool CoarseCorrection::build(const std::vector<int>& row_start, const std::vector<int>& column,
                             const std::vector<Eigen::Matrix3d>& upper,
                             const std::vector<Eigen::Matrix3d>& diagonal) {
  const int n = static_cast<int>(diagonal.size());
  const bool same_pattern = row_start == row_start_ && column == column_;
  if (!same_pattern) {
    row_start_ = row_start;
    column_ = column;
    aggregate_vertices(row_start, column);
    // Ac's block pattern: for each block column J the sorted block rows I.
    const int m = aggregate_count_;
    std::vector<std::vector<int>> rows(m);
    for (int i = 0; i < n; ++i) {
      const int a = aggregate_[i];
      rows[a].push_back(a);
      for (int k = row_start[i]; k < row_start[i + 1]; ++k) {
        const int b = aggregate_[column[k]];
        rows[b].push_back(a);
        rows[a].push_back(b);
      }
    }
    std::vector<int> outer(3 * static_cast<std::size_t>(m) + 1, 0);
    std::vector<int> inner;
    for (int j = 0; j < m; ++j) {
      std::sort(rows[j].begin(), rows[j].end());
      rows[j].erase(std::unique(rows[j].begin(), rows[j].end()), rows[j].end());
      for (int b = 0; b < 3; ++b) {
        for (int i : rows[j])
          for (int a = 0; a < 3; ++a) inner.push_back(3 * i + a);
        outer[3 * j + b + 1] = static_cast<int>(inner.size());
      }
    }
    std::vector<double> zeros(inner.size(), 0.0);
    coarse_ = Eigen::Map<const Eigen::SparseMatrix<double>>(
        3 * m, 3 * m, static_cast<int>(inner.size()), outer.data(), inner.data(), zeros.data());
    // Value index of entry (0, 0) of block (I, J): column 3J starts at outer[3J]; block row I
    // sits at its position among column J's block rows.
    const auto target = [&](int block_row, int block_column) {
      const std::vector<int>& list = rows[block_column];
      const int position =
          static_cast<int>(std::lower_bound(list.begin(), list.end(), block_row) - list.begin());
      return outer[3 * block_column] + 3 * position;
    };
    upper_target_.resize(column.size());
    lower_target_.resize(column.size());
    diagonal_target_.resize(n);
    for (int i = 0; i < n; ++i) {
      const int a = aggregate_[i];
      diagonal_target_[i] = target(a, a);
      for (int k = row_start[i]; k < row_start[i + 1]; ++k) {
        const int b = aggregate_[column[k]];
        upper_target_[k] = target(a, b);
        lower_target_[k] = target(b, a);
      }
    }
    analysed_ = false;
  }
  // Ac = Pᵀ B P: each fine block added into its aggregates' block; B_ij (i < j) and its
  // transpose B_ji.
  double* values = coarse_.valuePtr();
  const int* outer = coarse_.outerIndexPtr();
  std::fill(values, values + coarse_.nonZeros(), 0.0);
  // Column length of block column J (3 entries per block row): the same for its three columns.
  const auto add_block = [&](int index, int block_column, const Eigen::Matrix3d& block) {
    const int length = outer[3 * block_column + 1] - outer[3 * block_column];
    for (int b = 0; b < 3; ++b)
      for (int a = 0; a < 3; ++a) values[index + b * length + a] += block(a, b);
  };
  for (int i = 0; i < n; ++i) {
    const int a = aggregate_[i];
    add_block(diagonal_target_[i], a, diagonal[i]);
    for (int k = row_start[i]; k < row_start[i + 1]; ++k) {
      const int b = aggregate_[column[k]];
      add_block(upper_target_[k], b, upper[k]);
      add_block(lower_target_[k], a, upper[k].transpose());
    }
  }
  if (!analysed_) {
    factor_.analyzePattern(coarse_);
    analysed_ = true;
  }
  factor_.factorize(coarse_);
  return factor_.info() == Eigen::Success;
}

void CoarseCorrection::add_correction(const Eigen::VectorXd& r, Eigen::VectorXd& out) const {
  const int n = static_cast<int>(aggregate_.size());
  coarse_rhs_.setZero(3 * aggregate_count_);
  for (int i = 0; i < n; ++i) coarse_rhs_.segment<3>(3 * aggregate_[i]) += r.segment<3>(3 * i);
  coarse_solution_ = factor_.solve(coarse_rhs_);
  for (int i = 0; i < n; ++i)
    out.segment<3>(3 * i) += coarse_solution_.segment<3>(3 * aggregate_[i]);
}

}  // namespace sd::sim
