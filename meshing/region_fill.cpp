#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "meshing/loop_positions.hpp"
#include "meshing/region_partition.hpp"

// The second half of the region partition: filling a chosen layout (the polygon's grids, the
// Yasseen partition) and the strip regions.
namespace sd::meshing::detail {

void fill_polygon(QuadMeshBuilder& builder, std::span<const int> loop,
                  const PolygonLayout& layout) {
  const auto size = static_cast<int>(loop.size());
  const auto m = static_cast<int>(layout.corners.size());
  auto corner = [&](int j) { return layout.corners[static_cast<size_t>(wrap(j, m))]; };
  if (layout.spokes.empty()) {
    if (m != 4) throw std::logic_error("a grid layout has four corners");
    std::vector<std::vector<int>> sides;
    for (int j = 0; j < 4; ++j) sides.push_back(loop_segment(loop, corner(j), corner(j + 1)));
    builder.add_grid(sides[0], sides[1], sides[2], sides[3]);
    return;
  }
  // Nasri partition: centre G, spoke j from G to E_j on layout side j, E_j at d_{j-1} edges
  // from corner j; region j (at corner j) is a d_{j-1} by d_j grid.
  auto spoke = [&](int j) { return layout.spokes[static_cast<size_t>(wrap(j, m))]; };
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const int v : loop) centre += builder.position(v);
  const int g = builder.add_vertex(centre / size);
  std::vector<int> e(static_cast<size_t>(m));
  std::vector<std::vector<int>> spokes(static_cast<size_t>(m));
  for (int j = 0; j < m; ++j) {
    e[static_cast<size_t>(j)] = wrap(corner(j) + spoke(j - 1), size);
    spokes[static_cast<size_t>(j)] =
        builder.add_chain(g, loop[static_cast<size_t>(e[static_cast<size_t>(j)])], spoke(j));
  }
  for (int j = 0; j < m; ++j) {
    const int prev = wrap(j - 1, m);
    const std::vector<int> bottom = loop_segment(loop, corner(j), e[static_cast<size_t>(j)]);
    std::vector<int> right(spokes[static_cast<size_t>(j)].rbegin(),
                           spokes[static_cast<size_t>(j)].rend());
    const std::vector<int>& top = spokes[static_cast<size_t>(prev)];
    const std::vector<int> left = loop_segment(loop, e[static_cast<size_t>(prev)], corner(j));
    builder.add_grid(bottom, right, top, left);
  }
}

