#include "sim/forces.hpp"

#include <algorithm>
#include <cmath>

#include "sim/element_forces.hpp"

namespace sd::sim {
namespace {

using Eigen::Vector3d;

// Adds the contribution of one condition C with stiffness k and damping k_d to the force, the
// energy and the Jacobian target. `vertices`/`blocks` locate the element in the global arrays.
template <int N>
void add_condition(const Condition<N>& c, double rest_value, double stiffness, double damping,
                   bool keep_curvature_in_solve, const int* vertices, const int* blocks,
                   const Eigen::VectorXd& v, Eigen::VectorXd& force, double& energy,
                   const JacobianTarget* jacobian) {
  constexpr int kVertices = N / 3;
  using VectorN = Eigen::Matrix<double, N, 1>;
  using MatrixN = Eigen::Matrix<double, N, N>;
  const double c_value = c.value - rest_value;
  VectorN local_v;
  for (int k = 0; k < kVertices; ++k) local_v.template segment<3>(3 * k) = v.segment<3>(3 * vertices[k]);
  const double c_dot = damping > 0.0 ? c.gradient.dot(local_v) : 0.0;
  energy += 0.5 * stiffness * c_value * c_value;
  const VectorN local_force = -(stiffness * c_value + damping * c_dot) * c.gradient;
  for (int k = 0; k < kVertices; ++k)
    force.segment<3>(3 * vertices[k]) += local_force.template segment<3>(3 * k);
  if (jacobian == nullptr) return;

  const bool exact = jacobian->kind == JacobianKind::exact;
  const MatrixN outer = c.gradient * c.gradient.transpose();
  MatrixN dfdx = -stiffness * outer;
  if (exact || (keep_curvature_in_solve && c_value > 0.0)) dfdx -= stiffness * c_value * c.hessian;
  if (exact && damping > 0.0) {
    dfdx -= damping * (c_dot * c.hessian +
                       c.gradient * (c.hessian.transpose() * local_v).transpose());
  }
  if (jacobian->product_input != nullptr) {
    VectorN local_u;
    for (int k = 0; k < kVertices; ++k)
      local_u.template segment<3>(3 * k) = jacobian->product_input->segment<3>(3 * vertices[k]);
    const VectorN product = dfdx * local_u;
    for (int k = 0; k < kVertices; ++k)
      jacobian->product_output->segment<3>(3 * vertices[k]) += product.template segment<3>(3 * k);
  }
  if (jacobian->matrix == nullptr) return;
  const MatrixN local = jacobian->dfdx_scale * dfdx - (jacobian->dfdv_scale * damping) * outer;
  double* values = jacobian->matrix->valuePtr();
  for (int k = 0; k < kVertices; ++k)
    for (int l = 0; l < kVertices; ++l) {
      const int offset = blocks[kVertices * k + l];
      for (int a = 0; a < 3; ++a) {
        double* row = values + block_value_index(*jacobian->matrix, vertices[k], offset, a, 0);
        for (int b = 0; b < 3; ++b) row[b] += local(3 * k + a, 3 * l + b);
      }
    }
}

}  // namespace

void evaluate_forces(const ClothModel& model, const ForceSettings& settings,
                     const Eigen::VectorXd& x, const Eigen::VectorXd& v, Eigen::VectorXd& force,
                     EnergyBreakdown* energy, const JacobianTarget* jacobian) {
  const FabricParameters& fabric = model.fabric;
  const ForceTerms& terms = settings.terms;
  const int n = model.vertex_count;
  force.setZero(3 * n);
  EnergyBreakdown local_energy;
  const bool want_hessian = jacobian != nullptr;
  const bool exact = jacobian != nullptr && jacobian->kind == JacobianKind::exact;
  const double damping_scale = terms.damping ? 1.0 : 0.0;

  if (terms.stretch || terms.shear) {
    for (const TriangleElement& t : model.triangles) {
      const auto& vs = t.vertices;
      const TriangleConditions c =
          triangle_conditions(t, x.segment<3>(3 * vs[0]), x.segment<3>(3 * vs[1]),
                              x.segment<3>(3 * vs[2]), want_hessian);
      if (terms.stretch) {
        const double k_u = fabric.stretch_warp * t.rest_area;
        const double k_v = fabric.stretch_weft * t.rest_area;
        add_condition(c.warp, 0.0, k_u, damping_scale * fabric.damping * k_u, true, vs.data(),
                      t.blocks.data(), v, force, local_energy.stretch, jacobian);
        add_condition(c.weft, 0.0, k_v, damping_scale * fabric.damping * k_v, true, vs.data(),
                      t.blocks.data(), v, force, local_energy.stretch, jacobian);
      }
      if (terms.shear) {
        const double k_s = fabric.shear * t.rest_area;
        add_condition(c.shear, 0.0, k_s, damping_scale * fabric.damping * k_s, false, vs.data(),
                      t.blocks.data(), v, force, local_energy.shear, jacobian);
      }
    }
  }
  if (terms.bend && fabric.bend > 0.0) {
    // The bend Hessian is only needed for the exact Jacobian: the solve uses −k·∇θ∇θᵀ.
    for (const HingeElement& h : model.hinges) {
      const auto& vs = h.vertices;
      const Condition<12> c = dihedral_angle_condition(
          x.segment<3>(3 * vs[0]), x.segment<3>(3 * vs[1]), x.segment<3>(3 * vs[2]),
          x.segment<3>(3 * vs[3]), exact);
      const double k_b = fabric.bend * h.weight;
      add_condition(c, h.rest_angle, k_b, damping_scale * fabric.bend_damping * k_b, false,
                    vs.data(), h.blocks.data(), v, force, local_energy.bend, jacobian);
    }
  }
  if (terms.bend && fabric.bend > 0.0 && model.bend_stencil_stiffness > 0.0) {
    // Quadratic, so its Hessian is exact in both Jacobian kinds and positive semi-definite:
    // f_j = −k Σ_l C_jl (x_l + β v_l), ∂f_j/∂x_l = −k C_jl I, ∂f_j/∂v_l = −k β C_jl I.
    const double k = model.bend_stencil_stiffness * fabric.bend;
    const double beta = damping_scale * fabric.bend_damping;
    for (const BendStencil& b : model.stencils) {
      const int count = static_cast<int>(b.vertices.size());
      for (int j = 0; j < count; ++j) {
        Vector3d sum_x = Vector3d::Zero(), sum_v = Vector3d::Zero();
        for (int l = 0; l < count; ++l) {
          const double c = b.coupling(j, l);
          sum_x += c * x.segment<3>(3 * b.vertices[static_cast<std::size_t>(l)]);
          sum_v += c * v.segment<3>(3 * b.vertices[static_cast<std::size_t>(l)]);
        }
        const int vj = b.vertices[static_cast<std::size_t>(j)];
        local_energy.bend += 0.5 * k * sum_x.dot(x.segment<3>(3 * vj));
        force.segment<3>(3 * vj) -= k * (sum_x + beta * sum_v);
        if (jacobian == nullptr) continue;
        if (jacobian->product_input != nullptr) {
          Vector3d product = Vector3d::Zero();
          for (int l = 0; l < count; ++l)
            product += b.coupling(j, l) *
                       jacobian->product_input->segment<3>(3 * b.vertices[static_cast<std::size_t>(l)]);
          jacobian->product_output->segment<3>(3 * vj) -= k * product;
        }
        if (jacobian->matrix == nullptr) continue;
        double* values = jacobian->matrix->valuePtr();
        for (int l = 0; l < count; ++l) {
          const double entry =
              -k * b.coupling(j, l) * (jacobian->dfdx_scale + jacobian->dfdv_scale * beta);
          const int offset = b.blocks[static_cast<std::size_t>(count * j + l)];
          for (int a = 0; a < 3; ++a)
            values[block_value_index(*jacobian->matrix, vj, offset, a, a)] += entry;
        }
      }
    }
  }
  for (int i = 0; i < n; ++i) {
    if (terms.gravity) {
      force.segment<3>(3 * i) += model.mass[i] * settings.gravity;
      local_energy.potential -= model.mass[i] * settings.gravity.dot(x.segment<3>(3 * i));
    }
    local_energy.kinetic += 0.5 * model.mass[i] * v.segment<3>(3 * i).squaredNorm();
  }
  if (terms.drag && settings.air_drag > 0.0) {
    for (int i = 0; i < n; ++i) {
      const double c = settings.air_drag * model.vertex_area[i];
      force.segment<3>(3 * i) += c * (settings.wind - v.segment<3>(3 * i));
      if (jacobian != nullptr && jacobian->matrix != nullptr) {
        double* values = jacobian->matrix->valuePtr();
        for (int a = 0; a < 3; ++a)
          values[block_value_index(*jacobian->matrix, i, model.pattern.diagonal_offsets[i], a,
                                   a)] -= jacobian->dfdv_scale * c;
      }
    }
  }
  if (energy != nullptr) *energy = local_energy;
}

double max_stretch_strain(const ClothModel& model, const Eigen::VectorXd& x) {
  double strain = 0.0;
  for (const TriangleElement& t : model.triangles) {
    Vector3d wu = Vector3d::Zero();
    Vector3d wv = Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      wu += t.du[k] * x.segment<3>(3 * t.vertices[k]);
      wv += t.dv[k] * x.segment<3>(3 * t.vertices[k]);
    }
    strain = std::max({strain, wu.norm() - 1.0, wv.norm() - 1.0});
  }
  return strain;
}

double kinetic_energy(const ClothModel& model, const Eigen::VectorXd& v) {
  double energy = 0.0;
  for (int i = 0; i < model.vertex_count; ++i)
    energy += 0.5 * model.mass[i] * v.segment<3>(3 * i).squaredNorm();
  return energy;
}

}  // namespace sd::sim
