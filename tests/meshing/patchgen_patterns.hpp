#pragma once
// The topological patterns of Takayama, Panozzo & Sorkine-Hornung (2014), "Pattern-based
// quadrangulation for N-sided patches", as their reference implementation (patchgen) has them
// for n = 2..6 sides — every variant, 2-0 … 6-3, plus 3-2 and 3-3 that a later copy of it adds —
// written down here from their published descriptions: each pattern's coarse quads (to measure
// its distortion), its boundary counts as a base vector plus nonnegative integer parameters
// (edge loops x, y, z, w, q_i inserted through the pattern), and padding p_i >= 0 (a row of
// quads along side i, adding 1 to sides i − 1 and i + 1; for n = 2, 2 to the other side).
// patchgen picks, for side counts l, a pattern in some rotation or reflection whose integer
// system has a solution (an integer program with extra constraints and an objective, which only
// narrow the choice), so no layout it returns is less distorted than the least distortion of a
// pattern whose system is solvable: patchgen_distortion() below. Shared by the optimality test.

#include <algorithm>
#include <array>
#include <climits>
#include <numeric>
#include <vector>

namespace sd::meshing::test {

struct PatchgenPattern {
  const char* name;
  int distortion;                       // Σ |valence − regular| of the coarse quads (asserted)
  std::vector<int> base;                // side counts with every parameter 0
  std::vector<std::vector<int>> terms;  // what one unit of each parameter adds to each side
  // The coarse quads: corners C_i are vertices 0..n−1 (side i runs from C_i to C_i+1), the
  // other vertices follow; side vertices listed in `side_vertices` per side, in order.
  std::vector<std::array<int, 4>> quads;
  std::vector<std::vector<int>> side_vertices;
};

// Distortion by the pattern's own drawing (padding and edge loops add only regular vertices: a
// padding row turns a corner of valence v into a side vertex of valence v + 1, a side vertex
// into an interior one of valence + 1, and its own corners have valence 2).
inline const std::vector<PatchgenPattern>& patchgen_patterns() {
  static const std::vector<PatchgenPattern> patterns = {
      // n = 2: one quad, two flat side vertices either on one side (2-0) or one on each (2-1).
      {"2-0", 2, {3, 1}, {{1, 1}}, {{0, 2, 3, 1}}, {{2, 3}, {}}},
      {"2-1", 2, {2, 2}, {{1, 1}, {1, 1}}, {{0, 2, 1, 3}}, {{2}, {3}}},
      // n = 3.
      {"3-0", 1, {2, 1, 1}, {}, {{0, 3, 1, 2}}, {{3}, {}, {}}},
      {"3-1",
       3,
       {4, 1, 1},
       {{1, 0, 1}, {1, 1, 0}, {2, 0, 0}},
       {{0, 3, 6, 2}, {3, 4, 5, 6}, {2, 6, 5, 1}},
       {{3, 4, 5}, {}, {}}},
      {"3-2",
       3,
       {3, 2, 1},
       {{1, 1, 0}, {2, 0, 0}},
       {{0, 3, 6, 2}, {3, 4, 7, 6}, {1, 5, 7, 4}, {2, 6, 7, 5}},
       {{3, 4}, {5}, {}}},
      {"3-3",
       5,
       {4, 2, 2},
       {{1, 0, 1}, {1, 1, 0}, {2, 0, 0}},
       {{0, 3, 4, 8}, {4, 5, 1, 8}, {1, 6, 9, 8}, {6, 2, 7, 9}, {7, 0, 8, 9}},
       {{3, 4, 5}, {6}, {7}}},
      // n = 4.
      {"4-0", 0, {1, 1, 1, 1}, {}, {{0, 1, 2, 3}}, {{}, {}, {}, {}}},
      {"4-1",
       2,
       {2, 2, 1, 1},
       {{1, 1, 0, 0}},
       {{0, 4, 6, 3}, {4, 1, 5, 6}, {5, 2, 3, 6}},
       {{4}, {5}, {}, {}}},
      {"4-2",
       2,
       {3, 1, 1, 1},
       {{1, 1, 0, 0}, {1, 0, 0, 1}},
       {{0, 4, 2, 3}, {4, 5, 1, 2}},
       {{4, 5}, {}, {}, {}}},
      {"4-3",
       4,
       {3, 1, 1, 1},
       {{1, 0, 1, 0}, {2, 0, 0, 0}},
       {{0, 4, 7, 3}, {4, 5, 6, 7}, {5, 1, 2, 6}, {2, 3, 7, 6}},
       {{4, 5}, {}, {}, {}}},
      {"4-4",
       4,
       {4, 2, 1, 1},
       {{1, 0, 1, 0}, {2, 0, 0, 0}, {1, 1, 0, 0}},
       {{0, 4, 10, 3}, {4, 5, 9, 10}, {5, 6, 8, 9}, {6, 1, 7, 8}, {7, 2, 9, 8}, {2, 3, 10, 9}},
       {{4, 5, 6}, {7}, {}, {}}},
      // n = 5.
      {"5-0", 1, {2, 1, 1, 1, 1}, {}, {{5, 3, 4, 0}, {5, 1, 2, 3}}, {{5}, {}, {}, {}, {}}},
      {"5-1",
       3,
       {2, 1, 1, 1, 1},
       {{1, 0, 0, 1, 0}, {1, 1, 0, 0, 0}},
       {{0, 5, 1, 2}, {0, 2, 3, 4}},
       {{5}, {}, {}, {}, {}}},
      {"5-2",
       5,
       {4, 1, 1, 1, 1},
       {{0, 1, 0, 0, 1}, {1, 0, 1, 0, 0}, {1, 0, 0, 1, 0}, {2, 0, 0, 0, 0}},
       {{0, 5, 8, 9}, {1, 9, 8, 7}, {5, 6, 7, 8}, {9, 3, 4, 0}, {9, 1, 2, 3}},
       {{5, 6, 7}, {}, {}, {}, {}}},
      {"5-3",
       5,
       {5, 2, 1, 1, 1},
       {{1, 0, 1, 0, 0}, {1, 0, 0, 1, 0}, {2, 0, 0, 0, 0}, {1, 1, 0, 0, 0}},
       {{0, 5, 10, 4},
        {5, 6, 11, 10},
        {6, 7, 12, 11},
        {7, 8, 13, 12},
        {8, 1, 9, 13},
        {9, 2, 12, 13},
        {2, 3, 11, 12},
        {3, 4, 10, 11}},
       {{5, 6, 7, 8}, {9}, {}, {}, {}}},
      {"5-4",
       3,
       {3, 3, 3, 1, 2},
       {{0, 1, 0, 0, 1}, {1, 0, 1, 0, 0}, {1, 1, 0, 0, 0}},
       {{0, 5, 12, 11},
        {5, 6, 1, 7},
        {7, 8, 12, 5},
        {8, 2, 9, 12},
        {9, 10, 11, 12},
        {10, 3, 4, 11}},
       {{5, 6}, {7, 8}, {9, 10}, {}, {11}}},
      // n = 6.
      {"6-0",
       2,
       {1, 1, 1, 1, 1, 1},
       {{1, 0, 0, 1, 0, 0}},
       {{0, 1, 2, 5}, {2, 3, 4, 5}},
       {{}, {}, {}, {}, {}, {}}},
      {"6-1",
       4,
       {2, 2, 1, 1, 1, 1},
       {{1, 1, 0, 0, 0, 0}, {1, 0, 0, 1, 0, 0}, {0, 1, 0, 0, 1, 0}, {0, 0, 1, 0, 0, 1}},
       {{0, 6, 8, 9}, {1, 7, 8, 6}, {7, 2, 9, 8}, {2, 3, 4, 9}, {4, 5, 0, 9}},
       {{6}, {7}, {}, {}, {}, {}}},
      {"6-2",
       6,
       {3, 1, 1, 1, 1, 1},
       {{0, 1, 0, 0, 0, 1}, {0, 0, 1, 0, 1, 0}, {2, 0, 0, 0, 0, 0}, {1, 0, 0, 1, 0, 0}},
       {{0, 6, 8, 10},
        {6, 7, 9, 8},
        {7, 1, 11, 9},
        {1, 2, 3, 11},
        {3, 4, 10, 11},
        {4, 5, 0, 10},
        {8, 9, 11, 10}},
       {{6, 7}, {}, {}, {}, {}, {}}},
      {"6-3",
       8,
       {4, 2, 1, 1, 1, 1},
       {{0, 0, 1, 0, 1, 0}, {2, 0, 0, 0, 0, 0}, {1, 1, 0, 0, 0, 0}, {1, 0, 0, 1, 0, 0}},
       {{0, 6, 12, 5},
        {6, 7, 11, 12},
        {7, 8, 10, 11},
        {8, 1, 9, 10},
        {9, 2, 11, 10},
        {2, 3, 14, 11},
        {3, 4, 13, 14},
        {4, 5, 12, 13},
        {11, 14, 13, 12}},
       {{6, 7, 8}, {9}, {}, {}, {}, {}}},
  };
  return patterns;
}

// Whether p_i >= 0 (integers) exist with rest_k = Σ over paddings touching side k. For n >= 3
// that is p_{k−1} + p_{k+1} = rest_k, the Nasri system with a minimum of 0 (nasri_feasible),
// solved here without allocating: along each cycle of k -> k + 2, p = s v + c for the start
// value v, closing the cycle fixes v (s = −1) or needs c = 0 (s = +1).
inline bool padding_feasible(const std::vector<int>& rest) {
  const auto m = static_cast<int>(rest.size());
  if (m == 2)  // a row along one side of a 2-sided patch adds 2 to the other
    return rest[0] >= 0 && rest[1] >= 0 && rest[0] % 2 == 0 && rest[1] % 2 == 0;
  for (int start = 0; start < (m % 2 == 0 ? 2 : 1); ++start) {
    long low = 0, high = 1L << 40, c = 0;
    int j = start, s = 1;
    do {
      if (s == 1)
        low = std::max(low, -c);
      else
        high = std::min(high, c);
      c = rest[static_cast<size_t>((j + 1) % m)] - c;
      s = -s;
      j = (j + 2) % m;
    } while (j != start);
    if (s == -1) {
      if (c % 2 != 0 || c / 2 < low || c / 2 > high) return false;
    } else if (c != 0 || low > high) {
      return false;
    }
  }
  return true;
}

// Parameters from `term` on, each as often as the rest stays nonnegative.
inline bool parameters_feasible(const PatchgenPattern& pattern, std::vector<int>& rest,
                                size_t term) {
  if (term == pattern.terms.size()) return padding_feasible(rest);
  const std::vector<int>& add = pattern.terms[term];
  int taken = 0;
  bool found = false;
  while (true) {
    found = parameters_feasible(pattern, rest, term + 1);
    bool fits = true;
    for (size_t k = 0; k < rest.size(); ++k) fits = fits && rest[k] >= add[k];
    if (found || !fits) break;
    for (size_t k = 0; k < rest.size(); ++k) rest[k] -= add[k];
    ++taken;
  }
  for (size_t k = 0; k < rest.size(); ++k) rest[k] += taken * add[k];
  return found;
}

// Whether this pattern, in some rotation or reflection, fits side counts l.
inline bool pattern_fits(const PatchgenPattern& pattern, const std::vector<int>& counts) {
  const auto n = static_cast<int>(counts.size());
  if (static_cast<int>(pattern.base.size()) != n) return false;
  std::vector<int> rest(static_cast<size_t>(n));
  for (int flip = 0; flip < 2; ++flip)
    for (int r = 0; r < n; ++r) {
      bool nonnegative = true;
      for (int k = 0; k < n; ++k) {
        const int side = flip ? (r + n - k) % n : (r + k) % n;
        rest[static_cast<size_t>(k)] =
            counts[static_cast<size_t>(side)] - pattern.base[static_cast<size_t>(k)];
        nonnegative = nonnegative && rest[static_cast<size_t>(k)] >= 0;
      }
      if (nonnegative && parameters_feasible(pattern, rest, 0)) return true;
    }
  return false;
}

// The least distortion of a patchgen pattern that fits these counts, looking only at patterns
// below `limit` (INT_MAX: none fits below it). `fitting`, when given, gets the name of the
// first such pattern.
inline int patchgen_distortion(const std::vector<int>& counts, int limit = INT_MAX,
                               const char** fitting = nullptr) {
  std::vector<const PatchgenPattern*> order;  // this n's patterns, least distorted first
  for (const PatchgenPattern& pattern : patchgen_patterns())
    if (pattern.base.size() == counts.size()) order.push_back(&pattern);
  std::stable_sort(order.begin(), order.end(),
                   [](const auto* a, const auto* b) { return a->distortion < b->distortion; });
  for (const PatchgenPattern* pattern : order) {
    if (pattern->distortion >= limit) break;
    if (pattern_fits(*pattern, counts)) {
      if (fitting) *fitting = pattern->name;
      return pattern->distortion;
    }
  }
  return INT_MAX;
}

}  // namespace sd::meshing::test
