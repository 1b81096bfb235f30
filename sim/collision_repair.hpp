#pragma once
// Repair of an intersecting start: a garment designed partly inside the body (an imperfect
// sketch) is pushed out over the first steps instead of all at once, so the cloth stretches
// gently into place rather than exploding. Each vertex that starts inside gets a target on the
// outward side of its nearest surface point, `thickness` away from the body; the simulator moves
// it there linearly over `steps` steps (constraining the vertex's velocity along the push
// normal), and ordinary contacts take over afterwards.

#include <Eigen/Core>
#include <vector>

#include "sim/body_collider.hpp"

namespace sd::sim {

struct StartRepairOptions {
  double thickness = 0.005;  // m: final clearance of a pushed-out vertex
  int steps = 10;            // steps over which the push is spread (≥ 1)
};

struct StartRepair {
  int steps = 1;
  Eigen::VectorXd start;   // 3n: the designed positions
  Eigen::VectorXd target;  // 3n: the same, with every inside vertex moved out
  // One per vertex that starts inside, ascending by vertex: where it is pushed from (point,
  // normal, distance < 0 = minus the depth) on the body's current pose.
  std::vector<BodyContact> pushed;
  double max_depth = 0.0;  // m, deepest starting penetration

  bool empty() const { return pushed.empty(); }
  // Where `vertex` should be after `step` completed steps (0 → start, ≥ steps → target).
  Eigen::Vector3d goal(int vertex, int step) const;
  // All vertices after `step` completed steps, 3n.
  Eigen::VectorXd positions_after(int step) const;
};

// Finds the cloth vertices of `x` (3n) inside `body` and plans their push-out.
StartRepair plan_start_repair(const BodyCollider& body, const Eigen::VectorXd& x,
                              const StartRepairOptions& options = {});

}  // namespace sd::sim
