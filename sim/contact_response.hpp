#pragma once
// Body contact as constraints of the implicit step (Baraff & Witkin 1998 §5-6, with the
// active-set and friction treatment of Bridson et al. 2002): what the simulator does with the
// contacts the collider finds. Per step from t to t + h, with the body already at its pose
// for t + h:
//
//  1. Start contacts: every cloth vertex of the predicted start x̂ within `thickness` of the
//     body. Its normal velocity is constrained to the body's (filtered in PCG, eliminated in
//     CHOLMOD: the same ConstraintFilter), and if it would end closer than `thickness`, its
//     start is moved out along the normal first (the position correction y, which shifts the
//     state rather than adding a velocity, so a correction never turns into a bounce). A
//     contact whose constraint pulled the cloth towards the body in the last step is released.
//  2. Solve, with Coulomb friction. A contact pressed in the last step (normal force λ > 0)
//     has its friction inside the solve (implicit, so the cloth around it responds, and the
//     same for PCG and CHOLMOD): slower than `stick_speed` relative to the body, a drag
//     C = μ_s λ / stick_speed on its tangential velocity, which holds it (creep below
//     stick_speed) while the pull stays under μ_s λ; sliding, Coulomb's force −μ_k λ t̂
//     linearised at the start velocity (stopped after the solve if it would reverse the
//     motion). A new contact gets Coulomb's law after the solve from this step's normal impulse:
//     its tangential velocity is stopped if |v_t| ≤ μ_s Δv_n, else reduced by μ_k Δv_n.
//  3. End check (swept along each vertex's path, so a fast body cannot carry cloth through a
//     thin part unseen): vertices that ended deeper than `penetration_tolerance` inside or
//     passed through become constraints that land them at `thickness`, and the step is solved
//     again (at most `max_resolves` times). What is still too deep after that is projected
//     onto the surface (counted: it should not happen in practice).
//
// With `check_body_vertices`, body vertices are also kept behind the cloth triangles (sharp
// features: a cloth triangle can span a cone tip or a shoulder with its three corners
// outside). A body vertex through a triangle, or about to end the step closer than
// `kPiercingClearance`·thickness in front of it, pushes the triangle's point over it out to that
// clearance along the triangle's normal. The push is a critically damped spring of the implicit
// solve on the point's corners (PointSpring), on every triangle near the vertex, whose end force
// is carried to the next step and raised by the end check's re-solves: soft, so two body parts
// squeezing the cloth between them cannot ask for opposite motions of one corner, and never a
// jump in position. (Until 26 November the corners' normal velocities were constraints of the
// filter and what the re-solves left was lifted as a position change; that response failed
// where body parts close on the cloth, docs/collision.md.)
//
// The simulator (sim/simulation.hpp) drives this; it is separate so that the contact logic
// reads in one place and can be tested on its own.

#include <Eigen/Core>
#include <array>
#include <optional>
#include <stdexcept>
#include <vector>

#include "meshing/tri_mesh.hpp"
#include "sim/body_collider.hpp"
#include "sim/body_motion.hpp"
#include "sim/cloth_model.hpp"
#include "sim/collision_repair.hpp"
#include "sim/constraint_filter.hpp"
#include "sim/implicit_solver.hpp"

