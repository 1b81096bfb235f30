// Global forces and Jacobians against central finite differences over random configurations:
// f = −∂E/∂x for the conservative terms, ∂f/∂x and ∂f/∂v exactly as evaluate_forces claims.
// GCC 12 reports a false "may be used uninitialized" inside Eigen's eigensolver products.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

#include "sim/forces.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <random>
#include <string>

#include "test_scenes.hpp"
#include "tests/sim/force_differences.hpp"

namespace sd::sim {
namespace {

struct Term {
  std::string name;
  ForceTerms terms;
};

std::vector<Term> single_terms() {
  const ForceTerms none{false, false, false, false, false, false};
  std::vector<Term> out;
  ForceTerms t = none;
  t.stretch = true;
  out.push_back({"stretch", t});
  t = none;
  t.shear = true;
  out.push_back({"shear", t});
  t = none;
  t.bend = true;
  out.push_back({"bend", t});
  t = none;
  t.stretch = t.damping = true;
  out.push_back({"stretch+damping", t});
  t = none;
  t.shear = t.damping = true;
  out.push_back({"shear+damping", t});
  t = none;
  t.bend = t.damping = true;
  out.push_back({"bend+damping", t});
  t = none;
  t.gravity = t.drag = true;
  out.push_back({"gravity+drag", t});
  return out;
}

struct Fixture {
  SheetScene scene;
  ClothModel model;
};

Fixture make_fixture() {
  SheetSpec spec;
  spec.size = {0.3, 0.2};
  spec.columns = 3;
  spec.rows = 2;
  Fixture f{build_sheet(spec), {}};
  FabricParameters fabric;
  fabric.stretch_warp = 800.0;
  fabric.stretch_weft = 500.0;
  fabric.shear = 60.0;
  fabric.bend = 2e-3;  // comparable to the membrane terms so that no term hides another
  fabric.damping = 0.01;
  fabric.bend_damping = 0.05;
  ClothModelOptions options;
  options.bend_rest = BendRestShape::designed;
  f.model = build_cloth_model(f.scene.input, fabric, options);
  return f;
}

// At rest velocity, the membrane force is −∇(E_stretch + E_shear) (central differences of the
// energy, h = 1e-7 m) and the exact Jacobian matches central differences of the force, both to
// 1e-5 relative.
void expect_membrane_derivatives(const ClothModel& model, const ForceSettings& settings,
                                 const Eigen::VectorXd& x, int trial) {
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(x.size());
  const testing::ForceDifferences d = testing::force_differences(model, settings, x, v);
  Eigen::VectorXd force, scratch, gradient(x.size());
  evaluate_forces(model, settings, x, v, force);
  const double h = 1e-7;
  for (Eigen::Index j = 0; j < x.size(); ++j) {
    Eigen::VectorXd plus = x, minus = x;
    plus[j] += h;
    minus[j] -= h;
    EnergyBreakdown ep, em;
    evaluate_forces(model, settings, plus, v, scratch, &ep);
    evaluate_forces(model, settings, minus, v, scratch, &em);
    gradient[j] = (ep.stretch + ep.shear - em.stretch - em.shear) / (2 * h);
  }
  EXPECT_LE((gradient + force).norm(), 1e-5 * force.norm()) << "trial " << trial;
  const Eigen::MatrixXd dfdx =
      testing::dense_jacobian(model, settings, x, v, 1, 0, JacobianKind::exact);
  EXPECT_LE((d.dfdx - dfdx).norm(), 1e-5 * dfdx.norm()) << "trial " << trial;
}

TEST(Forces, ForceIsMinusTheEnergyGradient) {
  const Fixture f = make_fixture();
  std::mt19937 rng(3);
  for (const Term& term : single_terms()) {
    if (term.terms.damping || term.terms.drag) continue;  // not conservative
    ForceSettings settings;
    settings.terms = term.terms;
    for (int trial = 0; trial < 10; ++trial) {
      const Eigen::VectorXd x = testing::random_configuration(f.scene.input.rest_positions, rng);
      const Eigen::VectorXd v = Eigen::VectorXd::Zero(x.size());
      Eigen::VectorXd force, scratch;
      evaluate_forces(f.model, settings, x, v, force);
      Eigen::VectorXd fd(x.size());
      const double h = 1e-6;
      for (Eigen::Index j = 0; j < x.size(); ++j) {
        Eigen::VectorXd plus = x, minus = x;
        plus[j] += h;
        minus[j] -= h;
        EnergyBreakdown ep, em;
        evaluate_forces(f.model, settings, plus, v, scratch, &ep);
        evaluate_forces(f.model, settings, minus, v, scratch, &em);
        fd[j] = -((ep.elastic() + ep.potential) - (em.elastic() + em.potential)) / (2 * h);
      }
      EXPECT_LE((fd - force).norm(), 1e-5 * force.norm()) << term.name << " trial " << trial;
    }
  }
}

TEST(Forces, ExactJacobiansMatchFiniteDifferences) {
  const Fixture f = make_fixture();
  std::mt19937 rng(5);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (const Term& term : single_terms()) {
    ForceSettings settings;
    settings.terms = term.terms;
    settings.air_drag = 0.5;
    settings.wind = Eigen::Vector3d(1.0, 0.0, 2.0);
    for (int trial = 0; trial < 10; ++trial) {
      const Eigen::VectorXd x = testing::random_configuration(f.scene.input.rest_positions, rng);
      Eigen::VectorXd v(x.size());
      for (Eigen::Index j = 0; j < v.size(); ++j) v[j] = normal(rng);
      const Eigen::MatrixXd dfdx =
          testing::dense_jacobian(f.model, settings, x, v, 1, 0, JacobianKind::exact);
      const Eigen::MatrixXd dfdv =
          testing::dense_jacobian(f.model, settings, x, v, 0, 1, JacobianKind::exact);
      Eigen::MatrixXd fd_x(x.size(), x.size()), fd_v(x.size(), x.size());
      const double h = 1e-6;
      Eigen::VectorXd fp, fm;
      for (Eigen::Index j = 0; j < x.size(); ++j) {
        Eigen::VectorXd plus = x, minus = x;
        plus[j] += h;
        minus[j] -= h;
        evaluate_forces(f.model, settings, plus, v, fp);
        evaluate_forces(f.model, settings, minus, v, fm);
        fd_x.col(j) = (fp - fm) / (2 * h);
        plus = v;
        minus = v;
        plus[j] += h;
        minus[j] -= h;
        evaluate_forces(f.model, settings, x, plus, fp);
        evaluate_forces(f.model, settings, x, minus, fm);
        fd_v.col(j) = (fp - fm) / (2 * h);
      }
      // Relative error in the Frobenius norm of the whole Jacobian.
      const double floor = 1e-12;
      EXPECT_LE((fd_x - dfdx).norm(), 1e-5 * std::max(dfdx.norm(), floor))
          << term.name << " ∂f/∂x trial " << trial;
      EXPECT_LE((fd_v - dfdv).norm(), 1e-5 * std::max(dfdv.norm(), floor))
          << term.name << " ∂f/∂v trial " << trial;
      if (term.terms.damping || term.terms.drag) {
        EXPECT_GT(dfdv.norm(), 0.0) << term.name;
      }
    }
  }
}

TEST(Forces, SolveJacobianIsSymmetricNegativeSemidefinite) {
  const Fixture f = make_fixture();
  std::mt19937 rng(9);
  ForceSettings settings;
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::VectorXd x = testing::random_configuration(f.scene.input.rest_positions, rng, 0.1);
    const Eigen::VectorXd v = Eigen::VectorXd::Random(x.size());
    for (double xs : {1.0, 0.0}) {
      const Eigen::MatrixXd j =
          testing::dense_jacobian(f.model, settings, x, v, xs, 1.0 - xs, JacobianKind::solve);
      EXPECT_LE((j - j.transpose()).norm(), 1e-12 * j.norm());
      const Eigen::VectorXd eigenvalues =
          Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(j).eigenvalues();
      EXPECT_LE(eigenvalues.maxCoeff(), 1e-9 * j.norm()) << "trial " << trial;
    }
  }
}

TEST(Forces, JacobianProductEqualsMatrixProduct) {
  const Fixture f = make_fixture();
  std::mt19937 rng(13);
  ForceSettings settings;
  const Eigen::VectorXd x = testing::random_configuration(f.scene.input.rest_positions, rng);
  const Eigen::VectorXd v = Eigen::VectorXd::Random(x.size());
  const Eigen::VectorXd u = Eigen::VectorXd::Random(x.size());
  for (JacobianKind kind : {JacobianKind::exact, JacobianKind::solve}) {
    const Eigen::MatrixXd dfdx = testing::dense_jacobian(f.model, settings, x, v, 1, 0, kind);
    JacobianTarget target;
    target.kind = kind;
    Eigen::VectorXd product = Eigen::VectorXd::Zero(x.size()), force;
    target.product_input = &u;
    target.product_output = &product;
    evaluate_forces(f.model, settings, x, v, force, nullptr, &target);
    EXPECT_LE((product - dfdx * u).norm(), 1e-12 * (dfdx * u).norm());
  }
}

// The solve keeps the stretch curvature −φ'·∇²C only while stretched (its Hessians are computed
// after the energies, where needed). On the flat sheet scaled uniformly by 1.1 every triangle is
// stretched, the shear is zero (w_u ⟂ w_v) and the bend is at rest, so at zero velocity the solve
// Jacobian is the exact one; scaled by 0.9 the stretch curvature is dropped and they differ.
TEST(Forces, SolveJacobianKeepsTheStretchCurvatureOnlyWhileStretched) {
  const Fixture f = make_fixture();
  ForceSettings settings;
  const Eigen::VectorXd rest = flatten_positions(f.scene.input.rest_positions);
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(rest.size());
  for (double scale : {1.1, 0.9}) {
    const Eigen::VectorXd x = scale * rest;
    const Eigen::MatrixXd exact =
        testing::dense_jacobian(f.model, settings, x, v, 1, 0, JacobianKind::exact);
    const Eigen::MatrixXd solve =
        testing::dense_jacobian(f.model, settings, x, v, 1, 0, JacobianKind::solve);
    if (scale > 1.0) {
      EXPECT_LE((solve - exact).norm(), 1e-12 * exact.norm());
    } else {
      EXPECT_GT((solve - exact).norm(), 1e-3 * exact.norm());
    }
  }
}

// The calibrated hinge weights and the bend stencils (ClothModelOptions): force against the
// energy's gradient, exact ∂f/∂x and ∂f/∂v against finite differences, and the solve Jacobian
// symmetric and negative semi-definite, on a sheet with degree-8 vertices (stencils).
TEST(Forces, BendStencilsMatchFiniteDifferences) {
  SheetSpec spec;
  spec.size = {0.3, 0.3};
  spec.columns = 4;
  spec.rows = 4;
  const SheetScene scene = build_sheet(spec);
  FabricParameters fabric;
  fabric.bend = 2e-3;
  fabric.bend_damping = 0.05;
  ClothModelOptions options;
  options.bend_model = BendModel::hinges;
  options.bend_weights = BendWeights::calibrated;
  options.bend_stencil_stiffness = 50.0;
  const ClothModel model = build_cloth_model(scene.input, fabric, options);
  ASSERT_EQ(model.stencils.size(), 4u);  // the interior degree-8 vertices of the 4-8 sheet
  std::mt19937 rng(17);
  ForceSettings settings;
  settings.terms = {false, false, true, true, false, false};
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::VectorXd x = testing::random_configuration(scene.input.rest_positions, rng);
    const Eigen::VectorXd v = Eigen::VectorXd::Random(x.size());
    const Eigen::MatrixXd dfdx =
        testing::dense_jacobian(model, settings, x, v, 1, 0, JacobianKind::exact);
    const Eigen::MatrixXd dfdv =
        testing::dense_jacobian(model, settings, x, v, 0, 1, JacobianKind::exact);
    const testing::ForceDifferences d = testing::force_differences(model, settings, x, v);
    const Eigen::MatrixXd& fd_x = d.dfdx;
    const Eigen::MatrixXd& fd_v = d.dfdv;
    const Eigen::VectorXd& grad = d.bend_gradient;
    const Eigen::VectorXd& force = d.conservative_force;
    EXPECT_LE((force + grad).norm(), 1e-5 * force.norm()) << "trial " << trial;
    EXPECT_LE((fd_x - dfdx).norm(), 1e-5 * dfdx.norm()) << "trial " << trial;
    EXPECT_LE((fd_v - dfdv).norm(), 1e-5 * dfdv.norm()) << "trial " << trial;
    const Eigen::MatrixXd j =
        testing::dense_jacobian(model, settings, x, v, 1, 0, JacobianKind::solve);
    EXPECT_LE((j - j.transpose()).norm(), 1e-12 * j.norm());
    EXPECT_LE(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(j).eigenvalues().maxCoeff(),
              1e-9 * j.norm());
  }
}

