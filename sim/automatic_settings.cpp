#include "sim/automatic_settings.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace sd::sim {

AutomaticChoice choose_settings(const SceneTraits& scene) {
  AutomaticChoice choice;
  // Implicit Euler everywhere: BDF2 at film steps falls back to its linearised step on stiff
  // woven cloth and stretched a sheet dropped on a sphere by 81 % (issue 24); implicit Euler's
  // damping is what lets a drape come to rest early.
  choice.integrator = Integrator::implicit_euler;
  const int vertices = std::max(scene.vertices, scene.max_vertices);
  // Garments, and any cloth that can fold onto itself, keep CHOLMOD at 1/60 s. With the PCG
  // (tolerance 1e-3) four of the corpus's designs never came to rest within their duration (the
  // straight skirt on the human, the vest with a collar, the tee dress, the circle skirt:
  // vertices still moving at 1–13 cm/s where the at-rest test asks for 5 mm/s), and the
  // arms-lowering t-shirt (self-collision off) kept a body vertex 4.6 mm through it: the
  // inexact solves leave a velocity noise that the exact factorisation does not. Longer steps
  // stretch a garment more around its contacts: the t-shirt's largest strain grew from 1.8 % at
  // 1/60 s to 3.6 % at 1/40 s and 5.0 % at 1/30 s (docs/simulator.md, "Automatic settings").
  if (scene.garment || scene.self_contact) {
    choice.solver = LinearSolverKind::cholmod;
    choice.dt = 1.0 / 60.0;
  } else {
    // A sheet held by pins or lying on a body: the PCG, with IC(0) up to the size where the
    // two-level preconditioner becomes cheaper (it was cheaper than CHOLMOD too at 16,641 and
    // 66,049 vertices). The step: 1/20 s, the longest that kept the measured sheets within 1 %
    // stretch and let them rest. On the sphere 1/12 s stretched the sheet 5.5 %, 1/30 and 1/24 s
    // 1.1-1.5 %. Without a body 1/15 s kept five fabrics within 0.25-0.88 % and cost 17-25 %
    // less, but the polyester Cusick drape (quadratic bending, buckling) no longer came to rest
    // in 6 s (7 mm/s at the end, the test asks for 5); at 1/12 s denim and silk stretched 1.05 %.
    // Implicit Euler's trajectory error grows with the step (bench: 1.5-2.3x the 1/60 s run's at
    // 1/20 s), so when the motion is asked for the step is 1/60 s, the step every earlier
    // default and the bench's grid use, and within the bench's error band.
    choice.solver = LinearSolverKind::pcg;
    choice.preconditioner = vertices > kAutomaticTwoLevelVertices
                                ? PcgPreconditioner::two_level
                                : PcgPreconditioner::block_incomplete_cholesky;
    // Fourth round: the drape's step by what holds the sheet (bench, 1 s at L4 against the
    // 1/60 s run's RMS trajectory error): pins that hold its shape leave only elastic sag, and
    // 1/20 s stayed within the band (hanging sheet on three corners 1.46x); a sheet on two
    // corners swings as a pendulum, which long steps damp (1/20 s 1.93x, 1/30 s 1.57x, 1/40 s
    // 1.32x); on a body it slides and folds over it (1/30 s 1.81x, 1/40 s 1.51x, 1/50 s 1.12x).
    if (scene.motion)
      choice.dt = kAutomaticMotionStep;
    else if (scene.body)
      choice.dt = kAutomaticContactStep;
    else if (scene.pins_hold_shape)
      choice.dt = kAutomaticSheetStep;
    else {
      // Fifth round: the swing lasts about a second of a 2 s drape; the step follows implicit
      // Euler's local error from 1/40 s (the run starts at dt/2), so it is short only while
      // the sheet swings. Its linear solves need less precision than its step gives away
      // (bench: PCG tolerance 1e-3, 3e-3, 1e-2 at 1/40 s gave 1.32x, 1.32x, 1.39x the 1/60 s
      // run's error); the other cases were not measured and keep 1e-3.
      choice.dt = kAutomaticSheetStep;
      choice.step_error = kAutomaticSwingStepError;
      choice.pcg_tolerance = kAutomaticSwingPcgTolerance;
    }
  }
  choice.reason = fmt::format(
      "automatic: implicit Euler, {}{} ({} vertices), {} ({}{})",
      choice.solver == LinearSolverKind::cholmod              ? "CHOLMOD"
      : choice.preconditioner == PcgPreconditioner::two_level ? "the two-level PCG"
                                                              : "the IC(0) PCG",
      choice.solver == LinearSolverKind::pcg && choice.pcg_tolerance != kDefaultPcgTolerance
          ? fmt::format(" to {:g}", choice.pcg_tolerance)
          : std::string(),
      vertices,
      choice.step_error > 0.0
          ? fmt::format("steps from 1/{:.0f} s up to 1/{:.0f} s by a local error of {:g} mm",
                        2.0 / choice.dt, 1.0 / choice.dt, 1e3 * choice.step_error)
          : fmt::format("steps of 1/{:.0f} s", 1.0 / choice.dt),
      scene.garment           ? "a garment"
      : scene.self_contact    ? "self-contact"
      : scene.body            ? "a sheet on a body, without self-contact"
      : scene.pins_hold_shape ? "a sheet without a body or self-contact, its pins holding its shape"
                              : "a sheet without a body or self-contact, free to swing on its pins",
      scene.motion && !scene.garment && !scene.self_contact ? "; the motion asked for" : "");
  return choice;
}

bool pins_hold_shape(const Eigen::MatrixX3d& positions, const std::vector<int>& pinned) {
  if (pinned.size() < 3) return false;
  const auto at = [&](int v) -> Eigen::Vector3d { return positions.row(v).transpose(); };
  // The two farthest apart, approximately: the pin farthest from the first, then the pin
  // farthest from that one (exact for collinear pins, within a factor 2 otherwise).
  const auto farthest_from = [&](const Eigen::Vector3d& p) {
    int best = pinned.front();
    for (int v : pinned)
      if ((at(v) - p).squaredNorm() > (at(best) - p).squaredNorm()) best = v;
    return best;
  };
  const Eigen::Vector3d a = at(farthest_from(at(pinned.front())));
  const Eigen::Vector3d b = at(farthest_from(a));
  const double length = (b - a).norm();
  if (!(length > 0.0)) return false;
  const Eigen::Vector3d axis = (b - a) / length;
  double off_line = 0.0;
  for (int v : pinned) off_line = std::max(off_line, (at(v) - a).cross(axis).norm());
  return off_line >= 0.1 * length;
}

void apply_choice(const AutomaticChoice& choice, bool solver_automatic, bool step_automatic,
                  SimulationSettings& settings) {
  // The integrator is the file's (implicit Euler unless it asks for BDF2): the rule's choice is
  // the same default.
  if (solver_automatic) {
    settings.solver = choice.solver;
    settings.pcg_preconditioner = choice.preconditioner;
  }
  if (step_automatic) {
    settings.dt = choice.dt;
    settings.min_dt = std::min(settings.min_dt, choice.dt / 64);
    settings.step_error = choice.step_error;
  }
  if (solver_automatic && step_automatic) settings.pcg_tolerance = choice.pcg_tolerance;
}

}  // namespace sd::sim
