#include "sim/membrane_pattern.hpp"

namespace sd::sim {

bool MembranePattern::build(const SparseMatrixR& a, const std::vector<int>& diagonal_offsets) {
  if (a.rows() % 3 != 0 || a.cols() != a.rows() || !a.isCompressed()) return false;
  const int n = static_cast<int>(a.rows() / 3);
  if (static_cast<int>(diagonal_offsets.size()) != n) return false;
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  const double* values = a.valuePtr();
  outer_.assign(1, 0);
  inner_.clear();
  values_.clear();
  diagonal_offsets_.resize(n);
  dropped_ = 0;
  std::vector<char> keep;
  for (int i = 0; i < n; ++i) {
    const int begin = outer[3 * i];
    const int width = outer[3 * i + 1] - begin;
    if (width % 3 != 0 || outer[3 * i + 2] - outer[3 * i + 1] != width ||
        outer[3 * i + 3] - outer[3 * i + 2] != width || diagonal_offsets[i] % 3 != 0 ||
        inner[begin + diagonal_offsets[i]] != 3 * i)
      return false;
    keep.assign(static_cast<std::size_t>(width / 3), 1);
    double moved = 0.0;  // the dropped blocks' c, added to the diagonal
    for (int k = 0; k < width; k += 3) {
      if (k == diagonal_offsets[i]) continue;
      if (inner[begin + k] % 3 != 0) return false;
      if (is_scaled_identity(values + begin + k, width)) {
        keep[static_cast<std::size_t>(k / 3)] = 0;
        moved += values[begin + k];
        ++dropped_;
      }
    }
    for (int r = 0; r < 3; ++r) {
      const int row = begin + r * width;
      for (int k = 0; k < width; k += 3) {
        if (!keep[static_cast<std::size_t>(k / 3)]) continue;
        if (r == 0 && k == diagonal_offsets[i])
          diagonal_offsets_[i] = static_cast<int>(inner_.size()) - outer_.back();
        for (int d = 0; d < 3; ++d) {
          inner_.push_back(inner[row + k + d]);
          values_.push_back(values[row + k + d] +
                            (k == diagonal_offsets[i] && d == r ? moved : 0.0));
        }
      }
      outer_.push_back(static_cast<int>(inner_.size()));
    }
  }
  matrix_ = Eigen::Map<const SparseMatrixR>(3 * n, 3 * n, static_cast<int>(inner_.size()),
                                            outer_.data(), inner_.data(), values_.data());
  return true;
}

}  // namespace sd::sim
