#pragma once
// Global forces of the cloth, their energies, and their Jacobians ∂f/∂x and ∂f/∂v accumulated
// into the model's block-sparse pattern.

#include <Eigen/Core>

#include "sim/cloth_model.hpp"

namespace sd::sim {

// Which force terms are evaluated (all by default; tests switch them one at a time).
struct ForceTerms {
  bool stretch = true;
  bool shear = true;
  bool bend = true;
  bool damping = true;  // the damping of stretch, shear and bend along their gradients
  bool gravity = true;
  bool drag = true;  // linear air drag towards the wind velocity (only if air_drag > 0)
};

struct ForceSettings {
  Eigen::Vector3d gravity{0.0, -9.81, 0.0};        // m/s²
  Eigen::Vector3d wind = Eigen::Vector3d::Zero();  // m/s, velocity of the air
  double air_drag = 0.0;  // kg/(m²·s): f_i = air_drag · A_i · (wind − v_i), A_i vertex rest area
  ForceTerms terms;
};

// Energies in joules. `potential` is the gravitational potential energy −Σ m_i g·x_i.
struct EnergyBreakdown {
  double stretch = 0.0;
  double shear = 0.0;
  double bend = 0.0;
  double kinetic = 0.0;
  double potential = 0.0;
  double elastic() const { return stretch + shear + bend; }
  double total() const { return elastic() + kinetic + potential; }
};

enum class JacobianKind {
  // The exact derivatives of the force: with the curvature terms C·∇²C of every condition and
  // the (non-symmetric) position derivative of the damping forces. What the FD tests check.
  exact,
  // What the implicit solve uses: symmetric and negative semi-definite. Stretch keeps its
  // curvature term only while stretched (C > 0, where it is PSD); shear and bend keep the
  // Gauss-Newton part −k·∇C∇Cᵀ; damping contributes to ∂f/∂v only (its ∂/∂x is dropped,
  // as Baraff & Witkin do).
  solve,
};

// Where the Jacobians go: `matrix` (the model's pattern) receives
// dfdx_scale·∂f/∂x + dfdv_scale·∂f/∂v, added to what it holds. If `product_input` is set,
// `product_output` receives (added) ∂f/∂x · product_input without forming the matrix.
struct JacobianTarget {
  JacobianKind kind = JacobianKind::solve;
  SparseMatrixR* matrix = nullptr;
  double dfdx_scale = 0.0;
  double dfdv_scale = 0.0;
  const Eigen::VectorXd* product_input = nullptr;
  Eigen::VectorXd* product_output = nullptr;
};

// Evaluates the total force (3n, newtons) at positions x and velocities v (3n each), and
// optionally energies and Jacobians. `force` is overwritten.
void evaluate_forces(const ClothModel& model, const ForceSettings& settings,
                     const Eigen::VectorXd& x, const Eigen::VectorXd& v, Eigen::VectorXd& force,
                     EnergyBreakdown* energy = nullptr, const JacobianTarget* jacobian = nullptr);

// Largest stretch strain max(|w_u| − 1, |w_v| − 1) over the triangles (0 for a relaxed cloth).
// Stretch along the warp and the weft only: a triangle sheared by γ (w_v turned by γ towards
// w_u, a simple shear) keeps |w_u| = 1 and |w_v| = 1/cos γ (1.9 % at γ = 11°) while its principal
// stretches are 1.10 and 0.91.
double max_stretch_strain(const ClothModel& model, const Eigen::VectorXd& x);

// Triangle t's principal stretches σ₁ ≥ σ₂ at x: the singular values of its deformation
// gradient [w_u w_v] against the rest triangle (both 1 at rest, for any rotation). The
// engineering principal strains σ₁ − 1 (stretch) and 1 − σ₂ (compression) see stretch in any
// direction, the bias's and shear's included.
Eigen::Vector2d principal_stretches(const TriangleElement& t, const Eigen::VectorXd& x);

// The largest engineering principal strains over the triangles.
struct PrincipalStrain {
  double stretch = 0.0;      // max σ₁ − 1
  double compression = 0.0;  // max 1 − σ₂
};
PrincipalStrain max_principal_strain(const ClothModel& model, const Eigen::VectorXd& x);

// Kinetic energy ½ Σ m_i |v_i|² in joules.
double kinetic_energy(const ClothModel& model, const Eigen::VectorXd& v);

}  // namespace sd::sim
