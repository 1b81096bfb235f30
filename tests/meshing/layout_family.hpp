#pragma once
// The layout family F of the optimality proof (docs/meshing.md, "Proof of optimality"),
// enumerated by brute force with code independent of the filler's own search: Nasri centres on
// shifted corners and rectilinear layouts. Shared by the optimality and corpus tests.

#include <algorithm>
#include <array>
#include <climits>
#include <cstdlib>
#include <functional>
#include <numeric>
#include <set>
#include <utility>
#include <vector>

namespace sd::meshing::test {

// d_{j−1} + d_{j+1} = arcs_j with every d_j an integer >= 1. The map j -> j + 2 splits the
// indices into one cycle (m odd) or two (m even); along a cycle d = s v + c with v the start
// value, and closing the cycle fixes v (s = −1 at the end) or requires c = 0 (s = +1).
inline bool nasri_feasible(const std::vector<int>& arcs, int minimum = 1) {
  const auto m = static_cast<int>(arcs.size());
  for (int start = 0; start < (m % 2 == 0 ? 2 : 1); ++start) {
    std::vector<std::pair<int, int>> terms;  // (s, c) of every d on the cycle
    int j = start, s = 1, c = 0;
    do {
      terms.emplace_back(s, c);
      c = arcs[static_cast<size_t>((j + 1) % m)] - c;
      s = -s;
      j = (j + 2) % m;
    } while (j != start);
    long low = minimum, high = 1L << 40;  // the start value v itself is d_start >= minimum
    if (s == -1) {                        // −v + c = v
      if (c % 2 != 0) return false;
      low = high = c / 2;
    } else if (c != 0) {
      return false;
    }
    for (const auto& [ts, tc] : terms) {  // ts v + tc >= minimum
      if (ts == 1)
        low = std::max(low, static_cast<long>(minimum - tc));
      else
        high = std::min(high, static_cast<long>(tc - minimum));
    }
    if (low > high || low < minimum) return false;
  }
  return true;
}

// The lattice walk of these turns (position, turn) — nonzero turns by position, Σ = 4, on a
// loop of `total` positions — closes and visits no point twice.
inline bool walk_is_simple(const std::vector<std::pair<int, int>>& events, int total) {
  static constexpr std::array<std::array<int, 2>, 4> kStep{{{1, 0}, {0, 1}, {-1, 0}, {0, -1}}};
  long x = 0, y = 0;
  int d = 0;
  const size_t k = events.size();
  for (size_t i = 0; i < k; ++i) {
    d = (d + events[i].second + 4) % 4;
    const int run = (events[(i + 1) % k].first - events[i].first + total - 1) % total + 1;
    x += run * kStep[static_cast<size_t>(d)][0];
    y += run * kStep[static_cast<size_t>(d)][1];
  }
  if (x != 0 || y != 0) return false;
  std::set<std::pair<long, long>> seen;
  for (size_t i = 0; i < k; ++i) {
    d = (d + events[i].second + 4) % 4;
    const int run = (events[(i + 1) % k].first - events[i].first + total - 1) % total + 1;
    for (int step = 0; step < run; ++step) {
      if (!seen.insert({x, y}).second) return false;
      x += kStep[static_cast<size_t>(d)][0];
      y += kStep[static_cast<size_t>(d)][1];
    }
  }
  return true;
}

// Every way to pick `count` items of `from` (increasing), stopping when `visit` returns true.
inline bool any_subset(const std::vector<int>& from, int count, std::vector<int>& picked, size_t at,
                       const std::function<bool()>& visit) {
  if (static_cast<int>(picked.size()) == count) return visit();
  for (size_t i = at; i < from.size(); ++i) {
    picked.push_back(from[i]);
    const bool found = any_subset(from, count, picked, i + 1, visit);
    picked.pop_back();
    if (found) return true;
  }
  return false;
}

// Whether F has a layout of distortion <= level for these counts.
inline bool family_reaches(const std::vector<int>& counts, int level) {
  const auto n = static_cast<int>(counts.size());
  const int total = std::accumulate(counts.begin(), counts.end(), 0);
  std::vector<int> real, sides;
  std::vector<char> is_corner(static_cast<size_t>(total), 0);
  for (int p = 0, i = 0; i < n; p += counts[static_cast<size_t>(i)], ++i)
    is_corner[static_cast<size_t>(p)] = 1;
  for (int p = 0; p < total; ++p) (is_corner[static_cast<size_t>(p)] ? real : sides).push_back(p);
  std::vector<int> drops, promotes, reflex_corners, reflex_sides;
  // Nasri / grid on shifted corners: k real corners dropped, a side vertices promoted.
  for (int k = 0; k <= n; ++k)
    for (int a = 0; a <= static_cast<int>(sides.size()); ++a) {
      const int m = n - k + a;
      if (m < 3 || std::abs(m - 4) + k + a > level) continue;
      const bool found = any_subset(real, k, drops, 0, [&] {
        return any_subset(sides, a, promotes, 0, [&] {
          std::vector<int> corners;
          for (const int p : real)
            if (std::find(drops.begin(), drops.end(), p) == drops.end()) corners.push_back(p);
          corners.insert(corners.end(), promotes.begin(), promotes.end());
          std::sort(corners.begin(), corners.end());
          std::vector<int> arcs;
          for (int j = 0; j < m; ++j)
            arcs.push_back((corners[static_cast<size_t>((j + 1) % m)] -
                            corners[static_cast<size_t>(j)] + total) %
                           total);
          return nasri_feasible(arcs);
        });
      });
      if (found) return true;
    }
  // Rectilinear: k corners dropped (turn 0, cost 1), c corners reflex (turn −1, cost 2),
  // a side vertices promoted (turn +1, cost 1), r side vertices reflex (turn −1, cost 1).
  for (int k = 0; k <= n; ++k)
    for (int c = 0; k + c <= n; ++c)
      for (int a = 0; a <= level; ++a)
        for (int r = 0; a + r <= level; ++r) {
          if (k + 2 * c + a + r > level || n - k - 2 * c + a - r != 4) continue;
          const bool found = any_subset(real, k, drops, 0, [&] {
            std::vector<int> rest;
            for (const int p : real)
              if (std::find(drops.begin(), drops.end(), p) == drops.end()) rest.push_back(p);
            return any_subset(rest, c, reflex_corners, 0, [&] {
              return any_subset(sides, a, promotes, 0, [&] {
                std::vector<int> others;
                for (const int p : sides)
                  if (std::find(promotes.begin(), promotes.end(), p) == promotes.end())
                    others.push_back(p);
                return any_subset(others, r, reflex_sides, 0, [&] {
                  std::vector<std::pair<int, int>> events;
                  for (const int p : rest)
                    events.emplace_back(p, std::find(reflex_corners.begin(), reflex_corners.end(),
                                                     p) == reflex_corners.end()
                                               ? 1
                                               : -1);
                  for (const int p : promotes) events.emplace_back(p, 1);
                  for (const int p : reflex_sides) events.emplace_back(p, -1);
                  std::sort(events.begin(), events.end());
                  return walk_is_simple(events, total);
                });
              });
            });
          });
          if (found) return true;
        }
  return false;
}

// Takayama, Panozzo & Sorkine-Hornung (2014) describe each pattern by its boundary counts as a
// base vector plus nonnegative integer parameters; `padding` p_i (a row of quads along side i)
// adds 1 to sides i − 1 and i + 1. For the patterns whose distortion does not depend on the
// parameters, the least distortion any applies with, in any rotation or reflection (INT_MAX when
// none does): 3-0 and 5-0 (one irregular vertex: 1), 4-0 (a grid: 0), 4-1 (base (2,2,1,1), x on
// sides 0 and 1: two irregular vertices, taken as 2, the least a non-grid quadrilateral can
// have, which only makes the check stricter), 6-0 (base all ones, x on sides 0 and 3: two
// corners of valence 3 that padding moves inside as valence-5 vertices, 2). The solver: p_{i−1} +
// p_{i+1} = l_i − base_i with p >= 0 is the Nasri system with a minimum of 0.
inline int takayama_pattern_distortion(const std::vector<int>& counts) {
  const auto n = static_cast<int>(counts.size());
  struct Pattern {
    int distortion;
    std::vector<int> base, x;  // x: the sides the pattern's free parameter x lengthens
  };
  std::vector<Pattern> patterns;
  if (n == 3) patterns.push_back({1, {2, 1, 1}, {0, 0, 0}});
  if (n == 4) {
    patterns.push_back({0, {1, 1, 1, 1}, {0, 0, 0, 0}});
    patterns.push_back({2, {2, 2, 1, 1}, {1, 1, 0, 0}});
  }
  if (n == 5) patterns.push_back({1, {2, 1, 1, 1, 1}, {0, 0, 0, 0, 0}});
  if (n == 6) patterns.push_back({2, {1, 1, 1, 1, 1, 1}, {1, 0, 0, 1, 0, 0}});
  int best = INT_MAX;
  std::vector<int> image(static_cast<size_t>(n)), rest(static_cast<size_t>(n));
  for (const Pattern& pattern : patterns)
    for (int flip = 0; flip < 2; ++flip)
      for (int r = 0; r < n; ++r) {
        for (int k = 0; k < n; ++k)
          image[static_cast<size_t>(k)] =
              counts[static_cast<size_t>(flip ? (r + n - k) % n : (r + k) % n)];
        const bool has_x = std::accumulate(pattern.x.begin(), pattern.x.end(), 0) > 0;
        for (int x = 0; x <= (has_x ? 24 : 0); ++x) {
          bool nonnegative = true;
          for (int k = 0; k < n; ++k) {
            rest[static_cast<size_t>(k)] = image[static_cast<size_t>(k)] -
                                           pattern.base[static_cast<size_t>(k)] -
                                           x * pattern.x[static_cast<size_t>(k)];
            nonnegative = nonnegative && rest[static_cast<size_t>(k)] >= 0;
          }
          if (nonnegative && nasri_feasible(rest, 0)) best = std::min(best, pattern.distortion);
        }
      }
  return best;
}

}  // namespace sd::meshing::test
