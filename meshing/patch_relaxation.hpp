#pragma once
// Smoothing the interior of a filled patch without folding it.

#include <Eigen/Core>
#include <array>
#include <functional>
#include <limits>
#include <span>
#include <vector>

#include "meshing/quad_mesh.hpp"

namespace sd::meshing {

// Jacobi Laplacian sweeps over the vertices not marked fixed (#V flags, nonzero = fixed): each
// vertex moves to the mean of its edge neighbours. First all sweeps run unguarded and every
// quad is checked once at the end; if some quad's smallest scaled Jacobian (measured against
// reference normals from the starting positions) ended below min(its starting value, 0.05),
// the sweeps run again guarded: the vertices of a quad that would fall below min(its current
// value, 0.05) keep their place for that sweep. So the relaxation never folds a quad it did
// not receive folded, and can only unfold. `project`, when
// set, maps each moved vertex onto the target surface. Stops early once no vertex moves more
// than 1e-3 of the mean edge length in a sweep.
void relax_interior(QuadMesh& mesh, std::span<const char> fixed, int sweeps,
                    const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& project = {});

namespace detail {

// Where the reference normals that tell a quad's front from its back come from: the starting
// positions (vertex normals averaged over 4 rings), or the positions after the unguarded sweeps.
// The start misleads when Coons blocks overlap in a cluster too large for the averaging (a
// layout next to a reflex corner): the whole cluster counts as unfolded, and the guard keeps it
// folded; the sweeps untangle most such clusters. Taken for every fill, the sweeps' normals
// changed 483 of the notched test fills (docs/meshing.md), 179 of them to smaller angles, so
// the start is the default and fill_region turns to the sweeps' normals only when every plan
// it tried keeps inverted quads.
enum class ReferenceNormals { kStart, kAfterSweeps };

// The same on a mesh being built (QuadMeshBuilder's arrays): #V positions, relaxed in place,
// and #Q counter-clockwise quads; saves copying them into a QuadMesh and back.
// `probe`, when given, asks for an early answer on a layout that folds: the quads folded
// (smallest scaled Jacobian below 0) after the unguarded sweeps are counted when those sweeps
// left a quad below min(its start, 0.05) (0 otherwise); when there are at least
// probe->stop_at of them, the positions are left where the unguarded sweeps put them and
// nothing more is done (the guarded sweeps and the untangling that would follow are most of a
// folding plan's time); otherwise the relaxation runs to its end as without a probe, to the
// same bits.
struct RelaxProbe {
  int stop_at = std::numeric_limits<int>::max();  // in
  int folds = 0;                                  // out
  bool stopped = false;                           // out
};
void relax_interior(std::vector<Eigen::Vector3d>& positions,
                    std::span<const std::array<int, 4>> quads, std::span<const char> fixed,
                    int sweeps,
                    const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& project = {},
                    ReferenceNormals reference = ReferenceNormals::kStart,
                    RelaxProbe* probe = nullptr);

// This thread's relaxations since the tally was last reset (tests read it to check how much work
// a fill does, which its result alone does not show): those that went on to the guarded sweeps
// and the untangling (the expensive part of a folding plan), and those a probe stopped before.
struct RelaxationTally {
  int guarded = 0;
  int stopped = 0;
};
RelaxationTally& relaxation_tally();

// Foldover-free placement in a plane, after Garanzha, Kaporin, Kudryavtseva, Protais, Ray and
// Sokolov (2021), "Foldover-free maps in 50 lines of code": the free vertices of #Q
// counter-clockwise quads (about `normal`, unit) move in the plane square to `normal` to
// minimise Σ over quad corners of
//     ((1 − θ) |J|² + θ (det J² + 1)) / χ(det J, ε),   χ(D, ε) = (D + √(ε² + D²)) / 2,
// J the corner's two edges divided by h = √(area / #Q) (an ideal square corner has J = I), with
// ε lowered from the worst corner's |det J| towards 0 between minimisations (L-BFGS). As ε → 0
// the energy becomes a barrier on every corner's signed area, so once all corners are positive
// they stay so. Each vertex keeps its height along `normal`. Returns true, with the positions
// moved, when every corner ends with det J > 0 (every quad strictly convex and unfolded);
// false leaves the positions as they were.
// `rounds` bounds the minimisations and `steps` the L-BFGS steps of each: 60 of 200 to untangle;
// a start without folds needs far fewer to settle.
bool untangle_in_plane(std::vector<Eigen::Vector3d>& positions,
                       std::span<const std::array<int, 4>> quads, std::span<const char> fixed,
                       const Eigen::Vector3d& normal, int rounds = 60, int steps = 200);

// The energy above for 2D positions (#V), and its gradient (#V, fixed vertices included) when
// `gradient` is given; exposed for the finite-difference test.
double untangling_energy(std::span<const Eigen::Vector2d> x,
                         std::span<const std::array<int, 4>> quads, double h, double epsilon,
                         std::vector<Eigen::Vector2d>* gradient = nullptr);

}  // namespace detail

}  // namespace sd::meshing
