// The forces a step adds to the cloth's own (StepForces): a point spring is linear in x and v,
// so one linearised solve must give backward Euler's answer exactly, from any linearisation
// point, with either linear solver.

#include "sim/implicit_solver.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "sim/constraint_filter.hpp"
#include "tests/sim/test_scenes.hpp"

namespace sd::sim {
namespace {

using Eigen::Vector3d;

// Two separate triangles 3 mm apart, one above the other (a cloth's two layers in self-contact).
ClothInput two_facing_triangles() {
  ClothInput input;
  input.rest_positions.resize(6, 3);
  input.rest_positions << 0.0, 0.0, 0.0, 0.0, 0.0, 0.1, 0.1, 0.0, 0.0,  // lower
      0.0, 0.003, 0.0, 0.0, 0.003, 0.1, 0.1, 0.003, 0.0;                // upper
  input.triangles.resize(2, 3);
  input.triangles << 0, 1, 2, 3, 4, 5;
  return input;
}

// One quad (two equal triangles) at rest, gravity and air drag off, a spring through each
// triangle's centroid along its normal. Each triangle contributes a third of its mass to each
// of its corners and the spring a third of its force, so the quad translates rigidly (no
// stretch, shear or bending forces) along n and, per triangle of mass m,
//     m (v1 − v0) = β (F0 + k (target − p0 − β v1) − c (v1 − v_ref)),
//     v1 = (m v0 + β (F0 + k (target − p0) + c v_ref)) / (m + β² k + β c).
TEST(ImplicitSolver, PointSpringStepIsBackwardEulerExactly) {
  const testing::SheetSetup s = testing::horizontal_sheet(1, 0.1, Vector3d::Zero());
  const ClothModel& model = s.model;
  ASSERT_EQ(model.triangles.size(), 2u);
  const double m = model.total_mass() / 2.0;
  ASSERT_NEAR(model.triangles[0].rest_area, model.triangles[1].rest_area, 1e-15);

  ForceSettings forces;
  forces.gravity = Vector3d::Zero();
  forces.air_drag = 0.0;
  const Vector3d n = Vector3d::UnitY();
  const Eigen::VectorXd x0 = flatten_positions(s.scene.input.rest_positions);
  const int vertices = model.vertex_count;
  Eigen::VectorXd v0 = Eigen::VectorXd::Zero(3 * vertices);
  const double v0_normal = -0.3;  // falling onto the spring's target
  for (int i = 0; i < vertices; ++i) v0.segment<3>(3 * i) = v0_normal * n;

  StepForces extra;
  const double p0 = x0.segment<3>(0).dot(n);  // the flat quad's height
  for (int t = 0; t < 2; ++t) {
    PointSpring spring;
    spring.triangle = t;
    spring.weights = Vector3d::Constant(1.0 / 3.0);
    spring.normal = n;
    spring.target = p0 + 0.004;
    spring.preload = 0.02;
    spring.stiffness = 40.0;
    spring.damping = 0.5;
    spring.reference_velocity = 0.1 * n;
    extra.springs.push_back(spring);
  }
  const PointSpring& spring = extra.springs[0];
  const double beta = 1.0 / 60.0;
  const double expected =
      (m * v0_normal + beta * (spring.preload + spring.stiffness * (spring.target - p0) +
                               spring.damping * spring.reference_velocity.dot(n))) /
      (m + beta * beta * spring.stiffness + beta * spring.damping);

  const ConstraintFilter filter(vertices);
  // Linearised at the start (u = 0), and away from it (u ≠ 0: the product term).
  const Eigen::VectorXd shifted = x0 + Eigen::VectorXd::Constant(3 * vertices, 0.01);
  for (const LinearSolverKind kind : {LinearSolverKind::cholmod, LinearSolverKind::pcg})
    for (const Eigen::VectorXd* x_lin : {&x0, &shifted}) {
      NewtonSettings settings;
      settings.solver = kind;
      settings.pcg_tolerance = 1e-12;
      ImplicitSolver solver;
      const ImplicitSolveResult r =
          solver.solve(model, forces, filter, x0, v0, beta, *x_lin, v0, settings, &extra);
      ASSERT_TRUE(r.linear_converged);
      for (int i = 0; i < vertices; ++i) {
        EXPECT_NEAR(r.v.segment<3>(3 * i).dot(n), expected, 1e-9 * std::abs(expected));
        EXPECT_NEAR((r.v.segment<3>(3 * i) - r.v.segment<3>(3 * i).dot(n) * n).norm(), 0.0, 1e-10);
      }
    }
}

// Two separate equal triangles 3 mm apart, one above the other, joined by three pair springs
// (each corner of the upper one against the lower one's centroid). The springs join vertices
// that are not neighbours in the mesh, so the exact step needs the blocks across the pairs in
// the matrix; with only each side's own blocks (the first version) the answer differed. By
// symmetry each triangle translates along the normal, and the relative normal speed of the
// exact backward Euler step solves, with the same mass m at every vertex,
//   ṡ1 (1 + 2β(βk + c)/m) = ṡ0 + 2βk (target − s0)/m.
TEST(ImplicitSolver, PairSpringsAcrossTheMeshAreImplicitExactly) {
  const ClothInput input = two_facing_triangles();
  const ClothModel model = build_cloth_model(input, fabric_preset("cotton"));
  const double m = model.mass[0];
  for (int i = 1; i < 6; ++i) ASSERT_NEAR(model.mass[i], m, 1e-15);
  ASSERT_LT(block_offset(model.pattern.zero_matrix, 3, 0), 0);  // premise: not neighbours

  ForceSettings forces;
  forces.gravity = Vector3d::Zero();
  forces.air_drag = 0.0;
  const Vector3d n = Vector3d::UnitY();
  const Eigen::VectorXd x0 = flatten_positions(input.rest_positions);
  Eigen::VectorXd v0 = Eigen::VectorXd::Zero(18);
  for (int i = 3; i < 6; ++i) v0.segment<3>(3 * i) = -0.4 * n;  // the upper one falling
  const double s0 = 0.003, sdot0 = -0.4;
  StepForces extra;
  for (int corner = 3; corner < 6; ++corner) {
    PairSpring spring;
    spring.vertices = {corner, 0, 1, 2};
    spring.weights << 1.0, -1.0 / 3.0, -1.0 / 3.0, -1.0 / 3.0;
    spring.normal = n;
    spring.target = 0.005;
    spring.stiffness = 30.0;
    spring.damping = 0.4;
    extra.pair_springs.push_back(spring);
  }
  const PairSpring& spring = extra.pair_springs[0];
  const double beta = 1.0 / 60.0;
  // With these weights every spring's separation is n·(corner − lower centroid) = s0.
  const double expected = (sdot0 + 2.0 * beta * spring.stiffness * (spring.target - s0) / m) /
                          (1.0 + 2.0 * beta * (beta * spring.stiffness + spring.damping) / m);

  const ConstraintFilter filter(6);
  for (const LinearSolverKind kind : {LinearSolverKind::cholmod, LinearSolverKind::pcg}) {
    NewtonSettings settings;
    settings.solver = kind;
    settings.pcg_tolerance = 1e-12;
    ImplicitSolver solver;
    const ImplicitSolveResult r =
        solver.solve(model, forces, filter, x0, v0, beta, x0, v0, settings, &extra);
    ASSERT_TRUE(r.linear_converged);
    EXPECT_GT(solver.matrix().nonZeros(), model.pattern.zero_matrix.nonZeros());
    const double upper = r.v.segment<3>(9).dot(n), lower = r.v.segment<3>(0).dot(n);
    EXPECT_NEAR(upper - lower, expected, 1e-9 * std::abs(expected));
    // Momentum: the springs are internal.
    Vector3d momentum = Vector3d::Zero();
    for (int i = 0; i < 6; ++i) momentum += m * r.v.segment<3>(3 * i);
    EXPECT_NEAR((momentum - 3.0 * m * sdot0 * n).norm(), 0.0, 1e-12);
  }
}

// The friction between layers is a tangential dashpot on the pair's relative velocity. Its
// blocks, and the spring's, must be the force's derivatives: −β ∂f/∂v − β² ∂f/∂x by central
// differences of pair_spring_force (the force the solver adds) equals pair_block for every
// corner pair; and the solver's matrix with the spring minus the one without is exactly those
// blocks, across the pair (outside the mesh's pattern) too.
TEST(ImplicitSolver, PairFrictionBlocksAreTheForceDerivatives) {
  PairSpring spring;
  spring.vertices = {3, 0, 1, 2};
  spring.weights << 1.0, -0.2, -0.5, -0.3;
  spring.normal = Vector3d(0.2, 1.0, -0.3).normalized();
  spring.target = 0.004;
  spring.stiffness = 30.0;
  spring.damping = 0.4;
  spring.friction = 2.5;
  const double beta = 1.0 / 60.0;
  Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(18, -0.1, 0.2);
  Eigen::VectorXd v = Eigen::VectorXd::LinSpaced(18, 0.3, -0.2);
  const double step = 1e-6;
  for (int k = 0; k < 4; ++k)
    for (int l = 0; l < 4; ++l) {
      Eigen::Matrix3d numeric;
      for (int b = 0; b < 3; ++b) {
        const int column = 3 * spring.vertices[l] + b;
        Eigen::VectorXd xp = x, xm = x, vp = v, vm = v;
        xp[column] += step;
        xm[column] -= step;
        vp[column] += step;
        vm[column] -= step;
        const Vector3d dfdx =
            spring.weights[k] *
            (pair_spring_force(spring, xp, v) - pair_spring_force(spring, xm, v)) / (2.0 * step);
        const Vector3d dfdv =
            spring.weights[k] *
            (pair_spring_force(spring, x, vp) - pair_spring_force(spring, x, vm)) / (2.0 * step);
        numeric.col(b) = -beta * dfdv - beta * beta * dfdx;
      }
      EXPECT_LT((numeric - pair_block(spring, beta, k, l)).norm(),
                1e-8 * pair_block(spring, beta, k, l).norm() + 1e-12)
          << "block " << k << ", " << l;
    }

  // In the assembled matrix: the two triangles of PairSpringsAcrossTheMeshAreImplicitExactly.
  const ClothInput input = two_facing_triangles();
  const ClothModel model = build_cloth_model(input, fabric_preset("cotton"));
  ForceSettings forces;
  const Eigen::VectorXd x0 = flatten_positions(input.rest_positions);
  const Eigen::VectorXd v0 = Eigen::VectorXd::Zero(18);
  const ConstraintFilter filter(6);
  NewtonSettings settings;
  settings.solver = LinearSolverKind::cholmod;
  StepForces extra;
  extra.pair_springs.push_back(spring);
  ImplicitSolver with, without;
  with.solve(model, forces, filter, x0, v0, beta, x0, v0, settings, &extra);
  without.solve(model, forces, filter, x0, v0, beta, x0, v0, settings);
  const Eigen::MatrixXd difference =
      Eigen::MatrixXd(with.matrix()) - Eigen::MatrixXd(without.matrix());
  Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(18, 18);
  for (int k = 0; k < 4; ++k)
    for (int l = 0; l < 4; ++l)
      expected.block<3, 3>(3 * spring.vertices[k], 3 * spring.vertices[l]) +=
          pair_block(spring, beta, k, l);
  EXPECT_LT((difference - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff());
}

// A system CHOLMOD cannot factorise (not positive definite: a spring of negative stiffness
// strong enough to make m + β²k < 0 along the normal) must never yield a zero step taken for a
// solution (it did: the factorisation failed, the step was zero and, at the minimum step size,
// accepted). The solve falls back to PCG on the same system; PCG either solves it (then it is
// backward Euler's answer: the system is nonsingular) or the solve fails with the true cause.
TEST(ImplicitSolver, FailedCholmodFactorisationFallsBackToPcg) {
  const testing::SheetSetup s = testing::horizontal_sheet(1, 0.1, Vector3d::Zero());
  const ClothModel& model = s.model;
  const double m = model.total_mass() / 2.0;
  ForceSettings forces;
  forces.gravity = Vector3d::Zero();
  forces.air_drag = 0.0;
  const Vector3d n = Vector3d::UnitY();
  const Eigen::VectorXd x0 = flatten_positions(s.scene.input.rest_positions);
  const int vertices = model.vertex_count;
  const Eigen::VectorXd v0 = Eigen::VectorXd::Zero(3 * vertices);
  const double beta = 1.0 / 60.0;
  StepForces extra;
  const double p0 = x0.segment<3>(0).dot(n);
  for (int t = 0; t < 2; ++t) {
    PointSpring spring;
    spring.triangle = t;
    spring.weights = Vector3d::Constant(1.0 / 3.0);
    spring.normal = n;
    spring.target = p0 + 0.004;
    spring.stiffness = -4.0 * m / (beta * beta);  // m + β²k = −3m
    extra.springs.push_back(spring);
  }
  const PointSpring& spring = extra.springs[0];
  const double expected =
      beta * spring.stiffness * (spring.target - p0) / (m + beta * beta * spring.stiffness);
  NewtonSettings settings;
  settings.solver = LinearSolverKind::cholmod;
  settings.pcg_tolerance = 1e-12;
  ImplicitSolver solver;
  const ConstraintFilter filter(vertices);
  const ImplicitSolveResult r =
      solver.solve(model, forces, filter, x0, v0, beta, x0, v0, settings, &extra);
  EXPECT_GE(r.cholmod_failures, 1);
  if (!r.linear_failure.empty()) {
    EXPECT_FALSE(r.linear_converged);
    EXPECT_NE(r.linear_failure.find("not positive definite"), std::string::npos);
    return;
  }
  ASSERT_TRUE(r.linear_converged);
  for (int i = 0; i < vertices; ++i)
    EXPECT_NEAR(r.v.segment<3>(3 * i).dot(n), expected, 1e-8 * std::abs(expected));
}

// PCG with a preconditioner that is not positive definite (here the system's own negative
// definite block diagonal: r·M⁻¹r < 0 at the start) returned "converged" with the start as the
// answer. It must report no convergence.
TEST(ImplicitSolver, PcgNeverReportsTheStartAsASolutionOfAnIndefiniteSystem) {
  const testing::SheetSetup s = testing::horizontal_sheet(1, 0.1, Vector3d::Zero());
  const ClothModel& model = s.model;
  const double m = model.total_mass() / 2.0;
  ForceSettings forces;
  forces.gravity = Vector3d::Zero();
  forces.air_drag = 0.0;
  const Eigen::VectorXd x0 = flatten_positions(s.scene.input.rest_positions);
  const int vertices = model.vertex_count;
  const Eigen::VectorXd v0 = Eigen::VectorXd::Zero(3 * vertices);
  const double beta = 1.0 / 60.0;
  StepForces extra;
  for (int t = 0; t < 2; ++t) {
    PointSpring spring;
    spring.triangle = t;
    spring.weights = Vector3d::Constant(1.0 / 3.0);
    spring.normal = Vector3d::UnitY();
    spring.target = x0[1] + 0.004;
    spring.stiffness = -40.0 * m / (beta * beta);
    extra.springs.push_back(spring);
  }
  NewtonSettings settings;
  settings.solver = LinearSolverKind::pcg;
  settings.pcg_preconditioner = PcgPreconditioner::block_jacobi;
  ImplicitSolver solver;
  const ImplicitSolveResult r = solver.solve(model, forces, ConstraintFilter(vertices), x0, v0,
                                             beta, x0, v0, settings, &extra);
  EXPECT_FALSE(r.linear_converged && r.v.norm() == 0.0)
      << "a zero step was reported as the solution";
}

// Self-contact springs come and go from step to step. With CHOLMOD the solver keeps the blocks
// across the pairs that earlier steps had (as zeros), so that the widened pattern, and with it
// the symbolic analysis, stays: four steps with two, one, none and again two pair springs
// are analysed once. Zero blocks do not change the system, so each step's answer is the one a
// fresh solver (which widens by exactly that step's blocks) gives, to rounding. The PCG's
// preconditioner reads the pattern, so it gets exactly the step's blocks.
TEST(ImplicitSolver, CholmodKeepsThePairSpringPatternAcrossSteps) {
  const ClothInput input = two_facing_triangles();
  const ClothModel model = build_cloth_model(input, fabric_preset("cotton"));
  ForceSettings forces;
  const Eigen::VectorXd x0 = flatten_positions(input.rest_positions);
  Eigen::VectorXd v0 = Eigen::VectorXd::Zero(18);
  for (int i = 3; i < 6; ++i) v0.segment<3>(3 * i) = Vector3d(0.05, -0.4, 0.02);
  const ConstraintFilter filter(6);
  const auto springs = [](std::initializer_list<int> corners) {
    StepForces extra;
    for (int corner : corners) {
      PairSpring spring;
      spring.vertices = {corner, 0, 1, 2};
      spring.weights << 1.0, -0.2, -0.5, -0.3;
      spring.normal = Vector3d::UnitY();
      spring.target = 0.005;
      spring.stiffness = 30.0;
      spring.damping = 0.4;
      spring.friction = 1.5;
      extra.pair_springs.push_back(spring);
    }
    return extra;
  };
  const std::vector<StepForces> steps = {springs({3, 5}), springs({5}), springs({}),
                                         springs({3, 5})};
  const double beta = 1.0 / 60.0;
  for (const LinearSolverKind kind : {LinearSolverKind::cholmod, LinearSolverKind::pcg}) {
    NewtonSettings settings;
    settings.solver = kind;
    settings.pcg_tolerance = 1e-13;
    ImplicitSolver kept;
    for (std::size_t k = 0; k < steps.size(); ++k) {
      const ImplicitSolveResult r =
          kept.solve(model, forces, filter, x0, v0, beta, x0, v0, settings, &steps[k]);
      ImplicitSolver fresh;
      const ImplicitSolveResult expected =
          fresh.solve(model, forces, filter, x0, v0, beta, x0, v0, settings, &steps[k]);
      ASSERT_TRUE(r.linear_converged && expected.linear_converged);
      EXPECT_LT((r.v - expected.v).lpNorm<Eigen::Infinity>(),
                1e-11 * expected.v.lpNorm<Eigen::Infinity>())
          << "step " << k;
      if (kind == LinearSolverKind::pcg) {
        EXPECT_EQ(kept.matrix().nonZeros(), fresh.matrix().nonZeros()) << "step " << k;
      }
    }
    if (kind == LinearSolverKind::cholmod) {
      EXPECT_EQ(kept.cholmod().symbolic_analyses(), 1);
      EXPECT_EQ(kept.cholmod().numeric_factorizations(), 4);
      // The step without springs still has the first step's blocks, as zeros.
      EXPECT_GT(kept.matrix().nonZeros(), model.pattern.zero_matrix.nonZeros());
    }
  }
}

}  // namespace
}  // namespace sd::sim
