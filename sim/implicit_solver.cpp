#include "sim/implicit_solver.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

#include "sim/parallel.hpp"

namespace sd::sim {

std::string_view solver_name(LinearSolverKind solver) {
  return solver == LinearSolverKind::pcg ? "pcg" : "cholmod";
}

std::optional<LinearSolverKind> parse_solver(std::string_view name) {
  if (name == "pcg" || name == "pcg-two-level") return LinearSolverKind::pcg;
  if (name == "cholmod") return LinearSolverKind::cholmod;
  return std::nullopt;
}
namespace {

// Vertices per chunk when the pair springs' cross blocks widen the matrix (a vertex's rows
// hold about 27 entries each).
constexpr int kCrossRowGrain = 512;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

void ImplicitSolver::add_extra_force(const ClothModel& model, const StepForces* extra,
                                     const Eigen::VectorXd& x, const Eigen::VectorXd& v) {
  if (extra == nullptr) return;
  for (const VertexDamping& d : extra->drags)
    force_.segment<3>(3 * d.vertex) +=
        d.force - d.coefficient * (v.segment<3>(3 * d.vertex) - d.reference_velocity);
  for (const PointSpring& s : extra->springs) {
    const std::array<int, 3>& corners = model.triangles[s.triangle].vertices;
    const double f =
        s.preload + s.stiffness * (s.target - along_spring_normal(s, corners, x)) -
        s.damping * (along_spring_normal(s, corners, v) - s.normal.dot(s.reference_velocity));
    for (int k = 0; k < 3; ++k) force_.segment<3>(3 * corners[k]) += (s.weights[k] * f) * s.normal;
  }
  for (const PairSpring& s : extra->pair_springs) {
    const Eigen::Vector3d f = pair_spring_force(s, x, v);
    for (int k = 0; k < 4; ++k) force_.segment<3>(3 * s.vertices[k]) += s.weights[k] * f;
  }
}

void ImplicitSolver::assemble(const ClothModel& model, const ForceSettings& forces, double beta,
                              const Eigen::VectorXd& x, const Eigen::VectorXd& v,
                              const Eigen::VectorXd* u, const StepForces* extra,
                              ImplicitSolveResult& result, EnergyBreakdown* energy) {
  const auto start = std::chrono::steady_clock::now();
  const SparseMatrixR& pattern = model.pattern.zero_matrix;
  if (matrix_.rows() != pattern.rows() || matrix_.nonZeros() != pattern.nonZeros() ||
      !std::equal(pattern.outerIndexPtr(), pattern.outerIndexPtr() + pattern.rows() + 1,
                  matrix_.outerIndexPtr()) ||
      !std::equal(pattern.innerIndexPtr(), pattern.innerIndexPtr() + pattern.nonZeros(),
                  matrix_.innerIndexPtr())) {
    matrix_ = pattern;
    ++pattern_changes_;
  } else
    std::fill(matrix_.valuePtr(), matrix_.valuePtr() + matrix_.nonZeros(), 0.0);
  double* values = matrix_.valuePtr();
  for (int i = 0; i < model.vertex_count; ++i)
    for (int a = 0; a < 3; ++a)
      values[block_value_index(matrix_, i, model.pattern.diagonal_offsets[i], a, a)] =
          model.mass[i];
  JacobianTarget target;
  target.kind = JacobianKind::solve;
  target.matrix = &matrix_;
  target.dfdx_scale = -beta * beta;
  target.dfdv_scale = -beta;
  if (u != nullptr) {
    product_.setZero(u->size());
    target.product_input = u;
    target.product_output = &product_;
  }
  evaluate_forces(model, forces, x, v, force_, energy, &target);
  if (extra != nullptr) {
    // Vertex drags: ∂f/∂v = −C, so A gains β C on the vertex's diagonal block.
    for (const VertexDamping& d : extra->drags)
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
          values[block_value_index(matrix_, d.vertex, model.pattern.diagonal_offsets[d.vertex], a,
                                   b)] += beta * d.coefficient(a, b);
    // Point springs: ∂f_k/∂x_l = −k w_k w_l n nᵀ and ∂f_k/∂v_l = −c w_k w_l n nᵀ, so block
    // (k, l) of A gains (β² k + β c) w_k w_l n nᵀ; all within the triangle's own blocks.
    for (const PointSpring& s : extra->springs) {
      const TriangleElement& t = model.triangles[s.triangle];
      const Eigen::Matrix3d outer = s.normal * s.normal.transpose();
      const double scale = beta * beta * s.stiffness + beta * s.damping;
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) {
          const double w = scale * s.weights[k] * s.weights[l];
          for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
              values[block_value_index(matrix_, t.vertices[k], t.blocks[3 * k + l], a, b)] +=
                  w * outer(a, b);
        }
      if (u != nullptr) {
        const double along = along_spring_normal(s, t.vertices, *u);
        for (int k = 0; k < 3; ++k)
          product_.segment<3>(3 * t.vertices[k]) -= (s.stiffness * s.weights[k] * along) * s.normal;
      }
    }
    // Pair springs: the blocks between neighbours in the mesh (each side's own, and across the
    // pair where the two happen to be neighbours) go into matrix_; add_cross_blocks adds the
    // others on a widened pattern. The product term is exact.
    for (const PairSpring& s : extra->pair_springs) {
      for (int k = 0; k < 4; ++k)
        for (int l = 0; l < 4; ++l) {
          const int i = s.vertices[k];
          const int offset =
              k == l ? model.pattern.diagonal_offsets[i] : block_offset(matrix_, i, s.vertices[l]);
          if (offset < 0) continue;
          const Eigen::Matrix3d block = pair_block(s, beta, k, l);
          for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
              values[block_value_index(matrix_, i, offset, a, b)] += block(a, b);
        }
      if (u != nullptr) {
        const double along = along_pair_normal(s, *u);
        for (int k = 0; k < 4; ++k)
          product_.segment<3>(3 * s.vertices[k]) -= (s.stiffness * s.weights[k] * along) * s.normal;
      }
    }
  }
  add_extra_force(model, extra, x, v);
  add_cross_blocks(model, beta, extra);
  result.forces_seconds += seconds_since(start);
}

void ImplicitSolver::add_cross_blocks(const ClothModel& model, double beta,
                                      const StepForces* extra) {
  widened_ = false;
  const bool keep = keep_cross_pattern_ && kept_cross_pattern_ == pattern_changes_;
  if (!keep_cross_pattern_ || kept_cross_pattern_ != pattern_changes_) kept_cross_.clear();
  if ((extra == nullptr || extra->pair_springs.empty()) && kept_cross_.empty()) return;
  struct Block {
    int row = 0;  // vertices
    int column = 0;
    Eigen::Matrix3d value;
  };
  std::vector<Block> blocks;
  if (extra != nullptr)
    for (const PairSpring& s : extra->pair_springs)
      for (int k = 0; k < 4; ++k)
        for (int l = 0; l < 4; ++l) {
          const int i = s.vertices[k], j = s.vertices[l];
          if (k == l || i == j || block_offset(matrix_, i, j) >= 0) continue;
          blocks.push_back({i, j, pair_block(s, beta, k, l)});
        }
  if (blocks.empty() && kept_cross_.empty()) return;
  const auto before = [](const Block& a, const Block& b) {
    return a.row != b.row ? a.row < b.row : a.column < b.column;
  };
  std::sort(blocks.begin(), blocks.end(), before);
  // One block per (row, column): several springs can join the same two vertices.
  if (!blocks.empty()) {
    std::size_t kept = 0;
    for (std::size_t b = 1; b < blocks.size(); ++b) {
      if (blocks[b].row == blocks[kept].row && blocks[b].column == blocks[kept].column)
        blocks[kept].value += blocks[b].value;
      else
        blocks[++kept] = blocks[b];
    }
    blocks.resize(kept + 1);
  }
  if (keep_cross_pattern_) {
    // The kept pattern: the blocks in use joined with those kept from earlier steps (as zeros),
    // started afresh when it has grown to more than twice what is in use plus 16 blocks and 1 %
    // of the mesh's (the extra fill would cost more than the analyses it saves).
    std::vector<Block> joined;
    joined.reserve(blocks.size() + kept_cross_.size());
    std::size_t b = 0, k = 0;
    while (b < blocks.size() || k < kept_cross_.size()) {
      if (k == kept_cross_.size() ||
          (b < blocks.size() &&
           std::array<int, 2>{blocks[b].row, blocks[b].column} <= kept_cross_[k])) {
        if (k < kept_cross_.size() &&
            std::array<int, 2>{blocks[b].row, blocks[b].column} == kept_cross_[k])
          ++k;
        joined.push_back(blocks[b++]);
      } else {
        joined.push_back({kept_cross_[k][0], kept_cross_[k][1], Eigen::Matrix3d::Zero()});
        ++k;
      }
    }
    const std::size_t slack = 16 + static_cast<std::size_t>(matrix_.nonZeros()) / 900;
    if (keep && joined.size() <= 2 * blocks.size() + slack) blocks = std::move(joined);
    kept_cross_.clear();
    for (const Block& block : blocks) kept_cross_.push_back({block.row, block.column});
    kept_cross_pattern_ = pattern_changes_;
    if (blocks.empty()) return;
  }

  // Merge each vertex's rows with its cross blocks' columns (both sorted). Every row of a vertex
  // holds the same block columns, so the block structure (and offset(i, j)) stays per vertex.
  // coupled_ written in place, rows on all threads: vertex i's rows gain 3 entries per block in
  // its row, so row 3i + a starts 3·(3·B_i + a·c_i) entries later than in matrix_ (B_i blocks
  // in the rows of vertices before i, c_i in vertex i's). Each row is the same merge as before,
  // so the same entries in the same places on any thread count.
  const int n = model.vertex_count;
  const int* outer = matrix_.outerIndexPtr();
  const int* inner = matrix_.innerIndexPtr();
  const double* values = matrix_.valuePtr();
  std::vector<int> first_block(static_cast<std::size_t>(n) + 1, 0);  // B_i
  for (const Block& block : blocks) ++first_block[static_cast<std::size_t>(block.row) + 1];
  for (int i = 0; i < n; ++i) first_block[i + 1] += first_block[i];
  const int nonzeros = static_cast<int>(matrix_.nonZeros()) + 9 * static_cast<int>(blocks.size());
  coupled_.resize(3 * n, 3 * n);
  coupled_.resizeNonZeros(nonzeros);
  int* new_outer = coupled_.outerIndexPtr();
  int* new_inner = coupled_.innerIndexPtr();
  double* new_values = coupled_.valuePtr();
  coupled_diagonal_.assign(static_cast<std::size_t>(n), -1);
  parallel_chunks(n, kCrossRowGrain, [&](int, int low, int high) {
    for (int i = low; i < high; ++i) {
      const int first = first_block[i], last = first_block[i + 1];
      for (int a = 0; a < 3; ++a) {
        const int r = 3 * i + a;
        const int row_begin = outer[r] + 3 * (3 * first + a * (last - first));
        new_outer[r] = row_begin;
        int out = row_begin;
        int p = outer[r];
        int q = first;
        while (p < outer[r + 1] || q < last) {
          if (q == last || (p < outer[r + 1] && inner[p] < 3 * blocks[q].column)) {
            if (a == 0 && inner[p] == 3 * i) coupled_diagonal_[i] = out - row_begin;
            new_inner[out] = inner[p];
            new_values[out++] = values[p];
            ++p;
          } else {
            for (int b = 0; b < 3; ++b) {
              new_inner[out] = 3 * blocks[q].column + b;
              new_values[out++] = blocks[q].value(a, b);
            }
            ++q;
          }
        }
      }
    }
  });
  new_outer[3 * n] = nonzeros;
  widened_ = true;
}

bool ImplicitSolver::solve_on_earlier_factor(const ConstraintFilter& filter,
                                             const NewtonSettings& settings, bool refactor,
                                             ImplicitSolveResult& result) {
  if (cholmod_failed_ || cholmod_.factor_rows() != system().rows()) return false;
  if (!refactor && factor_current_) return false;  // the factor is this matrix's: solve directly
  // Keep the factor while the solves on it cost less than the average solve since it was made
  // (its own cost spread over them): the iterations grow as the cloth moves away from the
  // matrix it was made of, and a new factor is cheaper from where they pass that average.
  const double average =
      (factor_cost_ + iterations_since_factor_) / std::max(1, solves_since_factor_);
  if (last_reuse_iterations_ > average) return false;
  // After failed tries, skip as many solves as tries failed in a row before trying again.
  if (skipped_reuses_ < failed_reuses_) {
    ++skipped_reuses_;
    return false;
  }
  // Beyond the factor's own cost in iterations a new one is cheaper anyway.
  const int cap =
      std::clamp(static_cast<int>(std::ceil(factor_cost_)), 1, settings.factor_reuse_iterations);
  reuse_stats_ = cholmod_.solve_preconditioned(system(), filter, rhs_, z_, step_,
                                               settings.factor_reuse_tolerance, cap);
  iterations_since_factor_ += reuse_stats_.iterations;
  last_reuse_iterations_ = reuse_stats_.iterations;
  skipped_reuses_ = 0;
  if (!reuse_stats_.converged) {
    // Its iterations are spent; the caller factorises.
    result.cg_iterations += reuse_stats_.iterations;
    ++failed_reuses_;
    return false;
  }
  failed_reuses_ = 0;
  factor_current_ = false;
  ++result.factor_reuses;
  return true;
}

bool ImplicitSolver::linear_solve(const ClothModel& model, const ConstraintFilter& filter,
                                  const NewtonSettings& settings, bool refactor,
                                  ImplicitSolveResult& result) {
  const auto start = std::chrono::steady_clock::now();
  LinearSolveStats stats;
  if (settings.solver == LinearSolverKind::cholmod) {
    const bool reused = settings.factor_reuse_iterations > 0 &&
                        solve_on_earlier_factor(filter, settings, refactor, result);
    // A kept-matrix Newton iteration after a solve on an earlier factor has no factor of its
    // matrix to solve with directly.
    if (!reused && !factor_current_ && !cholmod_failed_) refactor = true;
    if (!reused && refactor) {
      cholmod_failed_ = !cholmod_.factorize(system(), filter);
      if (cholmod_failed_) ++result.cholmod_failures;
      factor_current_ = !cholmod_failed_;
      // The new factor's cost in the PCG iterations it can save (each a triangular solve pair
      // and a product with A: 4 lnz + 2 nnz(A) flops). The supernodal factorisation runs its
      // flops through dense BLAS about 3.5 times as fast as the memory-bound solves (the 2 cm
      // tee: 2.2e8 flops in 10.7 ms of CPU against 0.7 ms an iteration), hence the divisor.
      const FactorSize& size = cholmod_.analysed_size();
      factor_cost_ = size.flops / (3.5 * (4.0 * size.nonzeros + 2.0 * system().nonZeros()));
      solves_since_factor_ = 0;
      iterations_since_factor_ = 1;  // its direct solve, about an iteration's work
      last_reuse_iterations_ = 0;
    }
    if (reused) {
      stats = reuse_stats_;
    } else if (!cholmod_failed_) {
      stats = cholmod_.solve(system(), filter, rhs_, z_, step_);
    } else {
      // The system is not positive definite for CHOLMOD: PCG on the same system, its
      // preconditioner built afresh. A zero step must never pass for a solution.
      pcg_.set_preconditioner(settings.pcg_preconditioner);
      stats = pcg_.solve(system(), system_diagonal(model), filter, rhs_, z_, step_,
                         settings.pcg_tolerance, settings.pcg_max_iterations, refactor);
      pcg_pattern_ = -1;
      if (!stats.converged || !step_.allFinite()) {
        result.linear_failure =
            "the CHOLMOD factorisation failed (the system is not positive definite) and PCG on "
            "the same system did not converge either";
        step_.setZero(3 * model.vertex_count);  // callers still add step_
      }
    }
    ++solves_since_factor_;
  } else {
    pcg_.set_preconditioner(settings.pcg_preconditioner);
    // matrix_ keeps its pattern until the mesh changes (pattern_changes_); the widened matrix
    // is made anew each time.
    const bool same_pattern = !widened_ && pcg_pattern_ == pattern_changes_;
    stats = pcg_.solve(system(), system_diagonal(model), filter, rhs_, z_, step_,
                       settings.pcg_tolerance, settings.pcg_max_iterations, refactor, same_pattern);
    pcg_pattern_ = widened_ ? -1 : pattern_changes_;
  }
  ++result.linear_solves;
  result.cg_iterations += stats.iterations;
  result.cg_iterations_max = std::max(result.cg_iterations_max, stats.iterations);
  result.solve_seconds += seconds_since(start);
  return stats.converged && step_.allFinite();
}

void ImplicitSolver::record_constraint_impulse(const ConstraintFilter& filter,
                                               ImplicitSolveResult& result) {
  if (filter.constrained_count() == 0) {
    result.constraint_impulse.resize(0);
    return;
  }
  // A s − b is zero in the free directions (up to the solver's tolerance) and, in the
  // constrained ones, the impulse the constraint had to add: keep only that part, (I − S)(A s −
  // b), computed in the constrained vertices' rows only (a pinned sheet has two of a thousand).
  const SparseMatrixR& a = system();
  result.constraint_impulse = Eigen::VectorXd::Zero(step_.size());
  for (int i = 0; i < filter.vertex_count(); ++i) {
    if (filter.is_free(i)) continue;
    Eigen::Vector3d residual;
    for (int r = 0; r < 3; ++r) residual(r) = a.row(3 * i + r).dot(step_) - rhs_(3 * i + r);
    result.constraint_impulse.segment<3>(3 * i) =
        (Eigen::Matrix3d::Identity() - filter.filter_matrix(i)) * residual;
  }
}

ImplicitSolveResult ImplicitSolver::solve(const ClothModel& model, const ForceSettings& forces,
                                          const ConstraintFilter& filter,
                                          const Eigen::VectorXd& x_hat,
                                          const Eigen::VectorXd& v_hat, double beta,
                                          const Eigen::VectorXd& x_lin,
                                          const Eigen::VectorXd& v_lin,
                                          const NewtonSettings& settings, const StepForces* extra) {
  ImplicitSolveResult result;
  keep_cross_pattern_ = settings.solver == LinearSolverKind::cholmod;
  const int n = model.vertex_count;
  const auto mass_times = [&](const Eigen::VectorXd& w) {
    Eigen::VectorXd out(3 * n);
    for (int i = 0; i < n; ++i) out.segment<3>(3 * i) = model.mass[i] * w.segment<3>(3 * i);
    return out;
  };

  // First iteration, linearised at (x_lin, v_lin): with u = x̂ + β v_lin − x_lin,
  //   A s = M (v̂ − v_lin) + β f(x_lin, v_lin) + β (∂f/∂x) u,    v1 = v_lin + s.
  const Eigen::VectorXd u = x_hat + beta * v_lin - x_lin;
  const bool consistent = u.lpNorm<Eigen::Infinity>() == 0.0;
  assemble(model, forces, beta, x_lin, v_lin, consistent ? nullptr : &u, extra, result,
           std::exchange(start_energy_, nullptr));
  rhs_ = mass_times(v_hat - v_lin) + beta * force_;
  if (!consistent) rhs_ += beta * product_;
  filter.constrained_correction(v_lin, z_);
  result.v = v_lin;
  result.linear_converged = linear_solve(model, filter, settings, true, result);
  result.v += step_;
  result.x = x_hat + beta * result.v;
  result.newton_iterations = 1;
  result.last_update = beta * step_.lpNorm<Eigen::Infinity>();
  if (!result.linear_converged || !result.v.allFinite()) {
    result.newton_converged = false;
    return result;
  }
  record_constraint_impulse(filter, result);
  if (settings.max_iterations <= 1) return result;  // the linearised step, by design

  // Further iterations: residual g(v) = M (v − v̂) − β f(x̂ + β v, v), A s = −g.
  result.newton_converged = result.last_update <= settings.tolerance;
  double previous_update = result.last_update;
  bool refresh = settings.refresh_jacobian;
  while (!result.newton_converged && result.newton_iterations < settings.max_iterations) {
    if (refresh) {
      assemble(model, forces, beta, result.x, result.v, nullptr, extra, result);
    } else {
      const auto start = std::chrono::steady_clock::now();
      evaluate_forces(model, forces, result.x, result.v, force_);
      add_extra_force(model, extra, result.x, result.v);
      result.forces_seconds += seconds_since(start);
    }
    rhs_ = mass_times(v_hat - result.v) + beta * force_;
    filter.constrained_correction(result.v, z_);
    result.linear_converged = linear_solve(model, filter, settings, refresh, result);
    result.v += step_;
    result.x = x_hat + beta * result.v;
    ++result.newton_iterations;
    result.last_update = beta * step_.lpNorm<Eigen::Infinity>();
    if (!result.linear_converged || !result.v.allFinite()) break;
    record_constraint_impulse(filter, result);
    result.newton_converged = result.last_update <= settings.tolerance;
    if (result.newton_converged) break;
    // A growing update is a divergence that a refreshed (still projected) matrix does not cure
    // on buckling cloth: stop at once, the caller falls back to the linearised step. A poor
    // contraction means the kept matrix no longer describes the system near the iterate (EG
    // 2002 tutorial §2.2.3 needs J ≈ J^(k)): reassemble it there.
    const double contraction = result.last_update / previous_update;
    if (contraction >= 1.0 && result.newton_iterations > 2) break;
    refresh = settings.refresh_jacobian;
    if (contraction > settings.refresh_contraction &&
        result.jacobian_refreshes < settings.max_refreshes) {
      refresh = true;
      ++result.jacobian_refreshes;
    }
    previous_update = result.last_update;
  }
  return result;
}

}  // namespace sd::sim
