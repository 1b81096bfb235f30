#include "meshing/region_partition.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <bit>
#include <climits>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <tuple>

#include "meshing/loop_positions.hpp"

namespace sd::meshing::detail {
namespace {

// Arc lengths between consecutive corners (positions increasing) around a loop of size S.
std::vector<int> corner_arcs(std::span<const int> corners, int loop_size) {
  const auto m = static_cast<int>(corners.size());
  std::vector<int> arcs(static_cast<size_t>(m));
  for (int j = 0; j < m; ++j)
    arcs[static_cast<size_t>(j)] = wrap(
        corners[static_cast<size_t>(wrap(j + 1, m))] - corners[static_cast<size_t>(j)], loop_size);
  if (m == 1) arcs[0] = loop_size;
  return arcs;
}

// Σ as_side and the number of positions with a nonzero as_side: a layout's figures start from
// these (every position a side vertex) and change only at its corners.
struct SideTotals {
  int cost = 0, irregular = 0;
  explicit SideTotals(const PositionCosts& costs) {
    for (const int c : costs.as_side) {
      cost += c;
      irregular += c != 0 ? 1 : 0;
    }
  }
};

// Fills in cost, irregular and flat of a layout from its corners and the position costs
// (corners distinct), in O(corners).
void assess(PolygonLayout& layout, const PositionCosts& costs, const SideTotals& totals) {
  const auto m = static_cast<int>(layout.corners.size());
  // A grid (m = 4) has no centre; a Nasri centre of valence m costs |m − 4|.
  layout.cost = std::abs(m - 4) + totals.cost;
  layout.irregular = (m != 4 ? 1 : 0) + totals.irregular;
  layout.flat = 0;
  for (const int c : layout.corners) {
    const auto p = static_cast<size_t>(c);
    layout.cost += costs.as_corner[p] - costs.as_side[p];
    layout.irregular += (costs.as_corner[p] != 0 ? 1 : 0) - (costs.as_side[p] != 0 ? 1 : 0);
    if (!costs.flat.empty() && costs.flat[p]) ++layout.flat;
  }
}

// The always-available layouts: the cheapest single grid block over every placement of its
// corners (O(S²) constant-time checks), and triangles with arcs as equal as possible (each at
// most S/2 − 1, so every spoke is >= 1) starting at each natural corner. A loop of 4 is one quad.
PolygonLayout fallback_layout(int loop_size, std::span<const int> starts,
                              const PositionCosts& costs) {
  PolygonLayout best;
  best.cost = INT_MAX;
  const int half = loop_size / 2;
  auto delta = [&](int p) {  // p in [0, 2 loop_size)
    if (p >= loop_size) p -= loop_size;
    return costs.as_corner[static_cast<size_t>(p)] - costs.as_side[static_cast<size_t>(p)];
  };
  const int base = std::accumulate(costs.as_side.begin(), costs.as_side.end(), 0);
  auto flat = [&](int p) {  // p in [0, 2 loop_size)
    if (p >= loop_size) p -= loop_size;
    return costs.flat.empty() ? 0 : static_cast<int>(costs.flat[static_cast<size_t>(p)]);
  };
  // A grid's corners are two antipodal pairs (p, p + half) and (q, q + half), q = p + a: its
  // cost is base + g(p) + g(q) with g(p) = delta(p) + delta(p + half), which has period half.
  // Pairs that cannot reach the best cost so far are skipped (only a strictly higher cost is
  // skipped, so ties are still broken exactly as by the full double loop).
  std::vector<int> g(static_cast<size_t>(half)), flats_at(static_cast<size_t>(half));
  for (int p = 0; p < half; ++p) {
    g[static_cast<size_t>(p)] = delta(p) + delta(p + half);
    flats_at[static_cast<size_t>(p)] = flat(p) + flat(p + half);
  }
  // The q to pair with p, cheapest g first: once a cost is found, only a prefix needs looking
  // at. Ties keep the smallest a for the first p, as the plain double loop over (p, a) would.
  std::vector<int> by_g(static_cast<size_t>(half));
  std::iota(by_g.begin(), by_g.end(), 0);
  std::sort(by_g.begin(), by_g.end(), [&](int x, int y) {  // stable: ties by position
    return std::pair(g[static_cast<size_t>(x)], x) < std::pair(g[static_cast<size_t>(y)], y);
  });
  const int g_min = g[static_cast<size_t>(by_g.front())];
  int best_balance = -1, best_flat = INT_MAX, best_a = INT_MAX;
  for (int p = 0; p < half; ++p) {
    const int g_p = g[static_cast<size_t>(p)];
    if (best.cost != INT_MAX && base + g_p + g_min > best.cost) continue;
    bool found_here = false;
    for (const int q : by_g) {
      const int cost = base + g_p + g[static_cast<size_t>(q)];
      if (cost > best.cost) break;
      if (q == p) continue;
      const int a = q > p ? q - p : q + half - p;
      const int flats = flats_at[static_cast<size_t>(p)] + flats_at[static_cast<size_t>(q)];
      const int balance = std::min(a, half - a);
      const auto key = std::tuple(cost, flats, -balance);
      const auto best_key = std::tuple(best.cost, best_flat, -best_balance);
      if (key < best_key || (found_here && key == best_key && a < best_a)) {
        best.corners = {p, p + a, p + half, wrap(p + half + a, loop_size)};
        best.cost = cost;
        best_flat = flats;
        best_balance = balance;
        best_a = a;
        found_here = true;
      }
    }
  }
  std::sort(best.corners.begin(), best.corners.end());
  const SideTotals totals(costs);
  assess(best, costs, totals);
  if (loop_size < 6) return best;
  std::vector<int> start_list(starts.begin(), starts.end());
  if (start_list.empty()) start_list.push_back(0);
  PolygonLayout triangle;
  for (const int start : start_list) {
    const int a = loop_size / 3, b = (loop_size - a) / 2;
    triangle.corners = {start, wrap(start + a, loop_size), wrap(start + a + b, loop_size)};
    std::sort(triangle.corners.begin(), triangle.corners.end());
    assess(triangle, costs, totals);
    if (std::tuple(triangle.cost, triangle.irregular, triangle.flat) <
        std::tuple(best.cost, best.irregular, best.flat)) {
      best = triangle;  // its spokes only once it wins
      best.spokes = *nasri_spokes(corner_arcs(best.corners, loop_size));
    }
  }
  return best;
}

}  // namespace

std::vector<int> nasri_distances_doubled(std::span<const int> lengths) {
  const auto n = static_cast<int>(lengths.size());
  if (n % 4 == 0) throw std::logic_error("closed-form distances need n not divisible by 4");
  // n odd: one cycle j → j+2 of length n; n/2 odd: two cycles of length n/2.
  const int terms = n % 2 == 1 ? n : n / 2;
  std::vector<int> doubled(static_cast<size_t>(n), 0);
  for (int j = 0; j < n; ++j)
    for (int k = 0; k < terms; ++k)
      doubled[static_cast<size_t>(j)] +=
          (k % 2 == 0 ? 1 : -1) * lengths[static_cast<size_t>(wrap(j + 1 + 2 * k, n))];
  return doubled;
}

namespace {

// visit(j, 2 d_j) for every j of a polygon with m = arcs.size() >= 3 corners, m not divisible
// by 4, for any integer arcs, until visit returns false (then false). The closed form gives
// 2 d_j as an alternating sum of `terms` arcs; it is computed once per cycle j, j+2, j+4, ...
// (one cycle for m odd, two for m/2 odd) and the rest follows from arcs_{j+1} = d_j + d_{j+2}:
// O(m) instead of O(m²).
template <class Visit>
bool visit_doubled_spokes(std::span<const int> arcs, Visit&& visit) {
  const auto m = static_cast<int>(arcs.size());
  const int terms = m % 2 == 1 ? m : m / 2;
  for (int r = 0; r < (m % 2 == 1 ? 1 : 2); ++r) {
    int value = 0;
    for (int k = 0, i = r + 1; k < terms; ++k, i = i + 2 >= m ? i + 2 - m : i + 2)
      value += (k % 2 == 0 ? 1 : -1) * arcs[static_cast<size_t>(i)];
    for (int k = 0, j = r; k < terms; ++k) {
      if (!visit(static_cast<size_t>(j), value)) return false;
      const int next_arc = j + 1 == m ? 0 : j + 1;
      value = 2 * arcs[static_cast<size_t>(next_arc)] - value;
      j = j + 2 >= m ? j + 2 - m : j + 2;
    }
  }
  return true;
}

// Every 2 d_j (no feasibility check).
void doubled_spokes(std::span<const int> arcs, std::vector<int>& twice) {
  twice.resize(arcs.size());
  visit_doubled_spokes(arcs, [&](size_t j, int value) {
    twice[j] = value;
    return true;
  });
}

// For m = arcs.size() divisible by 4, the d's of parity r form an even cycle
// arcs_{r+2k+1} = d_{r+2k} + d_{r+2k+2}, k = 0 .. m/2 − 1; it closes only when this
// alternating sum of its arcs is zero.
int cycle_closure(std::span<const int> arcs, int r) {
  const auto m = static_cast<int>(arcs.size());
  int c = 0;
  for (int k = 0; k < m / 2; ++k) c = arcs[static_cast<size_t>(wrap(r + 2 * k + 1, m))] - c;
  return c;
}

// nasri_spokes() without allocation (d is resized); false when infeasible.
bool solve_spokes(std::span<const int> arcs, std::vector<int>& d) {
  const auto m = static_cast<int>(arcs.size());
  if (m < 3) return false;
  d.resize(static_cast<size_t>(m));
  if (m % 4 != 0) {
    // Stops at the first 2 d_j below 2 or odd (most candidates of a search fail early).
    return visit_doubled_spokes(arcs, [&](size_t j, int value) {
      if (value < 2 || value % 2 != 0) return false;
      d[j] = value / 2;
      return true;
    });
  }
  // m divisible by 4: the d's of each parity form an even cycle arcs_{j+1} = d_j + d_{j+2}.
  // Write d_{r+2k} = s_k t + c_k with s_k = (−1)^k, c_0 = 0, c_{k+1} = arcs_{r+2k+1} − c_k; the
  // cycle closes only if c_{m/2} = 0 (cycle_closure).
  const int h = m / 2;
  auto next_c = [&](int r, int k, int c) {
    return arcs[static_cast<size_t>(wrap(r + 2 * k + 1, m))] - c;
  };
  for (int r = 0; r < 2; ++r) {
    if (cycle_closure(arcs, r) != 0) return false;
    int lo = INT_MIN / 2, hi = INT_MAX / 2;
    for (int k = 0, c = 0; k < h; c = next_c(r, k, c), ++k) {
      if (k % 2 == 0)
        lo = std::max(lo, 1 - c);
      else
        hi = std::min(hi, c - 1);
    }
    if (lo > hi) return false;
    const int t = lo + (hi - lo) / 2;  // the middle keeps the shortest spoke longest
    for (int k = 0, c = 0; k < h; c = next_c(r, k, c), ++k)
      d[static_cast<size_t>(wrap(r + 2 * k, m))] = (k % 2 == 0 ? t : -t) + c;
  }
  return true;
}

// The positions p of one more layout corner, between two consecutive corners of a fixed set,
// for which solve_spokes can succeed. Along such a stretch every arc is an affine function of p
// (the two arcs at p change by +1 and −1 per step), and so is every 2 d_j and every cycle
// closure: the admissible p form an interval, of one parity when 2 d_j changes by an odd amount
// per step, a single p for m divisible by 4. Exact for m not divisible by 4; for m divisible by
// 4 only the closures are checked (necessary), the spokes' positivity is left to solve_spokes.
class LastCornerWindow {
 public:
  // arcs_at_p0 and arcs_after: the layout's arcs with the corner at p0 and at p0 + 1 (arcs of
  // zero or below are fine here: only the affine functions are read).
  void place(std::span<const int> arcs_at_p0, std::span<const int> arcs_after, int p0) {
    p0_ = p0;
    lo_ = INT_MIN / 2;
    hi_ = INT_MAX / 2;
    parity_ = {true, true};
    const auto m = static_cast<int>(arcs_at_p0.size());
    if (m % 4 == 0) {
      for (int r = 0; r < 2; ++r) {  // closure + offset · slope = 0
        const int closure = cycle_closure(arcs_at_p0, r);
        const int slope = cycle_closure(arcs_after, r) - closure;
        if (slope == 0) {
          if (closure != 0) close();
        } else if (closure % slope != 0) {
          close();
        } else {
          lo_ = std::max(lo_, -closure / slope);
          hi_ = std::min(hi_, -closure / slope);
        }
      }
      return;
    }
    doubled_spokes(arcs_at_p0, twice_at_p0_);
    doubled_spokes(arcs_after, twice_after_);
    for (size_t j = 0; j < twice_at_p0_.size(); ++j) {  // twice + offset · slope >= 2, even
      const int twice = twice_at_p0_[j], slope = twice_after_[j] - twice;
      if (slope > 0) lo_ = std::max(lo_, ceil_div(2 - twice, slope));
      if (slope < 0) hi_ = std::min(hi_, floor_div(twice - 2, -slope));
      if (slope == 0 && twice < 2) close();
      if (slope % 2 == 0 && twice % 2 != 0) close();
      if (slope % 2 != 0) parity_[(twice & 1) ^ 1] = false;  // the offset needs twice's parity
    }
  }

