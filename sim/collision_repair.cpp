#include "sim/collision_repair.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <stdexcept>
#include <utility>

namespace sd::sim {
namespace {

// m along unit `direction` from p to the first point `thickness` outside the body, marching by
// the signed distance (each step moves at most a thickness past the surface it is sure of), or
// a negative value when 64 steps or 1 m do not get there.
double exit_distance(const BodyCollider& body, const Eigen::Vector3d& p,
                     const Eigen::Vector3d& direction, double thickness) {
  double t = 0.0;
  for (int k = 0; k < 64 && t < 1.0; ++k) {
    const double s = body.signed_distance(p + t * direction);
    if (s >= thickness * (1.0 - 1e-6)) return t;
    t += std::max(thickness - s, 1e-4);
  }
  return -1.0;
}

// Each vertex's neighbours through the triangles' edges, with the edge's length at x (m).
std::vector<std::vector<std::pair<int, double>>> edge_neighbours(const ClothTriangles& cloth,
                                                                 const Eigen::VectorXd& x) {
  const int n = static_cast<int>(x.size() / 3);
  std::vector<std::vector<std::pair<int, double>>> out(static_cast<size_t>(n));
  for (const std::array<int, 3>& t : cloth.triangles)
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      const double length = (x.segment<3>(3 * a) - x.segment<3>(3 * b)).norm();
      out[static_cast<size_t>(a)].emplace_back(b, length);
      out[static_cast<size_t>(b)].emplace_back(a, length);
    }
  for (auto& list : out) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end(),
                           [](const auto& p, const auto& q) { return p.first == q.first; }),
               list.end());
  }
  return out;
}

}  // namespace

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
                              const StartRepairOptions& options, const ClothTriangles* cloth) {
  if (options.steps < 1) throw std::invalid_argument("the start repair needs at least one step");
  if (!(options.thickness >= 0.0))
    throw std::invalid_argument("the start repair thickness must be >= 0");
  if (!(options.falloff_slope > 0.0))
    throw std::invalid_argument("the start repair's falloff slope must be > 0");
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
    repair.max_depth = std::max(repair.max_depth, -contact.distance);
    repair.pushed.push_back(contact);
  }
  if (repair.pushed.empty()) return repair;
  const int n = static_cast<int>(x.size() / 3);
  // Each vertex's push (m, 3 per vertex).
  Eigen::VectorXd push = Eigen::VectorXd::Zero(x.size());
  const auto nearest_skin = [&](const BodyContact& c) {
    push.segment<3>(3 * c.vertex) =
        c.point + options.thickness * c.normal - x.segment<3>(3 * c.vertex);
  };
  if (cloth == nullptr || cloth->triangles.empty()) {
    for (const BodyContact& c : repair.pushed) nearest_skin(c);
  } else {
    const auto neighbours = edge_neighbours(*cloth, x);
    std::vector<int> inside(static_cast<size_t>(n), -1);  // index into pushed
    for (size_t k = 0; k < repair.pushed.size(); ++k)
      inside[static_cast<size_t>(repair.pushed[k].vertex)] = static_cast<int>(k);
    std::vector<char> seen(static_cast<size_t>(n), 0);
    // Per vertex outside the regions: Σ of the regions' falloff weights and of weight × push.
    std::vector<double> weight(static_cast<size_t>(n), 0.0);
    Eigen::VectorXd falloff = Eigen::VectorXd::Zero(x.size());
    for (const BodyContact& first : repair.pushed) {
      if (seen[static_cast<size_t>(first.vertex)]) continue;
      // One region: the inside vertices connected to `first` through edges.
      std::vector<int> region{first.vertex};
      seen[static_cast<size_t>(first.vertex)] = 1;
      for (size_t k = 0; k < region.size(); ++k)
        for (const auto& [w, length] : neighbours[static_cast<size_t>(region[k])])
          if (inside[static_cast<size_t>(w)] >= 0 && !seen[static_cast<size_t>(w)]) {
            seen[static_cast<size_t>(w)] = 1;
            region.push_back(w);
          }
      ++repair.regions;
      Eigen::Vector3d direction = Eigen::Vector3d::Zero();
      for (const int v : region) direction += repair.pushed[static_cast<size_t>(inside[v])].normal;
      // Normals that cancel out (cloth through the middle of a limb) name no side to move the
      // region to: each of its vertices goes to its own nearest skin, as without triangles.
      double along = -1.0;
      if (direction.norm() > 0.3 * static_cast<double>(region.size())) {
        direction.normalize();
        for (const int v : region) {
          const double t = exit_distance(body, x.segment<3>(3 * v), direction, options.thickness);
          if (t < 0.0) {
            along = -1.0;
            break;
          }
          along = std::max(along, t);
        }
      }
      if (along < 0.0) {
        for (const int v : region) nearest_skin(repair.pushed[static_cast<size_t>(inside[v])]);
        continue;
      }
      for (const int v : region) push.segment<3>(3 * v) = along * direction;
      // The falloff: 1 − smoothstep(s / L) of the distance s along the cloth from the region,
      // whose steepest slope 1.5·push / L is the option's.
      const double reach = 1.5 * along / options.falloff_slope;
      std::vector<double> distance(static_cast<size_t>(n), std::numeric_limits<double>::infinity());
      using Item = std::pair<double, int>;
      std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
      for (const int v : region) {
        distance[static_cast<size_t>(v)] = 0.0;
        queue.emplace(0.0, v);
      }
      while (!queue.empty()) {
        const auto [d, v] = queue.top();
        queue.pop();
        if (d > distance[static_cast<size_t>(v)]) continue;
        if (d > 0.0) {
          const double u = d / reach;
          const double w = 1.0 - u * u * (3.0 - 2.0 * u);
          weight[static_cast<size_t>(v)] += w;
          falloff.segment<3>(3 * v) += w * along * direction;
        }
        for (const auto& [w, length] : neighbours[static_cast<size_t>(v)]) {
          const double next = d + length;
          if (next < reach && next < distance[static_cast<size_t>(w)]) {
            distance[static_cast<size_t>(w)] = next;
            queue.emplace(next, w);
          }
        }
      }
    }
    // Where falloffs overlap, their pushes are averaged by weight (never more than the largest
    // of them); a vertex inside a region moves with it alone.
    for (int v = 0; v < n; ++v)
      if (inside[static_cast<size_t>(v)] < 0 && weight[static_cast<size_t>(v)] > 0.0)
        push.segment<3>(3 * v) =
            falloff.segment<3>(3 * v) / std::max(1.0, weight[static_cast<size_t>(v)]);
  }
  for (int v = 0; v < n; ++v) {
    const double distance = push.segment<3>(3 * v).norm();
    if (!(distance > 1e-9)) continue;
    repair.target.segment<3>(3 * v) += push.segment<3>(3 * v);
    repair.moved.push_back({v, push.segment<3>(3 * v) / distance, distance});
    repair.max_push = std::max(repair.max_push, distance);
  }
  return repair;
}

}  // namespace sd::sim
