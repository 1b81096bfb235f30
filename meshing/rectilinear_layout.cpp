#include "meshing/rectilinear_layout.hpp"

#include <algorithm>
#include <array>
#include <climits>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <stdexcept>
#include <tuple>

namespace sd::meshing::detail {
namespace {

// Unit steps of the four lattice directions, counter-clockwise from +x.
constexpr std::array<std::array<int, 2>, 4> kStep{{{1, 0}, {0, 1}, {-1, 0}, {0, -1}}};

int direction(int d) {
  return ((d % 4) + 4) % 4;
}

// The lattice point of every loop position (position 0 at the origin, the edge leaving it along
// +x turned by its own turn), and whether the walk closes without visiting a point twice.
bool lattice_walk(std::span<const int> turns, std::vector<std::array<int, 2>>& points) {
  const auto size = turns.size();
  points.resize(size);
  int x = 0, y = 0, d = 0;
  for (size_t p = 0; p < size; ++p) {
    points[p] = {x, y};
    d = direction(d + turns[p]);
    x += kStep[static_cast<size_t>(d)][0];
    y += kStep[static_cast<size_t>(d)][1];
  }
  if (x != 0 || y != 0) return false;
  std::vector<std::int64_t> keys(size);
  for (size_t p = 0; p < size; ++p)
    keys[p] =
        (static_cast<std::int64_t>(points[p][0]) << 32) ^ static_cast<std::uint32_t>(points[p][1]);
  std::sort(keys.begin(), keys.end());
  return std::adjacent_find(keys.begin(), keys.end()) == keys.end();
}

// How far the lattice walk's heading strays from the boundary's: after each position, the
// quarter turns the walk has made less those the boundary has made, its mean taken off (the
// walk may be turned as a whole). The boundary's turns are first evened out to add up to 4 like
// the walk's (a loop measured about one normal on a curved surface turns a little more or less),
// the difference spread over every position. So a reflex vertex placed where the boundary turns
// inwards costs nothing, and one placed on a straight hem bends the whole walk between it and the
// bend it should have been at.
double heading_mismatch(std::span<const int> turns, std::span<const double> boundary) {
  const auto size = static_cast<double>(turns.size());
  double total = 0;
  for (const double t : boundary) total += t;
  const double spread = (total - 4) / size;
  double heading = 0, sum = 0, sum_squares = 0;
  for (size_t p = 0; p < turns.size(); ++p) {
    heading += turns[p] - (boundary[p] - spread);
    sum += heading;
    sum_squares += heading * heading;
  }
  return sum_squares - sum * sum / size;
}

int turn_cost(const PositionCosts& costs, size_t p, int turn) {
  return turn == 1 ? costs.as_corner[p] : turn == 0 ? costs.as_side[p] : costs.as_reflex[p];
}

}  // namespace

std::optional<RectilinearLayout> best_rectilinear_layout(const PositionCosts& costs, int max_cost,
                                                         int& budget) {
  const auto size = static_cast<int>(costs.as_side.size());
  if (costs.as_reflex.size() != costs.as_side.size() || size < 4) return std::nullopt;
  if (!costs.turn.empty() && costs.turn.size() != costs.as_side.size())
    throw std::logic_error("a turn for every loop position");
  // Every position starts at its cheapest turn; a layout is a set of changes from there, each
  // adding `extra` >= 1 to the cost (|valence − regular| is convex in the turn, and the fold
  // penalty only raises a corner) and `shift` to Σ t.
  std::vector<int> base(static_cast<size_t>(size));
  int base_cost = 0, base_turns = 0;
  for (int p = 0; p < size; ++p) {
    int best_turn = 1;
    for (const int t : {0, -1})
      if (turn_cost(costs, static_cast<size_t>(p), t) <
          turn_cost(costs, static_cast<size_t>(p), best_turn))
        best_turn = t;
    base[static_cast<size_t>(p)] = best_turn;
    base_cost += turn_cost(costs, static_cast<size_t>(p), best_turn);
    base_turns += best_turn;
  }
  const int target = 4 - base_turns;  // Σ shift the changes must make
  struct Change {
    int position, turn, extra, shift;
  };
  std::vector<Change> changes;  // by position
  bool parity = true;           // every change's extra and shift have the same parity
  for (int p = 0; p < size; ++p)
    for (const int t : {1, 0, -1}) {
      if (t == base[static_cast<size_t>(p)]) continue;
      const int extra = turn_cost(costs, static_cast<size_t>(p), t) -
                        turn_cost(costs, static_cast<size_t>(p), base[static_cast<size_t>(p)]);
      const int shift = t - base[static_cast<size_t>(p)];
      if (extra < std::abs(shift)) throw std::logic_error("a turn change cheaper than its shift");
      parity = parity && (extra - shift) % 2 == 0;
      changes.push_back({p, t, extra, shift});
    }
  const int max_extra = max_cost - base_cost;
  if (max_extra < std::abs(target) || std::abs(target) > kMaxTurnShift) return std::nullopt;

  std::optional<RectilinearLayout> best;
  const int given = budget;
  std::vector<int> turns = base;
  std::vector<std::array<int, 2>> points;
  // The walk's displacement from its turning positions only (O(n + changes)): the base's
  // turning positions merged with the changed ones (`changed`, increasing); the dense walk,
  // which also checks that no point is visited twice, only for the few that close.
  std::vector<int> base_turning, changed;
  for (int p = 0; p < size; ++p)
    if (base[static_cast<size_t>(p)] != 0) base_turning.push_back(p);
  std::vector<int> turning;
  auto closes = [&] {
    turning.clear();
    size_t i = 0, j = 0;
    while (i < base_turning.size() || j < changed.size()) {
      int p;
      if (j == changed.size() || (i < base_turning.size() && base_turning[i] < changed[j])) {
        p = base_turning[i++];
      } else {
        p = changed[j++];
        if (i < base_turning.size() && base_turning[i] == p) ++i;
      }
      if (turns[static_cast<size_t>(p)] != 0) turning.push_back(p);
    }
    if (turning.empty()) return false;
    long x = 0, y = 0;
    int d = 0;
    for (size_t k = 0; k < turning.size(); ++k) {
      d = direction(d + turns[static_cast<size_t>(turning[k])]);
      const int next = k + 1 < turning.size() ? turning[k + 1] : turning.front() + size;
      x += static_cast<long>(next - turning[k]) * kStep[static_cast<size_t>(d)][0];
      y += static_cast<long>(next - turning[k]) * kStep[static_cast<size_t>(d)][1];
    }
    return x == 0 && y == 0;
  };
  auto evaluate = [&](int extra) {
    if (!closes() || !lattice_walk(turns, points)) return;
    RectilinearLayout layout;
    layout.cost = base_cost + extra;
    layout.shortest = INT_MAX;
    int run = 0;
    // Runs between turning positions, starting after the last one (which exists: Σ t = 4).
    int last = size - 1;
    while (turns[static_cast<size_t>(last)] == 0) --last;
    for (int k = 1; k <= size; ++k) {
      const int p = (last + k) % size;
      ++run;
      if (turns[static_cast<size_t>(p)] != 0) {
        layout.shortest = std::min(layout.shortest, run);
        run = 0;
      }
    }
    for (size_t p = 0; p < points.size(); ++p) {
      const auto& q = points[(p + 1) % points.size()];
      layout.cells += points[p][0] * q[1] - q[0] * points[p][1];
    }
    layout.cells /= 2;  // shoelace: the walk is counter-clockwise
    if (!costs.turn.empty()) layout.mismatch = heading_mismatch(turns, costs.turn);
    for (int p = 0; p < size; ++p) {
      const int t = turns[static_cast<size_t>(p)];
      layout.irregular += turn_cost(costs, static_cast<size_t>(p), t) % kFoldPenalty != 0 ? 1 : 0;
      if (t == 1 && !costs.flat.empty() && costs.flat[static_cast<size_t>(p)]) ++layout.flat;
    }
    if (!best ||
        std::tuple(layout.irregular, layout.flat, layout.mismatch, -layout.cells,
                   -layout.shortest) < std::tuple(best->irregular, best->flat, best->mismatch,
                                                  -best->cells, -best->shortest)) {
      layout.turns = turns;
      best = std::move(layout);
    }
  };
  // Sets of changes at distinct positions with Σ extra = level and Σ shift = target; each
  // candidate change looked at costs one unit of the budget.
  auto search = [&](auto&& self, size_t from, int left, int need, int level) -> void {
    if (left == 0) {
      if (need == 0) evaluate(level);
      return;
    }
    for (size_t i = from; i < changes.size() && budget > 0; ++i) {
      const Change& c = changes[i];
      --budget;
      if (c.extra > left || std::abs(need - c.shift) > left - c.extra) continue;
      turns[static_cast<size_t>(c.position)] = c.turn;
      changed.push_back(c.position);
      size_t next = i + 1;  // one change per position
      while (next < changes.size() && changes[next].position == c.position) ++next;
      self(self, next, left - c.extra, need - c.shift, level);
      changed.pop_back();
      turns[static_cast<size_t>(c.position)] = base[static_cast<size_t>(c.position)];
    }
  };
  for (int level = std::abs(target); level <= max_extra && !best && budget > 0; ++level) {
    if (parity && (level - target) % 2 != 0) continue;
    search(search, 0, level, target, level);
  }
  if (best) best->checks = given - budget;
  return best;
}

void fill_rectilinear(QuadMeshBuilder& builder, std::span<const int> loop,
                      std::span<const int> turns) {
  std::vector<std::array<int, 2>> points;
  if (loop.size() != turns.size() || !lattice_walk(turns, points))
    throw std::logic_error("a rectilinear layout must close without touching itself");
  int x0 = INT_MAX, y0 = INT_MAX, x1 = INT_MIN, y1 = INT_MIN;
  for (const auto& [x, y] : points) {
    x0 = std::min(x0, x), x1 = std::max(x1, x);
    y0 = std::min(y0, y), y1 = std::max(y1, y);
  }
  const int width = x1 - x0 + 1, height = y1 - y0 + 1;
  auto at = [&](int x, int y) { return static_cast<size_t>((y - y0) * width + (x - x0)); };
  // Vertex id of every lattice point (-1 outside), boundary first; vertical boundary edges by
  // their lower end, for the inside test of the cells (even-odd along each row of cells).
  std::vector<int> id(static_cast<size_t>(width * height), -1);
  std::vector<char> boundary(id.size(), 0), vertical(id.size(), 0);
  for (size_t p = 0; p < points.size(); ++p) {
    id[at(points[p][0], points[p][1])] = loop[p];
    boundary[at(points[p][0], points[p][1])] = 1;
    const auto& q = points[(p + 1) % points.size()];
    if (q[0] == points[p][0]) vertical[at(q[0], std::min(q[1], points[p][1]))] = 1;
  }
  std::vector<char> inside(id.size(), 0);  // cell with lower-left corner (x, y)
  for (int y = y0; y < y1; ++y) {
    bool in = false;
    for (int x = x0; x < x1; ++x) {
      if (vertical[at(x, y)]) in = !in;
      inside[at(x, y)] = in ? 1 : 0;
    }
  }
  // Nearest boundary point in each of the four directions along the grid lines (one sweep per
  // row and column each way, O(area)): the mean of the two linear interpolations, along the row
  // and along the column, places the interior vertices.
  std::vector<int> left(id.size()), right(id.size()), down(id.size()), up(id.size());
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0, last = x0; x <= x1; ++x) {
      if (boundary[at(x, y)]) last = x;
      left[at(x, y)] = last;
    }
    for (int x = x1, last = x1; x >= x0; --x) {
      if (boundary[at(x, y)]) last = x;
      right[at(x, y)] = last;
    }
  }
  for (int x = x0; x <= x1; ++x) {
    for (int y = y0, last = y0; y <= y1; ++y) {
      if (boundary[at(x, y)]) last = y;
      down[at(x, y)] = last;
    }
    for (int y = y1, last = y1; y >= y0; --y) {
      if (boundary[at(x, y)]) last = y;
      up[at(x, y)] = last;
    }
  }
  auto cell_inside = [&](int x, int y) {
    return x >= x0 && x < x1 && y >= y0 && y < y1 && inside[at(x, y)];
  };
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      if (boundary[at(x, y)] || !cell_inside(x, y)) continue;
      const size_t here = at(x, y);
      const int xl = left[here], xr = right[here], yd = down[here], yu = up[here];
      const double s = static_cast<double>(x - xl) / (xr - xl);
      const double t = static_cast<double>(y - yd) / (yu - yd);
      const Eigen::Vector3d position =
          0.5 * ((1 - s) * builder.position(id[at(xl, y)]) + s * builder.position(id[at(xr, y)]) +
                 (1 - t) * builder.position(id[at(x, yd)]) + t * builder.position(id[at(x, yu)]));
      id[here] = builder.add_vertex(position);
    }
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x)
      if (inside[at(x, y)])
        builder.add_quad({id[at(x, y)], id[at(x + 1, y)], id[at(x + 1, y + 1)], id[at(x, y + 1)]});
}

}  // namespace sd::meshing::detail
