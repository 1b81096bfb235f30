// Over 700 lines on purpose, for now: the topology plan (BoundaryShape, Plan, choose_plan,
// realize) and the geometric fill (fill_with_plan, untangle_planar, widen_thin_quads) share the
// private Plan and Built types, and issue 18 edits the geometric fill in parallel. Once it is
// merged, the plan goes behind a detail header of its own (patch_plan).
#include "meshing/patch_fill.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <optional>
#include <string>
#include <tuple>
#include <utility>

#include "meshing/patch_relaxation.hpp"
#include "meshing/quad_layout.hpp"
#include "meshing/rectilinear_layout.hpp"
#include "meshing/region_partition.hpp"

namespace sd::meshing {
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

void check_counts(std::span<const int> counts) {
  if (counts.size() < 2)
    throw FillError("a region needs at least 2 sides to be filled, got " +
                    std::to_string(counts.size()));
  long total = 0;
  for (size_t i = 0; i < counts.size(); ++i) {
    if (counts[i] < 1)
      throw FillError("side " + std::to_string(i) + " has " + std::to_string(counts[i]) +
                      " edges; every side needs at least 1");
    total += counts[i];
  }
  if (total % 2 != 0)
    throw FillError("the sides have " + std::to_string(total) +
                    " edges in total; a quad mesh needs an even total (change one side by 1)");
  if (total < 4)
    throw FillError(
        "the sides have only 2 edges in total, both joining the same two corners; "
        "a quad mesh needs at least 4 boundary edges");
}

struct Built {
  detail::QuadMeshBuilder builder;
  std::vector<std::vector<int>> sides;  // vertex ids per side, corner to corner
};

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

std::vector<int> corners_of(const std::vector<std::vector<int>>& sides) {
  std::vector<int> corners;
  for (const auto& side : sides) corners.push_back(side.front());
  return corners;
}

std::vector<int> corner_positions(std::span<const int> counts) {
  std::vector<int> corners;
  for (int p = 0; const int count : counts) {
    corners.push_back(p);
    p += count;
  }
  return corners;
}

// How the boundary bends at each loop position, for judging where a vertex of valence 2 (one
// quad, with the boundary's own angle) is acceptable.
struct BoundaryShape {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // the loop is counter-clockwise about it
  std::vector<char> reflex;  // interior angle above 180°: one quad there is folded
  std::vector<char> flat;    // interior angle above kFlatDegrees (reflex included)
  bool measured = false;     // from real side points (not the count-only assumption)
  // Every boundary vertex within 1e-9 of the boundary's extent from the plane through the
  // first one square to `normal`: a fill without projection then lies in that plane, and a
  // quad turning the wrong way about `normal` is folded even when its neighbours turned with
  // it (measure_quality's vertex normals cannot see such a cluster).
  bool planar = false;
};

// A quad corner wider than this is treated as flat (a side vertex of valence 2 on a straight
// or gently curved side); above 180° plus kReflexSlackDegrees it is reflex.
constexpr double kFlatDegrees = 165;
constexpr double kReflexSlackDegrees = 0.01;

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
BoundaryShape measured_shape(const std::vector<Eigen::MatrixX3d>& side_points) {
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
  for (size_t k = 0; k < size; ++k) {
    const Eigen::Vector3d in = loop[k] - loop[(k + size - 1) % size];
    const Eigen::Vector3d out = loop[(k + 1) % size] - loop[k];
    const double turn = std::atan2(shape.normal.dot(in.cross(out)), in.dot(out));
    const double interior = 180.0 - turn * 180.0 / std::numbers::pi;
    shape.reflex[k] = interior > 180.0 + kReflexSlackDegrees;
    shape.flat[k] = interior > kFlatDegrees;
  }
  return shape;
}

// A construction, chosen from the edge counts and the boundary's shape before any mesh is
// built (except the Yasseen candidate, which is built to be measured): strips of padding along
// some sides, then a layout of what is left.
struct Plan {
  bool yasseen = false;
  std::vector<int> strips;  // side indices, in the order they are added
  detail::PolygonLayout layout;
  // Nonempty: the left-over region is filled by this rectilinear layout (a turn per loop
  // position) instead of `layout`.
  std::vector<int> turns;
  std::string partition;
  int distortion = 0, irregular_vertices = 0;
  int folded = 0;  // boundary vertices of valence 2 where the boundary is reflex
  int flat = 0;    // boundary vertices of valence 2 where it is flat (or reflex)
  // Loop positions of the corners the strips work with: empty for the region's own corners;
  // without its reflex corners when those must not keep a single quad (a strip keeps the
  // corners it runs between at valence 2, so it can only pass a reflex corner as a side
  // vertex of valence 3).
  std::vector<int> strip_corners;