bool fill_yasseen(QuadMeshBuilder& builder, const std::vector<std::vector<int>>& sides,
                  int budget) {
  const auto n = static_cast<int>(sides.size());
  if (n < 3 || n % 4 == 0) return false;
  std::vector<int> l(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i)
    l[static_cast<size_t>(i)] = static_cast<int>(sides[static_cast<size_t>(i)].size()) - 1;
  auto at = [n](auto& v, int i) -> auto& {
    return v[static_cast<size_t>(wrap(i, n))];
  };
  const std::vector<int> doubled = nasri_distances_doubled(l);
  std::vector<int> d(static_cast<size_t>(n));
  bool any_short = false;
  for (int i = 0; i < n; ++i) {
    if (at(doubled, i) % 2 != 0) return false;
    at(d, i) = at(doubled, i) / 2;
    any_short = any_short || at(d, i) < 1;
  }
  if (!any_short) return false;

  // Large sides: those entering a non-positive d_i with a minus sign (i+3, i+7, ...).
  const int terms = n % 2 == 1 ? n : n / 2;
  std::vector<char> large(static_cast<size_t>(n), 0);
  for (int i = 0; i < n; ++i)
    if (at(d, i) < 1)
      for (int k = 1; k < terms; k += 2) at(large, i + 1 + 2 * k) = true;
  // Distorted regions (region i sits at corner i, between sides i-1 and i).
  std::vector<char> distorted(static_cast<size_t>(n), 0);
  for (int i = 0; i < n; ++i) {
    if (!at(large, i)) continue;
    const bool prev = at(large, i - 1), next = at(large, i + 1);
    if (!prev && !next) at(distorted, i) = at(distorted, i + 1) = true;
    if (next) at(distorted, i + 1) = true;
    if (prev) at(distorted, i) = true;
  }
  // New distances: the non-positive ones set to 2 (own side large) or 1, then propagated
  // through the sides that are not large (l_i = d_{i-1} + d_{i+1}).
  std::vector<char> known(static_cast<size_t>(n), 0);
  for (int i = 0; i < n; ++i)
    if (at(d, i) < 1) {
      at(d, i) = at(large, i) ? 2 : 1;
      at(known, i) = true;
    }
  for (int sweep = 0; sweep < 4 * n; ++sweep) {  // min() only lowers values: few sweeps
    bool changed = false;
    for (int i = 0; i < n; ++i) {
      if (at(large, i)) continue;
      auto settle = [&](int from, int to) {
        int value = at(l, i) - at(d, from);
        if (at(known, to)) value = std::min(value, at(d, to));
        if (!at(known, to) || value != at(d, to)) {
          at(d, to) = value;
          at(known, to) = true;
          changed = true;
        }
      };
      if (at(known, i - 1))
        settle(i - 1, i + 1);
      else if (at(known, i + 1))
        settle(i + 1, i - 1);
      else {
        at(d, i - 1) = at(l, i) / 2;
        at(d, i + 1) = at(l, i) - at(l, i) / 2;
        at(known, i - 1) = at(known, i + 1) = true;
        changed = true;
      }
    }
    if (!changed) break;
  }
  if (*std::min_element(d.begin(), d.end()) < 1) return false;

  // Where E_i splits side i: x_i edges from corner i, l_i − x_i to corner i+1.
  std::vector<int> x(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    if (at(l, i) < 2) return false;
    int split;
    if (!at(large, i))
      split = at(d, i - 1);
    else if (at(distorted, i) && !at(distorted, i + 1))
      split = at(l, i) - at(d, i + 1);
    else if (!at(distorted, i) && at(distorted, i + 1))
      split = at(d, i - 1);
    else
      split = static_cast<int>(std::lround(static_cast<double>(at(l, i)) * at(d, i - 1) /
                                           (at(d, i - 1) + at(d, i + 1))));
    at(x, i) = std::clamp(split, 1, at(l, i) - 1);
  }
  // A region that is not an exact rectangle is distorted too.
  for (int i = 0; i < n; ++i)
    if (at(l, i - 1) - at(x, i - 1) != at(d, i) || at(x, i) != at(d, i - 1))
      at(distorted, i) = true;
  if (std::all_of(distorted.begin(), distorted.end(), [](char b) { return b != 0; })) return false;
  // Runs of consecutive distorted regions are merged; each run must have an even perimeter.
  const int start =
      static_cast<int>(std::find(distorted.begin(), distorted.end(), 0) - distorted.begin());
  std::vector<std::pair<int, int>> runs;  // first and last region of each run
  for (int k = 1; k <= n; ++k) {
    const int i = start + k;
    if (!at(distorted, i)) continue;
    if (!runs.empty() && runs.back().second == i - 1)
      runs.back().second = i;
    else
      runs.emplace_back(i, i);
  }
  for (const auto& [a, b] : runs) {
    int perimeter = (at(l, a - 1) - at(x, a - 1)) + at(x, b) + at(d, b) + at(d, a - 1);
    for (int i = a; i < b; ++i) perimeter += at(l, i);
    if (perimeter % 2 != 0 || perimeter < 4) return false;
  }

  // Build: centre, the spokes that are not inside a merged run, rectangles, then the runs.
  auto side_vertex = [&](int i, int offset) {
    return sides[static_cast<size_t>(wrap(i, n))][static_cast<size_t>(offset)];
  };
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  int boundary_count = 0;
  for (const auto& side : sides)
    for (size_t k = 0; k + 1 < side.size(); ++k, ++boundary_count)
      centre += builder.position(side[k]);
  const int g = builder.add_vertex(centre / boundary_count);
  std::vector<std::vector<int>> spoke(static_cast<size_t>(n));  // G → E_i
  for (int i = 0; i < n; ++i)
    if (!(at(distorted, i) && at(distorted, i + 1)))
      at(spoke, i) = builder.add_chain(g, side_vertex(i, at(x, i)), at(d, i));
  auto side_part = [&](int i, int from, int to) {
    const auto& side = sides[static_cast<size_t>(wrap(i, n))];
    return std::vector<int>(side.begin() + from, side.begin() + to + 1);
  };
  for (int i = 0; i < n; ++i) {
    if (at(distorted, i)) continue;
    const std::vector<int> bottom = side_part(i, 0, at(x, i));
    const std::vector<int> right(at(spoke, i).rbegin(), at(spoke, i).rend());
    const std::vector<int> left = side_part(i - 1, at(x, i - 1), at(l, i - 1));
    builder.add_grid(bottom, right, at(spoke, i - 1), left);
  }
  // Regular valence of every vertex of the whole region: 2 at corners, 3 on sides, 4 inside.
  std::vector<int> regular(static_cast<size_t>(builder.vertex_count()), 4);
  for (int i = 0; i < n; ++i)
    for (size_t k = 0; k < sides[static_cast<size_t>(i)].size(); ++k)
      regular[static_cast<size_t>(sides[static_cast<size_t>(i)][k])] =
          k == 0 ? 2 : (k + 1 == sides[static_cast<size_t>(i)].size() ? 2 : 3);
  for (const auto& [a, b] : runs) {
    // Loop, counter-clockwise: E_{a-1} → corner a → … → E_b → G → E_{a-1}.
    std::vector<int> loop = side_part(a - 1, at(x, a - 1), at(l, a - 1));
    for (int i = a; i < b; ++i) {
      const std::vector<int> part = side_part(i, 1, at(l, i));
      loop.insert(loop.end(), part.begin(), part.end());
    }
    const std::vector<int> last = side_part(b, 1, at(x, b));
    loop.insert(loop.end(), last.begin(), last.end());
    loop.insert(loop.end(), at(spoke, b).rbegin() + 1, at(spoke, b).rend());
    loop.insert(loop.end(), at(spoke, a - 1).begin() + 1, at(spoke, a - 1).end() - 1);
    // Position costs from the edges each loop vertex already has outside this polygon.
    const std::vector<int> valence = builder.valences();
    PositionCosts costs;
    for (const int v : loop) {
      const int outside = valence[static_cast<size_t>(v)] - 2;
      const int reg = regular[static_cast<size_t>(v)];
      costs.as_corner.push_back(std::abs(2 + outside - reg));
      costs.as_side.push_back(std::abs(3 + outside - reg));
    }
    fill_polygon(builder, loop, best_layout(costs, budget));
  }
  return true;
}

