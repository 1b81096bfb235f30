// The topology plan of the patch filler (docs/meshing.md): the boundary's shape, the candidate
// constructions (Nasri and shifted-corner layouts, rectilinear layouts, padding strips, the
// Yasseen partition) ranked from the edge counts before any geometry, and the mesh of the chosen
// plan. meshing/patch_fill.cpp places it in 3D.
#include "meshing/patch_plan.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>

#include "meshing/quad_layout.hpp"
#include "meshing/rectilinear_layout.hpp"
#include "meshing/region_partition.hpp"

namespace sd::meshing::detail {
namespace {

// Feasibility checks the corner search may spend per fill (each is O(n²) integer work).
constexpr int kSearchBudget = 4000;
// The same for each padded candidate (up to n(n+1)/2 + 1 of them, only when the plain layout
// promotes a corner where the boundary is flat). 4,000 here finds three corpus cases with fewer
// irregular vertices but makes a skewed fill of Σl = 200 take 5 ms instead of 3.
constexpr int kStripSearchBudget = 400;
// ... and all padded candidates of one fill together (a skewed fill of n = 10 sides has 56 of
// them; without this cap its topology took 2 ms).
constexpr int kPaddedSearchBudget = 4000;
// Turn changes the rectilinear search may look at per plan (each O(1), a closure check O(S) only
// when the changes add up): enough for every pair of changes on a loop of 100 positions, the
// cheapest level that can beat a Nasri/shifted-corner layout of n <= 6 sides of <= 12 edges.
constexpr int kRectilinearBudget = 12000;
// ... for each padded plan, and for all padded plans of a fill together (without these caps a
// one-long-side region of n = 10 took 40 ms: dozens of padded plans, each searching deep levels).
constexpr int kStripRectilinearBudget = 1000;
constexpr int kPaddedRectilinearBudget = 4000;

// Creates the boundary vertices from side_points (corner i = side_points[i].row(0)).
std::vector<std::vector<int>> add_boundary(detail::QuadMeshBuilder& builder,
                                           const std::vector<Eigen::MatrixX3d>& side_points) {
  const size_t n = side_points.size();
  std::vector<std::vector<int>> sides(n);
  for (size_t i = 0; i < n; ++i)
    for (Eigen::Index r = 0; r + 1 < side_points[i].rows(); ++r)
      sides[i].push_back(builder.add_vertex(side_points[i].row(r).transpose()));
  for (size_t i = 0; i < n; ++i) {
    sides[i].push_back(sides[(i + 1) % n].front());
    builder.add_path(sides[i]);
  }
  return sides;
}

std::vector<int> boundary_loop_of(const std::vector<std::vector<int>>& sides) {
  std::vector<int> loop;
  for (const auto& side : sides) loop.insert(loop.end(), side.begin(), side.end() - 1);
  return loop;
}

}  // namespace

std::vector<int> corners_of(const std::vector<std::vector<int>>& sides) {
  std::vector<int> corners;
  for (const auto& side : sides) corners.push_back(side.front());
  return corners;
}

namespace {

std::vector<int> corner_positions(std::span<const int> counts) {
  std::vector<int> corners;
  for (int p = 0; const int count : counts) {
    corners.push_back(p);
    p += count;
  }
  return corners;
}

// A quad corner wider than this is treated as flat (a side vertex of valence 2 on a straight
// or gently curved side); above 180° plus kReflexSlackDegrees it is reflex.
constexpr double kFlatDegrees = 165;
constexpr double kReflexSlackDegrees = 0.01;

}  // namespace

// Straight sides, convex corners: what fill_region(counts) assumes.
BoundaryShape straight_sided_shape(std::span<const int> counts) {
  const int total = std::accumulate(counts.begin(), counts.end(), 0);
  BoundaryShape shape;
  shape.reflex.assign(static_cast<size_t>(total), 0);
  shape.flat.assign(static_cast<size_t>(total), 1);
  for (const int c : corner_positions(counts)) shape.flat[static_cast<size_t>(c)] = 0;
  return shape;
}

// Interior angles of the boundary loop about its Newell normal (for a panel on a curved body
// the overall normal; the sign of a turn is right as long as the surface tilts less than 90°
// from it).
BoundaryShape measured_shape(
    const std::vector<Eigen::MatrixX3d>& side_points,
    const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& surface_normal,
    bool flags_about_surface) {
  std::vector<Eigen::Vector3d> loop;
  for (const auto& side : side_points)
    for (Eigen::Index r = 0; r + 1 < side.rows(); ++r) loop.emplace_back(side.row(r).transpose());
  const size_t size = loop.size();
  BoundaryShape shape;
  Eigen::Vector3d newell = Eigen::Vector3d::Zero();
  const Eigen::Vector3d origin = loop.front();
  for (size_t k = 0; k < size; ++k)
    newell += (loop[k] - origin).cross(loop[(k + 1) % size] - origin);
  if (newell.norm() > 0) shape.normal = newell.normalized();
  shape.measured = true;
  double extent = 0, off_plane = 0;
  for (const Eigen::Vector3d& p : loop) {
    extent = std::max(extent, (p - origin).norm());
    off_plane = std::max(off_plane, std::abs((p - origin).dot(shape.normal)));
  }
  shape.planar = newell.norm() > 0 && off_plane <= 1e-9 * extent;
  shape.reflex.assign(size, 0);
  shape.flat.assign(size, 0);
  shape.turn.assign(size, 0.0);
  for (size_t k = 0; k < size; ++k) {
    const Eigen::Vector3d in = loop[k] - loop[(k + size - 1) % size];
    const Eigen::Vector3d out = loop[(k + 1) % size] - loop[k];
    Eigen::Vector3d normal = shape.normal;
    if (surface_normal) {
      const Eigen::Vector3d local = surface_normal(loop[k]);
      if (local.norm() > 0.5) normal = local.normalized();
    }
    // The flags keep the loop's own normal unless asked: about the body's normals they would
    // change which corners count as reflex in most garments (docs/meshing.md, "Reflex vertices
    // where the boundary turns": measured, not taken as the default).
    const Eigen::Vector3d& flag_normal = flags_about_surface ? normal : shape.normal;
    const double turn = std::atan2(flag_normal.dot(in.cross(out)), in.dot(out));
    const double interior = 180.0 - turn * 180.0 / std::numbers::pi;
    shape.turn[k] = std::atan2(normal.dot(in.cross(out)), in.dot(out)) / (std::numbers::pi / 2);
    shape.reflex[k] = interior > 180.0 + kReflexSlackDegrees;
    shape.flat[k] = interior > kFlatDegrees;
  }
  return shape;
}

namespace {

// The region to pad: every real corner regular at valence 2, the strips' sides between
// `strip_corners` (empty: the real corners).
detail::StripRegion region_of(std::span<const int> loop_ids, std::span<const int> counts,
                              const BoundaryShape& shape, std::span<const int> strip_corners) {
  detail::StripRegion region;
  region.measured = !shape.turn.empty();
  for (size_t p = 0; p < loop_ids.size(); ++p)
    region.loop.push_back({loop_ids[p], 0, 3, shape.flat[p] != 0, shape.reflex[p] != 0,
                           region.measured ? shape.turn[p] : 0.0});
  region.corners = corner_positions(counts);
  for (const int c : region.corners) region.loop[static_cast<size_t>(c)].regular = 2;
  if (!strip_corners.empty()) region.corners.assign(strip_corners.begin(), strip_corners.end());
  return region;
}

// The region to plan on (no vertex ids), before any strip.
detail::StripRegion planning_region(std::span<const int> counts, const BoundaryShape& shape,
                                    std::span<const int> strip_corners = {}) {
  const std::vector<int> no_ids(shape.flat.size(), -1);
  return region_of(no_ids, counts, shape, strip_corners);
}

// The plan for `region`, a planning region with `strips` added (nullopt when `rival` is given and
// the plan provably cannot rank before it).
std::optional<Plan> plan_with_strips(const detail::StripRegion& region, std::span<const int> counts,
                                     std::span<const int> strips, int budget,
                                     const Plan* rival = nullptr,
                                     std::span<const int> strip_corners = {},
                                     int* rectilinear_budget = nullptr) {
  const detail::PositionCosts costs = region.costs();
  if (rival != nullptr) {
    // The plan folds at least region.folded quads and costs at least this much distortion.
    const int least = region.fixed_cost + detail::layout_cost_lower_bound(costs);
    if (std::tuple(region.folded, least) > std::tuple(rival->folded, rival->distortion))
      return std::nullopt;
  }
  Plan plan;
  plan.strips.assign(strips.begin(), strips.end());
  plan.strip_corners.assign(strip_corners.begin(), strip_corners.end());
  plan.layout = detail::best_layout(costs, budget);
  int layout_folds = 0;
  for (const int c : plan.layout.corners)
    layout_folds += costs.as_corner[static_cast<size_t>(c)] >= detail::kFoldPenalty ? 1 : 0;
  plan.distortion = region.fixed_cost + plan.layout.cost - detail::kFoldPenalty * layout_folds;
  plan.irregular_vertices = region.fixed_irregular + plan.layout.irregular;
  plan.folded = region.folded + layout_folds;
  plan.flat = region.flat + plan.layout.flat;
  if (!strips.empty())
    plan.partition = "padded";
  else
    plan.partition = plan.layout.corners == corner_positions(counts) ? "nasri" : "shifted-corners";
  // A layout without interior irregular vertex (reflex layout vertices allowed), only when it
  // costs strictly less: ties keep the Nasri/shifted-corner layouts and their figures.
  // Against a rival that does not fold, only what beats its distortion is worth searching.
  int max_cost = plan.layout.cost - 1;
  if (rival != nullptr && rival->folded == 0)
    max_cost = std::min(max_cost, rival->distortion - region.fixed_cost - 1);
  int rect_budget = rectilinear_budget == nullptr
                        ? kRectilinearBudget
                        : std::min(kStripRectilinearBudget, *rectilinear_budget);
  const int rect_given = rect_budget;
  auto rect = detail::best_rectilinear_layout(costs, max_cost, rect_budget);
  if (rectilinear_budget != nullptr) *rectilinear_budget -= rect_given - rect_budget;
  if (rect) {
    int folds = 0;
    for (size_t p = 0; p < rect->turns.size(); ++p)
      folds += rect->turns[p] == 1 && costs.as_corner[p] >= detail::kFoldPenalty ? 1 : 0;
    plan.turns = std::move(rect->turns);
    plan.distortion = region.fixed_cost + rect->cost - detail::kFoldPenalty * folds;
    plan.irregular_vertices = region.fixed_irregular + rect->irregular;
    plan.folded = region.folded + folds;
    plan.flat = region.flat + rect->flat;
    if (strips.empty()) plan.partition = "rectilinear";
  }
  return plan;
}

// What the Yasseen construction gives on these sides, built (nullopt when it does not apply,
// or when it would not rank before `rival`). Its figures come from the builder's valences
// (corners regular at 2, other side vertices at 3, the rest at 4); the mesh is validated only
// when it would win.
std::optional<std::pair<Plan, Built>> yasseen_candidate(
    const std::vector<Eigen::MatrixX3d>& side_points, const BoundaryShape& shape,
    const Plan& rival) {
  Built built;
  built.sides = add_boundary(built.builder, side_points);
  if (!detail::fill_yasseen(built.builder, built.sides, kSearchBudget)) return std::nullopt;
  const std::vector<int> valence = built.builder.valences();
  std::vector<int> regular(valence.size(), 4);
  for (const auto& side : built.sides) {
    for (const int v : side) regular[static_cast<size_t>(v)] = 3;
  }
  for (const auto& side : built.sides) regular[static_cast<size_t>(side.front())] = 2;
  Plan plan;
  plan.yasseen = true;
  plan.partition = "yasseen";
  for (size_t v = 0; v < valence.size(); ++v) {
    const int deviation = std::abs(valence[v] - regular[v]);
    plan.distortion += deviation;
    plan.irregular_vertices += deviation != 0 ? 1 : 0;
  }
  const std::vector<int> loop = boundary_loop_of(built.sides);
  for (size_t p = 0; p < loop.size(); ++p)
    if (valence[static_cast<size_t>(loop[p])] == 2) {
      plan.folded += shape.reflex[p];
      plan.flat += shape.flat[p];
    }
  if (!(plan.rank(shape.measured) < rival.rank(shape.measured)) ||
      !validate(built.builder.build()).ok())
    return std::nullopt;
  return std::pair(std::move(plan), std::move(built));
}

}  // namespace

// The best plan for these counts on a boundary of this shape; when the Yasseen construction
// wins, `yasseen` receives it already built on `side_points`.
// Plans listed in `excluded` (same strips, strip corners and construction) are passed over.
Plan choose_plan(std::span<const int> counts, const BoundaryShape& shape,
                 const std::vector<Eigen::MatrixX3d>& side_points, std::optional<Built>& yasseen,
                 const std::vector<Plan>& excluded) {
  auto allowed = [&](const Plan& plan) {
    return std::none_of(excluded.begin(), excluded.end(), [&](const Plan& other) {
      return other.yasseen == plan.yasseen && other.strips == plan.strips &&
             other.strip_corners == plan.strip_corners;
    });
  };
  Plan best = *plan_with_strips(planning_region(counts, shape), counts, {}, kSearchBudget);
  if (!allowed(best)) {
    best.folded = std::numeric_limits<int>::max();  // anything else ranks before it
    best.distortion = std::numeric_limits<int>::max();
  }
  // Padding only pays when the plain layout promotes a side vertex where the boundary is flat
  // or reflex, or folds a quad (a reflex real corner it could not drop without promoting a
  // corner on a reflex stretch); strips keep the real corners at valence 2, so a merely flat
  // real corner is the layout's business.
  const std::vector<int> real_corners = corner_positions(counts);
  const auto n = static_cast<int>(counts.size());
  std::vector<int> exposed_sides;  // sides with a promoted corner where the boundary is flat
  std::vector<int> best_corners = best.layout.corners;
  if (!best.turns.empty()) {
    best_corners.clear();
    for (size_t p = 0; p < best.turns.size(); ++p)
      if (best.turns[p] == 1) best_corners.push_back(static_cast<int>(p));
  }
  for (const int c : best_corners)
    if (shape.flat[static_cast<size_t>(c)] &&
        !std::binary_search(real_corners.begin(), real_corners.end(), c)) {
      const int side =
          static_cast<int>(std::upper_bound(real_corners.begin(), real_corners.end(), c) -
                           real_corners.begin()) -
          1;
      if (std::find(exposed_sides.begin(), exposed_sides.end(), side) == exposed_sides.end())
        exposed_sides.push_back(side);
    }
  int padded_budget = kPaddedSearchBudget;
  int rectilinear_budget = kPaddedRectilinearBudget;
  // Every side and every pair of sides between these corners (the layout may move its
  // promotions elsewhere), and a full ring. A pair's region is its first strip's region with
  // one more strip; when a strip cannot be added, no plan with it exists.
  auto pad = [&](std::span<const int> strip_corners, bool with_plain) {
    auto consider = [&](const detail::StripRegion& region, std::span<const int> strips) {
      auto plan =
          plan_with_strips(region, counts, strips, std::min(kStripSearchBudget, padded_budget),
                           &best, strip_corners, &rectilinear_budget);
      if (!plan) return;
      padded_budget = std::max(0, padded_budget - plan->layout.checks);
      if (plan->rank(shape.measured) < best.rank(shape.measured) && allowed(*plan))
        best = std::move(*plan);
    };
    const detail::StripRegion unpadded = planning_region(counts, shape, strip_corners);
    const auto sides = static_cast<int>(strip_corners.empty() ? n : strip_corners.size());
    if (with_plain) consider(unpadded, {});
    for (int i = 0; i < sides; ++i) {
      detail::StripRegion one = unpadded;
      if (!one.strip(i)) continue;
      consider(one, std::vector<int>{i});
      for (int j = i + 1; j < sides; ++j) {
        detail::StripRegion two = one;
        if (two.strip(j)) consider(two, std::vector<int>{i, j});
      }
    }
    if (sides > 2) {
      detail::StripRegion ring = unpadded;
      bool complete = true;
      for (int i = 0; i < sides && complete; ++i) complete = ring.strip(i);
      std::vector<int> all(static_cast<size_t>(sides));
      std::iota(all.begin(), all.end(), 0);
      if (complete) consider(ring, all);
    }
  };
  if (!exposed_sides.empty() || best.folded > 0) pad({}, false);
  if (best.folded > 0) {
    // Strips that pass the reflex real corners as side vertices.
    std::vector<int> convex;
    for (const int c : real_corners)
      if (!shape.reflex[static_cast<size_t>(c)]) convex.push_back(c);
    if (convex.size() >= 2 && convex.size() < real_corners.size()) pad(convex, true);
  }
  // Nothing ranks before a fold-free plan with the least possible distortion, a single
  // irregular vertex (none for a grid) and no flat corner: no need to build the Yasseen one.
  const bool unbeatable = best.folded == 0 && best.distortion == std::abs(n - 4) &&
                          best.irregular_vertices == (n == 4 ? 0 : 1) && best.flat == 0;
  Plan yasseen_plan;
  yasseen_plan.yasseen = true;
  if (auto candidate = unbeatable || !allowed(yasseen_plan)
                           ? std::nullopt
                           : yasseen_candidate(side_points, shape, best)) {
    best = std::move(candidate->first);
    yasseen = std::move(candidate->second);
  }
  return best;
}

// The mesh of a plan on these sides (the same connectivity for any sides).
Built realize(const Plan& plan, std::span<const int> counts,
              const std::vector<Eigen::MatrixX3d>& side_points, const BoundaryShape& shape) {
  Built built;
  built.sides = add_boundary(built.builder, side_points);
  if (plan.yasseen) {
    if (!detail::fill_yasseen(built.builder, built.sides, kSearchBudget))
      throw std::logic_error("the Yasseen construction depends on geometry");
    return built;
  }
  detail::StripRegion region =
      region_of(boundary_loop_of(built.sides), counts, shape, plan.strip_corners);
  for (const int side : plan.strips)
    if (!region.strip(side, &built.builder, shape.normal))
      throw std::logic_error("a planned strip cannot be added");
  std::vector<int> loop;
  for (const auto& v : region.loop) loop.push_back(v.id);
  if (!plan.turns.empty())
    detail::fill_rectilinear(built.builder, loop, plan.turns);
  else
    detail::fill_polygon(built.builder, loop, plan.layout);
  return built;
}

PatchTopology to_topology(Built&& built, const Plan& plan) {
  PatchTopology topology;
  topology.mesh = built.builder.build();
  topology.side_vertices = std::move(built.sides);
  topology.partition = plan.partition;
  topology.distortion = plan.distortion;
  topology.irregular_vertices = plan.irregular_vertices;
  return topology;
}

}  // namespace sd::meshing::detail