  // Never fold where another construction does not; then least distortion; then, for a
  // count-only fill, fewest irregular vertices (the corpus figures) before fewest flat
  // corners, and for a fill of real sides (`shape_first`) the other way round: a side vertex
  // of valence 2 leaves one quad with a 180° corner and the other three sharing 180°, which on
  // a long side next to short ones makes a sliver (3° for (30,4,4,4,4) on the `fill` circle).
  auto rank(bool shape_first) const {
    return std::tuple(folded, distortion, shape_first ? flat : irregular_vertices,
                      shape_first ? irregular_vertices : flat);
  }
};

// The region to pad: every real corner regular at valence 2, the strips' sides between
// `strip_corners` (empty: the real corners).
detail::StripRegion region_of(std::span<const int> loop_ids, std::span<const int> counts,
                              const BoundaryShape& shape, std::span<const int> strip_corners) {
  detail::StripRegion region;
  for (size_t p = 0; p < loop_ids.size(); ++p)
    region.loop.push_back({loop_ids[p], 0, 3, shape.flat[p] != 0, shape.reflex[p] != 0});
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

// The best plan for these counts on a boundary of this shape; when the Yasseen construction
// wins, `yasseen` receives it already built on `side_points`.
// Plans listed in `excluded` (same strips, strip corners and construction) are passed over.
Plan choose_plan(std::span<const int> counts, const BoundaryShape& shape,
                 const std::vector<Eigen::MatrixX3d>& side_points, std::optional<Built>& yasseen,
                 const std::vector<Plan>& excluded = {}) {
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

// Sides for display: every boundary vertex on the unit circle at an angle proportional to its
// position along the boundary, so no three are collinear (a promoted corner never sits on a
// straight line) and side lengths follow the counts.
std::vector<Eigen::MatrixX3d> display_sides(std::span<const int> counts) {
  const int total = std::accumulate(counts.begin(), counts.end(), 0);
  std::vector<Eigen::MatrixX3d> sides;
  int start = 0;
  for (const int count : counts) {
    Eigen::MatrixX3d side(count + 1, 3);
    for (int k = 0; k <= count; ++k) {
      const double angle =
          2 * std::numbers::pi * ((start + k) % total) / total - std::numbers::pi / 2;
      side.row(k) << std::cos(angle), std::sin(angle), 0.0;
    }
    sides.push_back(side);
    start += count;
  }
  return sides;
}

void check_side_points(const std::vector<Eigen::MatrixX3d>& side_points) {
  if (side_points.size() < 2)
    throw FillError("a region needs at least 2 sides to be filled, got " +
                    std::to_string(side_points.size()));
  double scale = 0;
  for (size_t i = 0; i < side_points.size(); ++i) {
    if (side_points[i].rows() < 2)
      throw FillError("side " + std::to_string(i) + " has " +
                      std::to_string(side_points[i].rows()) +
                      " point(s); every side needs its two corners at least");
    if (!side_points[i].allFinite())
      throw FillError("side " + std::to_string(i) + " has a coordinate that is not a number");
    scale = std::max(scale, side_points[i].cwiseAbs().maxCoeff());
  }
  for (size_t i = 0; i < side_points.size(); ++i) {
    const auto& next = side_points[(i + 1) % side_points.size()];
    const double gap = (side_points[i].bottomRows<1>() - next.topRows<1>()).norm();
    if (gap > 1e-9 * std::max(scale, 1e-300))
      throw FillError("side " + std::to_string(i) + " does not end where side " +
                      std::to_string((i + 1) % side_points.size()) + " starts (gap " +
                      std::to_string(gap) + ")");
  }
}

// The 3D fill with this plan: build, the display layout, relaxation (with these reference
// normals), quality.
FilledPatch fill_with_plan(const Plan& plan, std::span<const int> counts,
                           const std::vector<Eigen::MatrixX3d>& side_points,
                           const BoundaryShape& shape, std::optional<Built>& yasseen,
                           const FillGeometryOptions& options,
                           detail::ReferenceNormals reference = detail::ReferenceNormals::kStart);

// Quads with a corner turning clockwise about `normal` (beyond rounding: a sine below −1e-9).
int quads_turned_against(const QuadMesh& mesh, const Eigen::Vector3d& normal) {
  int turned = 0;
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) {
    bool against = false;
    for (int k = 0; k < 4 && !against; ++k) {
      const Eigen::Vector3d p = mesh.vertices.row(mesh.faces(f, k)).transpose();
      const Eigen::Vector3d a = mesh.vertices.row(mesh.faces(f, (k + 1) % 4)).transpose() - p;
      const Eigen::Vector3d b = mesh.vertices.row(mesh.faces(f, (k + 3) % 4)).transpose() - p;
      against = normal.dot(a.cross(b)) < -1e-9 * a.norm() * b.norm();
    }
    turned += against ? 1 : 0;
  }
  return turned;
}

// Thin quads on a flat boundary: the barrier placement below, on the quads with a corner under
// kThinQuadDeg and kThinQuadRings rings of free vertices around them. Laplacian relaxation
// settles on thin quads where a short side meets a long one or next to a reflex corner; the
// placement's energy is smallest for square corners and infinite for folded ones.
constexpr double kThinQuadDeg = 15;
constexpr int kThinQuadRings = 2;
// Minimisation rounds and L-BFGS steps of that placement: it starts unfolded and only has to
// settle (untangling allows 60 rounds of 200).
constexpr int kThinQuadRounds = 4, kThinQuadSteps = 100;
// Only on patches of at most this many quads: on a flat 2,500-quad fill with thin quads
// ((25,50,75,25,75) on a circle) widening took 1.1 ms of CPU, more than the fill itself.
constexpr Eigen::Index kThinQuadMaxQuads = 1000;

// On a clean fill of a flat boundary without projection, moves the free vertices near its
// thinnest quads to the barrier placement of the quads around them (the rest fixed), then
// raises the smallest corner figure by a pattern search; kept only when that figure over the
// whole patch rises and nothing folds.
void widen_thin_quads(FilledPatch& patch, const Eigen::Vector3d& normal) {
  const QuadMesh& mesh = patch.mesh;
  const auto nv = static_cast<size_t>(mesh.vertices.rows());
  const auto nf = static_cast<int>(mesh.faces.rows());
  std::vector<Eigen::Vector3d> positions(nv);
  for (size_t v = 0; v < nv; ++v)
    positions[v] = mesh.vertices.row(static_cast<Eigen::Index>(v)).transpose();
  std::vector<char> boundary(nv, 0);
  for (const auto& side : patch.topology.side_vertices)
    for (const int v : side) boundary[static_cast<size_t>(v)] = 1;
  // The figure: the sine of a corner's angle about `normal` (negative when it turns the wrong
  // way), which for angles in [0°, 180°] orders corners as min(angle, 180° − angle) does; a
  // corner on the boundary wider than 90° counts 1, its width being the boundary's own (a side
  // vertex with one quad, a reflex corner split in two). No arc tangent: the pattern search
  // evaluates it some 10⁵ times.
  auto corner_figure = [&](int f, int k) {
    const auto at = static_cast<size_t>(mesh.faces(f, k));
    const Eigen::Vector3d& p = positions[at];
    const Eigen::Vector3d a = positions[static_cast<size_t>(mesh.faces(f, (k + 1) % 4))] - p;
    const Eigen::Vector3d b = positions[static_cast<size_t>(mesh.faces(f, (k + 3) % 4))] - p;
    const double sine = normal.dot(a.cross(b)) / std::sqrt(a.squaredNorm() * b.squaredNorm());
    return boundary[at] && sine > 0 && a.dot(b) < 0 ? 1.0 : sine;
  };
  auto quad_figure = [&](int f) {
    double smallest = 1;
    for (int k = 0; k < 4; ++k) smallest = std::min(smallest, corner_figure(f, k));
    return smallest;
  };
  const double thin = std::sin(kThinQuadDeg * std::numbers::pi / 180);
  double figure_before = 1;
  std::vector<int> thin_quads;
  for (int f = 0; f < nf; ++f) {
    const double figure = quad_figure(f);
    figure_before = std::min(figure_before, figure);
    if (figure < thin) thin_quads.push_back(f);
  }
  if (thin_quads.empty()) return;
  std::vector<std::vector<int>> faces_at(nv);
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 4; ++k) faces_at[static_cast<size_t>(mesh.faces(f, k))].push_back(f);
  std::vector<char> moving(nv, 0);
  std::vector<int> front;
  auto take = [&](int f) {
    for (int k = 0; k < 4; ++k) {
      const auto v = static_cast<size_t>(mesh.faces(f, k));
      if (!boundary[v] && !moving[v]) {
        moving[v] = 1;
        front.push_back(static_cast<int>(v));
      }
    }
  };
  for (const int f : thin_quads) take(f);
  std::vector<char> searched;  // the thin quads' free vertices and one ring more
  for (int ring = 0; ring < kThinQuadRings; ++ring) {
    if (ring == 1) searched = moving;
    const std::vector<int> last = std::move(front);
    front.clear();
    for (const int v : last)
      for (const int f : faces_at[static_cast<size_t>(v)]) take(f);
  }
  if (searched.empty()) searched = moving;  // kThinQuadRings = 1
  std::vector<std::array<int, 4>> window;
  std::vector<char> window_face(static_cast<size_t>(nf), 0);
  for (size_t v = 0; v < nv; ++v)
    if (moving[v])
      for (const int f : faces_at[v])
        if (!std::exchange(window_face[static_cast<size_t>(f)], 1))
          window.push_back(
              {mesh.faces(f, 0), mesh.faces(f, 1), mesh.faces(f, 2), mesh.faces(f, 3)});
  if (window.empty()) return;  // the thin quads have no free vertex
  std::vector<char> fixed(nv);
  for (size_t v = 0; v < nv; ++v) fixed[v] = moving[v] ? 0 : 1;
  if (!detail::untangle_in_plane(positions, window, fixed, normal, kThinQuadRounds, kThinQuadSteps))
    return;
  // Then a pattern search on the thin quads' free vertices and one ring more: 8 directions,
  // step halving, a move kept only when the smallest figure of the vertex's quads rises.
  auto figure_at = [&](size_t v) {
    double smallest = 1;
    for (const int f : faces_at[v]) smallest = std::min(smallest, quad_figure(f));
    return smallest;
  };
  const Eigen::Vector3d t1 = normal.unitOrthogonal(), t2 = normal.cross(t1);
  constexpr int kPasses = 20, kHalvings = 8;
  for (int pass = 0; pass < kPasses; ++pass) {
    bool moved = false;
    for (size_t v = 0; v < nv; ++v) {
      if (!searched[v]) continue;
      double length = 0;
      int edges = 0;
      for (const int f : faces_at[v])
        for (int k = 0; k < 4; ++k)
          if (static_cast<size_t>(mesh.faces(f, k)) == v) {
            length +=
                (positions[static_cast<size_t>(mesh.faces(f, (k + 1) % 4))] - positions[v]).norm();
            ++edges;
          }
      double step = 0.25 * length / std::max(edges, 1), current = figure_at(v);
      for (int halving = 0; halving < kHalvings; ++halving) {
        const Eigen::Vector3d start = positions[v];
        Eigen::Vector3d best_position = start;
        double best = current;
        for (int k = 0; k < 8; ++k) {
          const double angle = k * std::numbers::pi / 4;
          positions[v] = start + step * (std::cos(angle) * t1 + std::sin(angle) * t2);
          if (const double value = figure_at(v); value > best + 1e-12) {
            best = value;
            best_position = positions[v];
          }
        }
        positions[v] = best_position;
        if (best > current) {
          moved = moved || best > current + 1e-3;
          current = best;
        } else {
          step *= 0.5;
        }
      }
    }
    if (!moved) break;
  }
  double figure_after = 1;
  for (int f = 0; f < nf; ++f) figure_after = std::min(figure_after, quad_figure(f));
  if (figure_after <= figure_before) return;
  QuadMesh widened = mesh;
  for (size_t v = 0; v < nv; ++v)
    widened.vertices.row(static_cast<Eigen::Index>(v)) = positions[v].transpose();
  QuadQuality quality = measure_quality(widened, patch.topology.corner_vertices());
  if (quality.inverted_quads > 0) return;
  patch.mesh = std::move(widened);
  patch.quality = quality;
}

// Plans tried by the geometric fill before it settles for the one with fewest inverted quads.
constexpr int kGeometryAttempts = 4;
// A plan with fewer quads than this share of the region's area over its mean boundary edge
// length squared has quads too large for its edges (mean area above 1.33 e², sides ~1.15 e).
constexpr double kLeastQuadShare = 0.75;
// ... and one with more than this share has quads too small (a padded plan with a ring too many:
// the one-shoulder top's back, 408 quads at 2.5 cm against 401 at 2 cm).
constexpr double kMostQuadShare = 1.4;
// A quad this many times longer than wide is a sliver (the quality gate warns from 10): the
// next plans are tried as for a fold.
constexpr double kDegenerateAspect = 10;
// Sides whose mean edge lengths differ by more than this factor have no single edge length to
// size quads by.
constexpr double kEdgeSpread = 1.5;

// The foldover-free placement of a patch's interior in the plane square to `normal` (the
// boundary's, which it lies in); true, with the patch updated, when no quad is inverted or
// turned against `normal` afterwards.
bool untangle_planar(FilledPatch& patch, const Eigen::Vector3d& normal) {
  const auto nv = static_cast<size_t>(patch.mesh.vertices.rows());
  std::vector<Eigen::Vector3d> positions(nv);
  for (size_t v = 0; v < nv; ++v)
    positions[v] = patch.mesh.vertices.row(static_cast<Eigen::Index>(v)).transpose();
  std::vector<std::array<int, 4>> quads(static_cast<size_t>(patch.mesh.faces.rows()));
  for (size_t f = 0; f < quads.size(); ++f)
    for (int k = 0; k < 4; ++k)
      quads[f][static_cast<size_t>(k)] = patch.mesh.faces(static_cast<Eigen::Index>(f), k);
  std::vector<char> fixed(nv, 0);
  for (const auto& side : patch.topology.side_vertices)
    for (const int v : side) fixed[static_cast<size_t>(v)] = 1;
  if (!detail::untangle_in_plane(positions, quads, fixed, normal)) return false;
  QuadMesh mesh = patch.mesh;
  for (size_t v = 0; v < nv; ++v)
    mesh.vertices.row(static_cast<Eigen::Index>(v)) = positions[v].transpose();
  QuadQuality quality = measure_quality(mesh, patch.topology.corner_vertices());
  if (quality.inverted_quads > 0 || quads_turned_against(mesh, normal) > 0) return false;
  patch.mesh = std::move(mesh);
  patch.quality = quality;
  return true;
}

}  // namespace

