#pragma once
// Repair of an intersecting start: a garment designed partly inside the body (an imperfect
// sketch) is pushed out over the first steps instead of all at once, so the cloth stretches
// gently into place rather than exploding. The vertices that start inside form connected
// regions of the cloth; each region is moved out as one piece, along the depth-weighted mean of
// its vertices' outward normals, until its last vertex lies `thickness` outside the body, and the
// cloth round it follows with a smooth falloff, so that the push bends the cloth instead of
// stretching it round the body part (a hem drawn 4 cm into a leg: pushed vertex by vertex to
// the nearest skin, its vertices went to both sides of the leg and the cloth caught round it,
// held at the strain limit). The simulator moves every moved vertex to its target linearly over
// `steps` steps (constraining its velocity along its push), and ordinary contacts take over
// afterwards. Without the cloth's triangles each inside vertex is pushed to its nearest skin.

#include <Eigen/Core>
#include <vector>

#include "sim/body_collider.hpp"

namespace sd::sim {

struct StartRepairOptions {
  double thickness = 0.005;  // m: final clearance of a pushed-out vertex
  int steps = 10;            // steps over which the push is spread (≥ 1)
  // The falloff's steepest slope: metres of push per metre of cloth (along its edges) from a
  // region's rim. Pushed across its surface with slope s, cloth lengthens by about s²/2: 0.25
  // stretches it 3 %, which the drape takes up without reaching the strain limit.
  double falloff_slope = 0.25;
};

// One vertex the repair moves: `distance` m along the unit `direction`.
struct RepairMove {
  int vertex = -1;
  Eigen::Vector3d direction = Eigen::Vector3d::UnitY();
  double distance = 0.0;
};

struct StartRepair {
  int steps = 1;
  Eigen::VectorXd start;   // 3n: the designed positions
  Eigen::VectorXd target;  // 3n: the same, with every moved vertex at its target
  // One per vertex that starts inside, ascending by vertex: where it is pushed from (point,
  // normal, distance < 0 = minus the depth) on the body's current pose.
  std::vector<BodyContact> pushed;
  // Every vertex the repair moves (those inside, and the falloff round them), ascending.
  std::vector<RepairMove> moved;
  double max_depth = 0.0;  // m, deepest starting penetration
  double max_push = 0.0;   // m, the largest move
  int regions = 0;         // connected regions of inside vertices moved as one

  bool empty() const { return pushed.empty(); }
  // Where `vertex` should be after `step` completed steps (0 → start, ≥ steps → target).
  Eigen::Vector3d goal(int vertex, int step) const;
  // All vertices after `step` completed steps, 3n.
  Eigen::VectorXd positions_after(int step) const;
};

// Finds the cloth vertices of `x` (3n) inside `body` and plans their push-out. `cloth`: the
// cloth's triangles (their edges connect the regions and carry the falloff); without them, or
// empty, each inside vertex is pushed alone to its nearest skin.
StartRepair plan_start_repair(const BodyCollider& body, const Eigen::VectorXd& x,
                              const StartRepairOptions& options = {},
                              const ClothTriangles* cloth = nullptr);

}  // namespace sd::sim
