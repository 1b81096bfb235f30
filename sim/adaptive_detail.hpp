#pragma once
// Adaptive level of detail for the implicit cloth simulator (Birra & Santos 2008; DESIGN.md
// "Adaptive level of detail"): an AdaptiveCloth owns a 4-8 mesh and a Simulation on it. After
// every accepted step it estimates, per interior edge, how far the mesh is from a smooth surface,
// refines edges above a threshold (largest first, one level per block per step, forced splits
// as the 4-8 rules need) and merges blocks that are flat, steady and old enough; masses and
// velocities move with each split or merge so that total mass and linear momentum are conserved
// exactly, and the model is rebuilt only on steps where the topology changed. See
// docs/adaptive.md for the estimate, the rules, the transfer and measured figures.
//
// AdaptiveCloth orchestrates; the parts are the estimate (adaptive_estimate.hpp), the rules
// (adaptive_policy.hpp), the state transfer (adaptive_transfer.hpp) and the settings
// (adaptive_settings.hpp).

#include <Eigen/Core>
#include <array>
#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include "meshing/mesh48.hpp"
#include "sim/adaptive_estimate.hpp"
#include "sim/adaptive_policy.hpp"
#include "sim/adaptive_settings.hpp"
#include "sim/adaptive_transfer.hpp"
#include "sim/cloth_model.hpp"
#include "sim/fabric.hpp"
#include "sim/forces.hpp"
#include "sim/simulation.hpp"

namespace sd::sim {

// What the cloth is made of, beyond the mesh: fabric, bending rest shape and material frames.
struct AdaptiveMaterial {
  FabricParameters fabric;
  ClothModelOptions model_options;
  // Warp direction per input face (Mesh48::source_face of any triangle), #faces by 3, or empty:
  // then the in-plane direction closest to `up` (children's rest planes are their parent's, so
  // this is the parent's frame too).
  Eigen::MatrixX3d source_warp;
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  // Rest-shape scale per input face (a panel's `ease`, see scale_rest_shapes): #faces by 1
  // (isotropic) or by 2 (warp, weft), or empty: 1. Children inherit their input face's, so an
  // eased panel keeps its ease at every level; mass moves between triangles at the eased
  // density ρ·a·b.
  Eigen::MatrixXd source_ease;
  // Rest coordinates of each triangle of the mesh as given (ClothInput::rest_uv: a flattened
  // pattern's), or empty. The mesh must then be all level 0. A finer triangle gets its
  // coordinates from the level-0 triangle it lies in (Mesh48::root): the pattern map is affine
  // on it, and its vertices' rest positions are midpoints, so each vertex's coordinates are its
  // barycentric combination of the root's corners' (a split vertex is the midpoint in the
  // pattern too; a seam vertex keeps one position per piece, each triangle using its own).
  Eigen::MatrixXd rest_uv;
  // The rest ramp: with rest_uv and rest_ramp > 0 (s), the triangles' rest shapes start as
  // start_rest_uv (the same rows and frames: the drawn triangles' own coordinates, in which the
  // cloth starts unstrained) and move to rest_uv by the smoothstep 3a² − 2a³ of a = t/rest_ramp,
  // reaching it exactly at t = rest_ramp: a cloth cut from flat pieces is sewn up slowly instead
  // of being released 5-10 % stretched at once. Masses and bending are rest_uv's throughout.
  Eigen::MatrixXd start_rest_uv;
  double rest_ramp = 0.0;
};

// What one call of adapt() (or of the explicit operations) did.
struct AdaptStats {
  int splits = 0;         // requested splits made
  int forced_splits = 0;  // splits the 4-8 rules forced first
  int merges = 0;
  int moved_off_body = 0;           // split vertices moved out to the contact thickness
  int splits_declined_on_body = 0;  // requests not made: lifting E off the body would stretch
  int vertices = 0;                 // after the change
  int triangles = 0;
  double estimate_s = 0.0;    // wall time: error estimates and merge candidates
  double operations_s = 0.0;  // splits, merges, mass/velocity/pin transfer
  double rebuild_s = 0.0;     // compact, export, build_cloth_model, Simulation::replace_model
  bool changed() const { return splits + forced_splits + merges > 0; }
  // The state just before and after the change (measure_jumps only).
  ConservedQuantities before, after;
};

// The motion criterion's errors (AdaptiveSettings::motion_horizon), metres: how far the current
// mesh's motion over the horizon is from that of the mesh refined once everywhere.
struct MotionErrors {
  Eigen::VectorXd vertex;  // #V: at each vertex of the current mesh
  Eigen::VectorXd edge;    // per interior edge: the largest of its ends' and its midpoint's
};

// One accepted step: time after it and what the adaptation then did.
struct AdaptiveStepRecord {
  double time = 0.0;
  double dt = 0.0;
  int splits = 0;
  int forced_splits = 0;
  int merges = 0;
  int vertices = 0;
  int triangles = 0;
  int max_level = 0;
  bool measured = false;  // measure_jumps and the mesh changed
  ConservedQuantities before, after;
};

struct AdaptiveReport {
  SimulationReport simulation;  // wall time, solves, retries, energy series, ...
  int splits = 0;
  int forced_splits = 0;
  int merges = 0;
  int topology_changes = 0;         // steps on which the mesh changed (and the model was rebuilt)
  int moved_off_body = 0;           // split vertices moved out to the contact thickness
  int splits_declined_on_body = 0;  // per step, see split_stays_off_body
  int vertices_min = 0, vertices_max = 0;
  int max_level_reached = 0;
  // Body sags found by closest-point queries, and kept from an earlier step because the edge's
  // ends and the body had not moved (body_sags).
  long long body_sags_computed = 0;
  long long body_sags_reused = 0;
  double estimate_s = 0.0;
  double operations_s = 0.0;
  double rebuild_s = 0.0;
  std::vector<AdaptiveStepRecord> steps;
  double adaptivity_s() const { return estimate_s + operations_s + rebuild_s; }
};

class AdaptiveCloth {
 public:
  // mesh: a compact 4-8 mesh (e.g. fresh from Mesh48::from_quads), rest positions in metres.
  // positions: #V by 3 start positions by vertex id (empty: the rest positions). pins: vertex
  // ids (fixed where they start, or driven along a path). Throws InvalidAdaptiveSettingsError,
  // InvalidSimulationSettingsError, InvalidFabricError or InvalidClothError.
  AdaptiveCloth(meshing::Mesh48 mesh, AdaptiveMaterial material, Eigen::MatrixX3d positions,
                std::vector<Pin> pins, SimulationSettings simulation, AdaptiveSettings adaptive);
  ~AdaptiveCloth();
  AdaptiveCloth(AdaptiveCloth&&) noexcept;
  AdaptiveCloth& operator=(AdaptiveCloth&&) noexcept;

