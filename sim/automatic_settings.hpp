#pragma once
// The settings `"solver": "auto"` and `"time_step": "auto"` stand for (the sketch defaults): the
// integrator, linear solver, preconditioner and largest step chosen from what the scene is, by
// a rule read off the work-precision front (docs/simulator.md, "Automatic settings", has the
// measurements behind every threshold).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "sim/implicit_solver.hpp"
#include "sim/simulation.hpp"

namespace sd::sim {

// What the rule looks at: plain facts about the scene, known before the first step.
struct SceneTraits {
  int vertices = 0;      // at the start
  int max_vertices = 0;  // an adaptive cloth's particle budget (it may grow); 0: none
  // Cloth-cloth contact on (garments by default): cloth that can fold onto itself.
  bool self_contact = false;
  // Sewn panels worn on a body (not a sheet scene), with or without self-contact.
  bool garment = false;
  // A body the cloth can touch (a sheet dropped on a sphere): contact changes the step's limit.
  bool body = false;
  // The motion is asked for, not only the drape (`run --frames N`): the step must follow the
  // trajectory, not only reach the end state.
  bool motion = false;
  // The pins hold the sheet's shape: at least three pinned vertices not on one line
  // (pins_hold_shape below), so no rigid motion is left free. Two corners, one edge or no pins
  // leave a swing (or a slide, or a fall) that long implicit Euler steps damp away.
  bool pins_hold_shape = false;
};

// The PCG's tolerance everywhere but on a sheet free to swing (SimulationSettings' default), and
// on that sheet at its step: there implicit Euler's own error at 1/40 s is so much larger than the
// linear solve's that 1e-2 kept the bench's pinned 32x32 sheet inside the error band (1.39x the
// 1/60 s run's RMS trajectory error against 1.32x at 1e-3, band 1.5x) with half the PCG
// iterations (13.3 -> 6.5 a solve on the 32x32 sheet, 23.1 -> 10.0 on the 64x64) and the same
// final stretch (docs/simulator.md, "Automatic settings", fifth round).
inline constexpr double kDefaultPcgTolerance = 1e-3;
inline constexpr double kAutomaticSwingPcgTolerance = 1e-2;

struct AutomaticChoice {
  Integrator integrator = Integrator::implicit_euler;
  LinearSolverKind solver = LinearSolverKind::pcg;
  PcgPreconditioner preconditioner = PcgPreconditioner::block_incomplete_cholesky;
  double dt = 1.0 / 60.0;  // s, the largest step
  // The PCG's relative residual reduction (SimulationSettings::pcg_tolerance).
  double pcg_tolerance = kDefaultPcgTolerance;
  double step_error = 0.0;  // m, SimulationSettings::step_error; 0: the step does not follow it
  std::string reason;       // one sentence for report.json and logs
};

// Above this many vertices a sheet's PCG takes the two-level preconditioner: IC(0)'s iterations
// grow with the resolution (9, 114, 219, 451 per solve from 32x32 to 256x256 quads) and the
// two-level one's barely (7, 17, 20, 25), so above it the two-level PCG is cheaper than both
// IC(0) and CHOLMOD (docs/benchmarks.md, "Scaling"); below, IC(0) is (its cycle costs less).
// Garments and cloth with self-contact always use CHOLMOD.
inline constexpr int kAutomaticTwoLevelVertices = 8000;

// The sheets' steps (s): for a drape whose pins hold its shape, for one they leave free to swing
// (or unpinned), for one on a body, and when the motion is asked for. Each is the longest of the
// measured steps that kept the bench's sheets within the error band (1.5x the trajectory error
// at 1/60 s); the measurements are in docs/simulator.md, "Automatic settings".
inline constexpr double kAutomaticSheetStep = 1.0 / 20.0;
inline constexpr double kAutomaticSwingStep = 1.0 / 40.0;
inline constexpr double kAutomaticContactStep = 1.0 / 50.0;
inline constexpr double kAutomaticMotionStep = 1.0 / 60.0;
// Fifth round: the sheet free to swing starts at kAutomaticSwingStep (the largest step, dt, is
// kAutomaticSheetStep, the run starts at half of it) and its step then follows implicit Euler's
// local error estimate held near this (m, RMS; SimulationSettings::step_error): steps of 1/40 s
// and shorter while it swings, growing to 1/20 s as it settles (bench, 1 s at L4, against the
// 1/60 s run's RMS trajectory error, band 1.5x). Fourteenth round: 2.5 mm, the largest measured
// value that kept the three swinging sheets inside the band (two corners 1.26x, one edge 1.40x,
// one corner 1.13x, with 46, 47, 57 steps in that second against 53, 53, 66 at the fifth round's
// 2 mm); 3 mm took the edge sheet out (1.54x), 4 mm the two-corner sheet (1.55x);
// docs/simulator.md, "Automatic settings".
inline constexpr double kAutomaticSwingStepError = 2.5e-3;

// True when the pinned vertices (rows of `positions`, m) hold a rigid body still: at least three
// of them, not all near one line (the farthest from the line through the two farthest apart is at
// least a tenth of their distance). Two pins leave the swing about their axis.
bool pins_hold_shape(const Eigen::MatrixX3d& positions, const std::vector<int>& pinned);

AutomaticChoice choose_settings(const SceneTraits& scene);

// Fills the solver, preconditioner and dt of `settings` from `choice`, for the parts
// the caller left automatic; min_dt stays below dt. The PCG tolerance is the choice's only when
// both are automatic (it was measured at the rule's step).
void apply_choice(const AutomaticChoice& choice, bool solver_automatic, bool step_automatic,
                  SimulationSettings& settings);

}  // namespace sd::sim