namespace sd::sim {

struct ContactSettings {
  bool enabled = true;       // with a body set; off: the body is ignored
  double thickness = 0.003;  // m: distance kept between a cloth vertex and the body surface
  // m: no vertex may end an accepted step deeper than this inside the body (signed distance
  // below −tolerance); deeper ones are re-solved as contacts, then projected.
  double penetration_tolerance = 0.001;
  // Coulomb coefficients of the cloth on the body. Unset: the fabric's `friction` for both.
  std::optional<double> static_friction;
  std::optional<double> kinetic_friction;
  // m/s: relative tangential speed below which a contact is in the stick regime; the largest
  // creep of a vertex held by static friction.
  double stick_speed = 5.0e-4;
  int max_resolves = 2;   // extra solves per step for vertices that ended too deep
  int repair_steps = 10;  // steps over which a garment starting inside the body is pushed out
  // Also keep body vertices from poking through cloth triangles (sharp features: shoulder tips,
  // elbows, corners). See docs/collision.md, "Body vertices poking through the cloth", for
  // what it does and costs.
  bool check_body_vertices = false;
  // Body-vertex springs with a band between catching and releasing (docs/collision.md,
  // "Catching and releasing body-vertex springs"): a spring never starts a step pulling its
  // point back onto the body vertex (a point farther than the clearance keeps its distance), a
  // held spring is released when its force turned adhesive (more than a tenth of its point's
  // weight, as contacts are) or its point is a thickness past the clearance, and caught again
  // only within the clearance. Off by default (measured: the flat capelet rests with it, but a
  // sheet hung on a cone tip is let 1.09 mm through and a sheet on a sphere rests later).
  bool spring_band = false;
  // The push a body-vertex spring carries to the next step fades linearly to nothing across the
  // hold margin past its clearance, so a spring whose point leaves the hold is released at no
  // load instead of still pushing (docs/collision.md, "The hem's cycle, traced": the pump of
  // the flat arms-lowering t-shirt's hem). Off by default (measured: the flat t-shirt, the flat
  // sleeveless dress and the two quadratic-bending skirts rest with it, sooner, but the hooded
  // top's neckline cycles until 8.6 s, at rest at 3.3 s without it).
  bool fade_carried_push = false;
  // Where a second body part faces the contact's surface closer than 2.5 thicknesses along
  // its normal, across the cloth (the armpit as the arm comes down, between the thighs), each
  // side's contact keeps a third of the gap (at least `pinch_floor` thicknesses) instead of the
  // full thickness, leaving the middle third free; so do the body-vertex springs, at most their
  // clearance (docs/collision.md, "A thickness budget for a pinch"). Without it a vertex in a
  // gap narrower than two thicknesses is pushed out of one side's band into the other's and
  // pushed back: a contact cycle that never rests. Cloth bridging a gap's opening (the back of
  // a skirt over the seat's cleft: both surfaces beside it, not across it) is not squeezed and
  // keeps the full thickness.
  bool pinch_budget = true;
  // The least share of a pinch a contact or a body-vertex spring keeps, in thicknesses. At the
  // default, half a thickness, a spring's share is its clearance; measured, a quarter left the
  // flat arms-lowering t-shirt moving more (docs/collision.md).
  double pinch_floor = 0.5;
  // Collider query parameters (see sim/body_collider.hpp, ContactQuery).
  double search_margin = 0.02;
  double max_substep_motion = 0.005;

  void validate() const;  // throws InvalidContactSettingsError
};

// A contact setting that cannot work (negative thickness, static friction below kinetic, ...).
class InvalidContactSettingsError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// One constrained contact of a step: the body contact and what the solve was asked for.
struct ActiveContact {
  BodyContact contact;
  double normal_velocity = 0.0;    // m/s prescribed along contact.normal
  bool released = false;           // near the body but left free (its constraint was adhesive)
  bool stuck = false;              // slower than stick_speed at the start: held by the drag
  bool repair = false;             // pushed out of an intersecting start (moving target)
  bool friction_in_solve = false;  // its friction was a term of the solve
  Eigen::Vector3d slide_direction = Eigen::Vector3d::Zero();  // sliding: t̂ at the start
};

// Per-step contact figures, summed into the simulation report.
struct ContactStepStats {
  int contacts = 0;              // constrained contacts in the final solve
  int released = 0;              // near the body but released
  int resolves = 0;              // extra solves for vertices that ended too deep
  int projected = 0;             // vertices projected out after the last solve
  int stuck = 0;                 // contacts in the stick regime (or stopped by friction)
  int repairing = 0;             // vertices still being pushed out of an intersecting start
  double max_penetration = 0.0;  // m, deepest vertex inside the body at the end (repair excluded)
  // Body vertices poking through cloth triangles (sharp features): springs in the solve,
  // re-solved like deep vertices. Measured at the end of the step.
  int piercings_held = 0;      // springs at the start of the step
  int piercings_resolved = 0;  // springs added or raised by the end check
  int piercing = 0;            // body vertices more than the tolerance through the cloth at the end
  double max_piercing = 0.0;   // m, highest body vertex above the cloth at the end (0: none)
  int penetrating = 0;         // vertices deeper than the tolerance at the end (repair excluded)
  double collision_seconds = 0.0;  // collider queries and body motion
};

// The body, its motion, the per-cloth contact cache and the memory between steps (which
// contacts were adhesive, the start repair). Owned by the Simulation.
class ContactResponse {
 public:
  ContactResponse(const meshing::TriMesh& body, ContactSettings settings);
  ContactResponse(PoseSequence motion, double start_time, ContactSettings settings);

