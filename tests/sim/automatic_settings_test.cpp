#include "sim/automatic_settings.hpp"

#include <gtest/gtest.h>

namespace sd::sim {
namespace {

TEST(AutomaticSettings, IncompleteCholeskyUpToTheThresholdThenTwoLevel) {
  SceneTraits scene;
  scene.vertices = kAutomaticTwoLevelVertices;
  AutomaticChoice choice = choose_settings(scene);
  EXPECT_EQ(choice.integrator, Integrator::implicit_euler);
  EXPECT_EQ(choice.solver, LinearSolverKind::pcg);
  EXPECT_EQ(choice.preconditioner, PcgPreconditioner::block_incomplete_cholesky);
  scene.vertices = kAutomaticTwoLevelVertices + 1;
  choice = choose_settings(scene);
  EXPECT_EQ(choice.solver, LinearSolverKind::pcg);
  EXPECT_EQ(choice.preconditioner, PcgPreconditioner::two_level);
  EXPECT_NE(choice.reason.find("two-level"), std::string::npos) << choice.reason;
  // An adaptive cloth is judged by the most it may grow to.
  scene.vertices = 1000;
  scene.max_vertices = 20000;
  EXPECT_EQ(choose_settings(scene).preconditioner, PcgPreconditioner::two_level);
}

TEST(AutomaticSettings, SelfContactTakesCholmodAndShorterSteps) {
  SceneTraits scene;
  scene.vertices = 1089;
  EXPECT_DOUBLE_EQ(choose_settings(scene).dt, 1.0 / 20.0);
  scene.self_contact = true;
  const AutomaticChoice choice = choose_settings(scene);
  EXPECT_EQ(choice.solver, LinearSolverKind::cholmod);
  EXPECT_DOUBLE_EQ(choice.dt, 1.0 / 60.0);
  EXPECT_NE(choice.reason.find("1/60 s"), std::string::npos) << choice.reason;
  EXPECT_NE(choice.reason.find("1089 vertices"), std::string::npos) << choice.reason;
  // A garment without self-contact too.
  scene.self_contact = false;
  scene.garment = true;
  EXPECT_EQ(choose_settings(scene).solver, LinearSolverKind::cholmod);
  EXPECT_DOUBLE_EQ(choose_settings(scene).dt, 1.0 / 60.0);
}

TEST(AutomaticSettings, SettingsTheFileGivesAreKept) {
  SceneTraits scene;
  scene.vertices = 500;
  const AutomaticChoice choice = choose_settings(scene);
  SimulationSettings given;
  given.solver = LinearSolverKind::cholmod;
  given.integrator = Integrator::bdf2;
  given.dt = 0.01;
  SimulationSettings settings = given;
  apply_choice(choice, false, false, settings);
  EXPECT_EQ(settings.solver, LinearSolverKind::cholmod);
  EXPECT_DOUBLE_EQ(settings.dt, 0.01);
  apply_choice(choice, true, false, settings);
  EXPECT_EQ(settings.solver, LinearSolverKind::pcg);
  EXPECT_EQ(settings.integrator, Integrator::bdf2);  // the file's integrator stays
  EXPECT_DOUBLE_EQ(settings.dt, 0.01);
  apply_choice(choice, false, true, settings);
  EXPECT_DOUBLE_EQ(settings.dt, 1.0 / 20.0);
  EXPECT_LE(settings.min_dt, settings.dt / 64);
  EXPECT_NO_THROW(settings.validate());
}

// A sheet's step: 1/20 s with or without a body, 1/60 s when the motion is asked for (implicit
// Euler's trajectory error grows with the step); garments keep 1/60 s.
TEST(AutomaticSettings, SheetStepsFollowTheMotion) {
  SceneTraits scene;
  scene.vertices = 1089;
  AutomaticChoice choice = choose_settings(scene);
  EXPECT_DOUBLE_EQ(choice.dt, kAutomaticSheetStep);
  EXPECT_NE(choice.reason.find("1/20 s"), std::string::npos) << choice.reason;
  EXPECT_NE(choice.reason.find("without a body"), std::string::npos) << choice.reason;
  scene.body = true;
  choice = choose_settings(scene);
  EXPECT_DOUBLE_EQ(choice.dt, kAutomaticSheetStep);
  EXPECT_NE(choice.reason.find("on a body"), std::string::npos) << choice.reason;
  EXPECT_EQ(choice.solver, LinearSolverKind::pcg);
  scene.motion = true;
  choice = choose_settings(scene);
  EXPECT_DOUBLE_EQ(choice.dt, kAutomaticMotionStep);
  EXPECT_EQ(choice.solver, LinearSolverKind::pcg);
  EXPECT_NE(choice.reason.find("the motion asked for"), std::string::npos) << choice.reason;
  scene.body = false;
  EXPECT_DOUBLE_EQ(choose_settings(scene).dt, kAutomaticMotionStep);
  scene.garment = true;
  choice = choose_settings(scene);
  EXPECT_EQ(choice.solver, LinearSolverKind::cholmod);
  EXPECT_DOUBLE_EQ(choice.dt, 1.0 / 60.0);
  EXPECT_EQ(choice.reason.find("the motion asked for"), std::string::npos) << choice.reason;
  // Every step the rule gives is longer than the step control's floor it sets.
  SimulationSettings settings;
  apply_choice(choose_settings(SceneTraits{}), true, true, settings);
  EXPECT_NO_THROW(settings.validate());
}

}  // namespace
}  // namespace sd::sim
