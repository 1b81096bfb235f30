#include "sim/element_forces.hpp"

#include <Eigen/Geometry>
#include <cmath>

namespace sd::sim {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using Matrix9d = Eigen::Matrix<double, 9, 9>;
using Vector9d = Eigen::Matrix<double, 9, 1>;

Matrix3d cross_matrix(const Vector3d& v) {
  Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

// |w| − 1 with w = Σ_k d[k]·x_k.
Condition<9> stretch_condition(const Vector3d& d, const Vector3d& w, bool with_hessian) {
  Condition<9> c;
  const double length = w.norm();
  c.value = length - 1.0;
  if (length < 1e-300) return c;
  const Vector3d unit = w / length;
  for (int k = 0; k < 3; ++k) c.gradient.segment<3>(3 * k) = d[k] * unit;
  if (with_hessian) {
    const Matrix3d curvature = (Matrix3d::Identity() - unit * unit.transpose()) / length;
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l) c.hessian.block<3, 3>(3 * k, 3 * l) = d[k] * d[l] * curvature;
  }
  return c;
}

}  // namespace

TriangleConditions triangle_conditions(const TriangleElement& triangle, const Vector3d& x0,
                                       const Vector3d& x1, const Vector3d& x2, bool with_hessian) {
  const Vector3d& du = triangle.du;
  const Vector3d& dv = triangle.dv;
  const Vector3d wu = du[0] * x0 + du[1] * x1 + du[2] * x2;
  const Vector3d wv = dv[0] * x0 + dv[1] * x1 + dv[2] * x2;
  TriangleConditions out;
  out.warp_vector = wu;
  out.weft_vector = wv;
  out.warp = stretch_condition(du, wu, with_hessian);
  out.weft = stretch_condition(dv, wv, with_hessian);
  out.shear.value = wu.dot(wv);
  for (int k = 0; k < 3; ++k) out.shear.gradient.segment<3>(3 * k) = du[k] * wv + dv[k] * wu;
  if (with_hessian)
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l)
        out.shear.hessian.block<3, 3>(3 * k, 3 * l) =
            (du[k] * dv[l] + dv[k] * du[l]) * Matrix3d::Identity();
  return out;
}

double dihedral_angle(const Vector3d& x0, const Vector3d& x1, const Vector3d& x2,
                      const Vector3d& x3) {
  const Vector3d e = x1 - x0;
  const Vector3d n1 = e.cross(x2 - x0);
  const Vector3d n2 = (x3 - x0).cross(e);
  const double length = e.norm();
  if (length < 1e-300) return 0.0;
  const double y = n1.cross(n2).dot(e) / length;
  const double x = n1.dot(n2);
  if (x * x + y * y < 1e-300) return 0.0;
  return std::atan2(y, x);
}

