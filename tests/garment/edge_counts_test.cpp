#include "garment/edge_counts.hpp"

#include <gtest/gtest.h>

#include <random>

namespace sd::garment {
namespace {

// Cheapest subset by enumeration (variables ≤ 16), or -1 when none makes every parity even.
double brute_force(int constraints, const std::vector<bool>& odd, const std::vector<ParityVariable>& vars) {
  double best = -1;
  for (unsigned subset = 0; subset < (1u << vars.size()); ++subset) {
    std::vector<bool> parity = odd;
    double cost = 0;
    for (size_t v = 0; v < vars.size(); ++v)
      if (subset & (1u << v)) {
        cost += vars[v].cost;
        for (int c : vars[v].constraints) parity[static_cast<size_t>(c)] = !parity[static_cast<size_t>(c)];
      }
    bool even = true;
    for (int c = 0; c < constraints; ++c) even = even && !parity[static_cast<size_t>(c)];
    if (even && (best < 0 || cost < best)) best = cost;
  }
  return best;
}

TEST(Parity, ExactAgainstBruteForceOnRandomNetworks) {
  std::mt19937 rng(7);
  int infeasible = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const int constraints = 1 + static_cast<int>(rng() % 8);
    const int count = 1 + static_cast<int>(rng() % 12);
    std::vector<ParityVariable> vars(static_cast<size_t>(count));
    for (auto& v : vars) {
      // Seams touch two panels, hems one; a few touch three (mirror orbits shared oddly).
      const int touches = 1 + static_cast<int>(rng() % 3);
      for (int k = 0; k < touches; ++k) {
        const int c = static_cast<int>(rng() % static_cast<unsigned>(constraints));
        if (std::find(v.constraints.begin(), v.constraints.end(), c) == v.constraints.end()) v.constraints.push_back(c);
      }
      v.cost = 1.0 + 0.01 * static_cast<double>(rng() % 50);
    }
    std::vector<bool> odd(static_cast<size_t>(constraints));
    for (auto&& o : odd) o = rng() % 2 == 1;
    const double expected = brute_force(constraints, odd, vars);
    int unfixable = -1;
    const auto chosen = solve_parity(constraints, odd, vars, &unfixable);
    if (expected < 0) {
      ++infeasible;
      EXPECT_FALSE(chosen.has_value());
      ASSERT_GE(unfixable, 0);
      EXPECT_TRUE(odd[static_cast<size_t>(unfixable)]);
      continue;
    }
    ASSERT_TRUE(chosen.has_value());
    std::vector<bool> parity = odd;
    double cost = 0;
    for (int v : *chosen) {
      cost += vars[static_cast<size_t>(v)].cost;
      for (int c : vars[static_cast<size_t>(v)].constraints) parity[static_cast<size_t>(c)] = !parity[static_cast<size_t>(c)];
    }
    for (int c = 0; c < constraints; ++c) EXPECT_FALSE(parity[static_cast<size_t>(c)]);
    EXPECT_NEAR(cost, expected, 1e-9) << "trial " << trial;
  }
  EXPECT_GT(infeasible, 0);  // the random set exercises the error path too
}

TEST(Parity, ClosedNetworkOfSeamsPairsOddPanels) {
  // Four panels in a ring, every curve a seam between neighbours: panels 0 and 2 odd.
  std::vector<ParityVariable> ring = {{{0, 1}, 1.0}, {{1, 2}, 1.0}, {{2, 3}, 1.0}, {{3, 0}, 1.0}};
  const auto chosen = solve_parity(4, {true, false, true, false}, ring);
  ASSERT_TRUE(chosen.has_value());
  EXPECT_EQ(chosen->size(), 2u);  // a path of two seams between them
  // One odd panel in a closed ring cannot happen (the sum of totals is even), and cannot be fixed.
  EXPECT_FALSE(solve_parity(4, {true, false, false, false}, ring).has_value());
}

TEST(Parity, NothingToDoWhenAllEven) {
  const auto chosen = solve_parity(2, {false, false}, {{{0}, 1.0}, {{0, 1}, 1.0}});
  ASSERT_TRUE(chosen.has_value());
  EXPECT_TRUE(chosen->empty());
}

}  // namespace
}  // namespace sd::garment
