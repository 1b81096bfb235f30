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
  if (vertices > kAutomaticCholmodVertices) {
    choice.solver = LinearSolverKind::cholmod;
  } else {
    choice.solver = LinearSolverKind::pcg;
    choice.preconditioner = PcgPreconditioner::block_incomplete_cholesky;
  }
  // The step: the largest that kept every measured scene of its kind within 1 % stretch without
  // more than one step halving (docs/simulator.md, "Automatic settings"). A sheet held by pins or
  // lying on a body: 1/20 s (at 1/12 s the sheet on the sphere stretched 5.5 %). Cloth that can
  // fold onto itself (garments, self-contact on): 1/60 s; the t-shirt's largest strain grew
  // from 1.8 % at 1/60 s to 3.6 % at 1/40 s and 5.0 % at 1/30 s.
  choice.dt = scene.self_contact ? 1.0 / 60.0 : 1.0 / 20.0;
  choice.reason =
      fmt::format("automatic: implicit Euler, {} ({} vertices), steps of 1/{:.0f} s ({})",
                  choice.solver == LinearSolverKind::pcg ? "the IC(0) PCG" : "CHOLMOD", vertices,
                  1.0 / choice.dt, scene.self_contact ? "self-contact" : "no self-contact");
  return choice;
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
  }
}

}  // namespace sd::sim
