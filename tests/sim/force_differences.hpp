#pragma once
// Central finite differences of the cloth forces, for the tests that check forces and Jacobians:
// ∂f/∂x and ∂f/∂v column by column, and the gradient of the bending energy (the conservative
// forces with damping off must be its negative).

#include <Eigen/Core>

#include "sim/forces.hpp"

namespace sd::sim::testing {

// The assembled ∂f/∂x·x_scale + ∂f/∂v·v_scale of `kind` (exact or the solve's) as a dense matrix.
inline Eigen::MatrixXd dense_jacobian(const ClothModel& model, const ForceSettings& settings,
                                      const Eigen::VectorXd& x, const Eigen::VectorXd& v,
                                      double x_scale, double v_scale, JacobianKind kind) {
  SparseMatrixR matrix = model.pattern.zero_matrix;
  JacobianTarget target;
  target.kind = kind;
  target.matrix = &matrix;
  target.dfdx_scale = x_scale;
  target.dfdv_scale = v_scale;
  Eigen::VectorXd force;
  evaluate_forces(model, settings, x, v, force, nullptr, &target);
  return Eigen::MatrixXd(matrix);
}

struct ForceDifferences {
  Eigen::MatrixXd dfdx, dfdv;          // 3n × 3n
  Eigen::VectorXd bend_gradient;       // ∂E_bend/∂x
  Eigen::VectorXd conservative_force;  // f(x, v) with damping off
};

inline ForceDifferences force_differences(const ClothModel& model, const ForceSettings& settings,
                                          const Eigen::VectorXd& x, const Eigen::VectorXd& v,
                                          double h = 1e-6) {
  ForceSettings conservative = settings;
  conservative.terms.damping = false;
  ForceDifferences d;
  d.dfdx.resize(x.size(), x.size());
  d.dfdv.resize(x.size(), x.size());
  d.bend_gradient.resize(x.size());
  Eigen::VectorXd fp, fm;
  for (Eigen::Index j = 0; j < x.size(); ++j) {
    Eigen::VectorXd plus = x, minus = x;
    plus[j] += h;
    minus[j] -= h;
    evaluate_forces(model, settings, plus, v, fp);
    evaluate_forces(model, settings, minus, v, fm);
    d.dfdx.col(j) = (fp - fm) / (2 * h);
    EnergyBreakdown ep, em;
    evaluate_forces(model, conservative, plus, v, fp, &ep);
    evaluate_forces(model, conservative, minus, v, fm, &em);
    d.bend_gradient[j] = (ep.bend - em.bend) / (2 * h);
    Eigen::VectorXd vp = v, vm = v;
    vp[j] += h;
    vm[j] -= h;
    evaluate_forces(model, settings, x, vp, fp);
    evaluate_forces(model, settings, x, vm, fm);
    d.dfdv.col(j) = (fp - fm) / (2 * h);
  }
  evaluate_forces(model, conservative, x, v, d.conservative_force);
  return d;
}

}  // namespace sd::sim::testing
