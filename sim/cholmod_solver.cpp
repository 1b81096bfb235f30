#include "sim/cholmod_solver.hpp"

#include <fmt/format.h>

#include <Eigen/CholmodSupport>
#include <algorithm>
#include <cmath>
#include <vector>

#include "sim/solver_library_threads.hpp"

namespace sd::sim {

using ColMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

namespace {

// Eigen's CHOLMOD wrapper with one more entry point: the symbolic analysis for an ordering we
// give (CHOLMOD_GIVEN), which Eigen's analyzePattern cannot pass on.
class OrderedCholmod : public Eigen::CholmodDecomposition<ColMatrix, Eigen::Upper> {
 public:
  // The factor as the last analysis (or factorisation) left it; null before any.
  const cholmod_factor* factor() const { return m_cholmodFactor; }

  void analyze_with_ordering(const ColMatrix& a, std::vector<int>& permutation) {
    if (m_cholmodFactor != nullptr) {
      cholmod_free_factor(&m_cholmodFactor, &this->cholmod());
      m_cholmodFactor = nullptr;
    }
    cholmod_sparse view = Eigen::viewAsCholmod(a.selfadjointView<Eigen::Upper>());
    const int methods = this->cholmod().nmethods;
    const int ordering = this->cholmod().method[0].ordering;
    this->cholmod().nmethods = 1;
    this->cholmod().method[0].ordering = CHOLMOD_GIVEN;
    m_cholmodFactor = cholmod_analyze_p(&view, permutation.data(), nullptr, 0, &this->cholmod());
    this->cholmod().nmethods = methods;
    this->cholmod().method[0].ordering = ordering;
    m_isInitialized = true;
    m_info = m_cholmodFactor != nullptr ? Eigen::Success : Eigen::NumericalIssue;
    m_analysisIsOk = m_cholmodFactor != nullptr;
    m_factorizationIsOk = false;
  }

  // Takes the analysed factor's fill-reducing permutation P (its post-ordering included) out of
  // it: the factor is then that of a matrix given already permuted (natural ordering), so that
  // each factorisation reads tril(P A Pᵀ) as it is instead of making it by a permuted transpose
  // of the upper triangle (cholmod_factorize's only copy of A on the supernodal path), and each
  // solve permutes its right-hand side itself (as cholmod_solve did).
  std::vector<int> take_permutation() {
    const int n = static_cast<int>(m_cholmodFactor->n);
    int* perm = static_cast<int*>(m_cholmodFactor->Perm);
    std::vector<int> permutation(perm, perm + n);
    for (int k = 0; k < n; ++k) perm[k] = k;
    m_cholmodFactor->ordering = CHOLMOD_NATURAL;
    return permutation;
  }