TEST(Forces, BendingEnergyIsResolutionInvariantOnACylinder) {
  // Rolling a sheet onto a cylinder (axis along a grid direction) costs ½·B/R² per unit area in
  // the continuum. Each interior edge along the axis carries ½·B·θ²·|e|²/(A1+A2) = ½·B/R²·ΔxΔy
  // whatever the resolution; only the outermost half-columns have no hinge, which leaves the
  // factor (n−1)/n for n columns (BendModel::hinges). The quadratic model's vertex elements cover
  // the whole sheet, free edges included: the continuum energy up to the chord-versus-arc
  // difference O((h/R)²). No other resolution dependence is allowed.
  for (const BendModel bend_model : {BendModel::hinges, BendModel::quadratic}) {
    const double radius = 0.5;
    const double bend = 1e-4;
    const double continuum = 0.5 * bend / (radius * radius) * 0.25;
    for (int n : {4, 8, 16, 32}) {
      SheetSpec spec;
      spec.size = {0.5, 0.5};
      spec.columns = n;
      spec.rows = n;
      SheetScene scene = build_sheet(spec);
      FabricParameters fabric;
      fabric.bend = bend;
      ClothModelOptions options;
      options.bend_model = bend_model;
      const ClothModel model = build_cloth_model(scene.input, fabric, options);
      Eigen::VectorXd x = flatten_positions(scene.input.rest_positions);
      for (int i = 0; i < model.vertex_count; ++i) {
        const double s = x[3 * i];
        x[3 * i] = radius * std::sin(s / radius);
        x[3 * i + 2] = radius * (1 - std::cos(s / radius));
      }
      ForceSettings settings;
      settings.terms.gravity = false;
      Eigen::VectorXd force;
      EnergyBreakdown energy;
      evaluate_forces(model, settings, x, Eigen::VectorXd::Zero(x.size()), force, &energy);
      if (bend_model == BendModel::hinges)
        EXPECT_NEAR(energy.bend / continuum, (n - 1.0) / n, 1e-9) << n << " columns";
      else
        EXPECT_NEAR(energy.bend / continuum, 1.0, 0.25 * (0.5 / n) * (0.5 / n) / (radius * radius))
            << n << " columns";
    }
  }
}

