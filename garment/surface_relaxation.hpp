#pragma once
// Smoothing a filled panel along the body's offset surface. The quad filler relaxes in 3D
// (each vertex to the mean of its neighbours) and projects onto the surface after each sweep.
// Where a panel wraps a strongly curved part of the body (the t-shirt's back, from the shoulder
// blade over the shoulder to the side of the neck), those 3D means lie inside the body, and
// their closest surface points jump across a ridge: a crease of long, near-degenerate quads
// (aspect ratio 1,579 on the t-shirt's back). Here a vertex moves towards the mean of its
// neighbours only within the tangent plane at its own surface point and is lifted back onto
// the surface from there: a short move from a point on the surface, so its closest point moves
// continuously and the mesh slides along the surface instead of cutting through the body.

#include <Eigen/Core>
#include <functional>
#include <span>
#include <vector>

#include "meshing/quad_mesh.hpp"

namespace sd::garment {

// A point lifted onto the surface: where it lands and the surface's unit outward normal there;
// a zero normal when the point is off the surface (a free-hanging part) and stays as it is.
struct LiftedPoint {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
};
using SurfaceLift = std::function<LiftedPoint(const Eigen::Vector3d&)>;

struct SurfaceRelaxationOptions {
  int max_sweeps = 50;
  double tolerance = 2.5e-5;  // m: stop once no vertex moved more than this in a sweep
  // m: the longest tangential move of one vertex in one sweep. A lift that lands farther than
  // this from where the move aimed has jumped across a ridge of the closest-point map (under
  // the arm, between the arm and the torso) and is refused: the vertex stays for that sweep.
  double max_step = 0.0125;
  // Weigh free vertices of valence 5 and more by valence_weight(k) too (valence 3 always is).
  // Off by default: over every example and design at 2-3.5 cm it lowers the large quads at such
  // vertices (99 → 67) and the gate's warnings, but it moves the t-shirt fronts' vertices at the
  // armpit by up to 9.5 mm, and the arms-lowering t-shirt's drapes (adaptive and from the flat
  // pattern), whose armpit squeeze rests only at a few settings, then end moving there
  // (docs/garment.md, "Fill consistency, eleventh round").
  bool weigh_high_valence = false;
};

struct SurfaceRelaxationResult {
  int sweeps = 0;          // sweeps run
  double last_move = 0.0;  // m, the largest vertex move of the last sweep
  int refused = 0;         // lifts refused as jumps, over all sweeps
};

// Gauss-Seidel sweeps over the vertices not marked in `fixed` (#V flags, nonzero = fixed):
// each moves by the tangential part of (mean of its edge neighbours − itself), at most
// `max_step` long, then is lifted. In the mean a free neighbour of valence 3 weighs
// valence_weight(3) = 0, and with `weigh_high_valence` one of valence 5 or more weighs
// valence_weight(k) (below), else 1: a ring of rhombi of one size around such an irregular vertex
// is then an equilibrium, where uniform weights shrink the quads around a vertex of valence 3 to
// about half the size of the next ring and grow those around a vertex of valence 5 or more.
// The weight 1 + 2 cos(2π/k) of a vertex of valence k in its neighbours' means, the one that
// balances rhombi of one size around it: 0 at valence 3 (exactly), 1 at 4 (exactly: a grid
// relaxes as with plain means), 1.618 at 5, 2 at 6.
double valence_weight(int valence);

// Each vertex's weight in its neighbours' means (#V): valence_weight(k) for a vertex not marked in
// `fixed` of valence k below 5 (0 at 3, 1 at 4), and of 5 or more with `high_valence`; 1 for the
// rest (a fixed vertex, and one of valence 5 or more without `high_valence`).
std::vector<double> mean_weights(const meshing::QuadMesh& mesh, std::span<const char> fixed,
                                 bool high_valence);

SurfaceRelaxationResult relax_on_surface(meshing::QuadMesh& mesh, std::span<const char> fixed,
                                         const SurfaceLift& lift,
                                         const SurfaceRelaxationOptions& options = {});

}  // namespace sd::garment
