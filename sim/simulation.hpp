#pragma once
// The driver: time stepping with implicit Euler or variable-step BDF2, step control (rollback
// and halving on failure, growth after easy steps), at-rest detection and the run report.

#include <Eigen/Core>
#include <array>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "meshing/tri_mesh.hpp"
#include "sim/body_motion.hpp"
#include "sim/cloth_model.hpp"
#include "sim/contact_response.hpp"
#include "sim/forces.hpp"
#include "sim/implicit_solver.hpp"
#include "sim/self_contact.hpp"

namespace sd::sim {

// A setting that cannot work (dt ≤ 0, negative tolerance, ...). The message names it.
class InvalidSimulationSettingsError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

enum class Integrator { implicit_euler, bdf2 };

// The integrator's name in sketch files and reports ("implicit-euler", "bdf2"), its short form in
// run ids ("ie", "bdf2"), and the enum from either (nothing for another string).
std::string_view integrator_name(Integrator integrator);
std::string_view integrator_short_name(Integrator integrator);
std::optional<Integrator> parse_integrator(std::string_view name);

struct SimulationSettings {
  Integrator integrator = Integrator::implicit_euler;
  LinearSolverKind solver = LinearSolverKind::pcg;
  double dt = 1.0 / 60.0;  // s, the largest step (and the step the run starts with)
  double min_dt = 1.0e-5;  // s, halving stops here
  double duration = 2.0;   // s of simulated time
  // Newton iterations per step; empty: 1 for implicit Euler (the linearised step), 8 for BDF2.
  std::optional<int> newton_iterations;
  double newton_tolerance = 1.0e-6;  // m, see NewtonSettings
  double pcg_tolerance = 1.0e-3;
  int pcg_max_iterations = 1000;
  // Block IC(0) needs 6-12x fewer iterations than block Jacobi on stiff woven cloth and makes
  // the PCG step 4x faster (docs/benchmarks.md, "Simulator"); block Jacobi is kept to compare.
  PcgPreconditioner pcg_preconditioner = PcgPreconditioner::block_incomplete_cholesky;
  // CHOLMOD: a solve first tries the PCG preconditioned by the last factorisation (an earlier
  // step's, same size), to factor_reuse_tolerance within factor_reuse_iterations iterations, and
  // factorises only when that fails or the last such solve needed more than half of them
  // (NewtonSettings). 0: a factorisation every solve.
  // The PCG converges linearly, so its tolerance is close to CHOLMOD's own residual (1e-12 to
  // 1e-14): the adaptive 2 cm tee drapes within 0.1 µm of a factorisation every step; at 1e-6
  // its settling (chaotic under contact) took another path, at rest 0.25 s earlier, 10 mm away.
  int factor_reuse_iterations = 40;
  double factor_reuse_tolerance = 1.0e-9;
  double max_strain = 1.0;  // a step that stretches any triangle by more (100 %) fails
  double max_speed = 50.0;  // m/s, a step with a faster vertex fails
  // m; > 0 (implicit Euler only): the step follows a local error estimate instead of growing
  // back to dt after easy steps. Implicit Euler's position error over one step is about
  // (h/2)|v1 − v0| (h²/2 times the acceleration); the RMS of it over the vertices is held near
  // step_error: the next step is h·0.9·√(step_error/estimate), within [h/2, 2h] and [min_dt, dt].
  // No step is rejected for it. The run starts at dt/2 (nothing is known of the motion yet).
  // A swinging sheet takes short steps while it swings and long ones as it settles.
  double step_error = 0.0;
  int easy_steps_to_grow = 4;  // consecutive steps without trouble before the step grows
  double grow_factor = 2.0;    // capped at 2 for BDF2 (zero-stability needs ω < 1 + √2)
  // A drape stuck at the minimum step fails instead of creeping on for hours: when at least
  // stuck_share of the last stuck_steps accepted steps were forced (accepted at min_dt despite a
  // failed check), the next step is not taken and the run fails, naming the check and the vertex
  // (the most stretched one when the check is the strain limit). 0 steps: never. Drapes that
  // reach rest force no step at all (the trial-34 garments, the designs corpus); a hem drawn
  // 4 cm into the legs forced 342 steps in a row at 1.6e-5 s and 800 in its first 0.19 s
  // (docs/simulator.md, "Stuck drapes").
  int stuck_steps = 250;
  double stuck_share = 0.8;
  // A drape that had settled and is thrown about again fails before it blows up: once the
  // kinetic energy per kg has been below settled_energy (with the body still and the rest
  // shape no longer changing, rest_not_before), unsettled_retries steps retried within
  // unsettled_window seconds of simulated time stop the run, naming the place where the
  // attempts failed. Trial 35's strapless dress on the Collada human settled to 1.6e-6 J/kg by
  // 6.7 s, then its back, caught in the seat's cleft, was thrown about with 10-20 retries a
  // second until a vertex reached 497 m/s at 15.3 s (docs/collision.md, "Cloth caught in a
  // cleft"). The cloth must have moved first (its energy above settled_energy once): a scene
  // starting still has not settled (a stiff stress sheet, still at 0.03 s and retrying as it
  // fell, was stopped). 0 retries, the default: never; garment drapes set 10
  // (src/app/pipeline/cloth_scene.cpp).
  double settled_energy = 1.0e-5;  // J/kg
  int unsettled_retries = 0;
  double unsettled_window = 1.0;  // s
  bool stop_at_rest = true;
  double rest_speed = 5.0e-3;           // m/s, maximum vertex speed at rest
  double rest_kinetic_energy = 1.0e-6;  // J/kg, kinetic energy per unit mass at rest
  double rest_window = 0.25;            // s the two must stay below their thresholds
  // At rest: over rest_window no vertex moves farther than rest_speed·rest_window from where it
  // was when the window began (the window's mean speed, not the instantaneous one), with the
  // kinetic energy per kg over the window, its mean over time, below rest_kinetic_energy (a
  // patch chattering in place between contacts has a speed that flips every step: its energy
  // at one step can be twice its mean, while it goes nowhere).
  // s: the window starts no earlier (a rest shape still changing, AdaptiveMaterial::rest_ramp)
  double rest_not_before = 0.0;
  bool record_energy = true;  // energy time series in the report (one sample a step)
  // The sample of an accepted step taken from the next step's force evaluation where that one
  // is at the same state (implicit Euler without contact: Baraff-Witkin linearise at the start),
  // instead of a force evaluation of its own (a tenth of a pinned sheet's drape). The report's
  // series is the same; only an observer reading report().energy during the run sees it one
  // step behind (sketchdrape run --trace turns this off).
  bool energy_from_next_step = true;
  ForceSettings forces;
  ContactSettings contact;           // used once a body is set (set_body, set_body_motion)
  SelfContactSettings self_contact;  // cloth-cloth contact (off unless enabled)

