#pragma once
// Edge counts of the curve network. Each edge gets round(length / edge_length) (at least 1);
// then a parity fix makes every panel's total even with the fewest curve changes of ±1
// (docs/sketch-format.md, "Edge counts and parity").

#include <optional>
#include <vector>

#include "garment/curve_network.hpp"
#include "garment/garment_request.hpp"
#include "garment/panel_loop.hpp"

namespace sd::garment {

struct EdgeCounts {
  std::vector<int> counts;    // per network edge; a mirror copy equals its original
  std::vector<double> ideal;  // length / edge_length per edge
  std::vector<int> changed;   // original edges whose count parity changed (±1)
};

// One unknown of the parity problem: flipping it toggles the parity of `constraints` (each
// listed once; an edge counted twice by a panel does not toggle it). cost > 0.
struct ParityVariable {
  std::vector<int> constraints;
  double cost = 1.0;
};

// Chooses variables so that every constraint with odd[c] becomes even, at least total cost,
// per connected group of constraints: when each of the group's variables toggles at most two
// constraints (seams and hems) it is a minimum T-join, exact for any number of constraints and
// up to kExactParityOdd - 1 odd ones (shortest paths + exact minimum-weight perfect matching);
// otherwise exact by Dijkstra over the 2^k parity states for groups of up to
// kExactParityConstraints constraints; else a feasible Gaussian-elimination solution (warned).
// Empty optional when some group cannot be made even; `unfixable` then names one of its odd
// constraints.
inline constexpr int kExactParityConstraints = 16;
inline constexpr int kExactParityOdd = 20;
std::optional<std::vector<int>> solve_parity(int constraint_count, const std::vector<bool>& odd,
                                             const std::vector<ParityVariable>& variables,
                                             int* unfixable = nullptr);

// Counts for every edge used by a panel (others get their rounded count). Throws SketchError
// when a fixed "edges" cannot be honoured or a panel's total cannot be made even.
EdgeCounts compute_edge_counts(const GarmentRequest& sketch, const CurveNetwork& net,
                               const std::vector<PanelLoop>& loops);

}  // namespace sd::garment
