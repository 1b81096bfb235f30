#pragma once
// Adaptive level of detail for the implicit cloth simulator (Birra & Santos 2008; DESIGN.md
// "Adaptive level of detail"): an AdaptiveCloth owns a 4-8 mesh and a Simulation on it. After
// every accepted step it estimates, per interior edge, how far the mesh is from a smooth surface,
// refines edges above a threshold (largest first, one level per block per step, forced splits
// as the 4-8 rules need) and merges blocks that are flat, steady and old enough; masses and
// velocities move with each split or merge so that total mass and linear momentum are conserved
// exactly, and the model is rebuilt only on steps where the topology changed. See
// docs/adaptive.md for the estimate, the rules, the transfer and measured figures.

#include <array>
#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "meshing/mesh48.hpp"
#include "sim/cloth_model.hpp"
#include "sim/fabric.hpp"
#include "sim/forces.hpp"
#include "sim/simulation.hpp"

namespace sd::sim {

// An adaptive setting that cannot work (negative threshold, max level below min level, ...).
class InvalidAdaptiveSettingsError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// Thresholds of the adaptive level of detail. The error estimate of an interior edge is the sag
// of the polygon across it, ε = |θ − θ0|·w/8 in metres (θ the dihedral angle in rad, θ0 its
// rest value, w = (A1 + A2)/|e| the mean height of the two rest triangles): the distance
// between the mesh and a circular arc through the two triangles. The merge error of a split
// block is |x_E − (x_B + x_C)/2| in metres: exactly how far merging moves the surface.
struct AdaptiveSettings {
  bool enabled = true;               // false: a fixed mesh (no estimates, no operations)
  double refine_threshold = 2.0e-3;  // m: split an edge whose sag estimate is larger
  // m: merge a block whose merge moves the surface less. Must be below refine_threshold (the
  // gap is the hysteresis that keeps a merged block from being split back at once).
  double coarsen_threshold = 5.0e-4;
  // rad/s: merge only if every hinge around the split vertex turns slower than this
  // (dθ/dt = Σ ∂θ/∂x_i · v_i, Birra & Santos §4.1).
  double steady_rate = 0.05;
  double min_lifetime = 0.25;  // s of simulated time a triangle lives before it may be merged
  int min_level = 0;           // coarsest level a merge may return to
  int max_level = 6;           // finest triangle level a split may make
  int max_vertices = 0;        // particle budget (0: none); forced splits may exceed it slightly
  // Merges wait until they can share the model rebuild that a split makes anyway, or until at
  // least this fraction of the particles can be merged at once: a rebuild (and CHOLMOD's new
  // analysis) costs about half a step, more than the two or three particles a lone batch of
  // merges frees would save. 0: merge whenever a block qualifies.
  double merge_batch = 0.05;
  // Keep the leaves on even levels (0, 2, 4, ... of the input mesh): a complete block at an odd
  // level is split on the step after the split that made it, whatever its estimate, and an even
  // block merges together with its split children (two levels in one step, each merge judged as
  // usual). The edge directions of a 4-8 mesh turn
  // by 45° with each level, and where a cloth folds all at once (a sheet landing on a body) the
  // fold pattern follows them: a mesh that mixes levels of both parities folds unlike any fixed
  // level (docs/adaptive.md, "Even levels"). Only the strip around a refined region, where the
  // level rule needs it, stays odd.
  bool even_levels = false;
  bool refine = true;
  bool coarsen = true;
  // Measure energies, total mass and linear momentum just before and just after each topology
  // change (two extra force evaluations on those steps) and keep them in the step record: for
  // tests and studies.
  bool measure_jumps = false;