std::vector<int> PatchTopology::corner_vertices() const {
  return corners_of(side_vertices);
}

PatchTopology fill_region(std::span<const int> side_counts) {
  check_counts(side_counts);
  const std::vector<Eigen::MatrixX3d> sides = display_sides(side_counts);
  const BoundaryShape shape = straight_sided_shape(side_counts);
  std::optional<Built> yasseen;
  const Plan plan = choose_plan(side_counts, shape, sides, yasseen);
  return to_topology(yasseen ? std::move(*yasseen) : realize(plan, side_counts, sides, shape),
                     plan);
}

FilledPatch fill_region(const std::vector<Eigen::MatrixX3d>& side_points,
                        const FillGeometryOptions& options) {
  check_side_points(side_points);
  std::vector<int> counts;
  for (const auto& side : side_points) counts.push_back(static_cast<int>(side.rows()) - 1);
  check_counts(counts);
  const BoundaryShape shape = measured_shape(side_points);
  // The plans are ranked by their corners and valences, not by the size of their quads: a plan
  // with thin spokes can fill the region with a fraction of the quads its edges ask for (a
  // raglan sleeve of sides (12, 8, 5, 21, 2): 62 quads of ~15 cm² for 3 cm edges, where 108
  // fit, and counts that jump as edge_length changes). The first fill measures the region's
  // area A; with the boundary's mean edge length e it asks for about A / e² quads, and a plan
  // with fewer than kLeastQuadShare of those (or more than kMostQuadShare) is passed over for
  // the next ones (found again by
  // choose_plan with the others excluded), the counts-only plan among them.
  // The target only means something when the boundary's edges have about one length, as a
  // garment's do (each curve's count is its length over edge_length): sides whose mean edges
  // differ by more than kEdgeSpread (a regular pentagon with 5 edges on one side and 2 on the
  // next) ask for no particular count, and no plan is passed over for its quad count.
  double boundary_length = 0, shortest_edge = 1e300, longest_edge = 0;
  for (const auto& side : side_points) {
    double length = 0;
    for (Eigen::Index r = 0; r + 1 < side.rows(); ++r)
      length += (side.row(r + 1) - side.row(r)).norm();
    boundary_length += length;
    shortest_edge = std::min(shortest_edge, length / static_cast<double>(side.rows() - 1));
    longest_edge = std::max(longest_edge, length / static_cast<double>(side.rows() - 1));
  }
  const double mean_edge = boundary_length / std::accumulate(counts.begin(), counts.end(), 0);
  const bool one_edge_length = longest_edge <= kEdgeSpread * shortest_edge;
  const std::vector<Eigen::MatrixX3d> display = display_sides(counts);
  const BoundaryShape straight = straight_sided_shape(counts);
  const auto quads_of = [&](const Plan& plan) {
    return static_cast<double>(realize(plan, counts, display, straight).builder.faces().size());
  };
  std::optional<double> asked;  // A / e², from the first fill (0: no single edge length)
  const auto off_count = [&](double quads) {
    return *asked > 0 && (quads < kLeastQuadShare * *asked || quads > kMostQuadShare * *asked);
  };
  const auto same = [](const Plan& x, const Plan& y) {
    return x.yasseen == y.yasseen && x.strips == y.strips && x.strip_corners == y.strip_corners &&
           x.partition == y.partition;
  };
  // Fewer folds first, then no degenerate quad (a sliver the body's shape squeezed), then a plan
  // with enough quads.
  // with enough quads. (Slivers count only when the edges have one length: with 1 edge on one
  // side and 6 on the next, aspect ratios of 6 and more belong to the region).
  const auto key = [&](const FilledPatch& patch, bool coarse) {
    return std::tuple(patch.quality.inverted_quads,
                      one_edge_length && patch.quality.max_aspect_ratio >= kDegenerateAspect,
                      coarse);
  };
  // When the relaxed mesh still has inverted quads (a layout whose blocks start overlapping
  // near a reflex corner that relaxation and untangling could not undo), the next best plans
  // are tried; the first without inverted quads wins, else the one with fewest.
  std::vector<Plan> tried, filled;
  std::optional<FilledPatch> best_patch;
  bool best_coarse = false;
  std::optional<Plan> count_plan;  // chosen when first needed
  for (int choice = 0;
       choice < 3 * kGeometryAttempts && static_cast<int>(filled.size()) < kGeometryAttempts;
       ++choice) {
    std::optional<Built> yasseen;
    Plan plan = choose_plan(counts, shape, side_points, yasseen, tried);
    if (asked && *asked > 0 && !count_plan) {
      // After the first fill: the counts-only plan is the first alternative.
      std::optional<Built> none;
      count_plan = choose_plan(counts, straight, display, none);
      if (std::none_of(tried.begin(), tried.end(),
                       [&](const Plan& t) { return same(t, *count_plan); })) {
        plan = *count_plan;
        yasseen.reset();
      }
    }
    if (plan.folded == std::numeric_limits<int>::max()) break;  // nothing left to try
    const bool coarse = asked && off_count(quads_of(plan));
    if (coarse) {
      tried.push_back(plan);  // passed over, not filled
      continue;
    }
    FilledPatch patch = fill_with_plan(plan, counts, side_points, shape, yasseen, options);
    if (!asked) {
      double area = 0;
      for (Eigen::Index f = 0; f < patch.mesh.face_count(); ++f) {
        const auto corner = [&](int k) -> Eigen::Vector3d {
          return patch.mesh.vertices.row(patch.mesh.faces(f, k)).transpose();
        };
        area += 0.5 * (corner(2) - corner(0)).cross(corner(3) - corner(1)).norm();
      }
      asked = one_edge_length ? area / (mean_edge * mean_edge) : 0.0;
    }
    const bool too_few = off_count(static_cast<double>(patch.mesh.face_count()));
    if (!best_patch || key(patch, too_few) < key(*best_patch, best_coarse)) {
      best_patch = std::move(patch);
      best_coarse = too_few;
    }
    if (key(*best_patch, best_coarse) == std::tuple(0, false, false)) break;
    tried.push_back(plan);
    filled.push_back(plan);
  }
  // Every plan tried keeps inverted quads: relax the best of them again with reference normals
  // taken after the unguarded sweeps, which untangle the large overlapping clusters the starting
  // normals cannot see. Last, so that no fill that comes out clean the first way changes; and
  // only a clean result is taken: one that merely folds less can be worse in every other way
  // (the t-shirt's back: 1 inverted quad instead of 2, but a sliver that the garment's surface
  // smoothing turns into a quad of aspect 24). Only the best plan: retrying all of them also
  // cleans 5 more of the 210° chevrons of the concave test (20 instead of 25 of 648 keep a fold)
  // but cost the t-shirt's and the shorts' backs, which no plan cleans, 20 and 9 ms of meshing.
  if (!filled.empty() && best_patch->quality.inverted_quads > 0) {
    std::optional<Built> none;
    FilledPatch patch = fill_with_plan(filled.front(), counts, side_points, shape, none, options,
                                       detail::ReferenceNormals::kAfterSweeps);
    if (patch.quality.inverted_quads == 0) best_patch = std::move(patch);
  }
  // Still folded, on a flat boundary without projection: a foldover-free placement of the same
  // connectivity in the boundary's plane (a barrier on every quad corner's signed area,
  // detail::untangle_in_plane), on the best patch first and then on the other plans tried.
  // Relaxation and the pattern search above only ever look at one vertex or one sweep at a
  // time; a thin chevron next to a 210° reflex corner needs a whole row to move together. Last,
  // so that no fill that comes out clean before changes; taken only when it comes out clean.
  // Not on curved or projected patches: moving in one plane does not place a curved panel, and
  // on the garment examples' back panels that fold (the t-shirt's, the shorts') it never came
  // out clean but made their meshing 3.7 and 7 times slower.
  if (shape.planar && !options.project && best_patch->quality.inverted_quads > 0 &&
      !untangle_planar(*best_patch, shape.normal))
    for (const Plan& plan : tried) {  // built again only when the best patch cannot be placed
      std::optional<Built> none;
      FilledPatch candidate = fill_with_plan(plan, counts, side_points, shape, none, options);
      if (untangle_planar(candidate, shape.normal)) {
        best_patch = std::move(candidate);
        break;
      }
    }
  if (shape.planar && !options.project && best_patch->quality.inverted_quads == 0 &&
      best_patch->mesh.faces.rows() <= kThinQuadMaxQuads)
    widen_thin_quads(*best_patch, shape.normal);
  return std::move(*best_patch);
}

