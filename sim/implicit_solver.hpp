#pragma once
// The nonlinear system of one implicit step, shared by implicit Euler and BDF2. Both methods
// reduce to: find v1 with
//     x1 = x̂ + β v1,    M (v1 − v̂) = β f(x1, v1),
// implicit Euler with x̂ = x0, v̂ = v0, β = h; variable-step BDF2 with the history terms in x̂,
// v̂ and β = h(1+ω)/(1+2ω) (see docs/simulator.md). It is solved by Newton iterations on v1
// with the matrix A = M − β ∂f/∂v − β² ∂f/∂x (the "solve" Jacobian, SPD), linear systems
// filtered by the constraints and solved by the modified PCG or CHOLMOD.

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "sim/cholmod_solver.hpp"
#include "sim/cloth_model.hpp"
#include "sim/constraint_filter.hpp"
#include "sim/forces.hpp"
#include "sim/pcg_solver.hpp"

namespace sd::sim {

enum class LinearSolverKind { pcg, cholmod };

// The solver's name in sketch files and reports ("pcg", "cholmod"), and the enum from it.
std::string_view solver_name(LinearSolverKind solver);
std::optional<LinearSolverKind> parse_solver(std::string_view name);

struct NewtonSettings {
  // 1 = a single linearised step (Baraff & Witkin's implicit Euler). More iterations run an
  // inexact simplified Newton method: the matrix of the first iteration is kept (and its
  // CHOLMOD factor or PCG preconditioner reused) unless refresh_jacobian is set.
  int max_iterations = 1;
  double tolerance = 1e-6;        // m: converged when β·max|Δv| ≤ tolerance
  bool refresh_jacobian = false;  // reassemble at every iteration (full Newton, projected matrix)
  // When an update shrinks by less than this factor (contraction θ = |Δ_k|/|Δ_{k−1}|), the kept
  // matrix is too far from the current Jacobian: it is reassembled at the current iterate, at
  // most max_refreshes times per solve. θ ≥ 1 after the second iteration ends the iteration.
  double refresh_contraction = 0.5;
  int max_refreshes = 1;
  LinearSolverKind solver = LinearSolverKind::pcg;
  double pcg_tolerance = 1e-3;  // relative residual reduction (the inexact Newton forcing term)
  int pcg_max_iterations = 1000;
  // The default of SimulationSettings (see there).
  PcgPreconditioner pcg_preconditioner = PcgPreconditioner::block_incomplete_cholesky;
  // CHOLMOD only: a solve may first try the PCG preconditioned by the last factorisation (of an
  // earlier step's matrix of the same size, other contacts and pair springs) and factorises
  // when that does not reach factor_reuse_tolerance within the factor's own cost in iterations
  // (at most factor_reuse_iterations), or when the last such solve cost more than the average
  // solve since the factorisation. 0: a factorisation every solve (the same bits as before).
  int factor_reuse_iterations = 0;
  double factor_reuse_tolerance = 1e-9;  // relative Euclidean residual, as CHOLMOD's own solve
};

// A force on one vertex, affine in its velocity: f = force − C (v − v_ref), C symmetric
// positive semi-definite (kg/s). Contact friction enters the solve this way.
struct VertexDamping {
  int vertex = 0;
  Eigen::Matrix3d coefficient = Eigen::Matrix3d::Zero();
  Eigen::Vector3d reference_velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d force = Eigen::Vector3d::Zero();  // N
};

// A spring that pushes the point p = Σ_k w_k x_k of one cloth triangle (fixed weights) along
// the unit normal n towards n·p = target, with the force
//     F = preload + stiffness (target − n·p) − damping n·(Σ_k w_k v_k − reference_velocity),
// of which corner k takes w_k F n. A body vertex poking through the cloth enters the solve this
// way. F is linear in x and v, so the step treats it exactly; it is not one-sided within the
// step (the caller decides which springs a step has).
struct PointSpring {
  int triangle = 0;  // model element, for its corners and matrix blocks
  Eigen::Vector3d weights = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();
  double target = 0.0;                                           // m, along normal
  double preload = 0.0;                                          // N
  double stiffness = 0.0;                                        // N/m
  double damping = 0.0;                                          // kg/s
  Eigen::Vector3d reference_velocity = Eigen::Vector3d::Zero();  // m/s
};

// n·Σ_k w_k y_k over the spring's corners (given: its triangle's vertices) for any 3n vector y:
// the point's height along the normal for positions, its normal speed for velocities.
inline double along_spring_normal(const PointSpring& spring, const std::array<int, 3>& corners,
                                  const Eigen::VectorXd& y) {
  double along = 0.0;
  for (int k = 0; k < 3; ++k)
    along += spring.weights[k] * spring.normal.dot(y.segment<3>(3 * corners[k]));
  return along;
}

// A repulsion spring between two pieces of the same cloth (self-contact, sim/self_contact.hpp):
// with s = n·Σ_k w_k x_k the separation of the pair (weights signed: + on the first element,
// − on the second) and ṡ = n·Σ_k w_k v_k, the force
//     F = stiffness (target − s) − damping ṡ,
// of which vertex k takes w_k F n. The whole Jacobian goes into the system matrix: block (k, l)
// gains (β² k + β c) w_k w_l n nᵀ, a rank-one positive semi-definite term. The two elements are
// not neighbours in the mesh, so the blocks across the pair (k, l on different elements) are
// outside the mesh's pattern: the solver widens the pattern by them for the steps that have
// such springs (CHOLMOD then analyses the widened pattern again). With only the blocks within
// each side, the coupling across a pair was explicit and a compressed stack of layers gained
// energy (docs/collision.md).
//
// Friction between the two layers enters the same way: a tangential dashpot on the pair's
// relative velocity, f_k = −w_k c_t (I − n nᵀ) Σ_l w_l v_l (`friction` = c_t, kg/s), whose
// blocks β c_t w_k w_l (I − n nᵀ) join the spring's (rank two, positive semi-definite). The
// caller sizes c_t from Coulomb's law (sim/self_contact.cpp); a pair may carry friction alone
// (stiffness and damping 0).
struct PairSpring {
  std::array<int, 4> vertices{};
  Eigen::Vector4d weights = Eigen::Vector4d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();
  double target = 0.0;     // m
  double stiffness = 0.0;  // N/m
  double damping = 0.0;    // kg/s
  double friction = 0.0;   // kg/s: the tangential dashpot c_t
};

// The pair's relative velocity Σ_k w_k v_k (3) for a 3n velocity vector v.
inline Eigen::Vector3d pair_relative(const PairSpring& spring, const Eigen::VectorXd& v) {
  Eigen::Vector3d relative = Eigen::Vector3d::Zero();
  for (int k = 0; k < 4; ++k) relative += spring.weights[k] * v.segment<3>(3 * spring.vertices[k]);
  return relative;
}

// The force of a pair spring (3, N) on a vertex of weight w is w times this: the spring along n
// and the friction dashpot across it, at positions x and velocities v (3n each).
inline Eigen::Vector3d pair_spring_force(const PairSpring& spring, const Eigen::VectorXd& x,
                                         const Eigen::VectorXd& v) {
  double along = 0.0;
  for (int k = 0; k < 4; ++k)
    along += spring.weights[k] * spring.normal.dot(x.segment<3>(3 * spring.vertices[k]));
  const Eigen::Vector3d relative = pair_relative(spring, v);
  const double speed = spring.normal.dot(relative);
  return (spring.stiffness * (spring.target - along) - spring.damping * speed) * spring.normal -
         spring.friction * (relative - speed * spring.normal);
}

// The 3×3 block of A for corners (k, l) of a pair spring: (β² k + β c) w_k w_l n nᵀ +
// β c_t w_k w_l (I − n nᵀ).
inline Eigen::Matrix3d pair_block(const PairSpring& spring, double beta, int k, int l) {
  const Eigen::Matrix3d outer = spring.normal * spring.normal.transpose();
  const double w = spring.weights[k] * spring.weights[l];
  return (w * (beta * beta * spring.stiffness + beta * spring.damping)) * outer +
         (w * beta * spring.friction) * (Eigen::Matrix3d::Identity() - outer);
}

inline double along_pair_normal(const PairSpring& spring, const Eigen::VectorXd& y) {
  double along = 0.0;
  for (int k = 0; k < 4; ++k)
    along += spring.weights[k] * spring.normal.dot(y.segment<3>(3 * spring.vertices[k]));
  return along;
}

// Forces a step adds to the cloth's own, all implicit (their matrices go into A): contact
// friction as per-vertex drags, body vertices poking through as point springs, self-contact as
// pair springs.
struct StepForces {
  std::vector<VertexDamping> drags;
  std::vector<PointSpring> springs;
  std::vector<PairSpring> pair_springs;

