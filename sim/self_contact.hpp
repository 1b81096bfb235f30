#pragma once
// Cloth-cloth contact as the simulator handles it (detection in sim/self_collision.hpp). Per
// step from x0 to x1:
//
//  1. Repulsion inside the implicit solve: every vertex-face and edge-edge pair closer than
//     `thickness` at the step's start and not already separating becomes a PairSpring pushing it
//     a tenth of the way to `thickness` (a bounded repulsion, as Bridson et al. 2002 §7.2),
//     critically damped, its stiffness m ω² sized from the pair's effective mass m = 1/Σ w_k²/m_k
//     (as the body's piercing springs are), so its strength follows the cloth's resolution.
//  2. Friction between the layers inside the same solve: every pair closer than `thickness` that
//     carried a normal force in the last accepted steps (lagged, mean of two steps), or that gets
//     a spring now, gets a tangential dashpot on its relative velocity, c_t = μ F / max(|v_t|,
//     ε) with |v_t| the pair's tangential speed at the step's start (Coulomb's force μF for a
//     sliding pair; a pair slower than ε = 1 mm/s is held as hard as μF allows, creeping at most
//     ε·(tangential load / μF)), at most kMaxStick effective masses per β. The solve sees it, so
//     a sticking pair holds its neighbours too (a post-solve impulse held only the pair's four
//     vertices, and the t-shirt's underarm never came to rest).
//  3. Fail-safe: a continuous test of the straight paths x0 → x1. Every colliding pair gets an
//     inelastic impulse that lands it `kSeparation`·thickness apart on the side it came from, or
//     where it started when it started closer than that (Gauss-Seidel over the pairs,
//     `impulse_passes` times); pairs that still collide are merged into impact zones (Provot 1997;
//     Bridson et al. 2002 §7.4) that move rigidly over the step (the mass-weighted translation and
//     rotation of their vertices), growing until no path collides. A cloth that starts the step
//     free of intersections ends it free of them.
//
// Pinned vertices are immovable (infinite mass) in the impulses; a zone holding a pinned vertex
// moves with the pins' mean displacement. Vertices the body's contact holds are heavy, so that
// cloth pinched between cloth and body gives way on its free side rather than into the body.

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <limits>
#include <unordered_map>
#include <vector>

#include "sim/cloth_model.hpp"
#include "sim/implicit_solver.hpp"
#include "sim/self_collision.hpp"

namespace sd::sim {

// resolve()'s mark of a vertex the body's contact constrains this step.
constexpr unsigned char kHeldByBody = 2;

struct SelfContactSettings {
  bool enabled = false;
  double thickness = 0.002;  // m: distance kept between two layers of the cloth
  // m: the continuous test's tolerance; paths that come closer than this collide.
  double collision_tolerance = 1.0e-5;
  bool culling = true;       // curvature culling of flat regions (sim/self_collision.hpp)
  int impulse_passes = 3;    // rounds of impulses before impact zones take over
  int max_zone_passes = 64;  // rounds of zone growth; then the whole cloth moves rigidly
  // Coulomb coefficient between two layers; negative: the fabric's own friction.
  double friction = -1.0;

  void validate() const;  // throws std::invalid_argument naming the setting
};

struct SelfContactStepStats {
  int springs = 0;          // repulsion springs in the solve
  int collisions = 0;       // colliding pairs found by the first continuous test
  int impulse_rounds = 0;   // continuous tests with impulses after the first
  int zone_rounds = 0;      // rounds of impact-zone growth
  int zone_vertices = 0;    // vertices moved rigidly
  bool unresolved = false;  // collisions left after every round (should not happen)
  int triangles = 0;
  int culled_triangles = 0;  // in regions the curvature test declared safe (start query)
  double seconds = 0.0;      // wall time of everything above
};

class SelfContactResponse {
 public:
  explicit SelfContactResponse(SelfContactSettings settings);

  const SelfContactSettings& settings() const { return settings_; }
  // A new or changed mesh (adaptive refinement renumbers it): rebuilds the tree at x (3n).
  void set_cloth(const ClothModel& model, const Eigen::VectorXd& x);
  void set_fabric_friction(double friction) { fabric_friction_ = friction; }
  double friction() const {
    return settings_.friction >= 0.0 ? settings_.friction : fabric_friction_;
  }

