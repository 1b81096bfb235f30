// The modified PCG and CHOLMOD on the same constrained system, and one implicit step with each.
#include "sim/pcg_solver.hpp"

#include <gtest/gtest.h>

#include <random>

#include "sim/cholmod_solver.hpp"
#include "sim/forces.hpp"
#include "sim/simulation.hpp"
#include "test_scenes.hpp"

namespace sd::sim {
namespace {

struct System {
  SheetScene scene;
  ClothModel model;
  SparseMatrixR a;
  ConstraintFilter filter;
  Eigen::VectorXd b;
};

System make_system(double beta) {
  SheetSpec spec;
  spec.size = {0.5, 0.5};
  spec.columns = 10;
  spec.rows = 10;
  spec.pins = {"top-left", "top-right"};
  System s{build_sheet(spec), {}, {}, {}, {}};
  s.model = build_cloth_model(s.scene.input, fabric_preset("cotton"));
  std::mt19937 rng(17);
  const Eigen::VectorXd x = testing::random_configuration(s.scene.input.rest_positions, rng, 0.002);
  const Eigen::VectorXd v = Eigen::VectorXd::Random(x.size());
  s.a = s.model.pattern.zero_matrix;
  for (int i = 0; i < s.model.vertex_count; ++i)
    for (int k = 0; k < 3; ++k)
      s.a.valuePtr()[block_value_index(s.a, i, s.model.pattern.diagonal_offsets[i], k, k)] =
          s.model.mass[i];
  JacobianTarget target;
  target.matrix = &s.a;
  target.dfdx_scale = -beta * beta;
  target.dfdv_scale = -beta;
  Eigen::VectorXd force;
  evaluate_forces(s.model, ForceSettings{}, x, v, force, nullptr, &target);
  s.b = beta * force;
  s.filter = ConstraintFilter(s.model.vertex_count);
  s.filter.pin(s.scene.pinned_vertices[0], Eigen::Vector3d(0.1, -0.2, 0.3));
  s.filter.pin(s.scene.pinned_vertices[1], Eigen::Vector3d::Zero());
  s.filter.constrain_direction(50, Eigen::Vector3d(1, 1, 0), 0.05);     // a contact
  s.filter.constrain_direction(60, Eigen::Vector3d(0, 0, 1), -0.02);    // two contacts
  s.filter.constrain_direction(60, Eigen::Vector3d(1, 0, 1), 0.01);
  return s;
}

TEST(LinearSolvers, PcgAndCholmodAgreeOnTheConstrainedSystem) {
  for (double beta : {1.0 / 1000, 1.0 / 24}) {
    System s = make_system(beta);
    Eigen::VectorXd z;
    s.filter.constrained_correction(Eigen::VectorXd::Zero(s.b.size()), z);
    PcgSolver pcg;
    Eigen::VectorXd s_pcg, s_direct;
    const LinearSolveStats pcg_stats =
        pcg.solve(s.a, s.model.pattern.diagonal_offsets, s.filter, s.b, z, s_pcg, 1e-12, 5000);
    EXPECT_TRUE(pcg_stats.converged);
    EXPECT_GT(pcg_stats.iterations, 1);
    CholmodSolver cholmod;
    ASSERT_TRUE(cholmod.factorize(s.a, s.filter));
    const LinearSolveStats direct_stats = cholmod.solve(s.a, s.filter, s.b, z, s_direct);
    EXPECT_TRUE(direct_stats.converged);
    EXPECT_LT(direct_stats.relative_residual, 1e-10);
    EXPECT_LT(constrained_relative_residual(s.a, s.filter, s.b, z, s_pcg), 1e-9);
    EXPECT_LE((s_pcg - s_direct).norm(), 1e-8 * s_direct.norm()) << "beta " << beta;
    // Constrained directions take exactly the prescribed values.
    for (int i = 0; i < s.model.vertex_count; ++i) {
      if (s.filter.is_free(i)) continue;
      const Eigen::Matrix3d constrained = Eigen::Matrix3d::Identity() - s.filter.filter_matrix(i);
      EXPECT_LE((constrained * s_pcg.segment<3>(3 * i) - z.segment<3>(3 * i)).norm(), 1e-14);
      EXPECT_LE((constrained * s_direct.segment<3>(3 * i) - z.segment<3>(3 * i)).norm(), 1e-12);
    }
    EXPECT_NEAR(s_pcg[3 * 50] + s_pcg[3 * 50 + 1], 0.05 * std::sqrt(2.0), 1e-14);
  }
}

TEST(LinearSolvers, CholmodReusesTheSymbolicAnalysis) {
  System s = make_system(0.01);
  CholmodSolver cholmod;
  ASSERT_TRUE(cholmod.factorize(s.a, s.filter));
  s.a *= 2.0;  // new values, same pattern
  ASSERT_TRUE(cholmod.factorize(s.a, s.filter));
  EXPECT_EQ(cholmod.symbolic_analyses(), 1);
  EXPECT_EQ(cholmod.numeric_factorizations(), 2);
  SheetSpec spec;
  spec.columns = 3;
  spec.rows = 3;
  const ClothModel small = build_cloth_model(build_sheet(spec).input, FabricParameters{});
  SparseMatrixR identity = small.pattern.zero_matrix;
  for (int i = 0; i < small.vertex_count; ++i)
    for (int k = 0; k < 3; ++k)
      identity.valuePtr()[block_value_index(identity, i, small.pattern.diagonal_offsets[i], k, k)] = 1;
  ASSERT_TRUE(cholmod.factorize(identity, ConstraintFilter(small.vertex_count)));
  EXPECT_EQ(cholmod.symbolic_analyses(), 2);  // a new pattern is analysed again
}

TEST(LinearSolvers, OneImplicitStepIsTheSameWithEitherSolver) {
  for (Integrator integrator : {Integrator::implicit_euler, Integrator::bdf2}) {
    SheetSpec spec;
    spec.size = {0.5, 0.5};
    spec.columns = 12;
    spec.rows = 12;
    spec.pins = {"top-left", "top-right"};
    const SheetScene scene = build_sheet(spec);
    const ClothModel model = build_cloth_model(scene.input, fabric_preset("cotton"));
    std::vector<Eigen::VectorXd> ends;
    for (LinearSolverKind solver : {LinearSolverKind::pcg, LinearSolverKind::cholmod}) {
      SimulationSettings settings;
      settings.integrator = integrator;
      settings.solver = solver;
      settings.dt = 1.0 / 48;
      settings.pcg_tolerance = 1e-10;
      settings.newton_tolerance = 1e-10;
      Simulation sim(model, flatten_positions(scene.input.rest_positions),
                     testing::fixed_pins(scene), settings);
      for (int k = 0; k < 3; ++k) ASSERT_TRUE(sim.step().accepted);
      ends.push_back(sim.positions());
    }
    const double displacement =
        (ends[0] - flatten_positions(scene.input.rest_positions)).lpNorm<Eigen::Infinity>();
    EXPECT_GT(displacement, 1e-3);
    EXPECT_LE((ends[0] - ends[1]).lpNorm<Eigen::Infinity>(), 1e-7 * displacement);
  }
}

}  // namespace
}  // namespace sd::sim