  void clear() {
    drags.clear();
    springs.clear();
    pair_springs.clear();
  }
};

struct ImplicitSolveResult {
  Eigen::VectorXd x;  // 3n positions at the end of the step
  Eigen::VectorXd v;  // 3n velocities
  int newton_iterations = 0;
  int jacobian_refreshes = 0;  // reassemblies after a poor contraction
  int linear_solves = 0;
  int cg_iterations = 0;      // summed over the linear solves
  int cg_iterations_max = 0;  // largest single solve
  bool linear_converged = true;
  // CHOLMOD factorisations that failed (the system not positive definite); each solve fell
  // back to PCG on the same system.
  int cholmod_failures = 0;
  // CHOLMOD solves done by the PCG on an earlier factorisation (NewtonSettings::
  // factor_reuse_iterations) instead of a new one.
  int factor_reuses = 0;
  // Why the linear solve failed when no step can come of it (the factorisation failed and the
  // PCG fallback did not converge either); empty otherwise.
  std::string linear_failure;
  bool newton_converged = true;
  double last_update = 0.0;  // β·max|Δv| of the last Newton update, m
  // 3n, N·s: the impulse the constraints applied over the step, (I − S)(A s − b) of the last
  // linear solve (the linearised residual M(v1 − v̂) − β f at v1, in the constrained directions);
  // the constraint force is this divided by β. Zero at free vertices; empty without constraints.
  Eigen::VectorXd constraint_impulse;
  double forces_seconds = 0.0;
  double solve_seconds = 0.0;
};

class ImplicitSolver {
 public:
  // Solves the step. (x_lin, v_lin) is where the first iteration linearises the force: the
  // start of the step (x0, v0) for Baraff-Witkin's linearised implicit Euler, a consistent
  // predictor (x̂ + β v_guess, v_guess) for BDF2. The filter must hold the velocity targets
  // of the constrained vertices for the end of the step. `extra` (optional) adds per-vertex
  // drags and point springs to the force, implicitly (their matrices go into A).
  ImplicitSolveResult solve(const ClothModel& model, const ForceSettings& forces,
                            const ConstraintFilter& filter, const Eigen::VectorXd& x_hat,
                            const Eigen::VectorXd& v_hat, double beta, const Eigen::VectorXd& x_lin,
                            const Eigen::VectorXd& v_lin, const NewtonSettings& settings,
                            const StepForces* extra = nullptr);