namespace {

FilledPatch fill_with_plan(const Plan& plan, std::span<const int> counts,
                           const std::vector<Eigen::MatrixX3d>& side_points,
                           const BoundaryShape& shape, std::optional<Built>& yasseen,
                           const FillGeometryOptions& options, detail::ReferenceNormals reference) {
  FilledPatch patch;
  Built built = yasseen ? std::move(*yasseen) : realize(plan, counts, side_points, shape);
  // The same connectivity laid out flat for display.
  patch.topology =
      to_topology(realize(plan, counts, display_sides(counts), straight_sided_shape(counts)), plan);
  // Projection and relaxation work on the builder's arrays; the mesh is built once, after.
  std::vector<Eigen::Vector3d>& positions = built.builder.positions();
  std::vector<char> fixed(positions.size(), 0);
  for (const auto& side : patch.topology.side_vertices)
    for (const int v : side) fixed[static_cast<size_t>(v)] = 1;
  if (options.place)
    options.place(positions, built.builder.faces(), fixed);
  else if (options.project)
    for (size_t v = 0; v < positions.size(); ++v)
      if (!fixed[v]) positions[v] = options.project(positions[v]);
  detail::relax_interior(positions, built.builder.faces(), fixed, options.relax_iterations,
                         options.project, reference);
  patch.mesh = built.builder.build();
  if (patch.mesh.faces != patch.topology.mesh.faces)
    throw std::logic_error("the fill's connectivity depends on geometry");
  patch.quality = measure_quality(patch.mesh, patch.topology.corner_vertices());
  if (shape.planar && !options.project)
    patch.quality.inverted_quads =
        std::max(patch.quality.inverted_quads, quads_turned_against(patch.mesh, shape.normal));
  return patch;
}

}  // namespace