// The fixture's sheet scaled by sx across and sy down from its top (y = 1 m), each coordinate
// then moved by a draw of `noise`: a configuration with every triangle near a chosen strain.
Eigen::VectorXd scaled_noisy_positions(const Fixture& f, double sx, double sy,
                                       std::uniform_real_distribution<double>& noise,
                                       std::mt19937& rng) {
  Eigen::VectorXd x = flatten_positions(f.scene.input.rest_positions);
  for (Eigen::Index i = 0; i < x.size(); i += 3) {
    x(i) *= sx;
    x(i + 1) = 1.0 + (x(i + 1) - 1.0) * sy;
    for (int k = 0; k < 3; ++k) x(i + k) += noise(rng);
  }
  return x;
}

// w_u = ∂x/∂u of triangle t at positions x: its warp direction, of length 1 + warp strain.
Eigen::Vector3d warp_vector(const TriangleElement& t, const Eigen::VectorXd& x) {
  Eigen::Vector3d wu = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) wu += t.du(k) * x.segment<3>(3 * t.vertices[k]);
  return wu;
}

// Compression::buckling (Choi & Ko's post-buckling cap) against finite differences: the force is
// −∂E/∂x and the exact Jacobian ∂f/∂x, on random configurations squeezed by up to 5 % or
// stretched by up to 2 %, so that triangles lie on every branch (ε* = π²B/(l²K) = 2.5e-3 along
// the warp and 3.9e-3 along the weft here).
TEST(Forces, BucklingCompressionMatchesFiniteDifferences) {
  Fixture f = make_fixture();
  ClothModelOptions options;
  options.compression = Compression::buckling;
  f.model = build_cloth_model(f.scene.input, f.model.fabric, options);
  ForceSettings settings;
  settings.terms = ForceTerms{true, false, false, false, false, false};  // stretch only
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> squeeze(0.95, 1.02), noise(-2e-3, 2e-3);
  int buckled = 0, stretched = 0;
  for (int trial = 0; trial < 10; ++trial) {
    const double sx = squeeze(rng), sy = squeeze(rng);  // in this order: the draws are the seed's
    const Eigen::VectorXd x = scaled_noisy_positions(f, sx, sy, noise, rng);
    for (const TriangleElement& t : f.model.triangles) {
      const Eigen::Vector3d wu = warp_vector(t, x);
      const double eps = std::numbers::pi * std::numbers::pi * f.model.fabric.bend /
                         (t.width_u * t.width_u * f.model.fabric.stretch_warp);
      buckled += wu.norm() - 1.0 < -eps;
      stretched += wu.norm() > 1.0;
    }
    expect_membrane_derivatives(f.model, settings, x, trial);
  }
  EXPECT_GT(buckled, 10);  // both branches were exercised
  EXPECT_GT(stretched, 10);
}