  const ContactSettings& settings() const { return settings_; }
  const BodyCollider& collider() const { return collider_; }
  const PoseSequence* motion() const { return motion_ ? &*motion_ : nullptr; }
  const StartRepair& start_repair() const { return repair_; }
  bool repairing() const { return repair_step_ < repair_.steps && !repair_.empty(); }
  // Contacts of the last accepted step (constrained and released).
  const std::vector<ActiveContact>& contacts() const { return accepted_contacts_; }
  // Per cloth vertex, the normal force of its constrained contact in the last accepted step
  // (N; negative: the constraint pulled; NaN: none). After reset_cloth for a cloth that was
  // refined or coarsened (adaptive detail), the caller hands this memory back in the new
  // numbering, so that held contacts, friction inside the solve and releases carry on across
  // the change. `forces` must have one entry per vertex of the new cloth.
  const std::vector<double>& last_normal_forces() const { return last_normal_force_; }
  void restore_normal_forces(std::vector<double> forces);

  // The cloth's triangles, for the check of body vertices poking through them (sharp body
  // features). Without them (never called, or an empty model) only cloth vertices are checked.
  // Call with reset_cloth whenever the triangles change.
  void set_cloth_triangles(const ClothModel& model);

  // A new cloth (first call, or vertices renumbered by replace_model): resets the cache and the
  // memory of the last step, and plans the push-out of vertices inside the body. A repair in
  // progress is planned again for its remaining steps.
  // mass: #V lumped masses (kg); gravity: |g| (m/s²), which scale the force that releases a
  // contact.
  void reset_cloth(const Eigen::VectorXd& x, const Eigen::VectorXd& mass, double gravity);

  // Moves the body to its pose at t + h (a step from t). Handles retried steps.
  void move_body_to(double t, double h);

  // Step 1: start contacts of x̂ (3n) into `filter` (pins stay pins), the position correction
  // y (3n) the caller adds to x̂ and to the linearisation point, and the stick-regime friction
  // drags for the solve. v0: velocities at the start of the step (3n).
  void constrain_start(const Eigen::VectorXd& x_hat, const Eigen::VectorXd& v0, double beta,
                       ConstraintFilter& filter, Eigen::VectorXd& y, StepForces& extra);

  // Step 2: Coulomb friction on the sliding and new contacts, from the solve's constraint
  // impulse (3n, N·s). Changes v1 and x1 = x̂ + β v1 of those vertices.
  void apply_friction(const Eigen::VectorXd& impulse, const Eigen::VectorXd& mass,
                      const Eigen::VectorXd& x_hat, double beta, Eigen::VectorXd& v,
                      Eigen::VectorXd& x);

  // Step 3: swept check of the path x0 (previous pose) → x1 (current pose). Vertices deeper
  // than the tolerance (or that passed through) become constraints in `filter` (and y for the
  // ones already too close at x̂); body vertices more than the tolerance through the cloth get
  // a spring in `extra`, or raise theirs. Returns how many were added or raised, 0 when the
  // step is clean.
  int constrain_deep(const Eigen::VectorXd& x0, const Eigen::VectorXd& x1,
                     const Eigen::VectorXd& x_hat, double beta, ConstraintFilter& filter,
                     Eigen::VectorXd& y, StepForces& extra);

  // After the last solve: projects the vertices the last end check found too deep onto
  // point + thickness·normal with the body's normal velocity, remembers the springs' end
  // forces (`extra`: the step's forces) for the next step, and measures the penetration and
  // piercing.
  void finish_step(Eigen::VectorXd& x, Eigen::VectorXd& v, const StepForces& extra);

