#include "sim/static_equilibrium.hpp"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace sd::sim {
namespace {

using SparseMatrixC = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

// A net force below this fraction of a vertex weight counts as converged when the line search
// can no longer lower the energy (its changes are then at round-off).
constexpr double kRoundOffTolerance = 1e-2;

// Total potential energy (elastic + gravitational, the latter relative to x0 so that the
// line search compares energies without a large constant's round-off) and force at x.
double energy_and_force(const ClothModel& model, const ForceSettings& settings,
                        const Eigen::VectorXd& x0, const Eigen::VectorXd& x,
                        Eigen::VectorXd& force) {
  ForceSettings elastic = settings;
  elastic.terms.gravity = false;
  EnergyBreakdown energy;
  evaluate_forces(model, elastic, x, Eigen::VectorXd::Zero(x.size()), force, &energy, nullptr);
  double potential = 0.0;
  if (settings.terms.gravity)
    for (int i = 0; i < model.vertex_count; ++i) {
      force.segment<3>(3 * i) += model.mass[i] * settings.gravity;
      potential -= model.mass[i] * settings.gravity.dot(x.segment<3>(3 * i) - x0.segment<3>(3 * i));
    }
  return energy.elastic() + potential;
}

// −∂f/∂x restricted to the free coordinates (`free_index`: coordinate → free row or −1).
SparseMatrixC free_stiffness(const ClothModel& model, const ForceSettings& settings,
                             const Eigen::VectorXd& x, JacobianKind kind,
                             const std::vector<int>& free_index, int free_count) {
  SparseMatrixR jacobian = model.pattern.zero_matrix;
  JacobianTarget target;
  target.kind = kind;
  target.matrix = &jacobian;
  target.dfdx_scale = -1.0;
  Eigen::VectorXd force;
  evaluate_forces(model, settings, x, Eigen::VectorXd::Zero(x.size()), force, nullptr, &target);
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<std::size_t>(jacobian.nonZeros()));
  for (int row = 0; row < jacobian.outerSize(); ++row) {
    const int i = free_index[static_cast<std::size_t>(row)];
    if (i < 0) continue;
    for (SparseMatrixR::InnerIterator it(jacobian, row); it; ++it) {
      const int j = free_index[static_cast<std::size_t>(it.col())];
      if (j >= 0) entries.emplace_back(i, j, it.value());
    }
  }
  SparseMatrixC stiffness(free_count, free_count);
  stiffness.setFromTriplets(entries.begin(), entries.end());
  return stiffness;
}

}  // namespace