  void validate() const;  // throws InvalidSimulationSettingsError
};

// Where a vertex of a refined or coarsened mesh comes from, in the numbering of the mesh it
// replaces: a = b for the same particle; a ≠ b for a vertex made on the edge between a and b;
// a = −1 when unknown (treated as a new particle).
struct VertexOrigin {
  int a = -1;
  int b = -1;
};

// A constrained vertex: fixed where it starts, or driven along `path` (position at time t).
struct Pin {
  int vertex = 0;
  std::function<Eigen::Vector3d(double)> path;
};

struct EnergySample {
  double time = 0.0;
  double stretch = 0.0;
  double shear = 0.0;
  double bend = 0.0;
  double kinetic = 0.0;
  double potential = 0.0;
};

// What ended (or kept from starting) a still stretch of the at-rest test at an accepted step,
// the first that holds in this order: the body still moving, before rest_not_before, no anchor
// to measure from (a mesh change that could not carry it), the kinetic energy (the step's and
// its mean over the window both at or above rest_kinetic_energy), a vertex farther than
// rest_speed·rest_window from the anchor.
enum class RestBreak { none, body_moving, too_early, new_anchor, kinetic_energy, drift };
std::string_view rest_break_name(RestBreak reason);

struct SimulationReport {
  int steps = 0;          // accepted steps
  double sim_time = 0.0;  // s simulated
  double wall_time_s = 0.0;
  // CPU time of the process (all threads) while `run` stepped, s: the stepping alone, without
  // loading the scene or writing output.
  double cpu_time_s = 0.0;
  bool at_rest = false;          // the run stopped early because the cloth was at rest
  int retries = 0;               // rejected attempts (each one halved the step or, for BDF2, was
                                 // retried at the same step linearised: a fallback)
  int integrator_fallbacks = 0;  // BDF2 steps retried as one linearised solve
  int forced_steps = 0;          // steps accepted at min_dt despite a soft failure (logged)
  bool nan_free = true;          // no accepted state had a non-finite value (always, by design)
  bool failed = false;           // a step could not be completed even at min_dt
  std::string failure_reason;
  int failure_vertex = -1;  // where: the fastest (or first non-finite) vertex of the failed step
  bool stuck = false;       // failed because it was stuck at the minimum step (stuck_steps)
  // failed because, once settled, it was thrown about again (SimulationSettings::settled_energy)
  bool unsettled = false;
  double settled_time = -1.0;  // s: when the drape first settled (settled_energy), −1: never
  int vertices = 0;
  int triangles = 0;
  int linear_solves = 0;
  // per linear solve (with CHOLMOD, those of the PCG on an earlier factor: factor_reuse_*)
  double cg_iterations_mean = 0.0;
  int cg_iterations_max = 0;
  // CHOLMOD's numeric factorisations and symbolic analyses (0 with the PCG); fewer
  // factorisations than linear solves where an earlier factor preconditioned the PCG.
  int cholmod_factorizations = 0;
  int cholmod_analyses = 0;
  double newton_iterations_mean = 0.0;  // per accepted step
  double dt_min_used = 0.0;
  double dt_max_used = 0.0;
  double forces_s = 0.0;     // wall time in force and Jacobian evaluation
  double solve_s = 0.0;      // in linear solves (PCG or CHOLMOD factor + solve)
  double collision_s = 0.0;  // in collider queries, body motion and contact bookkeeping
  double other_s = 0.0;      // the rest (bookkeeping, checks, energy samples, callbacks)
  double max_strain = 0.0;   // largest stretch strain at the end (warp or weft, max_stretch_strain)
  // Largest engineering principal strains at the end (max_principal_strain): stretch σ₁ − 1
  // and compression 1 − σ₂ in any direction, shear's included, which max_strain does not see.
  double max_principal_stretch = 0.0;
  double max_principal_compression = 0.0;
  // Body contact (zero without a body). Penetration is depth inside the body (negative signed
  // distance), measured after every accepted step; vertices still being pushed out of an
  // intersecting start are left out of it until their repair is over.
  int contacts_max = 0;                // most constrained contacts in one accepted step
  int contacts_final = 0;              // constrained contacts in the last step
  double max_penetration_m = 0.0;      // deepest penetration at the end of any accepted step
  int penetrating_vertices_final = 0;  // vertices deeper than the tolerance at the end
  // Body vertices more than the tolerance through the cloth's triangles at the end (a body
  // feature narrower than the cloth's triangles showing through), and the highest, m.
  // Measured whether or not ContactSettings::check_body_vertices keeps them out.
  int piercing_body_vertices_final = 0;
  double max_piercing_final_m = 0.0;
  int contact_resolves = 0;           // extra solves for vertices that ended a solve too deep
  int projected_vertices = 0;         // vertices projected out after the re-solves (last resort)
  int start_repair_vertices = 0;      // vertices that started inside the body
  double start_repair_depth_m = 0.0;  // deepest of them
  // The at-rest residual: the largest vertex speed (m/s) and kinetic energy per kilogram
  // (J/kg) over the accepted steps of the last rest_window seconds, and the last step's; the
  // kinetic energy's time mean over those steps, which the at-rest test bounds.
  double rest_speed_window = 0.0;
  double rest_kinetic_per_kg_window = 0.0;
  double rest_kinetic_per_kg_window_mean = 0.0;
  double rest_speed_final = 0.0;
  double rest_kinetic_per_kg_final = 0.0;
  // m: the largest displacement of a vertex since the current still stretch began (the whole
  // run's still steps when at rest), the figure the at-rest test bounds by rest_speed·rest_window.
  double rest_drift = 0.0;
  // s: how long the current still stretch has lasted (at rest needs rest_window of it); 0 when
  // the last step was not still.
  double rest_still_time = 0.0;
  // Why the last step did not continue a still stretch (RestBreak::none when it did): what a
  // drape that does not rest keeps doing (run --trace's "rest"). Whenever there was an anchor,
  // the vertex farthest from it and how far (m): with RestBreak::drift, the one that ended the
  // stretch; −1 and 0 without an anchor or with no vertex moved.
  RestBreak rest_break = RestBreak::none;
  int rest_break_vertex = -1;
  double rest_break_drift = 0.0;
  // Self-contact (zero when off; sim/self_contact.hpp).
  int self_intersections_start = 0;  // intersecting triangle pairs of the start
  int self_untangled_vertices = 0;   // vertices the start's untangling moved
  int self_untangle_left = 0;        // pairs the untangling could not separate
  // The warning logged when it left some ("21 pair(s) of cloth triangles pass through each
  // other at the start ... and stay so ..."), for report.json's warnings; empty otherwise.
  std::string self_untangle_warning;
  int self_contacts_max = 0;      // most repulsion springs in one accepted step
  int self_contacts_final = 0;    // in the last step
  int self_collisions = 0;        // colliding pairs the continuous test found, summed over steps
  int self_zone_vertices = 0;     // vertices moved rigidly by impact zones, summed over steps
  int self_unresolved_steps = 0;  // accepted steps whose fail-safe left a collision
  double self_collision_s = 0.0;  // wall time of self-contact (detection and response)
  // Share of the cloth's triangles inside regions the curvature test culled, over all steps.
  double self_culled_share = 0.0;
  long long self_culled_triangles = 0;  // summed over accepted steps (for the share)
  long long self_tested_triangles = 0;
  std::vector<EnergySample> energy;
};

struct StepOutcome {
  bool accepted = false;
  double dt = 0.0;  // the step that was taken
  int retries = 0;
  bool forced = false;  // accepted at min_dt despite a soft failure
  int newton_iterations = 0;
  int cg_iterations = 0;
  std::string failure_reason;  // when not accepted
  int failure_vertex = -1;     // when not accepted: the vertex where it broke (fastest)
  bool stuck = false;          // not taken: the run was stuck at the minimum step
  bool unsettled = false;      // not taken: settled once, the drape is thrown about again
};

class Simulation {
 public:
  // x0: 3n start positions (flattened, see flatten_positions). Velocities start at zero.
  Simulation(ClothModel model, Eigen::VectorXd x0, std::vector<Pin> pins,
             SimulationSettings settings);