Eigen::MatrixX3d resample_by_arc_length(const Eigen::MatrixX3d& polyline, int count) {
  if (polyline.rows() < 2) throw FillError("a side polyline needs at least 2 points");
  if (count < 1) throw FillError("a side needs at least 1 edge");
  std::vector<double> along{0.0};
  for (Eigen::Index r = 1; r < polyline.rows(); ++r)
    along.push_back(along.back() + (polyline.row(r) - polyline.row(r - 1)).norm());
  const double length = along.back();
  Eigen::MatrixX3d points(count + 1, 3);
  points.row(0) = polyline.row(0);
  points.row(count) = polyline.bottomRows<1>();
  size_t segment = 1;
  for (int k = 1; k < count; ++k) {
    const double target = length * k / count;
    while (segment + 1 < along.size() && along[segment] < target) ++segment;
    const double span = along[segment] - along[segment - 1];
    const double t = span > 0 ? (target - along[segment - 1]) / span : 0.0;
    const auto s = static_cast<Eigen::Index>(segment);
    points.row(k) = (1 - t) * polyline.row(s - 1) + t * polyline.row(s);
  }
  return points;
}

FilledPatch fill_region(const std::vector<Eigen::MatrixX3d>& side_polylines,
                        std::span<const int> side_counts, const FillGeometryOptions& options) {
  if (side_polylines.size() != side_counts.size())
    throw FillError("got " + std::to_string(side_polylines.size()) + " side polylines but " +
                    std::to_string(side_counts.size()) + " edge counts");
  check_counts(side_counts);
  check_side_points(side_polylines);
  std::vector<Eigen::MatrixX3d> points;
  for (size_t i = 0; i < side_polylines.size(); ++i)
    points.push_back(resample_by_arc_length(side_polylines[i], side_counts[i]));
  // Consecutive sides share their corner exactly.
  for (size_t i = 0; i < points.size(); ++i)
    points[i].bottomRows<1>() = points[(i + 1) % points.size()].topRows<1>();
  return fill_region(points, options);
}

}  // namespace sd::meshing