  // The next solve's first force evaluation also fills `energy` (the energies at (x_lin,
  // v_lin)); the request holds for that solve only. Null: none.
  void request_start_energy(EnergyBreakdown* energy) { start_energy_ = energy; }

  // The system matrix of the last assembly (for tests and benchmarks): the mesh's pattern,
  // widened by the pair springs' blocks across their pairs when a step has them.
  const SparseMatrixR& matrix() const { return widened_ ? coupled_ : matrix_; }
  const CholmodSolver& cholmod() const { return cholmod_; }

 private:
  void assemble(const ClothModel& model, const ForceSettings& forces, double beta,
                const Eigen::VectorXd& x, const Eigen::VectorXd& v, const Eigen::VectorXd* u,
                const StepForces* extra, ImplicitSolveResult& result,
                EnergyBreakdown* energy = nullptr);
  // force_ += the drags' and springs' forces at (x, v).
  void add_extra_force(const ClothModel& model, const StepForces* extra, const Eigen::VectorXd& x,
                       const Eigen::VectorXd& v);
  // The pair springs' blocks between vertices that are not neighbours in the mesh: coupled_
  // becomes matrix_ on the widened pattern plus those blocks (widened_ set); else widened_ is
  // cleared and the solve uses matrix_.
  void add_cross_blocks(const ClothModel& model, double beta, const StepForces* extra);
  const SparseMatrixR& system() const { return widened_ ? coupled_ : matrix_; }
  const std::vector<int>& system_diagonal(const ClothModel& model) const {
    return widened_ ? coupled_diagonal_ : model.pattern.diagonal_offsets;
  }
  // CHOLMOD: the PCG on the last factorisation (NewtonSettings::factor_reuse_iterations) when
  // it pays; true when it solved (step_, reuse_stats_), false when the caller is to factorise.
  bool solve_on_earlier_factor(const ConstraintFilter& filter, const NewtonSettings& settings,
                               bool refactor, ImplicitSolveResult& result);
  bool linear_solve(const ClothModel& model, const ConstraintFilter& filter,
                    const NewtonSettings& settings, bool refactor, ImplicitSolveResult& result);
  void record_constraint_impulse(const ConstraintFilter& filter, ImplicitSolveResult& result);