StaticResult solve_static(const ClothModel& unclamped, Eigen::VectorXd& x,
                          const std::vector<int>& pinned, const StaticOptions& options) {
  ClothModel model = unclamped;
  clamp_bending(model, pinned, &x);
  const int n = model.vertex_count;
  std::vector<int> free_index(static_cast<std::size_t>(3 * n), 0);
  for (int v : pinned)
    for (int a = 0; a < 3; ++a) free_index[static_cast<std::size_t>(3 * v + a)] = -1;
  int free_count = 0;
  for (int& i : free_index)
    if (i == 0) i = free_count++;
  ForceSettings settings = options.forces;
  settings.terms.damping = false;
  settings.terms.drag = false;
  const Eigen::Vector3d gravity = options.forces.gravity;
  const double weight_scale =
      std::max(model.mass.maxCoeff() * gravity.norm(), 1e-300);  // N, largest vertex weight

  StaticResult result;
  const Eigen::VectorXd start = x;
  Eigen::VectorXd force, trial_force;
  const auto free_part = [&](const Eigen::VectorXd& full) {
    Eigen::VectorXd out(free_count);
    for (int k = 0; k < 3 * n; ++k)
      if (const int i = free_index[static_cast<std::size_t>(k)]; i >= 0) out(i) = full(k);
    return out;
  };
  const auto largest_vertex_force = [&](const Eigen::VectorXd& full) {
    double largest = 0.0;
    for (int v = 0; v < n; ++v)
      if (free_index[static_cast<std::size_t>(3 * v)] >= 0)
        largest = std::max(largest, full.segment<3>(3 * v).norm());
    return largest;
  };
  for (int step = 1; step <= options.load_steps; ++step) {
    settings.gravity = gravity * (static_cast<double>(step) / options.load_steps);
    double energy = energy_and_force(model, settings, start, x, force);
    bool converged = false;
    for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
      result.residual = largest_vertex_force(force);
      if (result.residual < options.tolerance * weight_scale) {
        converged = true;
        break;
      }
      ++result.iterations;
      const Eigen::VectorXd gradient = -free_part(force);  // of the energy
      // The exact stiffness, shifted by a multiple of its largest diagonal entry until it is
      // positive definite (compressed fibres make it slightly indefinite: their curvature
      // term is −k·|C|/|w| across the fibre); the solver's projected one if that fails.
      Eigen::SimplicialLDLT<SparseMatrixC> ldlt;
      Eigen::VectorXd direction;
      SparseMatrixC stiffness =
          free_stiffness(model, settings, x, JacobianKind::exact, free_index, free_count);
      const double largest = stiffness.diagonal().cwiseAbs().maxCoeff();
      SparseMatrixC identity(free_count, free_count);
      identity.setIdentity();
      for (int attempt = 0; attempt < 12 && direction.size() == 0; ++attempt) {
        const double shift = attempt == 0 ? 0.0 : largest * std::pow(10.0, attempt - 13);
        if (attempt == 11)
          stiffness =
              free_stiffness(model, settings, x, JacobianKind::solve, free_index, free_count);
        ldlt.compute(attempt == 0 || attempt == 11 ? stiffness
                                                   : SparseMatrixC(stiffness + shift * identity));
        if (ldlt.info() != Eigen::Success || (ldlt.vectorD().array() <= 0.0).any()) continue;
        direction = -ldlt.solve(gradient);
        if (!direction.allFinite() || direction.dot(gradient) >= 0.0) direction.resize(0);
      }
      if (direction.size() == 0) {
        result.failure = "no descent direction (singular stiffness)";
        return result;
      }
      // Backtracking on the energy (Armijo), then accept.
      double length = 1.0;
      Eigen::VectorXd trial;
      double trial_energy = energy;
      bool accepted = false;
      for (int halving = 0; halving < 40; ++halving) {
        trial = x;
        for (int k = 0; k < 3 * n; ++k)
          if (const int i = free_index[static_cast<std::size_t>(k)]; i >= 0)
            trial(k) += length * direction(i);
        trial_energy = energy_and_force(model, settings, start, trial, trial_force);
        if (trial_energy <= energy + 1e-4 * length * direction.dot(gradient)) {
          accepted = true;
          break;
        }
        length *= 0.5;
      }
      // A step whose energy equals the current one to the last bit passes the Armijo test only
      // because its decrease is below the energy's round-off: no progress either.
      if (!accepted || !(trial_energy < energy)) {
        // Near round-off the energy no longer decreases measurably: converged if the force is
        // already small (the tolerance is far below what shapes need), else a failure.
        if (result.residual < kRoundOffTolerance * weight_scale) {
          converged = true;
          break;
        }
        result.failure = "the line search found no lower energy";
        return result;
      }
      if (std::getenv("SD_STATIC_TRACE"))
        std::fprintf(stderr, "step %d it %d energy %.12g residual %.3g length %.3g\n", step,
                     iteration, trial_energy, result.residual, length);
      x.swap(trial);
      force.swap(trial_force);
      energy = trial_energy;
    }
    if (!converged) {
      result.residual = largest_vertex_force(force);
      result.failure = "no convergence in " + std::to_string(options.max_iterations) +
                       " iterations at load step " + std::to_string(step);
      return result;
    }
  }
  result.converged = true;
  return result;
}

}  // namespace sd::sim
