#include "sim/automatic_settings.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <utility>
#include <vector>

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
  scene.pins_hold_shape = true;
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
  // No pins holding it: free to swing, from 1/40 s by the local error up to 1/20 s.
  EXPECT_DOUBLE_EQ(settings.dt, kAutomaticSheetStep);
  EXPECT_DOUBLE_EQ(settings.step_error, kAutomaticSwingStepError);
  EXPECT_DOUBLE_EQ(0.5 * settings.dt, kAutomaticSwingStep);
  EXPECT_LE(settings.min_dt, settings.dt / 64);
  EXPECT_NO_THROW(settings.validate());
}

// A sheet's drape step by what holds it (the bench's error band, docs/simulator.md): 1/20 s when
// its pins hold its shape, 1/40 s when it can swing (or fall) freely, 1/50 s on a body; 1/60 s
// when the motion is asked for (implicit Euler's trajectory error grows with the step);
// garments keep 1/60 s.
TEST(AutomaticSettings, SheetStepsFollowThePinsTheBodyAndTheMotion) {
  SceneTraits scene;
  scene.vertices = 1089;
  AutomaticChoice choice = choose_settings(scene);
  EXPECT_DOUBLE_EQ(choice.dt, kAutomaticSheetStep);
  EXPECT_DOUBLE_EQ(choice.step_error, kAutomaticSwingStepError);
  EXPECT_NE(choice.reason.find("from 1/40 s up to 1/20 s by a local error of 2.5 mm"),
            std::string::npos)
      << choice.reason;
  EXPECT_NE(choice.reason.find("free to swing"), std::string::npos) << choice.reason;
  scene.pins_hold_shape = true;
  choice = choose_settings(scene);
  EXPECT_DOUBLE_EQ(choice.dt, kAutomaticSheetStep);
  EXPECT_DOUBLE_EQ(choice.step_error, 0.0);  // a fixed step where the pins hold the shape
  EXPECT_NE(choice.reason.find("1/20 s"), std::string::npos) << choice.reason;
  EXPECT_NE(choice.reason.find("holding its shape"), std::string::npos) << choice.reason;
  // Contact with a body takes the shorter step whatever the pins.
  scene.body = true;
  choice = choose_settings(scene);
  EXPECT_DOUBLE_EQ(choice.dt, kAutomaticContactStep);
  EXPECT_DOUBLE_EQ(choice.step_error, 0.0);
  EXPECT_NE(choice.reason.find("1/50 s"), std::string::npos) << choice.reason;
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
  for (const bool hold : {false, true})
    for (const bool body : {false, true}) {
      SceneTraits sheet;
      sheet.pins_hold_shape = hold;
      sheet.body = body;
      SimulationSettings settings;
      apply_choice(choose_settings(sheet), true, true, settings);
      EXPECT_NO_THROW(settings.validate());
    }
}

// The PCG's looser tolerance goes with the swinging sheet's step only (measured there against
// the bench's error band), and only into settings whose solver and step are both automatic.
TEST(AutomaticSettings, LooserPcgToleranceOnlyForTheSwingingSheet) {
  SceneTraits scene;
  scene.vertices = 1089;
  AutomaticChoice choice = choose_settings(scene);
  EXPECT_DOUBLE_EQ(choice.pcg_tolerance, kAutomaticSwingPcgTolerance);
  EXPECT_NE(choice.reason.find("PCG to 0.01"), std::string::npos) << choice.reason;
  SimulationSettings settings;
  apply_choice(choice, true, true, settings);
  EXPECT_DOUBLE_EQ(settings.pcg_tolerance, kAutomaticSwingPcgTolerance);
  EXPECT_NO_THROW(settings.validate());
  for (const auto& [solver_automatic, step_automatic] :
       {std::pair{true, false}, std::pair{false, true}, std::pair{false, false}}) {
    SimulationSettings given;
    apply_choice(choice, solver_automatic, step_automatic, given);
    EXPECT_DOUBLE_EQ(given.pcg_tolerance, kDefaultPcgTolerance);
  }
  EXPECT_DOUBLE_EQ(SimulationSettings{}.pcg_tolerance, kDefaultPcgTolerance);
  // Pins holding its shape, a body, the motion asked for, a garment: the default tolerance.
  for (int which = 0; which < 4; ++which) {
    SceneTraits other = scene;
    other.pins_hold_shape = which == 0;
    other.body = which == 1;
    other.motion = which == 2;
    other.garment = which == 3;
    choice = choose_settings(other);
    EXPECT_DOUBLE_EQ(choice.pcg_tolerance, kDefaultPcgTolerance) << which;
    EXPECT_EQ(choice.reason.find(" to 0.0"), std::string::npos) << choice.reason;
  }
}

// Pins hold a sheet's shape when at least three of them span a triangle: the corners of a
// 1 m sheet (z = 0) and a disc of pins do; two corners, a whole edge (a hinge, on one line) and
// one pin do not, nor three pins nearly on a line (3 cm off a 1 m line: 0.03 < 0.1).
TEST(AutomaticSettings, PinsHoldTheShapeOnlyOffOneLine) {
  Eigen::MatrixX3d corners(4, 3);
  corners << 0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0;
  EXPECT_FALSE(pins_hold_shape(corners, {}));
  EXPECT_FALSE(pins_hold_shape(corners, {0}));
  EXPECT_FALSE(pins_hold_shape(corners, {0, 1}));
  EXPECT_TRUE(pins_hold_shape(corners, {0, 1, 2}));
  EXPECT_TRUE(pins_hold_shape(corners, {0, 1, 2, 3}));
  EXPECT_TRUE(pins_hold_shape(corners, {3, 0, 2}));  // any order
  // An edge of 11 vertices along x, then one vertex off it by 3 cm and by 20 cm.
  Eigen::MatrixX3d edge(13, 3);
  std::vector<int> line;
  for (int i = 0; i <= 10; ++i) {
    edge.row(i) = Eigen::RowVector3d(0.1 * i, 1.2, 0.0);
    line.push_back(i);
  }
  edge.row(11) = Eigen::RowVector3d(0.5, 1.2, 0.03);
  edge.row(12) = Eigen::RowVector3d(0.5, 1.2, 0.2);
  EXPECT_FALSE(pins_hold_shape(edge, line));
  line.push_back(11);
  EXPECT_FALSE(pins_hold_shape(edge, line));
  line.push_back(12);
  EXPECT_TRUE(pins_hold_shape(edge, line));
  // A disc of pins (the Cusick drape's centre), 8 on a 9 cm circle.
  Eigen::MatrixX3d disc(8, 3);
  std::vector<int> ring;
  for (int i = 0; i < 8; ++i) {
    const double a = 2.0 * 3.141592653589793 * i / 8;
    disc.row(i) = Eigen::RowVector3d(0.09 * std::cos(a), 0.5, 0.09 * std::sin(a));
    ring.push_back(i);
  }
  EXPECT_TRUE(pins_hold_shape(disc, ring));
  // All pins at one point: nothing spans.
  Eigen::MatrixX3d same = Eigen::MatrixX3d::Zero(3, 3);
  EXPECT_FALSE(pins_hold_shape(same, {0, 1, 2}));
}

}  // namespace
}  // namespace sd::sim