// With measured tensile curves on warp and weft (three segments, strains spread across all of
// them and into compression), the force is −∇E and the exact Jacobian matches central
// differences, as for the linear and buckling models.
TEST(Forces, TensileCurveMatchesFiniteDifferences) {
  Fixture f = make_fixture();
  FabricParameters fabric = f.model.fabric;
  fabric.tensile_warp.strain = {0.0, 0.005, 0.015};
  fabric.tensile_warp.stress = {0.0, 2.0, 60.0};  // N/m: 400, then 5800 N/m
  fabric.tensile_weft.strain = {0.0, 0.01, 0.02};
  fabric.tensile_weft.stress = {0.0, 5.0, 30.0};
  f.model = build_cloth_model(f.scene.input, fabric);
  ForceSettings settings;
  settings.terms = ForceTerms{true, false, false, false, false, false};  // stretch only
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> stretch(0.99, 1.03), noise(-2e-3, 2e-3);
  int on_segment[3] = {0, 0, 0};
  for (int trial = 0; trial < 10; ++trial) {
    const double sx = stretch(rng), sy = stretch(rng);  // in this order: the draws are the seed's
    const Eigen::VectorXd x = scaled_noisy_positions(f, sx, sy, noise, rng);
    for (const TriangleElement& t : f.model.triangles) {
      const Eigen::Vector3d wu = warp_vector(t, x);
      const double e = wu.norm() - 1.0;
      ++on_segment[e <= 0.0 ? 0 : (e < 0.005 ? 1 : 2)];
    }
    expect_membrane_derivatives(f.model, settings, x, trial);
  }
  for (int segment = 0; segment < 3; ++segment)
    EXPECT_GT(on_segment[segment], 10) << "compression, first or later segment: " << segment;
}