  void validate() const;  // throws InvalidAdaptiveSettingsError
};

// What the cloth is made of, beyond the mesh: fabric, bending rest shape and material frames.
struct AdaptiveMaterial {
  FabricParameters fabric;
  ClothModelOptions model_options;
  // Warp direction per input face (Mesh48::source_face of any triangle), #faces by 3, or empty:
  // then the in-plane direction closest to `up` (children's rest planes are their parent's, so
  // this is the parent's frame too).
  Eigen::MatrixX3d source_warp;
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  // Rest-shape scale per input face (a panel's `ease`, see scale_rest_shapes), or empty: 1.
  // Children inherit their input face's, so an eased panel keeps its ease at every level; mass
  // moves between triangles at the eased density ρ·e².
  Eigen::VectorXd source_ease;
};

// What a topology change must conserve (mass, momentum) or may change only within a bound
// (energies; see docs/adaptive.md).
struct ConservedQuantities {
  double mass = 0.0;                                  // kg
  Eigen::Vector3d momentum = Eigen::Vector3d::Zero();  // kg·m/s
  EnergyBreakdown energy;                              // J
};

// What one call of adapt() (or of the explicit operations) did.
struct AdaptStats {
  int splits = 0;         // requested splits made
  int forced_splits = 0;  // splits the 4-8 rules forced first
  int merges = 0;
  int moved_off_body = 0;  // split vertices moved out to the contact thickness
  int splits_declined_on_body = 0;  // requests not made: lifting E off the body would stretch
  int vertices = 0;       // after the change
  int triangles = 0;
  double estimate_s = 0.0;    // wall time: error estimates and merge candidates
  double operations_s = 0.0;  // splits, merges, mass/velocity/pin transfer
  double rebuild_s = 0.0;     // compact, export, build_cloth_model, Simulation::replace_model
  bool changed() const { return splits + forced_splits + merges > 0; }
  // The state just before and after the change (measure_jumps only).
  ConservedQuantities before, after;
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
  int topology_changes = 0;  // steps on which the mesh changed (and the model was rebuilt)
  int moved_off_body = 0;    // split vertices moved out to the contact thickness
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
  // Steps until the duration, at rest or failure (as Simulation::run), adapting after each.
  AdaptiveReport run(const std::function<void(const AdaptiveCloth&)>& on_step = {});

  // Error estimates, then merges (flattest first) and splits (largest first) as the settings
  // allow; rebuilds the model only if something changed. Called by step().
  AdaptStats adapt();

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
  const Eigen::MatrixX3i& faces() const { return arrays_.faces; }      // #F by 3
  const Eigen::VectorXi& face_levels() const { return arrays_.face_level; }  // #F, for rendering
  const Eigen::MatrixX3d& rest_positions() const { return arrays_.rest_positions; }
  // Sag estimate ε per interior edge of the current mesh (rows of mesh().arrays().interior_edges)
  // for the current positions, metres: the larger of the bend sag |θ − θ0|·w/8 and, with a body
  // set, the body sag under the edge (body_sags).
  Eigen::VectorXd edge_errors() const;
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
  Eigen::VectorXd body_sags() const;
  // Σ m_i v_i, kg·m/s.
  Eigen::Vector3d linear_momentum() const;
  ConservedQuantities conserved_quantities() const;
  // Vertices that are pinned now (ids), sorted.
  std::vector<int> pinned_vertices() const;