  ContactStepStats& step_stats() { return stats_; }
  const ContactStepStats& step_stats() const { return stats_; }

  // The step was accepted: remember which contacts pulled (release next step) and advance the
  // start repair.
  void accept_step(const Eigen::VectorXd& impulse);

  // Vertices of x (3n) deeper than the tolerance inside the body at its current pose.
  int count_penetrating(const Eigen::VectorXd& x, double* deepest = nullptr) const;
  // Body vertices more than the tolerance through the cloth triangles (set_cloth_triangles) at
  // x, whether or not check_body_vertices keeps them out: what a preview shows as the body
  // poking through. `highest`: the largest height through, m (0 when none). Where a body vertex's
  // closest cloth point is a corner or an edge, it is sided by the cloth's pseudo-normal there.
  int count_piercing(const Eigen::VectorXd& x, double* highest = nullptr) const;
  // The cloth's own friction coefficient (FabricParameters::friction), used for whichever of
  // the two coefficients the settings leave unset.
  void set_fabric_friction(double friction) { fabric_friction_ = friction; }
  double static_friction() const { return settings_.static_friction.value_or(fabric_friction_); }
  double kinetic_friction() const { return settings_.kinetic_friction.value_or(fabric_friction_); }

 private:
  ContactQuery query() const;
  // Constrains one contact's normal velocity so that it ends at `thickness` (moving x̂ + y out
  // first when it is already too close); `allow_release`: leave it free if it was adhesive.
  // Returns the index of its ActiveContact.
  int add_contact(const BodyContact& contact, double thickness, const Eigen::VectorXd& x_hat,
                  double beta, ConstraintFilter& filter, Eigen::VectorXd& y, bool allow_release);
  // m: the distance a contact keeps its vertex from the body: the thickness, or with
  // pinch_budget a third of the gap to a body part facing it across a pinch. x: the cloth's
  // positions (3n), for the cloth's normal at the vertex (inside a gap or bridging its opening).
  double contact_thickness(const BodyContact& contact, const Eigen::VectorXd& x) const;
  // m: the clearance a body-vertex spring keeps between its body vertex and the cloth: half
  // the thickness, or with pinch_budget at most a third of the gap to a body part facing the
  // vertex across the cloth. x: the cloth's positions the piercing was found at.
  double spring_clearance(const BodyPiercing& p, const Eigen::VectorXd& x) const;
  // m: with pinch_budget, the gap from `point` on the body along its outward `normal` to a body
  // surface facing it within kPinchGapThicknesses thicknesses, when that surface lies across the
  // cloth (the gap runs along `cloth_normal`, any length and sign); none when nothing faces it
  // or the cloth bridges the gap's opening (the facing surface beside it, not across it).
  std::optional<double> pinch_gap(const Eigen::Vector3d& point, const Eigen::Vector3d& normal,
                                  const Eigen::Vector3d& cloth_normal) const;
  // The cloth's area-weighted normal at vertex `v` of x (3n), any orientation; zero without
  // triangles (set_cloth_triangles).
  Eigen::Vector3d cloth_vertex_normal(int v, const Eigen::VectorXd& x) const;
  // m: body vertices farther than this through the cloth are not looked for.
  double piercing_reach() const;
  // Piercings of x1 whose body vertex is more than `min_height` through the cloth; none when
  // check_body_vertices is off.
  std::vector<BodyPiercing> find_piercings(const Eigen::VectorXd& x1, double min_height,
                                           bool every_triangle = false) const;
  // The same whether or not the check is on (what count_piercing measures).
  std::vector<BodyPiercing> piercings_of(const Eigen::VectorXd& x, double min_height,
                                         bool every_triangle = false) const;
  // Normal forces (N) of the last solve's contacts from its constraint impulse (3n, N·s), per
  // cloth vertex into last_normal_force_.
  void record_normal_forces(const Eigen::VectorXd& impulse);
  // The spring that pushes piercing p's triangle to the clearance in
  // front of its body vertex, from positions x (the body at its end pose), with `preload`.
  PointSpring piercing_spring(const BodyPiercing& p, const Eigen::VectorXd& x,
                              const std::vector<unsigned char>& pinned, double preload,
                              double clearance) const;
  // The largest preload a spring carries (N): kMaxSpringLoadClothWeights times the cloth's
  // weight.
  double max_spring_preload() const;
  // m: how far past the clearance piercing_spring puts a spring's target (with spring_band, a
  // point already farther keeps its distance; 0 otherwise).
  double target_past_clearance(const BodyPiercing& p, double clearance) const;
  // kg: the cloth mass at a piercing's point (its triangle's corner masses by its weights).
  double point_mass(const BodyPiercing& p) const;
  // Start of step: body vertices through the cloth at `start` (x̂ + y), about to be, or held
  // last step, become springs in `extra`.
  void spring_start_piercings(const Eigen::VectorXd& start, const Eigen::VectorXd& v0, double beta,
                              const ConstraintFilter& filter, StepForces& extra);
  // End check: a piercing of x1 gets a spring, or its spring's preload rises by the springs'
  // force at x1. Returns how many changed.
  int spring_end_piercings(const Eigen::VectorXd& x1, StepForces& extra);
  // The force (N; negative: it ended pulling) each spring of this attempt ends with at x, to
  // carry to the next step.
  void record_spring_forces(const Eigen::VectorXd& x, const StepForces& extra);