  // One accepted step of at most min(current step, max_step), with retries. If it cannot be
  // completed even at min_dt the state is left unchanged and `accepted` is false.
  StepOutcome step(double max_step = 1e300);
  // Steps until `duration` (or at rest, or failure); calls on_step after each accepted step.
  SimulationReport run(const std::function<void(const Simulation&)>& on_step = {});
  // The run loop itself, for a driver that does more per step (sim/cloth_driver.hpp adapts the
  // mesh after each one): hooks.step takes one step of at most max_step (empty: step()), then,
  // for an accepted step, the energy is sampled and hooks.after_step is called; it is also
  // called with the failed outcome that ends the run. after_step returning false stops the run
  // after that step (the report is finished as for a run that reached its end).
  struct RunHooks {
    std::function<StepOutcome(double max_step)> step;
    std::function<bool(const StepOutcome&)> after_step;
  };
  SimulationReport run(const RunHooks& hooks);

  // Replaces the mesh (after an adaptive refine/coarsen) with matching 3n state; the BDF2
  // history restarts with an implicit Euler step.
  void replace_model(ClothModel model, Eigen::VectorXd x, Eigen::VectorXd v, std::vector<Pin> pins);
  // The same for a mesh refined or coarsened from the current one, origin[i] naming where new
  // vertex i comes from: the body contacts' memory of the last step (which contacts pressed
  // and how hard, per unit mass) carries over to the same particles, and to a vertex made
  // between two pressed ones, so that held contacts and friction do not restart at every
  // topology change.
  void replace_model(ClothModel model, Eigen::VectorXd x, Eigen::VectorXd v, std::vector<Pin> pins,
                     const std::vector<VertexOrigin>& origin);
  void set_velocities(const Eigen::VectorXd& v);
  // Gives the model's triangles the rest shapes (du, dv, rest_area, width_u, width_v) of `rest`,
  // the same triangles (same vertices, same order) with other rest shapes; masses, bending and
  // the state stay. For a rest shape that changes with time (AdaptiveMaterial::rest_ramp).
  // Throws std::invalid_argument for other triangles.
  void set_triangle_rest_shapes(const std::vector<TriangleElement>& rest);

