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

}  // namespace sd::meshing::test