// Chain rule through three layers: x (12) → p = (e, a, b) = (x1−x0, x2−x0, x3−x0) →
// q = (N1, N2, e) → θ = atan2(Y, X) with X = N1·N2, Y = Z/|e|, Z = (N1×N2)·e.
Condition<12> dihedral_angle_condition(const Vector3d& x0, const Vector3d& x1, const Vector3d& x2,
                                       const Vector3d& x3, bool with_hessian) {
  Condition<12> c;
  const Vector3d e = x1 - x0;
  const Vector3d a = x2 - x0;
  const Vector3d b = x3 - x0;
  const Vector3d n1 = e.cross(a);
  const Vector3d n2 = b.cross(e);
  const double length = e.norm();
  if (length < 1e-300) return c;
  const double z = n1.cross(n2).dot(e);
  const double y = z / length;
  const double x = n1.dot(n2);
  const double r2 = x * x + y * y;
  if (r2 < 1e-300) return c;
  c.value = std::atan2(y, x);

  // Derivatives of X, Z, L = |e| and Y with respect to q = (N1, N2, e).
  Vector9d grad_x = Vector9d::Zero();
  grad_x << n2, n1, Vector3d::Zero();
  Vector9d grad_z;
  grad_z << n2.cross(e), e.cross(n1), n1.cross(n2);
  const Vector3d unit_e = e / length;
  Vector9d grad_l = Vector9d::Zero();
  grad_l.segment<3>(6) = unit_e;
  const Vector9d grad_y = grad_z / length - z * grad_l / (length * length);

  const double theta_x = -y / r2;
  const double theta_y = x / r2;
  const Vector9d grad_q = theta_x * grad_x + theta_y * grad_y;

  // q as a function of p: N1 = e×a, N2 = b×e. With grad_n1, grad_n2, g_e = ∂θ/∂N1, ∂θ/∂N2,
  // ∂θ/∂e (the parts of grad_q): ∂θ/∂e = a×grad_n1 − b×grad_n2 + g_e, ∂θ/∂a = grad_n1×e,
  // ∂θ/∂b = e×grad_n2 (jqᵀ·grad_q, written out: every force evaluation needs the gradient).
  const Vector3d grad_n1 = grad_q.segment<3>(0), grad_n2 = grad_q.segment<3>(3);
  Vector9d grad_p;
  grad_p << a.cross(grad_n1) - b.cross(grad_n2) + grad_q.segment<3>(6), grad_n1.cross(e),
      e.cross(grad_n2);

  // p as a function of x: e, a, b each subtract x0.
  const auto to_x_gradient = [](const Vector9d& gp) {
    Eigen::Matrix<double, 12, 1> gx;
    gx.segment<3>(0) = -(gp.segment<3>(0) + gp.segment<3>(3) + gp.segment<3>(6));
    gx.segment<3>(3) = gp.segment<3>(0);
    gx.segment<3>(6) = gp.segment<3>(3);
    gx.segment<3>(9) = gp.segment<3>(6);
    return gx;
  };
  c.gradient = to_x_gradient(grad_p);
  if (!with_hessian) return c;

  Matrix9d hess_x = Matrix9d::Zero();
  hess_x.block<3, 3>(0, 3) = Matrix3d::Identity();
  hess_x.block<3, 3>(3, 0) = Matrix3d::Identity();
  Matrix9d hess_z = Matrix9d::Zero();
  hess_z.block<3, 3>(0, 3) = -cross_matrix(e);
  hess_z.block<3, 3>(3, 0) = cross_matrix(e);
  hess_z.block<3, 3>(0, 6) = cross_matrix(n2);
  hess_z.block<3, 3>(6, 0) = -cross_matrix(n2);
  hess_z.block<3, 3>(3, 6) = -cross_matrix(n1);
  hess_z.block<3, 3>(6, 3) = cross_matrix(n1);
  Matrix9d hess_l = Matrix9d::Zero();
  hess_l.block<3, 3>(6, 6) = (Matrix3d::Identity() - unit_e * unit_e.transpose()) / length;
  const double l2 = length * length;
  const Matrix9d hess_y = hess_z / length -
                          (grad_z * grad_l.transpose() + grad_l * grad_z.transpose()) / l2 +
                          2.0 * z * grad_l * grad_l.transpose() / (l2 * length) - z * hess_l / l2;
  const double r4 = r2 * r2;
  const double theta_xx = 2.0 * x * y / r4;
  const double theta_yy = -theta_xx;
  const double theta_xy = (y * y - x * x) / r4;
  const Matrix9d hess_q = theta_xx * grad_x * grad_x.transpose() +
                          theta_xy * (grad_x * grad_y.transpose() + grad_y * grad_x.transpose()) +
                          theta_yy * grad_y * grad_y.transpose() + theta_x * hess_x +
                          theta_y * hess_y;

  // q as a function of p: Jacobian jq (rows N1, N2, e; columns e, a, b).
  Matrix9d jq = Matrix9d::Zero();
  jq.block<3, 3>(0, 0) = -cross_matrix(a);
  jq.block<3, 3>(0, 3) = cross_matrix(e);
  jq.block<3, 3>(3, 0) = cross_matrix(b);
  jq.block<3, 3>(3, 6) = -cross_matrix(e);
  jq.block<3, 3>(6, 0) = Matrix3d::Identity();
  Matrix9d hess_p = jq.transpose() * hess_q * jq;
  // Second derivatives of N1 = e×a and N2 = b×e contracted with ∂θ/∂N1 and ∂θ/∂N2.
  const Matrix3d g1 = cross_matrix(grad_q.segment<3>(0));
  const Matrix3d g2 = cross_matrix(grad_q.segment<3>(3));
  hess_p.block<3, 3>(0, 3) -= g1;
  hess_p.block<3, 3>(3, 0) += g1;
  hess_p.block<3, 3>(6, 0) -= g2;
  hess_p.block<3, 3>(0, 6) += g2;

  // Hessian in x: Pᵀ hess_p P with P = [[−I, I, 0, 0], [−I, 0, I, 0], [−I, 0, 0, I]].
  Eigen::Matrix<double, 9, 12> p_matrix = Eigen::Matrix<double, 9, 12>::Zero();
  for (int k = 0; k < 3; ++k) {
    p_matrix.block<3, 3>(3 * k, 0) = -Matrix3d::Identity();
    p_matrix.block<3, 3>(3 * k, 3 * (k + 1)) = Matrix3d::Identity();
  }
  c.hessian = p_matrix.transpose() * hess_p * p_matrix;
  return c;
}

}  // namespace sd::sim