  // A start that passes through itself (a folded quad of a designed garment): the vertices of
  // the intersecting triangles and their neighbours are smoothed (each moved halfway to the mean
  // of its neighbours, pinned ones kept) in growing rings until no pair intersects, at most 120
  // rounds. Returns the vertices moved; `found`: pairs at the start, `remaining`: after.
  // A round that would stretch a triangle beyond `max_strain` (the simulator's stretch measure,
  // max_stretch_strain) is undone and the untangling stops there, leaving the pairs it could not
  // separate: smoothing a crumpled region with sliver quads (a corner of 0.1°) stretched the
  // Collada top's sleeve by 761 %, every first step was rejected for its strain down to the
  // minimum step, and the drape failed with a push-out speed of 90 m/s (docs/collision.md,
  // "An untangled start"). `where` (optional): the centre of one pair left, m.
  int untangle(const ClothModel& model, Eigen::VectorXd& x,
               const std::vector<unsigned char>& pinned, int* found = nullptr,
               int* remaining = nullptr,
               double max_strain = std::numeric_limits<double>::infinity(),
               Eigen::Vector3d* where = nullptr);

  // Steps 1 and 2: springs of the pairs closer than the thickness at `start` (3n) into extra,
  // each pushing its pair a tenth of the way to the thickness; with `velocity` (3n, the step's
  // start) none for pairs already separating faster than a fifth of that push over the step
  // (beta, s). Every spring, and every separating pair that carried a normal force in the last
  // accepted steps, gets the friction dashpot. pinned: per vertex, 1 when the step's filter
  // pins it.
  void add_springs(const Eigen::VectorXd& start, const Eigen::VectorXd& mass,
                   const std::vector<unsigned char>& pinned, StepForces& extra,
                   const Eigen::VectorXd* velocity = nullptr, double beta = 0.0);
  // Step 3 on the solve's result: x1 (3n) and v1 change together (v1 += Δx1 / beta). Records
  // each pair's normal force (its spring's at the solve's end plus its impulses) for accept_step.
  // pinned: per vertex, 0 free, kHeldByBody for a vertex the body's contact constrains (it
  // weighs a thousand times its mass in the impulses and moves with its zone), else pinned.
  void resolve(const Eigen::VectorXd& x0, Eigen::VectorXd& x1, Eigen::VectorXd& v1, double beta,
               const Eigen::VectorXd& mass, const std::vector<unsigned char>& pinned,
               const StepForces& extra);

  // The step was accepted: the normal forces resolve() measured become the lagged forces the
  // next step's friction is sized from (a rejected attempt leaves them as they were).
  void accept_step();

  const SelfContactStepStats& step_stats() const { return stats_; }
  SelfCollider& collider() { return collider_; }

  // A pair of elements across steps: its kind and its four vertices (the same pair keeps them
  // while the mesh does not change).
  using PairKey = std::array<int, 5>;
  struct PairKeyHash {
    std::size_t operator()(const PairKey& key) const;
  };

 private:
  // One Gauss-Seidel round of inelastic impulses over `hits`; each impulse's force (impulse/β²
  // in these position units) is added to the pair's normal force of the step.
  void apply_impulses(const std::vector<SelfPair>& hits, const Eigen::VectorXd& x0,
                      Eigen::VectorXd& x1, double beta, const Eigen::VectorXd& mass,
                      const std::vector<unsigned char>& pinned);
  // N: the normal force the pair carried over the last two accepted steps (their mean; 0 for a
  // pair that carried none).
  double lagged_force(const PairKey& key) const;

  SelfContactSettings settings_;
  SelfCollider collider_;
  double fabric_friction_ = 0.3;
  SelfContactStepStats stats_;
  // Friction between layers is sized from the normal force each pair carried in the accepted
  // steps before (lagged, as Li et al. 2020 lag it in IPC): per pair, the force of the last
  // step and of the one before it.
  std::unordered_map<PairKey, std::array<double, 2>, PairKeyHash> lagged_;
  std::unordered_map<PairKey, double, PairKeyHash> step_force_;  // this attempt's, N
  std::vector<PairKey> spring_keys_;  // the key of each pair spring added this attempt
  std::size_t first_spring_ = 0;      // index of this response's first spring in the extra forces
};

}  // namespace sd::sim
