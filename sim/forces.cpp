#include "sim/forces.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <span>
#include <utility>
#include <vector>

#include "sim/element_forces.hpp"
#include "sim/parallel.hpp"

namespace sd::sim {
namespace {

using Eigen::Vector3d;

// An energy φ(C) of a condition: its value, slope φ' and curvature φ''.
struct ConditionEnergy {
  double value = 0.0;
  double slope = 0.0;
  double curvature = 0.0;
};

// What one condition C with energy φ(C) and damping k_d adds: its energy, its force on the
// element's vertices, and (with a Jacobian target) its block of the matrix and of the product.
// The curvature term −φ'·∇²C is kept in the solve's Jacobian only where φ' > 0 (stretched): in
// compression it is indefinite.
template <int N>
struct ConditionContribution {
  bool energy_only = false;  // its force, product and matrix are in another condition's
  double energy = 0.0;
  Eigen::Matrix<double, N, 1> force;
  Eigen::Matrix<double, N, 1> product;  // ∂f/∂x·u on the element, with a product target
  Eigen::Matrix<double, N, N> matrix;  // dfdx_scale·∂f/∂x + dfdv_scale·∂f/∂v, with a matrix
};

template <int N>
void condition_contribution(const Condition<N>& c, const ConditionEnergy& phi, double damping,
                            bool keep_curvature_in_solve, const int* vertices,
                            const Eigen::VectorXd& v, const JacobianTarget* jacobian,
                            ConditionContribution<N>& out) {
  constexpr int kVertices = N / 3;
  out.energy_only = false;
  using VectorN = Eigen::Matrix<double, N, 1>;
  using MatrixN = Eigen::Matrix<double, N, N>;
  VectorN local_v;
  for (int k = 0; k < kVertices; ++k)
    local_v.template segment<3>(3 * k) = v.segment<3>(3 * vertices[k]);
  const double c_dot = damping > 0.0 ? c.gradient.dot(local_v) : 0.0;
  out.energy = phi.value;
  out.force = -(phi.slope + damping * c_dot) * c.gradient;
  if (jacobian == nullptr) return;

  const bool exact = jacobian->kind == JacobianKind::exact;
  if (!exact && !(keep_curvature_in_solve && phi.slope > 0.0)) {
    // The solve without a curvature term (the hinges): rank one, ∂f/∂x = −φ''·∇C∇Cᵀ.
    if (jacobian->product_input != nullptr) {
      VectorN local_u;
      for (int k = 0; k < kVertices; ++k)
        local_u.template segment<3>(3 * k) = jacobian->product_input->segment<3>(3 * vertices[k]);
      out.product = (-phi.curvature * c.gradient.dot(local_u)) * c.gradient;
    }
    if (jacobian->matrix == nullptr) return;
    const double alpha = -jacobian->dfdx_scale * phi.curvature - jacobian->dfdv_scale * damping;
    out.matrix.noalias() = (alpha * c.gradient) * c.gradient.transpose();
    return;
  }
  const MatrixN outer = c.gradient * c.gradient.transpose();
  MatrixN dfdx = -phi.curvature * outer;
  if (exact || (keep_curvature_in_solve && phi.slope > 0.0)) dfdx -= phi.slope * c.hessian;
  if (exact && damping > 0.0) {
    dfdx -=
        damping * (c_dot * c.hessian + c.gradient * (c.hessian.transpose() * local_v).transpose());
  }
  if (jacobian->product_input != nullptr) {
    VectorN local_u;
    for (int k = 0; k < kVertices; ++k)
      local_u.template segment<3>(3 * k) = jacobian->product_input->segment<3>(3 * vertices[k]);
    out.product = dfdx * local_u;
  }
  if (jacobian->matrix == nullptr) return;
  out.matrix = jacobian->dfdx_scale * dfdx - (jacobian->dfdv_scale * damping) * outer;
}

// Adds a condition's contribution to the rows of the element's vertices k with
// own(vertices[k]) (the force, the product and the matrix; not the energy). Every entry then
// receives its sums in the order the conditions are added, whichever rows a thread owns.
template <int N, class Own>
void scatter_contribution(const ConditionContribution<N>& c, const int* vertices, const int* blocks,
                          Eigen::VectorXd& force, const JacobianTarget* jacobian, const Own& own) {
  constexpr int kVertices = N / 3;
  if (c.energy_only) return;
  for (int k = 0; k < kVertices; ++k)
    if (own(vertices[k])) force.segment<3>(3 * vertices[k]) += c.force.template segment<3>(3 * k);
  if (jacobian == nullptr) return;
  if (jacobian->product_input != nullptr)
    for (int k = 0; k < kVertices; ++k)
      if (own(vertices[k]))
        jacobian->product_output->segment<3>(3 * vertices[k]) +=
            c.product.template segment<3>(3 * k);
  if (jacobian->matrix == nullptr) return;
  double* values = jacobian->matrix->valuePtr();
  for (int k = 0; k < kVertices; ++k) {
    if (!own(vertices[k])) continue;
    for (int l = 0; l < kVertices; ++l) {
      const int offset = blocks[kVertices * k + l];
      for (int a = 0; a < 3; ++a) {
        double* row = values + block_value_index(*jacobian->matrix, vertices[k], offset, a, 0);
        for (int b = 0; b < 3; ++b) row[b] += c.matrix(3 * k + a, 3 * l + b);
      }
    }
  }
}

constexpr auto kEveryRow = [](int) { return true; };

// The quadratic energy ½·k·(C − C0)² (Baraff & Witkin) at the condition's value C.
ConditionEnergy quadratic_energy(double value, double rest_value, double stiffness) {
  const double c_value = value - rest_value;
  return {0.5 * stiffness * c_value * c_value, stiffness * c_value, stiffness};
}

// Stretch along one direction with Choi & Ko's post-buckling cap (Compression::buckling): the
// strain C with stiffness k = K·A, quadratic down to −ε* and then linear with slope −k·ε*
// (force per width N* = K·ε*), so force and energy are continuous at −ε*.
ConditionEnergy buckling_stretch(double strain, double stiffness, double buckling_strain) {
  if (strain >= -buckling_strain)
    return {0.5 * stiffness * strain * strain, stiffness * strain, stiffness};
  return {stiffness * buckling_strain * (-strain - 0.5 * buckling_strain),
          -stiffness * buckling_strain, 0.0};
}

// No buckling strain: compression stays quadratic however far it goes.
constexpr double kLinearCompression = std::numeric_limits<double>::infinity();

// Stretch along one direction at strain C: in tension the fabric's measured curve when it has
// one (energy A·W(ε), force A·σ(ε), stiffness A·dσ/dε), otherwise ½·k·C² with k = K·A; in
// compression ½·k·C² capped beyond the buckling strain (buckling_stretch).
ConditionEnergy stretch_energy(double strain, double stiffness, double buckling_strain,
                               const TensileCurve& curve, double rest_area) {
  if (strain > 0.0 && !curve.empty()) {
    const TensileCurve::Point p = curve.at(strain);
    return {rest_area * p.energy, rest_area * p.stress, rest_area * p.tangent};
  }
  return buckling_stretch(strain, stiffness, buckling_strain);
}

// Bias wrinkling (Compression::buckling, docs/simulator.md "Compression and buckling"): the
// membrane energy of a triangle per unit rest area as the least energy over wrinkle strains
// β_u, β_v, β_b ≥ 0 along warp, weft and the compressed bias n = (u − s·v)/√2 (s = sign γ):
// W(c) = min_β ½·eᵀ·D·e + Σ N*·β with the elastic strain e = c + P·β, c = (ε_u, ε_v, γ),
// D = diag(K_u, K_v, G) and P's columns (1,0,0), (0,1,0), (½,½,−s) (a wrinkle of β along n
// shortens warp and weft by β/2 and shears by s·β). Each wrinkle costs the element's Euler
// load N* per unit strain. The problem is strictly convex; its value is C¹ with gradient the
// elastic stress σ = D·e (N/m) and, on the active set S, Hessian D − D·P_S·(P_Sᵀ·D·P_S)⁻¹·P_Sᵀ·D.
// With β_b = 0 it is the warp and weft caps (buckling_stretch); this is called only where that
// answer would compress the bias beyond its load, so β_b > 0 and S holds b.
struct BiasWrinkle {
  Eigen::Vector3d elastic = Eigen::Vector3d::Zero();  // e
  Eigen::Vector3d wrinkle = Eigen::Vector3d::Zero();  // β_u, β_v, β_b
  Eigen::Matrix3d hessian = Eigen::Matrix3d::Zero();  // N/m
};

BiasWrinkle bias_wrinkle(const Eigen::Vector3d& c, const Eigen::Vector3d& stiffness,
                         const Eigen::Vector3d& load, double s) {
  Eigen::Matrix3d p = Eigen::Matrix3d::Identity();
  p.col(2) << 0.5, 0.5, -s;
  const Eigen::Matrix3d d = stiffness.asDiagonal();
  // The sets holding b: {b}, {u,b}, {v,b}, {u,v,b}. Exactly one satisfies the optimality
  // conditions (β_S ≥ 0, p_jᵀ·σ + N*_j ≥ 0 off S); rounding at a boundary may leave none or
  // two, so the one violating them least is taken.
  BiasWrinkle best;
  double best_violation = std::numeric_limits<double>::infinity();
  for (const int mask : {4, 5, 6, 7}) {
    std::array<int, 3> set{};
    int m = 0;
    for (int j = 0; j < 3; ++j)
      if (mask & (1 << j)) set[static_cast<std::size_t>(m++)] = j;
    // At most 3 × 3: fixed-capacity storage, no allocation per triangle.
    using Columns = Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, 3>;
    using Square = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3>;
    using Vector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1>;
    Columns ps(3, m);
    Vector loads(m);
    for (int k = 0; k < m; ++k) {
      ps.col(k) = p.col(set[static_cast<std::size_t>(k)]);
      loads(k) = load(set[static_cast<std::size_t>(k)]);
    }
    const Square normal = ps.transpose() * d * ps;
    const Vector beta = normal.ldlt().solve(-(ps.transpose() * d * c + loads));
    const Eigen::Vector3d e = c + ps * beta;
    const Eigen::Vector3d sigma = d * e;
    double violation = 0.0;
    for (int k = 0; k < m; ++k) violation = std::max(violation, -beta(k) * stiffness.maxCoeff());
    for (int j = 0; j < 3; ++j)
      if (!(mask & (1 << j))) violation = std::max(violation, -(p.col(j).dot(sigma) + load(j)));
    if (violation >= best_violation) continue;
    best_violation = violation;
    best.elastic = e;
    best.wrinkle.setZero();
    for (int k = 0; k < m; ++k) best.wrinkle(set[static_cast<std::size_t>(k)]) = beta(k);
    const Columns dp = d * ps;
    best.hessian = d - dp * normal.ldlt().solve(dp.transpose());
    if (violation <= 0.0) break;
  }
  return best;
}

// The rest triangle's extent along the bias (u − s·v)/√2, m. Its rest edges (Δu_k, Δv_k),
// k = 1, 2, are the columns of D = [[du1, dv1], [du2, dv2]]⁻¹ (build_cloth_model makes du, dv
// from D⁻¹), so the extent follows the rest shape wherever du, dv are replaced.
double bias_width(const TriangleElement& t, double s) {
  Eigen::Matrix2d inverse;
  inverse << t.du[1], t.dv[1], t.du[2], t.dv[2];
  const Eigen::Matrix2d d = inverse.inverse();
  const double p1 = (d(0, 0) - s * d(1, 0)) / std::numbers::sqrt2;
  const double p2 = (d(0, 1) - s * d(1, 1)) / std::numbers::sqrt2;
  return std::max({0.0, p1, p2}) - std::min({0.0, p1, p2});
}

// What the coupling O between a triangle's warp, weft and shear conditions (3×3, zero diagonal,
// N·m: the off-diagonal of the energy's Hessian in the conditions) adds to its Jacobian:
// ∂f/∂x gains −Σ_{i≠j} O_ij·∇C_i·∇C_jᵀ. Damping stays per condition.
void add_condition_coupling(const TriangleConditions& c, const Eigen::Matrix3d& coupling,
                            const int* vertices, const JacobianTarget& jacobian,
                            ConditionContribution<9>& into) {
  Eigen::Matrix<double, 9, 3> g;
  g << c.warp.gradient, c.weft.gradient, c.shear.gradient;
  const Eigen::Matrix<double, 9, 9> dfdx = -(g * coupling * g.transpose());
  if (jacobian.product_input != nullptr) {
    Eigen::Matrix<double, 9, 1> local_u;
    for (int k = 0; k < 3; ++k)
      local_u.segment<3>(3 * k) = jacobian.product_input->segment<3>(3 * vertices[k]);
    into.product += dfdx * local_u;
  }
  if (jacobian.matrix != nullptr) into.matrix += jacobian.dfdx_scale * dfdx;
}

// [a]_×: the matrix of a × ·.
Eigen::Matrix3d cross_matrix(const Vector3d& a) {
  Eigen::Matrix3d m;
  m << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return m;
}

// G(y) = ∂N/∂x of the element's area vector N(x) = ½·Σ_fan (x_b − x_v)×(x_c − x_v), evaluated
// with the positions y (3 by 3·#vertices). N is a symmetric bilinear form Q(x, x), so
// G(x)·u = 2Q(x, u) and ∂(G(x)·u)/∂x = G(u).
Eigen::MatrixXd area_vector_jacobian(const VertexBendElement& b, const Eigen::MatrixX3d& y) {
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(3, 3 * static_cast<Eigen::Index>(b.vertices.size()));
  const int v = b.centre;
  for (const auto& [pb, pc] : b.fan) {
    const Vector3d p = (y.row(pb) - y.row(v)).transpose(), q = (y.row(pc) - y.row(v)).transpose();
    // ∂(½ p×q)/∂p = −½[q]_×, ∂/∂q = ½[p]_×; p = x_b − x_v, q = x_c − x_v.
    g.block<3, 3>(0, 3 * pb) -= 0.5 * cross_matrix(q);
    g.block<3, 3>(0, 3 * pc) += 0.5 * cross_matrix(p);
    g.block<3, 3>(0, 3 * v) += 0.5 * (cross_matrix(q) - cross_matrix(p));
  }
  return g;
}

// ∇²(s·N(x)) for a fixed vector s (3·#vertices square, constant): from ½·s·(p×q),
// ∂²/∂p∂qᵀ = −½[s]_× and ∂²/∂q∂pᵀ = ½[s]_×.
Eigen::MatrixXd area_vector_hessian(const VertexBendElement& b, const Vector3d& s) {
  const auto m = static_cast<Eigen::Index>(b.vertices.size());
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(3 * m, 3 * m);
  const Eigen::Matrix3d pq = -0.5 * cross_matrix(s);
  const int v = b.centre;
  for (const auto& [pb, pc] : b.fan) {
    const std::array<std::pair<int, double>, 2> p{{{pb, 1.0}, {v, -1.0}}};
    const std::array<std::pair<int, double>, 2> q{{{pc, 1.0}, {v, -1.0}}};
    for (const auto& [i, si] : p)
      for (const auto& [j, sj] : q) {
        h.block<3, 3>(3 * i, 3 * j) += si * sj * pq;
        h.block<3, 3>(3 * j, 3 * i) += si * sj * pq.transpose();
      }
  }
  return h;
}

// What the quadratic bending of one vertex adds (VertexBendElement): its energy row by row, its
// force and, with a Jacobian target, its product and matrix block. A flat rest's rows are linear,
// so its matrix is coupling ⊗ I times `scale` (m × m, m the element's vertices); a curved rest's
// is dense (3m × 3m). The buffers keep their size between evaluations.
struct VertexBendContribution {
  std::array<double, 3> energy{};
  bool flat = true;
  Eigen::MatrixX3d flat_force, flat_product;  // m × 3
  Eigen::MatrixXd coupling;                   // m × m
  double scale = 0.0;
  Eigen::VectorXd force, product;  // 3m
  Eigen::MatrixXd local;           // 3m × 3m
};

// The quadratic bending of one vertex (VertexBendElement): energy ½·k·Σ_k s_k|r_k|², force
// −k·Σ_k s_k·J_kᵀ(r_k + β·ṙ_k) with J_k = ∂r_k/∂x = rows_k ⊗ I − c_k·G(x), ṙ_k = J_k·v,
// k = B/A_v and s = (½, ½, 2).
void vertex_bend_contribution(const VertexBendElement& b, double bend, double beta,
                              const Eigen::VectorXd& x, const Eigen::VectorXd& v,
                              const JacobianTarget* jacobian, VertexBendContribution& out) {
  static constexpr std::array<double, 3> kRowScale{0.5, 0.5, 2.0};
  const auto m = static_cast<Eigen::Index>(b.vertices.size());
  const double k = bend * b.inverse_area;
  Eigen::MatrixX3d xs(m, 3), vs(m, 3);
  for (Eigen::Index j = 0; j < m; ++j) {
    xs.row(j) = x.segment<3>(3 * b.vertices[static_cast<std::size_t>(j)]).transpose();
    vs.row(j) = v.segment<3>(3 * b.vertices[static_cast<std::size_t>(j)]).transpose();
  }
  const Eigen::Matrix3d r_lin = b.rows * xs;  // row k: Σ_j rows(k, j)·x_j
  const Eigen::Matrix3d r_dot_lin = b.rows * vs;
  out.flat = b.fan.empty();
  if (out.flat) {
    // r_k linear: every 3×3 block of Σ s_k J_kᵀJ_k is (Σ_k s_k·rows(k,j)·rows(k,l))·I.
    Eigen::Matrix3d pull;  // row k: k·s_k·(r_k + β ṙ_k)
    for (int row = 0; row < 3; ++row) {
      out.energy[static_cast<std::size_t>(row)] =
          0.5 * k * kRowScale[row] * r_lin.row(row).squaredNorm();
      pull.row(row) = k * kRowScale[row] * (r_lin.row(row) + beta * r_dot_lin.row(row));
    }
    out.flat_force.noalias() = -b.rows.transpose() * pull;  // m × 3
    if (jacobian == nullptr) return;
    const Eigen::Vector3d scales(kRowScale[0], kRowScale[1], kRowScale[2]);
    out.coupling.noalias() = b.rows.transpose() * scales.asDiagonal() * b.rows;  // m × m
    if (jacobian->product_input != nullptr) {
      Eigen::MatrixX3d us(m, 3);
      for (Eigen::Index j = 0; j < m; ++j)
        us.row(j) = jacobian->product_input->segment<3>(3 * b.vertices[static_cast<std::size_t>(j)])
                        .transpose();
      out.flat_product.noalias() = -k * out.coupling * us;
    }
    out.scale = -k * (jacobian->dfdx_scale + jacobian->dfdv_scale * beta);
    return;
  }
  Vector3d area_vector = Vector3d::Zero();
  for (const auto& [pb, pc] : b.fan)
    area_vector += 0.5 * (xs.row(pb) - xs.row(b.centre))
                             .transpose()
                             .cross((xs.row(pc) - xs.row(b.centre)).transpose());
  const Eigen::MatrixXd g_x = area_vector_jacobian(b, xs);
  const bool want = jacobian != nullptr;
  const bool exact = want && jacobian->kind == JacobianKind::exact;
  const Eigen::MatrixXd g_v = exact && beta > 0.0 ? area_vector_jacobian(b, vs) : Eigen::MatrixXd();
  out.force = Eigen::VectorXd::Zero(3 * m);
  // The three rows' Jacobians stacked, each scaled by √(k·s_k): Σ_k k·s_k·J_kᵀJ_k = SᵀS.
  Eigen::MatrixXd stacked(9, 3 * m);
  Eigen::MatrixXd dfdx;
  if (exact) dfdx = Eigen::MatrixXd::Zero(3 * m, 3 * m);
  Eigen::VectorXd local_v(3 * m);
  for (Eigen::Index j = 0; j < m; ++j) local_v.segment<3>(3 * j) = vs.row(j).transpose();
  for (int row = 0; row < 3; ++row) {
    const double c = b.rest_normal(row);
    const double weight = k * kRowScale[row];
    const Vector3d r = r_lin.row(row).transpose() - c * area_vector;
    auto jac = stacked.middleRows<3>(3 * row);
    jac = -c * g_x;
    for (Eigen::Index j = 0; j < m; ++j)
      jac.block<3, 3>(0, 3 * j).diagonal().array() += b.rows(row, j);
    const Vector3d r_dot = jac * local_v;
    out.energy[static_cast<std::size_t>(row)] = 0.5 * weight * r.squaredNorm();
    out.force.noalias() -= weight * (jac.transpose() * (r + beta * r_dot));
    if (exact) {
      // ∇²E_k = w(JᵀJ − c·∇²(r·N)); damping: ∂(JᵀJv)/∂x = −c·∇²(ṙ·N) − c·Jᵀ·G(v).
      dfdx += weight * c * area_vector_hessian(b, r);
      if (beta > 0.0)
        dfdx += beta * weight * c * (area_vector_hessian(b, r_dot) + jac.transpose() * g_v);
    }
    jac *= std::sqrt(weight);
  }
  if (!want) return;
  Eigen::MatrixXd gauss_newton;
  gauss_newton.noalias() = stacked.transpose() * stacked;
  if (exact)
    dfdx -= gauss_newton;
  else
    dfdx = -gauss_newton;
  if (jacobian->product_input != nullptr) {
    Eigen::VectorXd local_u(3 * m);
    for (Eigen::Index j = 0; j < m; ++j)
      local_u.segment<3>(3 * j) =
          jacobian->product_input->segment<3>(3 * b.vertices[static_cast<std::size_t>(j)]);
    out.product.noalias() = dfdx * local_u;
  }
  if (jacobian->matrix == nullptr) return;
  out.local = jacobian->dfdx_scale * dfdx - (jacobian->dfdv_scale * beta) * gauss_newton;
}

// Adds a vertex bend's contribution to the rows of its vertices with own(vertex) (not the
// energy), as scatter_contribution does for the conditions.
template <class Own>
void scatter_vertex_bend(const VertexBendElement& b, const VertexBendContribution& c,
                         Eigen::VectorXd& force, const JacobianTarget* jacobian, const Own& own) {
  const auto m = static_cast<Eigen::Index>(b.vertices.size());
  const auto vertex = [&](Eigen::Index j) { return b.vertices[static_cast<std::size_t>(j)]; };
  for (Eigen::Index j = 0; j < m; ++j)
    if (own(vertex(j)))
      force.segment<3>(3 * vertex(j)) +=
          c.flat ? Vector3d(c.flat_force.row(j).transpose()) : Vector3d(c.force.segment<3>(3 * j));
  if (jacobian == nullptr) return;
  if (jacobian->product_input != nullptr)
    for (Eigen::Index j = 0; j < m; ++j)
      if (own(vertex(j)))
        jacobian->product_output->segment<3>(3 * vertex(j)) +=
            c.flat ? Vector3d(c.flat_product.row(j).transpose())
                   : Vector3d(c.product.segment<3>(3 * j));
  if (jacobian->matrix == nullptr) return;
  double* values = jacobian->matrix->valuePtr();
  for (Eigen::Index j = 0; j < m; ++j) {
    if (!own(vertex(j))) continue;
    for (Eigen::Index l = 0; l < m; ++l) {
      const int offset = b.blocks[static_cast<std::size_t>(m * j + l)];
      if (c.flat) {
        const double entry = c.scale * c.coupling(j, l);
        for (int a = 0; a < 3; ++a)
          values[block_value_index(*jacobian->matrix, vertex(j), offset, a, a)] += entry;
        continue;
      }
      for (int a = 0; a < 3; ++a) {
        double* row = values + block_value_index(*jacobian->matrix, vertex(j), offset, a, 0);
        for (int e = 0; e < 3; ++e) row[e] += c.local(3 * j + a, 3 * l + e);
      }
    }
  }
}

// The quadratic bending of every vertex, as add_elements does for the conditions: on more than
// one thread a block of elements is computed in parallel, then added in parallel by rows, the
// energies in element order; the same bits on any thread count.
// The flat-rest vertex bends through their operators (FlatBendOperator): for each bend row r
// (in parallel), r = R x and ṙ = R v, its energy ½·B·w|r|² and pull B·w(r + β ṙ); then for each
// vertex i (in parallel), the force −Σ R_ri pull_r, the product −B·(Ku)_i and the matrix blocks
// B·K_ij·(−dfdx_scale − β dfdv_scale)·I. Each row and vertex is computed whole by one thread and
// the energies are summed in row order: the same bits on any thread count.
void add_flat_bends(const ClothModel& model, double bend, double beta, const Eigen::VectorXd& x,
                    const Eigen::VectorXd& v, Eigen::VectorXd& force, double& energy,
                    const JacobianTarget* jacobian) {
  const FlatBendOperator& k = model.flat_bends;
  const int n = model.vertex_count;
  const int rows = static_cast<int>(k.row_weight.size());
  const Eigen::VectorXd* u = jacobian != nullptr ? jacobian->product_input : nullptr;
  double* values =
      jacobian != nullptr && jacobian->matrix != nullptr ? jacobian->matrix->valuePtr() : nullptr;
  const double scale =
      jacobian != nullptr ? -bend * (jacobian->dfdx_scale + jacobian->dfdv_scale * beta) : 0.0;
  thread_local std::vector<double> kept_energy;  // the caller's, named once (see add_elements)
  thread_local std::vector<Vector3d> kept_pull;
  std::vector<double>& row_energy = kept_energy;
  std::vector<Vector3d>& pull = kept_pull;
  row_energy.resize(static_cast<std::size_t>(rows));
  pull.resize(static_cast<std::size_t>(rows));
  const auto bend_rows = [&](int, int low, int high) {
    for (int r = low; r < high; ++r) {
      Vector3d rx = Vector3d::Zero(), rv = Vector3d::Zero();
      for (int p = k.row_start[static_cast<std::size_t>(r)];
           p < k.row_start[static_cast<std::size_t>(r) + 1]; ++p) {
        const double c = k.row_value[static_cast<std::size_t>(p)];
        const int j = k.row_vertex[static_cast<std::size_t>(p)];
        rx += c * x.segment<3>(3 * j);
        rv += c * v.segment<3>(3 * j);
      }
      const double w = bend * k.row_weight[static_cast<std::size_t>(r)];
      row_energy[static_cast<std::size_t>(r)] = 0.5 * w * rx.squaredNorm();
      pull[static_cast<std::size_t>(r)] = w * (rx + beta * rv);
    }
  };
  const auto vertices = [&](int, int low, int high) {
    for (int i = low; i < high; ++i) {
      Vector3d f = Vector3d::Zero();
      for (int p = k.vertex_start[static_cast<std::size_t>(i)];
           p < k.vertex_start[static_cast<std::size_t>(i) + 1]; ++p)
        f += k.vertex_value[static_cast<std::size_t>(p)] *
             pull[static_cast<std::size_t>(k.vertex_row[static_cast<std::size_t>(p)])];
      force.segment<3>(3 * i) -= f;
      if (jacobian == nullptr) continue;
      Vector3d ku = Vector3d::Zero();
      for (int p = k.k_start[static_cast<std::size_t>(i)];
           p < k.k_start[static_cast<std::size_t>(i) + 1]; ++p) {
        const double c = k.k_value[static_cast<std::size_t>(p)];
        if (u != nullptr) ku += c * u->segment<3>(3 * k.k_column[static_cast<std::size_t>(p)]);
        if (values != nullptr) {
          const double entry = scale * c;
          const int offset = k.k_offset[static_cast<std::size_t>(p)];
          for (int a = 0; a < 3; ++a)
            values[block_value_index(*jacobian->matrix, i, offset, a, a)] += entry;
        }
      }
      if (u != nullptr) jacobian->product_output->segment<3>(3 * i) -= bend * ku;
    }
  };
  const int threads = thread_count();
  constexpr int kGrain = 512;
  if (threads <= 1 || n < 2 * kGrain) {
    bend_rows(0, 0, rows);
    vertices(0, 0, n);
  } else {
    parallel_chunks(rows, std::max(kGrain, (rows + threads - 1) / threads), bend_rows);
    parallel_chunks(n, std::max(kGrain, (n + threads - 1) / threads), vertices);
  }
  for (int r = 0; r < rows; ++r) energy += row_energy[static_cast<std::size_t>(r)];
}

void add_vertex_bends(const ClothModel& model, double bend, double beta, const Eigen::VectorXd& x,
                      const Eigen::VectorXd& v, Eigen::VectorXd& force, double& energy,
                      const JacobianTarget* jacobian) {
  constexpr int kBlock = 256;
  constexpr int kGrain = 64;
  // The flat-rest bends through their operator when it was built for these bends, then the
  // curved ones element by element; without it, every element.
  const bool summed =
      model.flat_bends.elements == model.vertex_bends.size() &&
      model.flat_bends.k_start.size() == static_cast<std::size_t>(model.vertex_count) + 1;
  if (summed) add_flat_bends(model, bend, beta, x, v, force, energy, jacobian);
  const int count = summed ? static_cast<int>(model.flat_bends.curved.size())
                           : static_cast<int>(model.vertex_bends.size());
  const auto element = [&](int k) -> const VertexBendElement& {
    return model.vertex_bends[static_cast<std::size_t>(
        summed ? model.flat_bends.curved[static_cast<std::size_t>(k)] : k)];
  };
  const int threads = thread_count();
  const auto add_energy = [&](const VertexBendContribution& c) {
    for (double e : c.energy) energy += e;
  };
  if (threads <= 1 || count < 2 * kGrain) {
    VertexBendContribution c;
    for (int k = 0; k < count; ++k) {
      const VertexBendElement& b = element(k);
      vertex_bend_contribution(b, bend, beta, x, v, jacobian, c);
      add_energy(c);
      scatter_vertex_bend(b, c, force, jacobian, kEveryRow);
    }
    return;
  }
  thread_local std::vector<VertexBendContribution> kept;  // see add_elements
  std::vector<VertexBendContribution>& buffer = kept;
  buffer.resize(static_cast<std::size_t>(std::min(count, kBlock)));
  const int row_grain = std::max(1, (model.vertex_count + threads - 1) / threads);
  for (int first = 0; first < count; first += kBlock) {
    const int size = std::min(kBlock, count - first);
    parallel_chunks(size, kGrain, [&](int, int begin, int end) {
      for (int k = begin; k < end; ++k)
        vertex_bend_contribution(element(first + k), bend, beta, x, v, jacobian,
                                 buffer[static_cast<std::size_t>(k)]);
    });
    parallel_chunks(model.vertex_count, row_grain, [&](int, int low, int high) {
      const auto own = [low, high](int vertex) { return vertex >= low && vertex < high; };
      for (int k = 0; k < size; ++k)
        scatter_vertex_bend(element(first + k), buffer[static_cast<std::size_t>(k)], force,
                            jacobian, own);
    });
    for (int k = 0; k < size; ++k) add_energy(buffer[static_cast<std::size_t>(k)]);
  }
}

// The contributions of one element: up to K conditions of N coordinates, each with the energy
// it adds to (a member of EnergyBreakdown).
template <int N, int K>
struct ElementContribution {
  std::array<ConditionContribution<N>, K> conditions;
  std::array<double EnergyBreakdown::*, K> energy{};
  int count = 0;  // conditions filled, in the order they are added