  // The numeric factorisation of a matrix given as its permuted lower triangle (see
  // take_permutation); as Eigen's factorize() otherwise.
  void factorize_lower(const ColMatrix& lower) {
    cholmod_sparse view = Eigen::viewAsCholmod(lower.selfadjointView<Eigen::Lower>());
    cholmod_factorize_p(&view, m_shiftOffset, nullptr, 0, m_cholmodFactor, &this->cholmod());
    m_info = m_cholmodFactor->minor == m_cholmodFactor->n ? Eigen::Success : Eigen::NumericalIssue;
    m_factorizationIsOk = true;
  }
};

}  // namespace

struct CholmodSolver::Factor {
  OrderedCholmod llt;
};

std::vector<int> CholmodSolver::block_ordering(const int* outer, const int* inner, int rows) {
  // The vertex graph: vertex j's neighbours are the block columns of its first row (A is
  // structurally symmetric and its rows list their columns in increasing order).
  const int n = rows / 3;
  std::vector<int> graph_outer(static_cast<std::size_t>(n) + 1, 0);
  std::vector<int> graph_inner;
  graph_inner.reserve(static_cast<std::size_t>(outer[rows] / 9));
  for (int j = 0; j < n; ++j) {
    for (int k = outer[3 * j]; k < outer[3 * j + 1]; k += 3) graph_inner.push_back(inner[k] / 3);
    graph_outer[j + 1] = static_cast<int>(graph_inner.size());
  }
  cholmod_sparse graph{};
  graph.nrow = graph.ncol = static_cast<std::size_t>(n);
  graph.nzmax = graph_inner.size();
  graph.p = graph_outer.data();
  graph.i = graph_inner.data();
  graph.stype = -1;  // symmetric, lower part read
  graph.itype = CHOLMOD_INT;
  graph.xtype = CHOLMOD_PATTERN;
  graph.dtype = CHOLMOD_DOUBLE;
  graph.sorted = 1;
  graph.packed = 1;
  std::vector<int> vertex_order(static_cast<std::size_t>(n));
  std::vector<int> order;
  if (!cholmod_amd(&graph, nullptr, 0, vertex_order.data(), &factor_->llt.cholmod())) return order;
  order.resize(static_cast<std::size_t>(rows));
  for (int k = 0; k < n; ++k)
    for (int a = 0; a < 3; ++a) order[3 * k + a] = 3 * vertex_order[k] + a;
  return order;
}

CholmodSolver::CholmodSolver(CholmodMethod method)
    : method_(method), factor_(std::make_unique<Factor>()) {
  factor_->llt.setMode(method == CholmodMethod::supernodal ? Eigen::CholmodSupernodalLLt
                                                           : Eigen::CholmodSimplicialLLt);
}
CholmodSolver::~CholmodSolver() = default;
CholmodSolver::CholmodSolver(CholmodSolver&&) noexcept = default;
CholmodSolver& CholmodSolver::operator=(CholmodSolver&&) noexcept = default;

void CholmodSolver::throw_if_out_of_memory(int rows, const char* stage) {
  cholmod_common& common = factor_->llt.cholmod();
  if (common.status != CHOLMOD_OUT_OF_MEMORY && common.status != CHOLMOD_TOO_LARGE) return;
  common.status = CHOLMOD_OK;
  factorized_ = false;
  analyses_ = 0;  // analyse again next time
  outer_.clear();
  throw CholmodOutOfMemoryError(fmt::format(
      "out of memory: CHOLMOD could not allocate the {} of the {} unknowns' system (a factor of "
      "about {:.2g} GB was needed; {:.2g} GB were in use)",
      stage, rows, common.lnz * 8.0 / 1e9, static_cast<double>(common.memory_inuse) / 1e9));
}

void CholmodSolver::record_analysed_size() {
  const cholmod_common& common = factor_->llt.cholmod();
  const cholmod_factor* factor = factor_->llt.factor();
  analysed_size_ = {};
  if (factor == nullptr) return;
  analysed_size_.nonzeros = common.lnz;
  analysed_size_.flops = common.fl;
  analysed_size_.bytes =
      factor->is_super
          ? 8.0 * (static_cast<double>(factor->xsize) + static_cast<double>(factor->maxcsize)) +
                static_cast<double>(sizeof(int)) * static_cast<double>(factor->ssize)
          : (8.0 + sizeof(int)) * common.lnz;
}

void CholmodSolver::make_permuted_lower() {
  // Entry (i, j), i ≤ j, of A's upper triangle is entry (max(p_i, p_j), min(p_i, p_j)) of
  // tril(P A Pᵀ), with p the inverse permutation; columns sorted by row, as CHOLMOD's permuted
  // transpose made them.
  const int rows = static_cast<int>(upper_.rows());
  std::vector<int> inverse(static_cast<std::size_t>(rows));
  for (int k = 0; k < rows; ++k) inverse[static_cast<std::size_t>(permutation_[k])] = k;
  struct Entry {
    int row, column, source;
  };
  std::vector<Entry> entries;
  entries.reserve(upper_source_.size());
  std::size_t e = 0;
  for (int j = 0; j < rows; ++j)
    for (int k = upper_.outerIndexPtr()[j]; k < upper_.outerIndexPtr()[j + 1]; ++k, ++e) {
      const int pi = inverse[upper_.innerIndexPtr()[k]], pj = inverse[j];
      entries.push_back({std::max(pi, pj), std::min(pi, pj), upper_source_[e]});
    }
  // Two stable counting passes, by row and then by column: sorted by (column, row) in O(nnz)
  // (a comparison sort of the entries cost 5 % of a garment drape's profile, once per analysis).
  std::vector<Entry> by_row(entries.size());
  std::vector<int> start(static_cast<std::size_t>(rows) + 1, 0);
  for (const Entry& entry : entries) ++start[static_cast<std::size_t>(entry.row) + 1];
  for (int r = 0; r < rows; ++r) start[r + 1] += start[r];
  for (const Entry& entry : entries) by_row[static_cast<std::size_t>(start[entry.row]++)] = entry;
  lower_.resize(rows, rows);
  lower_.resizeNonZeros(static_cast<Eigen::Index>(entries.size()));
  int* outer = lower_.outerIndexPtr();
  std::fill(outer, outer + rows + 1, 0);
  for (const Entry& entry : by_row) ++outer[entry.column + 1];
  for (int j = 0; j < rows; ++j) outer[j + 1] += outer[j];
  std::vector<int> next(outer, outer + rows);
  lower_source_.resize(entries.size());
  for (const Entry& entry : by_row) {
    const int k = next[static_cast<std::size_t>(entry.column)]++;
    lower_.innerIndexPtr()[k] = entry.row;
    lower_.valuePtr()[k] = 0.0;
    lower_source_[static_cast<std::size_t>(k)] = entry.source;
  }
}

bool CholmodSolver::factorize(const SparseMatrixR& a, const ConstraintFilter& filter) {
  // The arrays below are read as a compressed matrix's (a matrix filled by insert() is not).
  if (!a.isCompressed()) {
    SparseMatrixR compressed = a;
    compressed.makeCompressed();
    return factorize(compressed, filter);
  }
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
    // CHOLMOD reads only the upper triangle of a symmetric matrix (stype 1), but its numeric
    // factorisation first makes the permuted transpose, scanning every stored entry: given the
    // upper triangle alone it scans half as many. The same entries in the same column order,
    // so the same factor, bit for bit. Column j of the upper triangle is the head of row j's
    // sorted columns, written in place (a set of triplets and a copy of A's pattern had cost 2 %
    // of an adaptive garment drape, once per new pattern).
    upper_source_.clear();
    std::vector<int> upper_outer(static_cast<std::size_t>(rows) + 1, 0);
    std::vector<int> upper_inner;
    upper_inner.reserve(static_cast<std::size_t>(a.nonZeros()) / 2 +
                        static_cast<std::size_t>(rows));
    for (int j = 0; j < rows; ++j) {
      for (int k = outer[j]; k < outer[j + 1] && inner[k] <= j; ++k) {
        if (k > outer[j] && inner[k] <= inner[k - 1]) {
          outer_.clear();  // analyse again next time
          throw std::invalid_argument(
              "the system matrix repeats an entry of its pattern or does not sort a row");
        }
        upper_inner.push_back(inner[k]);
        upper_source_.push_back(k);
      }
      upper_outer[j + 1] = static_cast<int>(upper_inner.size());
    }
    upper_.resize(rows, rows);
    upper_.resizeNonZeros(static_cast<Eigen::Index>(upper_inner.size()));
    std::copy(upper_outer.begin(), upper_outer.end(), upper_.outerIndexPtr());
    std::copy(upper_inner.begin(), upper_inner.end(), upper_.innerIndexPtr());
    std::fill(upper_.valuePtr(), upper_.valuePtr() + upper_.nonZeros(), 0.0);
  }
  // Values of S A S + (I − S), block by block; blocks between free vertices (S = I) stay A's.
  filtered_.assign(a.valuePtr(), a.valuePtr() + a.nonZeros());
  if (filter.constrained_count() > 0) {
    const int n = rows / 3;
    std::vector<Eigen::Matrix3d> filters(n);
    for (int i = 0; i < n; ++i) filters[i] = filter.filter_matrix(i);
    double* values = filtered_.data();
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
  limit_solver_library_threads();  // before CHOLMOD's OpenMP loops and OpenBLAS kernels
  if (!same_pattern) {
    // AMD on the vertex graph (a ninth of the scalar pattern's entries), each vertex's three
    // rows kept together: the analysis of a new pattern (after every adaptive topology change)
    // costs about a numeric factorisation when CHOLMOD orders the 3n scalar rows itself.
    std::vector<int> order = block_ordering(outer, inner, rows);
    if (order.empty())
      factor_->llt.analyzePattern(upper_);
    else
      factor_->llt.analyze_with_ordering(upper_, order);
    ++analyses_;
    throw_if_out_of_memory(rows, "analysis");
    record_analysed_size();
    permutation_.clear();
    pattern_factorizations_ = 0;
  }
  // The permuted lower triangle's index map costs about three of CHOLMOD's permuted transposes
  // to make, so a pattern is given to CHOLMOD permuted from its third factorisation on (an
  // adaptive run that changes its mesh at every step never pays for it).
  if (++pattern_factorizations_ == 3 && permutation_.empty() &&
      method_ == CholmodMethod::supernodal && factor_->llt.factor() != nullptr) {
    permutation_ = factor_->llt.take_permutation();
    make_permuted_lower();
  }
  if (!permutation_.empty()) {
    for (std::size_t e = 0; e < lower_source_.size(); ++e)
      lower_.valuePtr()[e] = filtered_[lower_source_[e]];
    factor_->llt.factorize_lower(lower_);
  } else {
    // The upper triangle's values (A's columns are sorted, so upper_'s entries are in the
    // order they were collected in).
    for (std::size_t e = 0; e < upper_source_.size(); ++e)
      upper_.valuePtr()[e] = filtered_[upper_source_[e]];
    factor_->llt.factorize(upper_);
  }
  ++factorizations_;
  throw_if_out_of_memory(rows, "factorisation");
  factorized_ = factor_->llt.info() == Eigen::Success;
  return factorized_;
}

Eigen::VectorXd CholmodSolver::apply_factor(const Eigen::VectorXd& r) const {
  if (permutation_.empty()) return factor_->llt.solve(r);
  // The factor is of P A Pᵀ: solve for P y with P r.
  const Eigen::Index rows = r.size();
  Eigen::VectorXd permuted(rows);
  for (Eigen::Index k = 0; k < rows; ++k) permuted[k] = r[permutation_[k]];
  const Eigen::VectorXd solved = factor_->llt.solve(permuted);
  Eigen::VectorXd y(rows);
  for (Eigen::Index k = 0; k < rows; ++k) y[permutation_[k]] = solved[k];
  return y;
}

LinearSolveStats CholmodSolver::solve_preconditioned(const SparseMatrixR& a,
                                                     const ConstraintFilter& filter,
                                                     const Eigen::VectorXd& b,
                                                     const Eigen::VectorXd& z, Eigen::VectorXd& s,
                                                     double tolerance, int max_iterations) {
  LinearSolveStats stats;
  if (factor_rows() != a.rows()) return stats;
  // With s = z + y, y in the filtered subspace: S A y = S (b − A z) =: r₀. On that subspace
  // S A S + (I − S) acts as S A, and S M⁻¹ S (M the old factor's matrix, SPD) is a symmetric
  // positive definite preconditioner, so the conjugate gradients stay in it.
  Eigen::VectorXd residual = b - a * z;
  filter.apply(residual);
  const double scale = residual.norm();
  Eigen::VectorXd y = Eigen::VectorXd::Zero(residual.size());
  s = z;
  if (scale == 0.0 || !std::isfinite(scale)) {
    stats.converged = scale == 0.0;
    return stats;
  }
  Eigen::VectorXd direction = apply_factor(residual);
  filter.apply(direction);
  double rho = residual.dot(direction);
  Eigen::VectorXd product;
  double relative = 1.0;
  while (stats.iterations < max_iterations) {
    product = a * direction;
    filter.apply(product);
    const double curvature = direction.dot(product);
    if (!(curvature > 0.0) || !(rho > 0.0)) break;  // the old factor no longer preconditions
    const double alpha = rho / curvature;
    y += alpha * direction;
    residual -= alpha * product;
    ++stats.iterations;
    relative = residual.norm() / scale;
    if (relative <= tolerance) break;
    Eigen::VectorXd preconditioned = apply_factor(residual);
    filter.apply(preconditioned);
    const double rho_next = residual.dot(preconditioned);
    direction = preconditioned + (rho_next / rho) * direction;
    rho = rho_next;
  }
  s = z + y;
  stats.relative_residual = relative;
  stats.converged = relative <= tolerance && s.allFinite();
  return stats;
}

LinearSolveStats CholmodSolver::solve(const SparseMatrixR& a, const ConstraintFilter& filter,
                                      const Eigen::VectorXd& b, const Eigen::VectorXd& z,
                                      Eigen::VectorXd& s) {
  LinearSolveStats stats;
  if (!factorized_) return stats;
  Eigen::VectorXd rhs = b - a * z;
  filter.apply(rhs);
  // The start's constrained residual, which constrained_relative_residual would compute again
  // the same way: the scale of the relative residual.
  const double scale = rhs.norm();
  Eigen::VectorXd y = apply_factor(rhs);
  filter.apply(y);
  s = z + y;
  Eigen::VectorXd residual = b - a * s;
  filter.apply(residual);
  stats.relative_residual = scale > 0.0 ? residual.norm() / scale : residual.norm();
  stats.converged = s.allFinite() && factor_->llt.info() == Eigen::Success;
  return stats;
}

}  // namespace sd::sim