// Tension is exactly the linear model's; a uniform compression s along the warp costs the
// post-buckling energy A·K·ε*·(s − ε*/2) per triangle (force per width N* = K·ε* = π²B/l²),
// against ½·A·K·s² for the linear model.
TEST(Forces, BucklingKeepsTensionExactAndCapsCompressionAtTheEulerLoad) {
  Fixture f = make_fixture();
  const ClothModel linear = f.model;
  ClothModelOptions options;
  options.compression = Compression::buckling;
  const ClothModel buckling = build_cloth_model(f.scene.input, f.model.fabric, options);
  ForceSettings settings;
  settings.terms = ForceTerms{true, false, false, false, false, false};
  const FabricParameters& fabric = linear.fabric;
  for (const double s : {0.01, 0.05, -0.01, -0.05}) {  // strain along the warp (the sheet's y)
    Eigen::VectorXd x = flatten_positions(f.scene.input.rest_positions);
    for (Eigen::Index i = 1; i < x.size(); i += 3) x(i) = 1.0 + (x(i) - 1.0) * (1.0 + s);
    const Eigen::VectorXd v = Eigen::VectorXd::Zero(x.size());
    Eigen::VectorXd f_linear, f_buckling;
    EnergyBreakdown e_linear, e_buckling;
    evaluate_forces(linear, settings, x, v, f_linear, &e_linear);
    evaluate_forces(buckling, settings, x, v, f_buckling, &e_buckling);
    if (s > 0) {
      EXPECT_EQ(f_linear, f_buckling) << s;
      EXPECT_EQ(e_linear.stretch, e_buckling.stretch) << s;
      continue;
    }
    double expected = 0.0, quadratic = 0.0;
    for (const TriangleElement& t : buckling.triangles) {
      const double n_star =
          std::numbers::pi * std::numbers::pi * fabric.bend / (t.width_u * t.width_u);
      const double eps = n_star / fabric.stretch_warp;
      ASSERT_LT(eps, -s);  // every triangle is past its buckling strain
      expected += t.rest_area * fabric.stretch_warp * eps * (-s - 0.5 * eps);
      quadratic += 0.5 * t.rest_area * fabric.stretch_warp * s * s;
    }
    EXPECT_NEAR(e_buckling.stretch, expected, 1e-12 * expected) << s;
    EXPECT_NEAR(e_linear.stretch, quadratic, 1e-9 * quadratic) << s;
    EXPECT_LT(e_buckling.stretch, e_linear.stretch) << s;
  }
}

// The fixture's sheet under the homogeneous in-plane map F of its rest (warp, weft) coordinates
// (F's columns: the deformed warp and weft, so (ε_u, ε_v, γ) = (|F₀| − 1, |F₁| − 1, F₀·F₁) in
// every triangle), each coordinate then moved by a draw of `noise` (none: exactly homogeneous).
Eigen::VectorXd mapped_positions(const Fixture& f, const Eigen::Matrix2d& map,
                                 std::uniform_real_distribution<double>* noise = nullptr,
                                 std::mt19937* rng = nullptr) {
  const Eigen::VectorXd rest = flatten_positions(f.scene.input.rest_positions);
  const TriangleElement& t = f.model.triangles[0];
  const Eigen::Vector3d warp = warp_vector(t, rest);
  Eigen::Vector3d weft = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) weft += t.dv(k) * rest.segment<3>(3 * t.vertices[k]);
  Eigen::VectorXd x = rest;
  for (Eigen::Index i = 0; i < x.size(); i += 3) {
    const Eigen::Vector3d p = rest.segment<3>(i);
    const Eigen::Vector2d uv(p.dot(warp), p.dot(weft));
    const Eigen::Vector2d mapped = map * uv;
    x.segment<3>(i) = p + (mapped(0) - uv(0)) * warp + (mapped(1) - uv(1)) * weft;
    if (noise != nullptr)
      for (int k = 0; k < 3; ++k) x(i + k) += (*noise)(*rng);
  }
  return x;
}