  ContactSettings settings_;
  BodyCollider collider_;
  std::optional<PoseSequence> motion_;
  double body_time_ = 0.0;  // time of the collider's current pose
  ContactCache cache_;
  StartRepair repair_;
  bool repair_planned_ = false;
  int repair_step_ = 0;  // accepted steps of the repair so far
  double fabric_friction_ = 0.3;
  // Per vertex: normal force of its contact in the last accepted step (N, < 0: adhesive), NaN
  // when it had no constrained contact.
  std::vector<double> last_normal_force_;
  Eigen::VectorXd release_force_;         // per vertex, N: an adhesive force above this releases
  double beta_ = 0.0;                     // β of the step being solved
  std::vector<unsigned char> in_repair_;  // 1 for vertices the start repair is pushing
  // Current attempt.
  std::vector<ActiveContact> active_;
  std::vector<int> active_index_;      // per vertex: index into active_, or −1
  std::vector<BodyContact> too_deep_;  // from the last end check, after the last solve
  std::vector<BodyContact> end_contacts_;
  ClothTriangles cloth_;                 // the cloth's triangles (set_cloth_triangles)
  std::vector<BodyPiercing> piercings_;  // from the last end check, after the last solve
  // Per body vertex: the force (N, along the triangles' normals; < 0: it ended pulling) its
  // springs ended the last accepted step with, NaN when it had none.
  std::vector<double> last_piercing_force_;
  std::vector<unsigned char> pinned_;  // per cloth vertex, pinned in the step's filter
  Eigen::VectorXd mass_;               // per cloth vertex, kg
  double gravity_ = 9.81;              // m/s²
  // Per spring of the attempt's StepForces, its body vertex.
  std::vector<int> spring_body_vertex_;
  // Per spring of the attempt's StepForces, m its target lies past the clearance in front of its
  // body vertex (target_past_clearance).
  std::vector<double> spring_past_clearance_;
  // How a spring ended a step: its pair and the force (N; negative: it ended pulling).
  struct SpringEnd {
    int body_vertex = -1;
    int triangle = -1;
    double force = 0.0;
    Eigen::Vector3d point = Eigen::Vector3d::Zero();  // m: the spring's point on the cloth
  };
  // This attempt's springs at its end (record_spring_forces), and those of the last accepted
  // step, whose pairs the next start follows even where find_piercings does not report them (a
  // body vertex in front of a cloth edge).
  std::vector<SpringEnd> spring_ends_;
  std::vector<SpringEnd> held_springs_;
  ContactStepStats stats_;
  std::vector<ActiveContact> accepted_contacts_;
};

}  // namespace sd::sim
