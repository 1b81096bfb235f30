#pragma once
// Runs one stress case step by step and checks, after every accepted step, that the state is
// finite and bounded (docs/stress.md, "Bounds"): strain, speed, and the total energy once
// nothing drives the cloth any more.

#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "src/app/stress/stress_cases.hpp"

namespace sd::app {

// Energy the cloth may hold at the end above what it had when it was left to itself (the
// reference state), as a multiple of the energy scale M·|g|·L + elastic + kinetic energy of the
// reference: exact dynamics can only lose energy; what an implicit step injects (its one-step
// overshoot, reported as the peak) must have been dissipated by the end. See docs/stress.md.
inline constexpr double kStressEnergyTolerance = 1.0;
// Step attempts (accepted + rejected) a case may use: a healthy run at the smallest step of the
// matrix (1/100 s for 1 s) needs 100; beyond this, step control has collapsed to steps far too
// small to be useful and the case counts as stalled.
inline constexpr int kStressMaxAttempts = 5000;

struct StressOptions {
  std::optional<double> min_dt;  // s: overrides every case's minimum step (capped at its dt)
};

struct StressResult {
  std::string id, family, condition;
  nlohmann::json parameters;
  // stable | rejected (invalid input refused, as expected) | failed (the simulator gave up) |
  // exploded (a bound broken) | stalled (step budget spent) | crashed (the process died) |
  // error (unexpected exception, or an invalid input that was not refused)
  std::string status;
  bool ok = false;          // stable, or rejected when the case expects it
  std::string reason;       // why not ok; for rejected cases, the error message
  bool finite = true;       // every accepted state finite
  bool ran_to_end = false;  // reached the duration or rest
  bool at_rest = false;
  double duration = 0.0, sim_time = 0.0;
  int steps = 0, attempts = 0, retries = 0, forced_steps = 0;
  double dt = 0.0, min_dt = 0.0, dt_min_used = 0.0;
  double max_strain = 0.0, strain_bound = 0.0;  // largest stretch strain of any accepted state
  double max_speed = 0.0, speed_bound = 0.0;    // m/s
  double energy_scale = 0.0;                    // J
  double energy_growth = 0.0;  // J: peak E(t) − E(ref) once undriven (0: never above E(ref))
  double energy_final_growth = 0.0;  // J: E(end) − E(ref), what the bound applies to
  double energy_bound = 0.0;         // J: kStressEnergyTolerance · energy_scale
  int vertices = 0;
  int topology_changes = 0;  // adaptive cases: steps that changed the mesh
  int contacts_max = 0;
  double max_penetration_m = 0.0;
  // Self-contact cases: intersecting triangle pairs of the final mesh (CGAL, independent of the
  // simulator), −1 when self-contact is off; most repulsion springs in a step.
  int self_intersections_final = -1;
  int self_contacts_max = 0;
  double wall_time_s = 0.0;
};

// Runs the case (never throws for what the simulation does; a recipe that cannot be built is
// an `error`, or `rejected` when the case expects rejection).
StressResult run_stress_case(const StressCase& c, const StressOptions& options = {});

// The same in a child process (fork), so that a simulator crash ends only that case: it is
// then `crashed`, with the signal as its reason.
StressResult run_stress_case_isolated(const StressCase& c, const StressOptions& options = {});

nlohmann::json stress_result_json(const StressResult& r);
StressResult stress_result_from_json(const nlohmann::json& j);

}  // namespace sd::app