// F with warp and weft of length a = 1 − s/2, each turned by θ toward the other, a²·sin 2θ = s:
// exactly (ε_u, ε_v, γ) = (−s/2, −s/2, s), a squeeze s along the bias (u − v)/√2 (to first
// order the map I − s·nnᵀ) whose conditions move along that bias's direction, dc/ds = (−½, −½, 1).
Eigen::Matrix2d bias_squeeze(double s) {
  const double a = 1.0 - 0.5 * s;
  const double theta = 0.5 * std::asin(s / (a * a));
  Eigen::Matrix2d map;
  map.col(0) = a * Eigen::Vector2d(std::cos(theta), std::sin(theta));
  map.col(1) = a * Eigen::Vector2d(std::sin(theta), std::cos(theta));
  return map;
}

// Each triangle's compressed bias Euler load (docs/simulator.md, "Compression and buckling"),
// computed here from the rest positions: N*_b = max(π²B/l_b², ½(N*_u + N*_v)), l_b the rest
// triangle's extent along (u − s·v)/√2.
double bias_euler_load(const ClothModel& model, const TriangleElement& t,
                       const Eigen::VectorXd& rest, double s) {
  const Eigen::Vector3d warp = warp_vector(model.triangles[0], rest);
  Eigen::Vector3d weft = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k)
    weft += model.triangles[0].dv(k) * rest.segment<3>(3 * model.triangles[0].vertices[k]);
  const Eigen::Vector3d bias = (warp - s * weft) / std::numbers::sqrt2;
  double low = 1e300, high = -1e300;
  for (int k = 0; k < 3; ++k) {
    const double p = rest.segment<3>(3 * t.vertices[k]).dot(bias);
    low = std::min(low, p);
    high = std::max(high, p);
  }
  const double pi2b = std::numbers::pi * std::numbers::pi * model.fabric.bend;
  const double mean_yarn =
      0.5 * pi2b * (1.0 / (t.width_u * t.width_u) + 1.0 / (t.width_v * t.width_v));
  return std::max(pi2b / ((high - low) * (high - low)), mean_yarn);
}

ClothModel buckling_model(const Fixture& f) {
  ClothModelOptions options;
  options.compression = Compression::buckling;
  return build_cloth_model(f.scene.input, f.model.fabric, options);
}

// Bias wrinkling against finite differences: random squeezes along either bias (1-12 %) with
// yarn strains of ±1 % and position noise, so that triangles lie with and without a bias wrinkle
// (counted here from the criterion: the capped yarns leave the compressed bias's stress
// ½(σ_u + σ_v) − G|γ| below −N*_b), the force is −∇E and the exact Jacobian ∂f/∂x; the solve's
// Jacobian is symmetric, negative semi-definite and its product is the matrix's.
TEST(Forces, BiasWrinklingMatchesFiniteDifferences) {
  Fixture f = make_fixture();
  f.model = buckling_model(f);
  const FabricParameters& fabric = f.model.fabric;
  ForceSettings settings;
  settings.terms = ForceTerms{true, true, false, false, false, false};  // stretch and shear
  const Eigen::VectorXd rest = flatten_positions(f.scene.input.rest_positions);
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> squeeze(0.01, 0.12), yarn(-0.01, 0.01), noise(-1e-3, 1e-3);
  const double pi2b = std::numbers::pi * std::numbers::pi * fabric.bend;
  const auto capped = [](double strain, double stiffness, double load) {
    return std::max(stiffness * strain, -load);
  };
  int wrinkled = 0, plain = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const double s = squeeze(rng), su = yarn(rng), sv = yarn(rng);
    Eigen::Matrix2d map = bias_squeeze(s);
    map.col(0) *= 1.0 + su;
    map.col(1) *= 1.0 + sv;
    // Odd trials squeeze the other bias: F ↦ R·F·R with R = diag(1, −1) flips the sign of γ.
    const Eigen::Matrix2d flip = Eigen::Vector2d(1.0, trial % 2 == 1 ? -1.0 : 1.0).asDiagonal();
    const Eigen::VectorXd x = mapped_positions(f, flip * map * flip, &noise, &rng);
    for (const TriangleElement& t : f.model.triangles) {
      const Eigen::Vector3d wu = warp_vector(t, x);
      Eigen::Vector3d wv = Eigen::Vector3d::Zero();
      for (int k = 0; k < 3; ++k) wv += t.dv(k) * x.segment<3>(3 * t.vertices[k]);
      const double gamma = wu.dot(wv);
      const double n_u = pi2b / (t.width_u * t.width_u), n_v = pi2b / (t.width_v * t.width_v);
      const double bias = 0.5 * (capped(wu.norm() - 1.0, fabric.stretch_warp, n_u) +
                                 capped(wv.norm() - 1.0, fabric.stretch_weft, n_v)) -
                          fabric.shear * std::abs(gamma);
      const bool active = bias < -bias_euler_load(f.model, t, rest, gamma < 0.0 ? -1.0 : 1.0);
      wrinkled += active;
      plain += !active;
    }
    expect_membrane_derivatives(f.model, settings, x, trial);
    const Eigen::VectorXd v = Eigen::VectorXd::Zero(x.size());
    const Eigen::MatrixXd j =
        testing::dense_jacobian(f.model, settings, x, v, 1, 0, JacobianKind::solve);
    EXPECT_LE((j - j.transpose()).norm(), 1e-12 * j.norm()) << "trial " << trial;
    EXPECT_LE(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(j).eigenvalues().maxCoeff(),
              1e-9 * j.norm())
        << "trial " << trial;
    const Eigen::VectorXd u = Eigen::VectorXd::Random(x.size());
    JacobianTarget target;
    Eigen::VectorXd product = Eigen::VectorXd::Zero(x.size()), force;
    target.product_input = &u;
    target.product_output = &product;
    evaluate_forces(f.model, settings, x, v, force, nullptr, &target);
    EXPECT_LE((product - j * u).norm(), 1e-12 * (j * u).norm()) << "trial " << trial;
  }
  EXPECT_GT(wrinkled, 20);  // both kinds of triangles were exercised
  EXPECT_GT(plain, 20);
}