  // The body the cloth rests on and cannot enter: a still mesh (metres, closed, counter-
  // clockwise seen from outside), or a pose sequence the body follows in simulation time
  // (from the current time on). Cloth vertices that start inside are pushed out over
  // settings.contact.repair_steps steps. Throws InvalidBodyMeshError / InvalidBodyMotionError.
  void set_body(const meshing::TriMesh& body);
  void set_body_motion(PoseSequence motion);
  void clear_body();
  bool has_body() const { return contact_ != nullptr; }
  // The contact state (collider, last step's contacts, start repair); null without a body.
  const ContactResponse* contact() const { return contact_.get(); }

  const ClothModel& model() const { return model_; }
  const SimulationSettings& settings() const { return settings_; }
  const Eigen::VectorXd& positions() const { return x_; }
  const Eigen::VectorXd& velocities() const { return v_; }
  double time() const { return time_; }
  double current_dt() const { return dt_; }
  // The step follows the local error estimate (SimulationSettings::step_error).
  bool error_controlled() const {
    return settings_.step_error > 0.0 && settings_.integrator == Integrator::implicit_euler;
  }
  bool at_rest() const {
    return rest_time_ >= settings_.rest_window &&
           report_.rest_kinetic_per_kg_window_mean < settings_.rest_kinetic_energy;
  }
  const SimulationReport& report() const { return report_; }
  EnergyBreakdown energy() const;
  // |S f(x, 0)|∞ over the free vertices, newtons: the residual force of a static state.
  double residual_force() const;

