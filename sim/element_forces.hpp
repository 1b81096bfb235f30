#pragma once
// Baraff-Witkin conditions of one element with exact gradients and Hessians. A condition C is
// a scalar function of the element's vertex positions; its energy is ½·k·(C − C0)², its force
// −k·(C − C0)·∇C and its damping force −k_d·∇C·Ċ (Baraff & Witkin 1998, §4-5).

#include <Eigen/Core>

#include "sim/cloth_model.hpp"

namespace sd::sim {

// Value, gradient and Hessian with respect to the N stacked vertex coordinates (N = 9 for a
// triangle, 12 for a hinge). The Hessian is only filled when asked for.
template <int N>
struct Condition {
  double value = 0.0;
  Eigen::Matrix<double, N, 1> gradient = Eigen::Matrix<double, N, 1>::Zero();
  Eigen::Matrix<double, N, N> hessian = Eigen::Matrix<double, N, N>::Zero();
};

// The three conditions of a triangle: C_u = |w_u| − 1 (warp stretch), C_v = |w_v| − 1 (weft
// stretch) and C_s = w_u·w_v (shear). Where |w| vanishes the stretch condition is −1 with zero
// derivatives (a collapsed triangle is not differentiable there; the step control rejects it).
struct TriangleConditions {
  Condition<9> warp;
  Condition<9> weft;
  Condition<9> shear;
  Eigen::Vector3d warp_vector, weft_vector;  // w_u and w_v (dimensionless)
};

TriangleConditions triangle_conditions(const TriangleElement& triangle, const Eigen::Vector3d& x0,
                                       const Eigen::Vector3d& x1, const Eigen::Vector3d& x2,
                                       bool with_hessian);

// Signed dihedral angle θ ∈ (−π, π] of the hinge (x0,x1) between triangles (x0,x1,x2) and
// (x1,x0,x3): θ = atan2((N1×N2)·ê, N1·N2), with N1 = e×(x2−x0), N2 = (x3−x0)×e, e = x1−x0.
// Zero for a flat hinge; well defined up to a fold of ±π. A degenerate hinge (a zero normal or
// edge) gives value 0 and zero derivatives.
Condition<12> dihedral_angle_condition(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1,
                                       const Eigen::Vector3d& x2, const Eigen::Vector3d& x3,
                                       bool with_hessian);

double dihedral_angle(const Eigen::Vector3d& x0, const Eigen::Vector3d& x1,
                      const Eigen::Vector3d& x2, const Eigen::Vector3d& x3);

}  // namespace sd::sim
