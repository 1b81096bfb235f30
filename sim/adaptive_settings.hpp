#pragma once
// The settings of adaptive detail (docs/adaptive.md): thresholds of the error estimate and of the
// merge rules, levels, budget. Plain values with defaults; validate() says what cannot work.

#include <stdexcept>

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
  // Refine to the level the estimate asks for at once: the sag of a smooth curve halves with
  // each level, so an edge whose sag is ε > refine_threshold is refined by
  // ⌈log2(ε / refine_threshold)⌉ levels in one step (the blocks made by its split are split again
  // until then) instead of one level per step. A region that starts to bend reaches its level in
  // one topology change instead of one per level.
  bool target_levels = false;
  // s: refine ahead of the motion. The estimate is also taken where the cloth will be after
  // this time at its current velocity (x + lookahead·v; on regular changes, see
  // change_interval), and before the first step a trial run of this length from the start state
  // (a copy of the simulation: pins, gravity, a still body) shows where the cloth is about to
  // bend: the mesh is refined there, by the same rule, before it moves (AdaptiveCloth::
  // refine_ahead). 0: refine on the current shape only.
  double lookahead = 0.0;
  // s: regular topology changes at most this often. In between, the estimate still runs every
  // step but only an edge a whole level behind (sag above twice refine_threshold) changes the
  // mesh; merges wait for the next regular change. Every change costs a model update and a new
  // CHOLMOD analysis; with lookahead ≥ this interval the regions that will bend before the next
  // change are refined at this one. 0: every step.
  double change_interval = 0.0;
  // s: the motion criterion's horizon (docs/adaptive.md, "Where the motion differs"). 0: off.
  // Before the first step (round by round until nothing changes) and then at most every
  // horizon, one implicit step of the horizon is taken from the current state on two copies of
  // the cloth, the mesh as it is and the mesh with every leaf block split once; per vertex the
  // two displacements differ by d (a vertex the split made is compared with the midpoint of its
  // diagonal's), the motion error. An edge whose ends or midpoint have a motion error above
  // refine_threshold is split, and merges are made only on those steps and only where the
  // motion error at the split vertex is below coarsen_threshold. The sag estimate sees how far
  // the mesh is from a smooth surface; this sees how far its motion is from a finer mesh's (a
  // flat coarse region that swings or lands unlike a fine one). Not applied to pattern rest
  // shapes (rest_uv): the copies are built from the current mesh.
  double motion_horizon = 0.0;
  bool refine = true;
  bool coarsen = true;
  // Measure energies, total mass and linear momentum just before and just after each topology
  // change (two extra force evaluations on those steps) and keep them in the step record: for
  // tests and studies.
  bool measure_jumps = false;

  void validate() const;  // throws InvalidAdaptiveSettingsError
};

}  // namespace sd::sim