  ConditionContribution<N>& next(double EnergyBreakdown::*into) {
    energy[static_cast<std::size_t>(count)] = into;
    return conditions[static_cast<std::size_t>(count++)];
  }
};

// One condition of a triangle: its condition, energy φ and damping k_d; for a stretch condition
// also d (du or dv) and w = Σ_k d[k]·x_k, whose gradient is d ⊗ ŵ and Hessian
// d dᵀ ⊗ (I − ŵŵᵀ)/|w| (element_forces.cpp).
struct TriangleTerm {
  const Condition<9>* condition = nullptr;
  ConditionEnergy energy;
  double damping = 0.0;
  const Vector3d* d = nullptr;  // null for the shear
  const Vector3d* w = nullptr;
  double EnergyBreakdown::*into = nullptr;
};

// The solve's contribution of a triangle (JacobianKind::solve): the same force, product and
// matrix as condition_contribution gives each condition, summed into the first condition (the
// others keep only their energies) so that the element is scattered once, and built from the
// conditions' structure instead of 9×9 products: a stretch term is d dᵀ ⊗ S with one symmetric
// 3×3 S = α·ŵŵᵀ − dfdx_scale·φ'·(I − ŵŵᵀ)/|w| (the curvature only while stretched), the shear
// α·∇C∇Cᵀ, with α = −dfdx_scale·φ'' − dfdv_scale·k_d.
void triangle_solve_contribution(std::span<const TriangleTerm> parts, const int* vertices,
                                 const Eigen::VectorXd& v, const JacobianTarget& jacobian,
                                 ElementContribution<9, 3>& out) {
  using Vector9d = Eigen::Matrix<double, 9, 1>;
  if (parts.empty()) return;
  const bool want_product = jacobian.product_input != nullptr;
  const bool want_matrix = jacobian.matrix != nullptr;
  Vector9d local_v, local_u = Vector9d::Zero();
  for (int k = 0; k < 3; ++k) {
    local_v.segment<3>(3 * k) = v.segment<3>(3 * vertices[k]);
    if (want_product)
      local_u.segment<3>(3 * k) = jacobian.product_input->segment<3>(3 * vertices[k]);
  }
  Vector9d force = Vector9d::Zero(), product = Vector9d::Zero();
  Eigen::Matrix<double, 9, 9> matrix = Eigen::Matrix<double, 9, 9>::Zero();
  for (const TriangleTerm& part : parts) {
    ConditionContribution<9>& slot = out.next(part.into);
    slot.energy = part.energy.value;
    slot.energy_only = true;
    const Vector9d& gradient = part.condition->gradient;
    const double c_dot = part.damping > 0.0 ? gradient.dot(local_v) : 0.0;
    force -= (part.energy.slope + part.damping * c_dot) * gradient;
    const double alpha =
        -jacobian.dfdx_scale * part.energy.curvature - jacobian.dfdv_scale * part.damping;
    if (part.d == nullptr) {  // the shear: rank one
      if (want_product) product -= (part.energy.curvature * gradient.dot(local_u)) * gradient;
      if (want_matrix) matrix.noalias() += (alpha * gradient) * gradient.transpose();
      continue;
    }
    const double length = part.w->norm();
    if (length < 1e-300) continue;  // zero derivatives (element_forces.hpp)
    const Vector3d unit = *part.w / length;
    const bool curved = part.energy.slope > 0.0;
    const Eigen::Matrix3d along = unit * unit.transpose();
    const Eigen::Matrix3d across = (Eigen::Matrix3d::Identity() - along) / length;
    const Vector3d& d = *part.d;
    if (want_product) {
      const Vector3d w_u = d[0] * local_u.segment<3>(0) + d[1] * local_u.segment<3>(3) +
                           d[2] * local_u.segment<3>(6);
      Vector3d p = (-part.energy.curvature * unit.dot(w_u)) * unit;
      if (curved) p -= part.energy.slope * (across * w_u);
      for (int k = 0; k < 3; ++k) product.segment<3>(3 * k) += d[k] * p;
    }
    if (want_matrix) {
      Eigen::Matrix3d block = alpha * along;
      if (curved) block -= (jacobian.dfdx_scale * part.energy.slope) * across;
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) matrix.block<3, 3>(3 * k, 3 * l) += (d[k] * d[l]) * block;
    }
  }
  ConditionContribution<9>& total = out.conditions[0];
  total.energy_only = false;
  total.force = force;
  if (want_product) total.product = product;
  if (want_matrix) total.matrix = matrix;
}

// The membrane (stretch, shear, the compression model) of triangle t at positions x0, x1, x2 of
// its vertices: what evaluate_forces adds for it. `vertices` index its vertices in `v` and in the
// jacobian's product input (the triangle's own, or local ones for a diamond).
void triangle_membrane(const ClothModel& model, const ForceTerms& terms, double damping_scale,
                       const TriangleElement& t, const Vector3d& x0, const Vector3d& x1,
                       const Vector3d& x2, const int* vertices, const Eigen::VectorXd& v,
                       const JacobianTarget* jacobian, ElementContribution<9, 3>& out) {
  const bool exact = jacobian != nullptr && jacobian->kind == JacobianKind::exact;
  const bool solve = jacobian != nullptr && !exact;
  // The solve (triangle_solve_contribution) needs no Hessian matrices.
  TriangleConditions c = triangle_conditions(t, x0, x1, x2, exact);
  const FabricParameters& fabric = model.fabric;
  std::array<TriangleTerm, 3> parts;
  int count = 0;
  // ε* = N*/K with N* = π²·B / l² for the triangle's width l along each direction (only
  // with the buckling compression; infinity leaves compression quadratic).
  const bool buckling = model.compression == Compression::buckling;
  const double pi2b = std::numbers::pi * std::numbers::pi * fabric.bend;
  if (terms.stretch) {
    const double k_u = fabric.stretch_warp * t.rest_area;
    const double k_v = fabric.stretch_weft * t.rest_area;
    const double eps_u =
        buckling ? pi2b / (t.width_u * t.width_u * fabric.stretch_warp) : kLinearCompression;
    const double eps_v =
        buckling ? pi2b / (t.width_v * t.width_v * fabric.stretch_weft) : kLinearCompression;
    parts[count++] = {&c.warp,
                      stretch_energy(c.warp.value, k_u, eps_u, fabric.tensile_warp, t.rest_area),
                      damping_scale * fabric.damping * k_u,
                      &t.du,
                      &c.warp_vector,
                      &EnergyBreakdown::stretch};
    parts[count++] = {&c.weft,
                      stretch_energy(c.weft.value, k_v, eps_v, fabric.tensile_weft, t.rest_area),
                      damping_scale * fabric.damping * k_v,
                      &t.dv,
                      &c.weft_vector,
                      &EnergyBreakdown::stretch};
  }
  if (terms.shear) {
    const double k_s = fabric.shear * t.rest_area;
    parts[count++] = {&c.shear,
                      quadratic_energy(c.shear.value, 0.0, k_s),
                      damping_scale * fabric.damping * k_s,
                      nullptr,
                      nullptr,
                      &EnergyBreakdown::shear};
  }
  // Bias wrinkling (bias_wrinkle), where the capped warp and weft leave the compressed bias
  // beyond its Euler load N*_b: the larger of the triangle's own along the bias and the mean
  // of its warp and weft loads, so that it never acts without shear (at γ = 0 the capped
  // yarns keep ½·(σ_u + σ_v) ≥ −N*_b). The measured tensile curves keep the yarn caps only.
  Eigen::Matrix3d coupling = Eigen::Matrix3d::Zero();
  bool coupled = false;
  if (buckling && terms.stretch && terms.shear && fabric.tensile_warp.empty() &&
      fabric.tensile_weft.empty()) {
    const double area = t.rest_area;
    const double s = c.shear.value < 0.0 ? -1.0 : 1.0;
    const double n_u = pi2b / (t.width_u * t.width_u), n_v = pi2b / (t.width_v * t.width_v);
    const double bias_stress = 0.5 * (parts[0].energy.slope + parts[1].energy.slope) / area -
                               fabric.shear * std::abs(c.shear.value);
    // N*_b is at least the mean: the triangle's bias extent is needed only below it.
    double n_b = 0.5 * (n_u + n_v);
    if (bias_stress + n_b < 0.0) {
      const double width_b = bias_width(t, s);
      n_b = std::max(n_b, pi2b / (width_b * width_b));
    }
    const Eigen::Vector3d n_star(n_u, n_v, n_b);
    if (bias_stress + n_b < 0.0) {
      const Eigen::Vector3d stiffness(fabric.stretch_warp, fabric.stretch_weft, fabric.shear);
      const BiasWrinkle w = bias_wrinkle(Eigen::Vector3d(c.warp.value, c.weft.value, c.shear.value),
                                         stiffness, n_star, s);
      for (int j = 0; j < 3; ++j) {
        const double e = w.elastic(j);
        parts[static_cast<std::size_t>(j)].energy = {
            area * (0.5 * stiffness(j) * e * e + n_star(j) * w.wrinkle(j)), area * stiffness(j) * e,
            area * w.hessian(j, j)};
      }
      coupling = area * w.hessian;
      coupling.diagonal().setZero();
      coupled = true;
    }
  }
  if (solve) {
    triangle_solve_contribution(
        std::span<const TriangleTerm>(parts.data(), static_cast<std::size_t>(count)), vertices, v,
        *jacobian, out);
    if (coupled) add_condition_coupling(c, coupling, vertices, *jacobian, out.conditions[0]);
    return;
  }
  for (int j = 0; j < count; ++j) {
    const TriangleTerm& part = parts[static_cast<std::size_t>(j)];
    condition_contribution(*part.condition, part.energy, part.damping, part.d != nullptr, vertices,
                           v, jacobian, out.next(part.into));
  }
  if (coupled && jacobian != nullptr)
    add_condition_coupling(c, coupling, vertices, *jacobian, out.conditions[0]);
}

// Adds the contributions of elements 0 … count − 1: contribute(k, out) fills element k's (the
// conditions and their derivatives: most of the work of a force evaluation), element(k) gives
// its vertices and block offsets. On one thread each element is added as it is computed. On
// more, a block of elements is computed in parallel, then added in parallel by rows: each
// thread owns a range of vertices and adds, element by element in order, what lands in its
// rows. Every entry of the force, the product and the matrix so receives its sums in the same
// order as on one thread, and the energies are summed in that order too: the result is the same
// bits on any thread count. Blocks of kBlock elements keep the buffer (2.4 kB per triangle
// with its matrices) in the cache.
template <int N, int K, class Element, class Contribute>
void add_elements(int count, int vertex_count, const Element& element, const Contribute& contribute,
                  Eigen::VectorXd& force, EnergyBreakdown& energy, const JacobianTarget* jacobian) {
  using Contribution = ElementContribution<N, K>;
  constexpr int kBlock = 512;
  constexpr int kGrain = 128;
  const auto add_energy = [&](const Contribution& c) {
    for (int j = 0; j < c.count; ++j)
      energy.*c.energy[static_cast<std::size_t>(j)] +=
          c.conditions[static_cast<std::size_t>(j)].energy;
  };
  const int threads = thread_count();
  if (threads <= 1 || count < 2 * kGrain) {
    Contribution c;
    for (int k = 0; k < count; ++k) {
      c.count = 0;
      contribute(k, c);
      const auto [vertices, blocks] = element(k);
      add_energy(c);
      for (int j = 0; j < c.count; ++j)
        scatter_contribution(c.conditions[static_cast<std::size_t>(j)], vertices, blocks, force,
                             jacobian, kEveryRow);
    }
    return;
  }
  // Kept between calls (one per thread that evaluates forces): no allocation per evaluation.
  // Named through a reference: inside the lambdas the thread_local itself would be the worker
  // thread's own.
  thread_local std::vector<Contribution> kept;
  std::vector<Contribution>& buffer = kept;
  buffer.resize(static_cast<std::size_t>(std::min(count, kBlock)));
  // One range of rows per thread: which thread adds into a row does not change the order.
  const int row_grain = std::max(1, (vertex_count + threads - 1) / threads);
  for (int first = 0; first < count; first += kBlock) {
    const int size = std::min(kBlock, count - first);
    parallel_chunks(size, kGrain, [&](int, int begin, int end) {
      for (int k = begin; k < end; ++k) {
        Contribution& c = buffer[static_cast<std::size_t>(k)];
        c.count = 0;
        contribute(first + k, c);
      }
    });
    parallel_chunks(vertex_count, row_grain, [&](int, int low, int high) {
      const auto own = [low, high](int vertex) { return vertex >= low && vertex < high; };
      for (int k = 0; k < size; ++k) {
        const Contribution& c = buffer[static_cast<std::size_t>(k)];
        const auto [vertices, blocks] = element(first + k);
        for (int j = 0; j < c.count; ++j)
          scatter_contribution(c.conditions[static_cast<std::size_t>(j)], vertices, blocks, force,
                               jacobian, own);
      }
    });
    for (int k = 0; k < size; ++k) add_energy(buffer[static_cast<std::size_t>(k)]);
  }
}

// The map's curvature Σ_i f_c,i·∇²g_i (f_c the force on the mapped centre) as the implicit solve
// keeps it: Lᵀ·C₋·L, C₋ the negative semi-definite part of C = Σ_i f_c,i·H_i in the six points'
// coordinates (the eigenvalues above zero, which soften, dropped), so the solve matrix stays
// symmetric negative semi-definite. Near flat it is of order |f_c|/ε; left out, a hanging sheet's
// step is explicit in it (docs/simulator.md, "The diamond membrane").
DiamondMatrix solve_curvature(const DiamondElement& d, const DiamondVector& x,
                              const Vector3d& f_centre) {
  using Matrix18 = Eigen::Matrix<double, 18, 18>;
  DiamondMap full;
  diamond_centre_map(d, x, true, full);
  Matrix18 c = Matrix18::Zero();
  for (int i = 0; i < 3; ++i) c += f_centre(i) * full.point_hessian[static_cast<std::size_t>(i)];
  const Matrix18 symmetric = 0.5 * (c + c.transpose());
  const Eigen::SelfAdjointEigenSolver<Matrix18> eig(symmetric);
  const Eigen::Matrix<double, 18, 1> lambda = eig.eigenvalues().cwiseMin(0.0);
  const Eigen::Matrix<double, 18, 3 * DiamondElement::kVertices> vl =
      eig.eigenvectors().transpose() * full.points;
  return vl.transpose() * lambda.asDiagonal() * vl;
}

// The membrane of the diamonds (ClothModel::diamonds, docs/simulator.md "The diamond membrane"):
// each of a diamond's four triangles is evaluated by triangle_membrane at the mapped positions
// y = (x_c + g(x), x_1 … x_4) with the velocities J·v, J = ∂y/∂x = I + E_c·G (G = ∂g/∂x in the
// centre's rows). The energy is the triangles' at y; the force Jᵀ·f(y); the solve's matrix
// Jᵀ·(dfdx_scale·K + dfdv_scale·D)·J and product Jᵀ·K·J·u, K and D the triangles' own at y, plus
// the negative semi-definite part of the map's curvature Σ_i f_c,i·∇²g_i (solve_curvature). The
// exact Jacobian adds the whole curvature and the damping's dependence on x through J·v, which
// the solve leaves out (the damping's ∂/∂x, dropped for every element).
void add_diamonds(const ClothModel& model, const ForceTerms& terms, double damping_scale,
                  const Eigen::VectorXd& x, const Eigen::VectorXd& v, Eigen::VectorXd& force,
                  EnergyBreakdown& energy, const JacobianTarget* jacobian) {
  constexpr int kN = 3 * DiamondElement::kVertices;
  using LocalVector = DiamondVector;  // the diamond's 13 vertices (39 coordinates)
  using LocalMatrix = DiamondMatrix;
  const bool exact = jacobian != nullptr && jacobian->kind == JacobianKind::exact;
  const bool want_product = jacobian != nullptr && jacobian->product_input != nullptr;
  const bool want_matrix = jacobian != nullptr && jacobian->matrix != nullptr;
  const bool damped = damping_scale * model.fabric.damping > 0.0;
  // Any matrix: triangle_membrane only asks whether there is one, and fills its local block.
  static const SparseMatrixR kLocalMatrix;
  const auto element = [&](int k) {
    const DiamondElement& d = model.diamonds[static_cast<std::size_t>(k)];
    return std::make_pair(d.vertices.data(), d.blocks.data());
  };
  const auto contribute = [&](int k, ElementContribution<kN, 2>& out) {
    const DiamondElement& d = model.diamonds[static_cast<std::size_t>(k)];
    LocalVector local_x, local_v, local_u = LocalVector::Zero();
    for (int j = 0; j < DiamondElement::kVertices; ++j) {
      const int vertex = d.vertices[static_cast<std::size_t>(j)];
      local_x.segment<3>(3 * j) = x.segment<3>(3 * vertex);
      local_v.segment<3>(3 * j) = v.segment<3>(3 * vertex);
      if (want_product) local_u.segment<3>(3 * j) = jacobian->product_input->segment<3>(3 * vertex);
    }
    DiamondMap map;
    diamond_centre_map(d, local_x, exact, map);
    const Eigen::Matrix<double, 3, kN>& g = map.jacobian;
    LocalVector y = local_x;
    y.head<3>() += map.offset;
    // The triangles read velocities and the product's input by local index (0 the centre).
    thread_local Eigen::VectorXd mapped_v, mapped_u, unused;
    mapped_v = local_v;
    mapped_v.head<3>() += g * local_v;
    if (want_product) {
      mapped_u = local_u;
      mapped_u.head<3>() += g * local_u;
    }
    JacobianTarget local;
    local.kind = exact ? JacobianKind::exact : JacobianKind::solve;
    local.matrix = want_matrix || exact ? const_cast<SparseMatrixR*>(&kLocalMatrix) : nullptr;
    local.dfdx_scale = exact ? 1.0 : jacobian != nullptr ? jacobian->dfdx_scale : 0.0;
    local.dfdv_scale = exact ? 0.0 : jacobian != nullptr ? jacobian->dfdv_scale : 0.0;
    local.product_input = want_product && !exact ? &mapped_u : nullptr;
    local.product_output = &unused;
    LocalVector f = LocalVector::Zero(), product = LocalVector::Zero();
    LocalMatrix matrix = LocalMatrix::Zero(), damping = LocalMatrix::Zero();  // exact: K and D
    double stretch = 0.0, shear = 0.0;
    ElementContribution<9, 3> part;
    for (int f_index : d.triangles) {
      if (f_index < 0) continue;  // a partial diamond's split sector
      const TriangleElement& t = model.triangles[static_cast<std::size_t>(f_index)];
      std::array<int, 3> at{};  // the triangle's vertices as local indices
      for (int j = 0; j < 3; ++j)
        at[static_cast<std::size_t>(j)] =
            static_cast<int>(std::find(d.vertices.begin(), d.vertices.begin() + 5,
                                       t.vertices[static_cast<std::size_t>(j)]) -
                             d.vertices.begin());
      const auto add = [&](const ElementContribution<9, 3>& c, bool forces, LocalMatrix& into) {
        for (int j = 0; j < c.count; ++j) {
          const ConditionContribution<9>& cc = c.conditions[static_cast<std::size_t>(j)];
          if (forces) {
            (c.energy[static_cast<std::size_t>(j)] == &EnergyBreakdown::shear ? shear : stretch) +=
                cc.energy;
          }
          if (cc.energy_only) continue;
          for (int a = 0; a < 3; ++a) {
            const int p = at[static_cast<std::size_t>(a)];
            if (forces) {
              f.segment<3>(3 * p) += cc.force.segment<3>(3 * a);
              if (want_product && !exact) product.segment<3>(3 * p) += cc.product.segment<3>(3 * a);
            }
            if (local.matrix == nullptr) continue;
            for (int b = 0; b < 3; ++b)
              into.block<3, 3>(3 * p, 3 * at[static_cast<std::size_t>(b)]) +=
                  cc.matrix.block<3, 3>(3 * a, 3 * b);
          }
        }
      };
      const Vector3d y0 = y.segment<3>(3 * at[0]), y1 = y.segment<3>(3 * at[1]),
                     y2 = y.segment<3>(3 * at[2]);
      part.count = 0;
      triangle_membrane(model, terms, damping_scale, t, y0, y1, y2, at.data(), mapped_v,
                        jacobian != nullptr ? &local : nullptr, part);
      add(part, true, matrix);
      if (exact && damped) {  // ∂f/∂v of the triangle at y, apart from its ∂f/∂x
        JacobianTarget rates = local;
        rates.dfdx_scale = 0.0;
        rates.dfdv_scale = 1.0;
        part.count = 0;
        triangle_membrane(model, terms, damping_scale, t, y0, y1, y2, at.data(), mapped_v, &rates,
                          part);
        add(part, false, damping);
      }
    }
    ConditionContribution<kN>& total = out.next(&EnergyBreakdown::stretch);
    total.energy = stretch;
    total.energy_only = false;
    ConditionContribution<kN>& shear_part = out.next(&EnergyBreakdown::shear);
    shear_part.energy = shear;
    shear_part.energy_only = true;
    // Pulled back through J: Jᵀ·w = w + Gᵀ·w_c.
    const Vector3d f_centre = f.head<3>();
    total.force = f + g.transpose() * f_centre;
    if (jacobian == nullptr) return;
    // J's action on a matrix's columns: M·J = M + M_{·c}·G.
    const auto times_j = [&](const LocalMatrix& m) -> LocalMatrix {
      return m + m.leftCols<3>() * g;
    };
    const auto pull_back = [&](const LocalMatrix& m) -> LocalMatrix {
      return m + g.transpose() * m.topRows<3>();
    };
    if (!exact) {
      const LocalMatrix stiff = solve_curvature(d, local_x, f_centre);
      if (want_product)
        total.product = product + g.transpose() * product.head<3>() + stiff * local_u;
      if (want_matrix) total.matrix = pull_back(times_j(matrix)) + jacobian->dfdx_scale * stiff;
      return;
    }
    LocalMatrix dfdx = pull_back(times_j(matrix));
    std::array<LocalMatrix, 3> hessian;
    for (int i = 0; i < 3; ++i) {
      hessian[static_cast<std::size_t>(i)] = diamond_map_hessian(map, i);
      dfdx += f_centre(i) * hessian[static_cast<std::size_t>(i)];
    }
    LocalMatrix dfdv = LocalMatrix::Zero();
    if (damped) {
      Eigen::Matrix<double, 3, kN> velocity_map;  // ∂(G·v)/∂x: row i is (∇²g_i·v)ᵀ
      for (int i = 0; i < 3; ++i)
        velocity_map.row(i) = (hessian[static_cast<std::size_t>(i)] * local_v).transpose();
      dfdx += pull_back(damping.leftCols<3>() * velocity_map);
      dfdv = pull_back(times_j(damping));
    }
    if (want_product) total.product = dfdx * local_u;
    if (want_matrix) total.matrix = jacobian->dfdx_scale * dfdx + jacobian->dfdv_scale * dfdv;
  };
  add_elements<kN, 2>(static_cast<int>(model.diamonds.size()), model.vertex_count, element,
                      contribute, force, energy, jacobian);
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
  const bool exact = jacobian != nullptr && jacobian->kind == JacobianKind::exact;
  const double damping_scale = terms.damping ? 1.0 : 0.0;

  if (terms.stretch || terms.shear) {
    const auto element = [&](int k) {
      const TriangleElement& t = model.triangles[static_cast<std::size_t>(
          model.diamonds.empty() ? k : model.lone_triangles[static_cast<std::size_t>(k)])];
      return std::make_pair(t.vertices.data(), t.blocks.data());
    };
    const auto contribute = [&](int k, ElementContribution<9, 3>& out) {
      const TriangleElement& t = model.triangles[static_cast<std::size_t>(
          model.diamonds.empty() ? k : model.lone_triangles[static_cast<std::size_t>(k)])];
      const auto& vs = t.vertices;
      triangle_membrane(model, terms, damping_scale, t, x.segment<3>(3 * vs[0]),
                        x.segment<3>(3 * vs[1]), x.segment<3>(3 * vs[2]), vs.data(), v, jacobian,
                        out);
    };
    const int lone = static_cast<int>(model.diamonds.empty() ? model.triangles.size()
                                                             : model.lone_triangles.size());
    add_elements<9, 3>(lone, n, element, contribute, force, local_energy, jacobian);
    if (!model.diamonds.empty())
      add_diamonds(model, terms, damping_scale, x, v, force, local_energy, jacobian);
  }
  if (terms.bend && fabric.bend > 0.0 && model.bend_model == BendModel::quadratic) {
    const double beta = damping_scale * fabric.bend_damping;
    add_vertex_bends(model, fabric.bend, beta, x, v, force, local_energy.bend, jacobian);
  }
  if (terms.bend && fabric.bend > 0.0 && model.bend_model == BendModel::hinges) {
    const auto element = [&](int k) {
      const HingeElement& h = model.hinges[static_cast<std::size_t>(k)];
      return std::make_pair(h.vertices.data(), h.blocks.data());
    };
    const auto contribute = [&](int k, ElementContribution<12, 1>& out) {
      const HingeElement& h = model.hinges[static_cast<std::size_t>(k)];
      const auto& vs = h.vertices;
      // The bend Hessian is only needed for the exact Jacobian: the solve uses −k·∇θ∇θᵀ.
      const Condition<12> c =
          dihedral_angle_condition(x.segment<3>(3 * vs[0]), x.segment<3>(3 * vs[1]),
                                   x.segment<3>(3 * vs[2]), x.segment<3>(3 * vs[3]), exact);
      const double k_b = fabric.bend * h.weight;
      condition_contribution(c, quadratic_energy(c.value, h.rest_angle, k_b),
                             damping_scale * fabric.bend_damping * k_b, false, vs.data(), v,
                             jacobian, out.next(&EnergyBreakdown::bend));
    };
    add_elements<12, 1>(static_cast<int>(model.hinges.size()), n, element, contribute, force,
                        local_energy, jacobian);
  }
  if (terms.bend && fabric.bend > 0.0 && model.bend_model == BendModel::hinges &&
      model.bend_stencil_stiffness > 0.0) {
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
            product += b.coupling(j, l) * jacobian->product_input->segment<3>(
                                              3 * b.vertices[static_cast<std::size_t>(l)]);
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

Eigen::Vector2d principal_stretches(const TriangleElement& t, const Eigen::VectorXd& x) {
  Eigen::Matrix<double, 3, 2> f = Eigen::Matrix<double, 3, 2>::Zero();
  for (int k = 0; k < 3; ++k) {
    f.col(0) += t.du[k] * x.segment<3>(3 * t.vertices[k]);
    f.col(1) += t.dv[k] * x.segment<3>(3 * t.vertices[k]);
  }
  return Eigen::JacobiSVD<Eigen::Matrix<double, 3, 2>>(f).singularValues();
}

PrincipalStrain max_principal_strain(const ClothModel& model, const Eigen::VectorXd& x) {
  PrincipalStrain strain;
  for (const TriangleElement& t : model.triangles) {
    const Eigen::Vector2d sigma = principal_stretches(t, x);
    strain.stretch = std::max(strain.stretch, sigma(0) - 1.0);
    strain.compression = std::max(strain.compression, 1.0 - sigma(1));
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