  SparseMatrixR matrix_;
  int pattern_changes_ = 0;  // times matrix_ took a new mesh pattern (an adaptive change)
  int pcg_pattern_ = -1;     // pattern_changes_ at the PCG's last solve of matrix_, else -1
  // With CHOLMOD: the cross blocks the widened pattern keeps (vertex row, column; sorted), a
  // superset of this step's, so that a spring pair that comes and goes does not change the
  // pattern and cost a new symbolic analysis (zero blocks do not change the system). Reset when
  // the mesh pattern changes or when it holds much more than the blocks in use.
  std::vector<std::array<int, 2>> kept_cross_;
  int kept_cross_pattern_ = -1;              // pattern_changes_ when kept_cross_ was started
  EnergyBreakdown* start_energy_ = nullptr;  // request_start_energy
  bool keep_cross_pattern_ = false;    // set per solve: CHOLMOD (the PCG's IC(0) reads the pattern)
  SparseMatrixR coupled_;              // matrix_ widened by the cross-pair blocks
  std::vector<int> coupled_diagonal_;  // offset(i, i) in coupled_, #V
  bool widened_ = false;
  PcgSolver pcg_;
  CholmodSolver cholmod_;
  bool cholmod_failed_ = false;  // the last factorisation failed: solves go to PCG until the next
  // The CHOLMOD factor is of the current system matrix (false after a solve that reused an
  // earlier step's factor: a kept-matrix Newton iteration must not solve directly with it).
  bool factor_current_ = false;
  double factor_cost_ = 0.0;         // the last factorisation's cost in PCG iterations
  int solves_since_factor_ = 0;      // CHOLMOD solves since it (the direct one included)
  int iterations_since_factor_ = 0;  // PCG iterations on it since
  int last_reuse_iterations_ = 0;    // of the last solve on it; 0 right after it
  int failed_reuses_ = 0;            // tries on an earlier factor that failed in a row
  int skipped_reuses_ = 0;           // solves since the last try that did not try
  LinearSolveStats reuse_stats_;
  Eigen::VectorXd force_, product_, rhs_, z_, step_;
};

}  // namespace sd::sim