  // One accepted simulation step (see Simulation::step), then adapt() if it was accepted.
  StepOutcome step(double max_step = 1e300);
  // Steps until the duration, at rest or failure (Simulation::run's loop and report), adapting
  // after each step.
  AdaptiveReport run(const std::function<void(const AdaptiveCloth&)>& on_step = {});
  // The same with the loop's hooks (Simulation::RunHooks); hooks.step, when given, must take
  // its step through step() above (e.g. to stop at sample times, or change the mesh first).
  AdaptiveReport run(const Simulation::RunHooks& hooks);

  // Error estimates, then merges (flattest first) and splits (largest first) as the settings
  // allow; rebuilds the model only if something changed. Called by step().
  AdaptStats adapt();
  // Refinement ahead of the motion (AdaptiveSettings::lookahead > 0): splits, by the rule of
  // adapt(), the edges whose sag estimate is above the threshold now or at any step of a trial
  // run of `lookahead` seconds from the current state (same model, pins, settings and still
  // body, on a copy: the cloth is not changed). The first step() calls it until it changes
  // nothing (at most max_level times); a cloth that starts flat is then refined where it is
  // about to bend instead of after it has bent on the coarse mesh.
  AdaptStats refine_ahead();

  // Explicit operations through the same transfer and rebuild path (pre-refinement, tests).
  // Blocks that are no longer leaves (or, for merges, no longer mergeable) are skipped; max_level
  // and the budget are not applied.
  AdaptStats split_blocks(const std::vector<meshing::BlockId>& blocks);
  AdaptStats merge_blocks(const std::vector<meshing::BlockId>& blocks);
  // Splits every leaf block until all triangles are at `level` (a uniform fixed-resolution mesh),
  // except, with a body set, blocks whose new vertex could not be lifted off the body without
  // stretching the cloth (split_stays_off_body; counted in splits_declined_on_body).
  AdaptStats refine_uniformly(int level);