// Under a squeeze s along the bias, (ε_u, ε_v, γ) = (−s/2, −s/2, s) in every triangle, the
// membrane energy grows at dE/ds = Σ A·N*_b once every triangle has wrinkled along the bias: the
// compressive force per width along the bias is its Euler load, as N* is along a buckled yarn
// (for the linear membrane it is A·((K_u + K_v)/4 + G)·s, here 6-13 times more). Tension and
// shear under tension are the linear model's to the bit: a stretch along a bias (the other bias
// is then free of stress) and a 2 % pretension in both yarns with a shear G·γ below it. On
// cells ten times smaller the same squeeze is the linear membrane's (the caps converge).
TEST(Forces, BiasWrinklingCapsBiasCompressionAtItsEulerLoadAndKeepsTension) {
  Fixture f = make_fixture();
  const ClothModel linear = f.model;
  const ClothModel buckling = buckling_model(f);
  ForceSettings settings;
  settings.terms = ForceTerms{true, true, false, false, false, false};
  const Eigen::VectorXd rest = flatten_positions(f.scene.input.rest_positions);
  const auto membrane = [&](const ClothModel& model, const Eigen::VectorXd& x) {
    Eigen::VectorXd force;
    EnergyBreakdown e;
    evaluate_forces(model, settings, x, Eigen::VectorXd::Zero(x.size()), force, &e);
    return e.stretch + e.shear;
  };
  double euler = 0.0;
  for (const TriangleElement& t : buckling.triangles)
    euler += t.rest_area * bias_euler_load(buckling, t, rest, 1.0);
  const double h = 1e-6;
  for (const double s : {0.05, 0.1}) {
    const double slope = (membrane(buckling, mapped_positions(f, bias_squeeze(s + h))) -
                          membrane(buckling, mapped_positions(f, bias_squeeze(s - h)))) /
                         (2 * h);
    EXPECT_NEAR(slope, euler, 1e-6 * euler) << s;
    const double linear_slope = (membrane(linear, mapped_positions(f, bias_squeeze(s + h))) -
                                 membrane(linear, mapped_positions(f, bias_squeeze(s - h)))) /
                                (2 * h);
    EXPECT_GT(linear_slope, 4.0 * slope) << s;
  }
  // The caps converge to the linear membrane: on the same sheet in cells ten times smaller
  // (N* a hundred times larger, 197 N/m along the yarns) the squeeze s = 0.05 is below every
  // Euler load and the buckling membrane is the linear one to the bit.
  {
    SheetSpec spec;
    spec.size = {0.3, 0.2};
    spec.columns = 30;
    spec.rows = 20;
    Fixture fine{build_sheet(spec), {}};
    fine.model = build_cloth_model(fine.scene.input, linear.fabric);
    const ClothModel fine_buckling = buckling_model(fine);
    const Eigen::VectorXd x = mapped_positions(fine, bias_squeeze(0.05));
    EXPECT_EQ(membrane(fine.model, x), membrane(fine_buckling, x));
    EXPECT_LT(membrane(buckling, mapped_positions(f, bias_squeeze(0.05))),
              0.5 * membrane(linear, mapped_positions(f, bias_squeeze(0.05))));
  }
  // Pretension 2 % (½(σ_u + σ_v) = 13 N/m) and γ = 1.02²·sin 0.1 = 0.104 (G·γ = 6.2 N/m, which
  // without the pretension would wrinkle the bias: N*_b ≤ 3.95 N/m here).
  const double c = std::cos(0.05), sn = std::sin(0.05);
  Eigen::Matrix2d stretched_bias, pretension_and_shear;
  stretched_bias << 1.03, 0.03, 0.03, 1.03;  // 4.2 % along u + v
  pretension_and_shear << 1.02 * c, 1.02 * sn, 1.02 * sn, 1.02 * c;
  for (const Eigen::Matrix2d& map : {stretched_bias, pretension_and_shear}) {
    const Eigen::VectorXd x = mapped_positions(f, map);
    const Eigen::VectorXd v = Eigen::VectorXd::Zero(x.size());
    Eigen::VectorXd f_linear, f_buckling;
    EnergyBreakdown e_linear, e_buckling;
    evaluate_forces(linear, settings, x, v, f_linear, &e_linear);
    evaluate_forces(buckling, settings, x, v, f_buckling, &e_buckling);
    EXPECT_EQ(f_linear, f_buckling);
    EXPECT_EQ(e_linear.stretch + e_linear.shear, e_buckling.stretch + e_buckling.shear);
    EXPECT_GT(e_linear.shear, 0.0);
  }
}