 private:
  struct Attempt {
    Eigen::VectorXd x, v;
    ImplicitSolveResult solve;   // the last solve
    Eigen::VectorXd correction;  // 3n contact position correction of the start (or empty)
    // Summed over the attempt's solves (more than one when contacts are re-solved).
    double forces_seconds = 0.0;
    double solve_seconds = 0.0;
    int linear_solves = 0;
    int cg_iterations = 0;
    int cg_iterations_max = 0;
    std::string failure;        // empty when the attempt passed every check
    int failure_vertex = -1;    // the fastest (or first non-finite) vertex of a failed attempt
    bool hard_failure = false;  // non-finite or too fast: never accepted
  };
  Attempt attempt(double h);
  void accept(Attempt& attempt, double h);
  void start_body();
  // Appends the pending energy sample (SimulationSettings::energy_from_next_step) from `energy`
  // when given, else from a force evaluation at the current state.
  void flush_energy_sample(const EnergyBreakdown* energy = nullptr);

  ClothModel model_;
  SimulationSettings settings_;
  std::vector<Pin> pins_;
  std::vector<Eigen::Vector3d> pin_rest_;
  Eigen::VectorXd x_, v_;
  Eigen::VectorXd x_previous_, v_previous_;
  bool has_history_ = false;
  bool fallback_ = false;     // the next attempt is one linearised solve (BDF2's Newton failed)
  int linearised_steps_ = 0;  // BDF2 steps still to take linearised after a fallback
  double h_previous_ = 0.0;
  double time_ = 0.0;
  double dt_ = 0.0;
  int easy_steps_ = 0;
  double rest_time_ = 0.0;
  // (time, largest speed, kinetic energy per kg, step) of the steps in the last rest window.
  std::vector<std::array<double, 4>> rest_history_;
  // Positions when the current still stretch began (empty: none yet). At rest asks how far the
  // cloth has moved since, not how fast it moves now: a vertex chattering in place between
  // contacts has a speed but goes nowhere (docs/simulator.md, "Step control and at rest").
  Eigen::VectorXd rest_anchor_;
  ConstraintFilter filter_;
  StepForces contact_forces_;  // friction drags and piercing springs of the current attempt
  ImplicitSolver solver_;
  std::unique_ptr<ContactResponse> contact_;
  std::unique_ptr<SelfContactResponse> self_contact_;  // null when self-contact is off
  SimulationReport report_;
  bool energy_pending_ = false;  // the sample of the current state is still to be appended
  long long newton_total_ = 0;
  long long cg_total_ = 0;
  // Whether each of the last stuck_steps accepted steps was forced, and how many were; the
  // last forced step's failed check and vertex (SimulationSettings::stuck_steps).
  std::deque<bool> recent_forced_;
  int recent_forced_count_ = 0;
  std::string last_forced_reason_;
  int last_forced_vertex_ = -1;
  double last_forced_dt_ = 0.0;
  // Since the drape settled (SimulationSettings::settled_energy): the times of the steps that
  // were retried within the last unsettled_window, and the last failed attempt's check and vertex.
  std::deque<double> unsettled_retry_times_;
  bool moved_ = false;  // the kinetic energy has been above settled_energy (settling needs it)
  std::string last_retry_reason_;
  int last_retry_vertex_ = -1;
};

}  // namespace sd::sim