  // The body the cloth drapes on, as Simulation::set_body / set_body_motion (contacts, Coulomb
  // friction, start repair, swept end checks). The simulation and its collider live through
  // every split and merge (the hierarchy is never rebuilt; the per-vertex contact memory
  // restarts with each new numbering), and a split vertex that the midpoint rule puts closer to
  // the body than the contact thickness (a chord across a curved or sharp body) is moved out
  // to the thickness along the body's normal before the next step. Call before stepping.
  // Throws InvalidBodyMeshError / InvalidBodyMotionError.
  void set_body(const meshing::TriMesh& body);
  void set_body_motion(PoseSequence motion);
  void clear_body();
  bool has_body() const { return simulation_->has_body(); }

  const meshing::Mesh48& mesh() const { return mesh_; }  // compact between calls
  const Simulation& simulation() const { return *simulation_; }
  const AdaptiveSettings& settings() const { return settings_; }
  const AdaptiveReport& report() const { return report_; }
  double time() const { return simulation_->time(); }
  // Current positions and velocities, #V by 3 (row = vertex id).
  Eigen::MatrixX3d positions() const;
  Eigen::MatrixX3d velocities() const;
  // The masses carried through every split and merge (what the model uses), #V.
  const Eigen::VectorXd& masses() const { return masses_; }
  const Eigen::MatrixX3i& faces() const { return arrays_.faces; }            // #F by 3
  const Eigen::VectorXi& face_levels() const { return arrays_.face_level; }  // #F, for rendering
  // #F: the input face (quad) each triangle descends from (Mesh48::source_face).
  Eigen::VectorXi source_faces() const;
  const Eigen::MatrixX3d& rest_positions() const { return arrays_.rest_positions; }
  // Sag estimate ε per interior edge of the current mesh (rows of mesh().arrays().interior_edges)
  // for the current positions, metres: the larger of the bend sag |θ − θ0|·w/8 and, with a body
  // set, the body sag under the edge (body_sags).
  Eigen::VectorXd edge_errors();
  // Per interior edge with an end within reach of the body (the contact thickness plus its
  // search margin), how far the body's surface under the edge bulges out of the straight line
  // between the body points under its two ends, metres; 0 for the other edges, for edges whose
  // two triangles are at the finest level already (they cannot be refined), and without a
  // body. It is the sag the edge will have once the cloth lies on the body, known while the
  // cloth is still approaching: refining on it gives the cloth the resolution the body's
  // curvature asks for before the contact instead of after it. An edge whose ends and the body
  // moved less than half the coarsen threshold since its sag was found keeps that sag (counted
  // in AdaptiveReport::body_sags_reused), so a cloth lying still asks the body nothing; so does
  // an edge whose sag plus twice that motion stays below the refine threshold (it cannot decide
  // a split either way).
  Eigen::VectorXd body_sags();
  // The motion criterion at the current state (AdaptiveSettings::motion_horizon; zeros when it
  // is off, with pattern rest shapes, on the rest ramp, or when a trial step fails): one
  // implicit step of the horizon from the current positions and velocities on a copy of the
  // cloth as it is and on a copy with every leaf block below max_level split once (same pins,
  // settings and still body; the cloth is not changed). Per vertex of the refined copy, d =
  // |its displacement − the coarse displacement there| (the midpoint of its diagonal's for a
  // vertex the split made).
  MotionErrors motion_errors() const;
  // Σ m_i v_i, kg·m/s.
  Eigen::Vector3d linear_momentum() const;
  ConservedQuantities conserved_quantities() const;
  // Vertices that are pinned now (ids), sorted.
  std::vector<int> pinned_vertices() const;