  bool admits(int p) const {
    const int offset = p - p0_;
    return lo_ <= offset && offset <= hi_ && parity_[static_cast<size_t>(offset & 1)];
  }

 private:
  static int floor_div(int a, int b) { return a / b - (a % b != 0 && (a < 0) != (b < 0) ? 1 : 0); }
  static int ceil_div(int a, int b) { return -floor_div(-a, b); }
  void close() { hi_ = lo_ - 1; }

  int p0_ = 0;
  int lo_ = 0, hi_ = -1;                        // admissible offsets p − p0
  std::array<bool, 2> parity_{true, true};      // admissible offset parities
  std::vector<int> twice_at_p0_, twice_after_;  // reused by every place()
};

}  // namespace

std::optional<std::vector<int>> nasri_spokes(std::span<const int> arcs) {
  std::vector<int> d;
  if (!solve_spokes(arcs, d)) return std::nullopt;
  return d;
}

PositionCosts region_costs(std::span<const int> side_counts) {
  const int total = std::accumulate(side_counts.begin(), side_counts.end(), 0);
  PositionCosts costs{std::vector<int>(static_cast<size_t>(total), 1),
                      std::vector<int>(static_cast<size_t>(total), 0),
                      std::vector<char>(static_cast<size_t>(total), 1),
                      std::vector<int>(static_cast<size_t>(total), 1),
                      {}};
  int p = 0;
  for (const int count : side_counts) {
    costs.as_corner[static_cast<size_t>(p)] = 0;
    costs.as_side[static_cast<size_t>(p)] = 1;
    costs.flat[static_cast<size_t>(p)] = 0;
    costs.as_reflex[static_cast<size_t>(p)] = 2;  // valence 4 where 2 is regular
    p += count;
  }
  return costs;
}

PolygonLayout best_layout(const PositionCosts& costs, int budget) {
  const int given = budget;
  const auto size = static_cast<int>(costs.as_side.size());
  if (size < 4 || size % 2 != 0)
    throw std::logic_error("a quad-fillable loop has an even size >= 4");
  std::vector<int> naturals, others;  // positions that would rather be corners / the rest
  others.reserve(static_cast<size_t>(size));
  for (int p = 0; p < size; ++p)
    (costs.as_corner[static_cast<size_t>(p)] < costs.as_side[static_cast<size_t>(p)] ? naturals
                                                                                     : others)
        .push_back(p);
  const PolygonLayout fallback = fallback_layout(size, naturals, costs);
  auto delta = [&](int p) {
    return costs.as_corner[static_cast<size_t>(p)] - costs.as_side[static_cast<size_t>(p)];
  };
  const int base = std::accumulate(costs.as_side.begin(), costs.as_side.end(), 0);
  const auto n_natural = static_cast<int>(naturals.size());
  int natural_sum = 0;
  std::vector<int> drop_costs;  // what dropping each natural corner adds, cheapest first
  for (const int p : naturals) {
    natural_sum += delta(p);
    drop_costs.push_back(-delta(p));
  }
  std::sort(drop_costs.begin(), drop_costs.end());
  int min_add = INT_MAX;
  for (const int p : others) min_add = std::min(min_add, delta(p));

  // (dropped, added) pairs with a lower bound on their cost, cheapest first.
  constexpr int kMaxAdded = 4;
  struct Plan {
    int dropped, added, bound;
  };
  std::vector<Plan> plans;
  for (int k = 0; k <= n_natural && k <= 20; ++k)
    for (int a = 0; a <= kMaxAdded && a <= static_cast<int>(others.size()); ++a) {
      const int corners = n_natural - k + a;
      if (corners < 3) continue;
      const int drop = std::accumulate(drop_costs.begin(), drop_costs.begin() + k, 0);
      plans.push_back({k, a, std::abs(corners - 4) + base + natural_sum + drop + a * min_add});
    }
  std::stable_sort(plans.begin(), plans.end(), [](const Plan& x, const Plan& y) {
    return x.bound != y.bound ? x.bound < y.bound : x.dropped + x.added < y.dropped + y.added;
  });

  std::optional<PolygonLayout> best;
  int best_balance = -1;
  const auto base_irregular = static_cast<int>(
      std::count_if(costs.as_side.begin(), costs.as_side.end(), [](int c) { return c != 0; }));
  std::vector<int> arcs, spokes, kept, added, chosen;  // reused: a check allocates nothing
  auto arcs_of = [size](const std::vector<int>& corners, std::vector<int>& out) {
    const auto m = corners.size();
    out.resize(m);
    for (size_t j = 0; j + 1 < m; ++j) out[j] = corners[j + 1] - corners[j];
    out[m - 1] = corners[0] + size - corners[m - 1];
  };
  // One feasibility check (the budget is counted by the caller).
  auto evaluate = [&](const std::vector<int>& corners) {
    const auto m = corners.size();
    arcs_of(corners, arcs);
    int balance;
    bool grid = false;
    if (m == 4 && arcs[0] == arcs[2] && arcs[1] == arcs[3]) {
      grid = true;
      balance = std::min(arcs[0], arcs[1]);
    } else if (solve_spokes(arcs, spokes)) {
      balance = *std::min_element(spokes.begin(), spokes.end());
    } else {
      return;
    }
    int cost = std::abs(static_cast<int>(m) - 4) + base;
    int irregular = (m != 4 ? 1 : 0) + base_irregular;
    int flats = 0;
    for (const int p : corners) {
      cost += delta(p);
      irregular += (costs.as_corner[static_cast<size_t>(p)] != 0 ? 1 : 0) -
                   (costs.as_side[static_cast<size_t>(p)] != 0 ? 1 : 0);
      if (!costs.flat.empty() && costs.flat[static_cast<size_t>(p)]) ++flats;
    }
    // Least distortion, then fewest irregular vertices, fewest flat corners, and the longest
    // shortest spoke.
    if (!best || std::tuple(cost, irregular, flats, -balance) <
                     std::tuple(best->cost, best->irregular, best->flat, -best_balance)) {
      best = PolygonLayout{corners, grid ? std::vector<int>{} : spokes, cost, irregular, flats};
      best_balance = balance;
    }
  };
  auto consider = [&](const std::vector<int>& corners) {
    --budget;
    evaluate(corners);
  };
  // The last promoted corner p runs over others[from..] with the other corners fixed: each
  // candidate still counts as a check, but only those the window admits are solved.
  std::vector<int> fixed, arcs_after;
  LastCornerWindow window;
  auto scan_last = [&](size_t from) {
    fixed.resize(kept.size() + added.size());
    std::merge(kept.begin(), kept.end(), added.begin(), added.end(), fixed.begin());
    size_t stretch = fixed.size() + 1;  // where p goes among the fixed corners, for `window`
    for (size_t i = from; i < others.size() && budget > 0; ++i) {
      const int p = others[i];
      --budget;
      const auto at =
          static_cast<size_t>(std::lower_bound(fixed.begin(), fixed.end(), p) - fixed.begin());
      if (at != stretch) {
        stretch = at;
        chosen = fixed;
        chosen.insert(chosen.begin() + static_cast<std::ptrdiff_t>(at), p + 1);
        arcs_of(chosen, arcs_after);
        chosen[at] = p;
        arcs_of(chosen, arcs);
        window.place(arcs, arcs_after, p);
      }
      if (!window.admits(p)) continue;
      chosen[at] = p;  // the fixed corners with p in loop order
      evaluate(chosen);
    }
  };
  for (const Plan& plan : plans) {
    // Ties with the fallback are still searched: a Nasri centre beats a grid with moved corners
    // of equal distortion by having fewer irregular vertices.
    if ((best && plan.bound > best->cost) || plan.bound > fallback.cost || budget <= 0) break;
    // Every subset of `plan.dropped` natural corners (bit masks), then every choice of
    // `plan.added` promoted positions in increasing order.
    // Masks with `plan.dropped` bits in increasing order (Gosper's next-combination step).
    const unsigned full = 1u << std::min(n_natural, 20);
    for (unsigned mask = (1u << plan.dropped) - 1; mask < full && budget > 0;) {
      kept.clear();
      for (unsigned rest = ~mask & (full - 1); rest != 0; rest &= rest - 1)
        kept.push_back(naturals[static_cast<size_t>(std::countr_zero(rest))]);
      // Natural corners beyond the 20 a mask can drop are always kept.
      for (int i = 20; i < n_natural; ++i) kept.push_back(naturals[static_cast<size_t>(i)]);
      auto recurse = [&](auto&& self, size_t from) -> void {
        if (budget <= 0) return;
        if (static_cast<int>(added.size()) == plan.added) {
          // kept and added are both increasing: the corners in loop order
          chosen.resize(kept.size() + added.size());
          std::merge(kept.begin(), kept.end(), added.begin(), added.end(), chosen.begin());
          consider(chosen);
          return;
        }
        if (static_cast<int>(added.size()) + 1 == plan.added) {
          scan_last(from);
          return;
        }
        for (size_t i = from; i < others.size() && budget > 0; ++i) {
          added.push_back(others[i]);
          self(self, i + 1);
          added.pop_back();
        }
      };
      recurse(recurse, 0);
      if (mask == 0) break;
      const unsigned low = mask & (~mask + 1u), ripple = mask + low;
      mask = (((ripple ^ mask) >> 2) / low) | ripple;
    }
  }
  PolygonLayout chosen_layout = fallback;
  if (best && std::tuple(best->cost, best->irregular, best->flat) <=
                  std::tuple(fallback.cost, fallback.irregular, fallback.flat))
    chosen_layout = std::move(*best);
  chosen_layout.checks = given - budget;
  return chosen_layout;
}

int layout_cost_lower_bound(const PositionCosts& costs) {
  // Every layout costs |m − 4| + Σ as_side + Σ over its corners (as_corner − as_side): with k
  // of the positions that would rather be corners dropped and a others added, at least
  // |m − 4| + base + (sum of the natural deltas) + (k cheapest drops) + a · (cheapest add).
  auto corner_cost = [&](size_t p) {
    const int c = costs.as_corner[p];
    return c >= kFoldPenalty ? c - kFoldPenalty : c;
  };
  int base = 0, natural_sum = 0, min_add = INT_MAX, others = 0;
  std::vector<int> drop_costs;
  for (size_t p = 0; p < costs.as_side.size(); ++p) {
    base += costs.as_side[p];
    const int delta = corner_cost(p) - costs.as_side[p];
    if (delta < 0) {
      natural_sum += delta;
      drop_costs.push_back(-delta);
    } else {
      min_add = std::min(min_add, delta);
      ++others;
    }
  }
  std::sort(drop_costs.begin(), drop_costs.end());
  const auto naturals = static_cast<int>(drop_costs.size());
  int best = INT_MAX, drop = 0;
  for (int k = 0; k <= naturals; ++k) {
    if (k > 0) drop += drop_costs[static_cast<size_t>(k) - 1];
    // Beyond m = 4 another added corner raises |m − 4| and costs min_add >= 0 more.
    for (int a = 0; a <= others; ++a) {
      const int m = naturals - k + a;
      if (m >= 3) best = std::min(best, std::abs(m - 4) + base + natural_sum + drop + a * min_add);
      if (m >= 4) break;
    }
  }
  return best;
}

}  // namespace sd::meshing::detail