 private:
  struct PinRecord {
    int vertex = 0;
    std::function<Eigen::Vector3d(double)> path;  // empty: fixed at `fixed`
    Eigen::Vector3d fixed = Eigen::Vector3d::Zero();
  };
  // Sag estimate |θ − θ0|·w/8 of the hinge (x0, x1, x2, x3) at dihedral angle theta, from the
  // rest shape of the current mesh (ids).
  double hinge_sag(const std::array<int, 4>& hinge, double theta) const;
  // m: vertices closer to the body than this get a body sag (contact thickness + search margin).
  double body_reach() const;
  // Whether an interior edge (row of the mesh's interior edges) has a triangle below max_level.
  bool refinable(Eigen::Index edge) const;
  // A triangle made less than min_lifetime ago (may not be merged away yet).
  bool is_young(meshing::TriangleId t, double now) const;
  // Whether a hinge (bending's vertex order) sags less than the coarsen threshold, and, for
  // hinge_is_quiet, also turns slower than steady_rate (dθ/dt = Σ ∂θ/∂x_i · v_i).
  bool hinge_is_flat(const std::array<int, 4>& hinge, const Eigen::VectorXd& x) const;
  bool hinge_is_quiet(const std::array<int, 4>& hinge, const Eigen::VectorXd& x,
                      const Eigen::VectorXd& v) const;
  // The merge error |x_E − (x_B + x_C)/2| of split block k (children leaves) if it may merge
  // now (old enough, flat and steady around E, outer edges flat, no body under its diagonal).
  std::optional<double> merge_error(meshing::BlockId k, const Eigen::VectorXd& x,
                                    const Eigen::VectorXd& v, double now) const;
  // even_levels' merge candidates: even blocks that merge with their split children at once.
  std::vector<std::pair<double, meshing::BlockId>> even_level_merges(const Eigen::VectorXd& x,
                                                                     const Eigen::VectorXd& v,
                                                                     double now) const;
  // After a topology change: keeps the body-sag memory of every edge whose two ends were joined
  // before (old_edges: the interior edges before it; origin: per new vertex, its old id).
  void carry_body_sag_memory(const Eigen::MatrixX4i& old_edges,
                             const std::vector<VertexOrigin>& origin);
  // Body sag (see body_sags) under the edge xi–xj, 0 when neither end is within reach; at_i,
  // at_j: the body points under the ends if already known. Needs a body.
  double body_sag(const Eigen::Vector3d& xi, const Eigen::Vector3d& xj,
                  const BodyProximity* at_i = nullptr, const BodyProximity* at_j = nullptr) const;
  struct Transfer;  // the state by vertex/triangle id while a batch of changes is applied

  // Compacts the mesh and state, rebuilds the model and hands it to the simulation (creates the
  // simulation with first_settings on the first call). Returns the wall time taken.
  double rebuild(Transfer& state, const SimulationSettings* first_settings = nullptr);
  Transfer begin_transfer() const;
  void apply(const meshing::BlockChange& change, Transfer& state);
  // Moves the split vertex `e` (row of state.x) out to the contact thickness if the body is
  // closer than that (splits that would need more than safe_lift are declined before).
  void keep_off_body(int e, Transfer& state) const;
  // The rest-shape scale of triangle t (its input face's ease, 1 without), and of an input face.
  double ease(meshing::TriangleId t) const;
  double face_ease(int source_face) const;
  // False when splitting block k would put its new vertex so deep inside the body (a chord of a
  // coarse block across a sharp body feature, or of a flat block) that moving it out to the
  // contact thickness would stretch its children by more than a few per cent; such blocks stay
  // coarse (and are counted in splits_declined_on_body).
  bool split_stays_off_body(meshing::BlockId k, const Eigen::MatrixX3d& x) const;
  AdaptStats finish(Transfer& state, AdaptStats stats,
                    std::chrono::steady_clock::time_point operations_start);
  void count_split(const std::vector<meshing::BlockChange>& changes, Transfer& state,
                   AdaptStats& stats);
  void record(const StepOutcome& outcome, const AdaptStats& stats);

  meshing::Mesh48 mesh_;
  AdaptiveMaterial material_;
  AdaptiveSettings settings_;
  std::unique_ptr<Simulation> simulation_;
  meshing::Mesh48Arrays arrays_;
  Eigen::VectorXd masses_;        // #V, by vertex id
  std::vector<double> birth_;     // #F, simulated time each triangle was made
  std::vector<PinRecord> pins_;
  Eigen::VectorXd edge_rest_angle_;  // per interior edge (rows of arrays_.interior_edges), rad
  Eigen::VectorXd edge_width_;       // per interior edge: (A1 + A2)/|e| in the rest shape, m
  // The body sag each interior edge was last given, with where its ends and the body were then
  // (body_sags reuses it while they stay put; carried through topology changes by rebuild).
  struct BodySagMemory {
    Eigen::Vector3d xi = Eigen::Vector3d::Zero(), xj = Eigen::Vector3d::Zero();
    double body_motion = 0.0;  // BodyCollider::total_motion at the time
    double sag = 0.0;
    bool valid = false;
  };
  mutable std::vector<BodySagMemory> body_sag_memory_;
  mutable long long body_sags_computed_ = 0, body_sags_reused_ = 0;
  AdaptiveReport report_;
  long long newton_total_ = 0;
  long long cg_total_ = 0;
};

}  // namespace sd::sim