bool StripRegion::strip(int side, QuadMeshBuilder* builder, const Eigen::Vector3d& normal) {
  const auto size = static_cast<int>(loop.size());
  const auto n = static_cast<int>(corners.size());
  auto corner = [&](int i) { return corners[static_cast<size_t>(wrap(i, n))]; };
  auto arc = [&](int i) { return wrap(corner(i + 1) - corner(i), size); };
  const int a = corner(side), b = corner(side + 1), l = arc(side);
  if (n < 2 || size - 2 < 4 ||
      (n == 2 ? arc(side + 1) < 3 : arc(side - 1) < 2 || arc(side + 1) < 2))
    return false;
  auto at = [&](int p) -> LoopVertex& { return loop[static_cast<size_t>(wrap(p, size))]; };
  // Vertices a..b leave the loop: the corners with no further edge, the rest with one.
  for (int k = 0; k <= l; ++k) {
    const LoopVertex& v = at(a + k);
    const int valence = v.outside + (k == 0 || k == l ? 2 : 3);
    fixed_cost += std::abs(valence - v.regular);
    fixed_irregular += valence != v.regular ? 1 : 0;
    if (valence == 2 && v.exposed) {
      ++flat;
      folded += v.reflex ? 1 : 0;
    }
  }
  std::vector<LoopVertex> chain(static_cast<size_t>(l - 1), LoopVertex{-1, 1, 4, false, false});
  // A chain runs one edge inside the side and turns where the side does.
  for (int k = 1; k < l; ++k) chain[static_cast<size_t>(k - 1)].turn = at(a + k).turn;
  if (builder != nullptr) {
    auto pos = [&](int p) -> Eigen::Vector3d { return builder->position(at(p).id); };
    for (int k = 1; k < l; ++k) {
      Eigen::Vector3d position;
      if (k == 1 || k == l - 1) {  // next to a corner: complete the corner quad's parallelogram
        position = Eigen::Vector3d::Zero();
        if (k == 1) position += pos(a - 1) + pos(a + 1) - pos(a);
        if (k == l - 1) position += pos(b + 1) + pos(b - 1) - pos(b);
        if (l == 2) position /= 2;
      } else {  // one mean edge length inwards, square to the chord through the neighbours
        const Eigen::Vector3d before = pos(a + k - 1), here = pos(a + k), after = pos(a + k + 1);
        Eigen::Vector3d inward = normal.cross(after - before);
        if (inward.norm() > 0) inward.normalize();
        position = here + 0.5 * ((here - before).norm() + (after - here).norm()) * inward;
      }
      chain[static_cast<size_t>(k - 1)].id = builder->add_vertex(position);
    }
    // Quad k: side edge (a+k, a+k+1) and chain edge (inner k+1, inner k), where the chain runs
    // a−1, w_1, ..., w_{l−1}, b+1.
    auto inner = [&](int k) {
      return k == 0 ? at(a - 1).id : k == l ? at(b + 1).id : chain[static_cast<size_t>(k - 1)].id;
    };
    for (int k = 0; k < l; ++k)
      builder->add_quad({at(a + k).id, at(a + k + 1).id, inner(k + 1), inner(k)});
  }
  at(a - 1).outside += 1;
  at(b + 1).outside += 1;
  // New loop from b+1 around to a−1, then the chain; corner side+1 at b+1, corner side at a−1.
  std::vector<LoopVertex> next;
  std::vector<int> position_of(static_cast<size_t>(size), -1);
  for (int p = b + 1; wrap(p, size) != wrap(a, size); ++p) {
    position_of[static_cast<size_t>(wrap(p, size))] = static_cast<int>(next.size());
    next.push_back(at(p));
  }
  const int last_kept = static_cast<int>(next.size()) - 1;
  next.insert(next.end(), chain.begin(), chain.end());
  for (int i = 0; i < n; ++i) {
    int& c = corners[static_cast<size_t>(i)];
    if (i == wrap(side, n))
      c = last_kept;
    else if (i == wrap(side + 1, n))
      c = 0;
    else
      c = position_of[static_cast<size_t>(c)];
  }
  loop = std::move(next);
  return true;
}

PositionCosts StripRegion::costs() const {
  PositionCosts costs;
  for (const LoopVertex& v : loop) {
    const bool single_quad = v.outside == 0;
    costs.as_corner.push_back(std::abs(v.outside + 2 - v.regular) +
                              (single_quad && v.reflex ? kFoldPenalty : 0));
    costs.as_side.push_back(std::abs(v.outside + 3 - v.regular));
    costs.flat.push_back(single_quad && v.exposed ? 1 : 0);
    costs.as_reflex.push_back(std::abs(v.outside + 4 - v.regular));
    if (measured) costs.turn.push_back(v.turn);
  }
  return costs;
}

}  // namespace sd::meshing::detail
