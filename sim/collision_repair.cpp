#include "sim/collision_repair.hpp"

#include <algorithm>
#include <stdexcept>

namespace sd::sim {

Eigen::Vector3d StartRepair::goal(int vertex, int step) const {
  if (step <= 0) return start.segment<3>(3 * vertex);
  if (step >= steps) return target.segment<3>(3 * vertex);
  const double s = static_cast<double>(step) / steps;
  return start.segment<3>(3 * vertex) +
         s * (target.segment<3>(3 * vertex) - start.segment<3>(3 * vertex));
}

Eigen::VectorXd StartRepair::positions_after(int step) const {
  if (step <= 0) return start;
  if (step >= steps) return target;
  const double s = static_cast<double>(step) / steps;
  return start + s * (target - start);
}

StartRepair plan_start_repair(const BodyCollider& body, const Eigen::VectorXd& x,
                              const StartRepairOptions& options) {
  if (options.steps < 1) throw std::invalid_argument("the start repair needs at least one step");
  if (!(options.thickness >= 0.0))
    throw std::invalid_argument("the start repair thickness must be >= 0");
  StartRepair repair;
  repair.steps = options.steps;
  repair.start = x;
  repair.target = x;
  // Contacts with thickness 0 are exactly the vertices inside (negative signed distance) plus
  // any lying on the surface; only the inside ones need pushing.
  ContactQuery query;
  query.thickness = 0.0;
  for (const BodyContact& contact : body.find_contacts(x, query)) {
    if (!(contact.distance < 0.0)) continue;
    repair.target.segment<3>(3 * contact.vertex) =
        contact.point + options.thickness * contact.normal;
    repair.max_depth = std::max(repair.max_depth, -contact.distance);
    repair.pushed.push_back(contact);
  }
  return repair;
}

}  // namespace sd::sim