 private:
  // The body's contact response when the simulation has one and contact is on; null otherwise.
  const ContactResponse* active_contact() const;
  // What the merge rules read (adaptive_policy.hpp) at the current state.
  MergeInputs merge_inputs() const;
  // Compacts the mesh and state, rebuilds the model and hands it to the simulation (creates the
  // simulation with first_settings on the first call). Returns the wall time taken.
  double rebuild(AdaptiveTransfer& state, const SimulationSettings* first_settings = nullptr);
  AdaptiveTransfer begin_transfer() const;
  // One change made on the mesh: the state follows it (adaptive_transfer.hpp) and a split vertex
  // inside the body is moved out to the contact thickness.
  void apply(const meshing::BlockChange& change, AdaptiveTransfer& state);
  bool split_stays_off_body(meshing::BlockId k, const Eigen::MatrixX3d& x) const;
  AdaptStats finish(AdaptiveTransfer& state, AdaptStats stats,
                    std::chrono::steady_clock::time_point operations_start);
  void count_split(const std::vector<meshing::BlockChange>& changes, AdaptiveTransfer& state,
                   AdaptStats& stats);
  // Splits the blocks on the edges of `refinements` (error, interior edge row; largest first),
  // each towards the level its error asks for (levels_asked), within max_level and the budget.
  void split_edges(const std::vector<std::pair<double, int>>& refinements, AdaptiveTransfer& state,
                   AdaptStats& stats);
  // How many levels an edge of sag `error` asks for: 1, or with target_levels
  // ⌈log2(error / refine_threshold)⌉.
  int levels_asked(double error) const;
  // Splits leaf block k, then the blocks its splits make, until their triangles reach `level`.
  void split_towards(meshing::BlockId k, int level, AdaptiveTransfer& state, AdaptStats& stats);
  // Per interior edge, the largest sag estimate over a trial run of `lookahead` seconds from the
  // current state (the simulation's own steps, on a copy; bend sags after each step, the body
  // sag where the trial ends). Zero where the trial's first step fails.
  Eigen::VectorXd preview_sags() const;
  void record(const StepOutcome& outcome, const AdaptStats& stats);

  meshing::Mesh48 mesh_;
  AdaptiveMaterial material_;
  AdaptiveSettings settings_;
  std::unique_ptr<Simulation> simulation_;
  meshing::Mesh48Arrays arrays_;
  Eigen::VectorXd masses_;     // #V, by vertex id
  std::vector<double> birth_;  // #F, simulated time each triangle was made
  std::vector<PinRecord> pins_;
  // The pattern rest shape (AdaptiveMaterial::rest_uv) per level-0 triangle: its rest
  // coordinates (#roots by 6), its corners' 3D rest positions (#roots by 9) and its rest area
  // over its 3D area (#roots); all empty without rest_uv.
  Eigen::MatrixXd root_uv_, root_rest_;
  Eigen::VectorXd root_area_scale_;
  // The rest ramp's start coordinates per level-0 triangle (#roots by 6), empty without a ramp.
  Eigen::MatrixXd root_start_uv_;
  // The rest coordinates of every triangle of the current mesh (rows of arrays_.faces), from
  // the roots' coordinates `roots` (root_uv_ or a blend on the ramp).
  Eigen::MatrixXd pattern_rest_uv() const { return pattern_rest_uv(root_uv_); }
  Eigen::MatrixXd pattern_rest_uv(const Eigen::MatrixXd& roots) const;
  // The buckling widths (ClothInput::buckling_width) of each level-0 triangle (#roots by 2):
  // its own rest extent along warp and weft, for the roots' coordinates `roots` (root_uv_ or a
  // blend on the ramp; empty without rest_uv: the 3D rest shape). Set on the first rebuild.
  Eigen::MatrixX2d root_width_;
  Eigen::MatrixX2d root_widths(const Eigen::MatrixXd& roots) const;
  // Those of every triangle of the current mesh: its level-0 ancestor's, so that a split or
  // merge keeps the Euler load that caps a buckled triangle's compression (docs/adaptive.md,
  // "A gathered panel that never rests").
  Eigen::MatrixX2d buckling_widths(const Eigen::MatrixX2d& roots) const;
  // The ease of every triangle of the current mesh (its input face's; #F by 2: warp, weft), or
  // empty without ease.
  Eigen::MatrixXd ease_scale() const;
  // The rest ramp's triangles at the current time (a = min(time() / rest_ramp, 1)), with ease:
  // build_cloth_model's triangles for the blended coordinates; rest_uv's exactly at a = 1.
  std::vector<TriangleElement> ramped_triangles() const;
  bool ramp_finished_ = true;    // no ramp, or the rest shapes have reached rest_uv
  EdgeRestGeometry edge_rest_;   // per interior edge (rows of arrays_.interior_edges)
  BodySagCache body_sag_cache_;  // carried through topology changes by rebuild
  meshing::TriMesh still_body_;  // the body of set_body, for the trial step; empty otherwise
  bool looked_ahead_ = false;    // refine_ahead has been called by the first step
  // The motion criterion: refinement before the first step done; the time of the next check.
  bool motion_started_ = false;
  double next_motion_check_ = 0.0;
  // Where each vertex of the last rebuild comes from (ids before its batch): the motion
  // criterion's refined copy reads it.
  std::vector<VertexOrigin> last_origin_;
  double next_change_ = 0.0;  // s: the next regular topology change (change_interval)
  AdaptiveReport report_;
};

}  // namespace sd::sim