// A simple shear by γ (the weft turned by γ towards the warp, F = [1 tan γ; 0 1] in (warp, weft)
// coordinates) keeps the warp's length and lengthens the weft by 1/cos γ only, while its
// principal stretches are the singular values of F, √(1 + k²/4) ± k/2 with k = tan γ: at
// γ = 11° (the flat arms-lowering tee's armpit, docs/collision.md) 1.102 and 0.908 against
// 1.9 % along the weft. Both for any rigid rotation of the sheet. Tolerance 1e-12: du, dv and
// the rest positions carry a few ulps of 1/m (cloth_model_test), the SVD a few of 1.
TEST(Forces, PrincipalStrainSeesTheShearThatWarpAndWeftStrainMisses) {
  const Fixture f = make_fixture();
  const double k = std::tan(11.0 * std::numbers::pi / 180.0);
  Eigen::Matrix2d shear;
  shear << 1.0, k, 0.0, 1.0;
  const Eigen::VectorXd sheared = mapped_positions(f, shear);
  Eigen::VectorXd turned = sheared;
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, 2.0, -0.5).normalized()).toRotationMatrix();
  for (Eigen::Index i = 0; i < turned.size(); i += 3)
    turned.segment<3>(i) = rotation * sheared.segment<3>(i) + Eigen::Vector3d(0.3, -1.0, 2.0);
  const double sigma1 = std::sqrt(1.0 + k * k / 4.0) + k / 2.0;
  const double sigma2 = std::sqrt(1.0 + k * k / 4.0) - k / 2.0;
  for (const Eigen::VectorXd& x : {sheared, turned}) {
    for (const TriangleElement& t : f.model.triangles) {
      const Eigen::Vector2d sigma = principal_stretches(t, x);
      EXPECT_NEAR(sigma(0), sigma1, 1e-12);
      EXPECT_NEAR(sigma(1), sigma2, 1e-12);
    }
    const PrincipalStrain principal = max_principal_strain(f.model, x);
    EXPECT_NEAR(principal.stretch, sigma1 - 1.0, 1e-12);      // 10.2 %
    EXPECT_NEAR(principal.compression, 1.0 - sigma2, 1e-12);  // 9.2 %
    EXPECT_NEAR(max_stretch_strain(f.model, x),
                1.0 / std::cos(11.0 * std::numbers::pi / 180.0) - 1.0,
                1e-12);  // 1.9 %
  }
  // Unstrained (at rest and moved rigidly): both zero; stretched 5 % along the warp: the same
  // 5 % in both measures, and no compression.
  const PrincipalStrain rest =
      max_principal_strain(f.model, flatten_positions(f.scene.input.rest_positions));
  EXPECT_NEAR(rest.stretch, 0.0, 1e-12);
  EXPECT_NEAR(rest.compression, 0.0, 1e-12);
  const Eigen::VectorXd pulled = mapped_positions(f, Eigen::Vector2d(1.05, 1.0).asDiagonal());
  EXPECT_NEAR(max_principal_strain(f.model, pulled).stretch, 0.05, 1e-12);
  EXPECT_NEAR(max_principal_strain(f.model, pulled).compression, 0.0, 1e-12);
  EXPECT_NEAR(max_stretch_strain(f.model, pulled), 0.05, 1e-12);
}

}  // namespace
}  // namespace sd::sim
