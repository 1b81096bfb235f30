#include "garment/edge_counts.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <functional>
#include <map>
#include <numeric>
#include <queue>

namespace sd::garment {
namespace {

// Exact minimum-cost subset of `masks` whose XOR equals `start` (Dijkstra over 2^P states: a
// shortest path never uses a variable twice, since two uses cancel at positive cost).
std::optional<std::vector<int>> exact_group(int p, std::uint32_t start,
                                            const std::vector<std::uint32_t>& masks,
                                            const std::vector<double>& costs) {
  const size_t states = size_t{1} << p;
  std::vector<double> dist(states, std::numeric_limits<double>::infinity());
  std::vector<int> via(states, -1);
  using Item = std::pair<double, std::uint32_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  dist[start] = 0;
  queue.emplace(0.0, start);
  while (!queue.empty()) {
    const auto [d, s] = queue.top();
    queue.pop();
    if (d > dist[s]) continue;
    if (s == 0) break;
    for (size_t v = 0; v < masks.size(); ++v) {
      const std::uint32_t t = s ^ masks[v];
      if (d + costs[v] < dist[t]) {
        dist[t] = d + costs[v];
        via[t] = static_cast<int>(v);
        queue.emplace(dist[t], t);
      }
    }
  }
  if (!std::isfinite(dist[0])) return std::nullopt;
  std::vector<int> chosen;
  for (std::uint32_t s = 0; s != start;) {
    const int v = via[s];
    chosen.push_back(v);
    s ^= masks[static_cast<size_t>(v)];
  }
  return chosen;
}

// Minimum T-join (Edmonds & Johnson) when every variable toggles one or two constraints: the
// variables are edges of a graph on the group's constraints plus an "outside" node (a variable
// of one constraint, a hem, joins it to the outside); T is the odd constraints, plus the outside
// when their number is odd. A cheapest set of edges with odd degree exactly on T is the union
// of shortest paths between the pairs of a minimum-weight perfect matching of T in the
// shortest-path metric. The matching is exact by dynamic programming over subsets of T (the
// lowest unmatched node is paired first), O(2^|T|·|T|) for |T| up to kExactParityOdd.
// `edges[v]` = (a, b), b = outside for one-constraint variables. Empty optional when T cannot be
// paired (an odd number of odd panels with no hem).
std::optional<std::vector<int>> t_join(int nodes, const std::vector<int>& terminals,
                                       const std::vector<std::pair<int, int>>& edges,
                                       const std::vector<double>& costs) {
  const size_t k = terminals.size();
  std::vector<std::vector<std::pair<int, int>>> adjacent(
      static_cast<size_t>(nodes));  // (node, edge)
  for (size_t e = 0; e < edges.size(); ++e) {
    adjacent[static_cast<size_t>(edges[e].first)].emplace_back(edges[e].second,
                                                               static_cast<int>(e));
    adjacent[static_cast<size_t>(edges[e].second)].emplace_back(edges[e].first,
                                                                static_cast<int>(e));
  }
  // Shortest paths from every terminal (Dijkstra), with the edge each node was reached by.
  std::vector<std::vector<double>> dist(k);
  std::vector<std::vector<int>> via(k);
  for (size_t t = 0; t < k; ++t) {
    dist[t].assign(static_cast<size_t>(nodes), std::numeric_limits<double>::infinity());
    via[t].assign(static_cast<size_t>(nodes), -1);
    using Item = std::pair<double, int>;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
    dist[t][static_cast<size_t>(terminals[t])] = 0;
    queue.emplace(0.0, terminals[t]);
    while (!queue.empty()) {
      const auto [d, u] = queue.top();
      queue.pop();
      if (d > dist[t][static_cast<size_t>(u)]) continue;
      for (const auto& [w, e] : adjacent[static_cast<size_t>(u)])
        if (d + costs[static_cast<size_t>(e)] < dist[t][static_cast<size_t>(w)]) {
          dist[t][static_cast<size_t>(w)] = d + costs[static_cast<size_t>(e)];
          via[t][static_cast<size_t>(w)] = e;
          queue.emplace(dist[t][static_cast<size_t>(w)], w);
        }
    }
  }
  // best[S]: cheapest perfect matching of the terminals in S (bit i = terminal i).
  const size_t states = size_t{1} << k;
  std::vector<double> best(states, std::numeric_limits<double>::infinity());
  std::vector<int> partner(states, -1);
  best[0] = 0;
  for (size_t s = 1; s < states; ++s) {
    if (std::popcount(s) % 2 != 0) continue;
    const int i = std::countr_zero(s);
    for (size_t j = static_cast<size_t>(i) + 1; j < k; ++j) {
      if (!(s >> j & 1)) continue;
      const double c = best[s & ~(size_t{1} << i) & ~(size_t{1} << j)] +
                       dist[static_cast<size_t>(i)][static_cast<size_t>(terminals[j])];
      if (c < best[s]) best[s] = c, partner[s] = static_cast<int>(j);
    }
  }
  if (!std::isfinite(best[states - 1])) return std::nullopt;
  std::vector<char> used(edges.size(), 0);
  for (size_t s = states - 1; s != 0;) {
    const size_t i = static_cast<size_t>(std::countr_zero(s)), j = static_cast<size_t>(partner[s]);
    for (int node = terminals[j]; node != terminals[i];) {  // walk back from j to i
      const int e = via[i][static_cast<size_t>(node)];
      used[static_cast<size_t>(e)] ^= 1;  // a shared stretch of two paths cancels
      node = edges[static_cast<size_t>(e)].first == node ? edges[static_cast<size_t>(e)].second
                                                         : edges[static_cast<size_t>(e)].first;
    }
    s &= ~(size_t{1} << i) & ~(size_t{1} << j);
  }
  std::vector<int> chosen;
  for (size_t e = 0; e < edges.size(); ++e)
    if (used[e]) chosen.push_back(static_cast<int>(e));
  return chosen;
}

// Any solution by Gaussian elimination over GF(2) (rows = constraints, columns = variables).
std::optional<std::vector<int>> eliminate(const std::vector<int>& group,
                                          const std::vector<bool>& odd,
                                          const std::vector<std::vector<int>>& columns) {
  const size_t rows = group.size(), cols = columns.size();
  std::vector<std::vector<bool>> a(rows, std::vector<bool>(cols + 1, false));
  for (size_t c = 0; c < cols; ++c)
    for (int r : columns[c]) a[static_cast<size_t>(r)][c] = true;
  for (size_t r = 0; r < rows; ++r) a[r][cols] = odd[static_cast<size_t>(group[r])];
  std::vector<int> pivot_col(rows, -1);
  size_t rank = 0;
  for (size_t c = 0; c < cols && rank < rows; ++c) {
    size_t r = rank;
    while (r < rows && !a[r][c]) ++r;
    if (r == rows) continue;
    std::swap(a[r], a[rank]);
    for (size_t o = 0; o < rows; ++o)
      if (o != rank && a[o][c])
        for (size_t k = 0; k <= cols; ++k) a[o][k] = a[o][k] != a[rank][k];
    pivot_col[rank++] = static_cast<int>(c);
  }
  for (size_t r = rank; r < rows; ++r)
    if (a[r][cols]) return std::nullopt;
  std::vector<int> chosen;
  for (size_t r = 0; r < rank; ++r)
    if (a[r][cols]) chosen.push_back(pivot_col[r]);
  return chosen;
}

}  // namespace

std::optional<std::vector<int>> solve_parity(int constraint_count, const std::vector<bool>& odd,
                                             const std::vector<ParityVariable>& variables,
                                             int* unfixable) {
  // Groups: constraints connected through shared variables are solved together.
  std::vector<int> parent(static_cast<size_t>(constraint_count));
  std::iota(parent.begin(), parent.end(), 0);
  std::function<int(int)> find = [&](int a) {
    return parent[static_cast<size_t>(a)] == a
               ? a
               : parent[static_cast<size_t>(a)] = find(parent[static_cast<size_t>(a)]);
  };
  for (const ParityVariable& v : variables)
    for (size_t k = 1; k < v.constraints.size(); ++k)
      parent[static_cast<size_t>(find(v.constraints[k]))] = find(v.constraints[0]);
  std::map<int, std::vector<int>> groups;
  for (int c = 0; c < constraint_count; ++c) groups[find(c)].push_back(c);

  std::vector<int> chosen;
  for (const auto& [root, group] : groups) {
    const bool any_odd =
        std::any_of(group.begin(), group.end(), [&](int c) { return odd[static_cast<size_t>(c)]; });
    if (!any_odd) continue;
    std::map<int, int> local;
    for (size_t k = 0; k < group.size(); ++k) local[group[k]] = static_cast<int>(k);
    std::vector<int> ids;
    std::vector<std::vector<int>> columns;
    for (size_t v = 0; v < variables.size(); ++v) {
      if (variables[v].constraints.empty() || find(variables[v].constraints[0]) != root) continue;
      ids.push_back(static_cast<int>(v));
      std::vector<int> rows;
      for (int c : variables[v].constraints) rows.push_back(local[c]);
      columns.push_back(rows);
    }
    std::optional<std::vector<int>> solution;
    const bool graph = std::all_of(columns.begin(), columns.end(),
                                   [](const std::vector<int>& c) { return c.size() <= 2; });
    const int odd_count = static_cast<int>(std::count_if(
        group.begin(), group.end(), [&](int c) { return odd[static_cast<size_t>(c)]; }));
    if (graph && odd_count + 1 <= kExactParityOdd) {
      const int outside = static_cast<int>(group.size());
      std::vector<int> terminals;
      for (size_t k = 0; k < group.size(); ++k)
        if (odd[static_cast<size_t>(group[k])]) terminals.push_back(static_cast<int>(k));
      if (terminals.size() % 2 == 1) terminals.push_back(outside);
      std::vector<std::pair<int, int>> edges;
      std::vector<double> costs;
      for (size_t k = 0; k < ids.size(); ++k) {
        edges.emplace_back(columns[k][0], columns[k].size() == 2 ? columns[k][1] : outside);
        costs.push_back(variables[static_cast<size_t>(ids[k])].cost);
      }
      solution = t_join(outside + 1, terminals, edges, costs);
    } else if (static_cast<int>(group.size()) <= kExactParityConstraints) {
      std::uint32_t start = 0;
      for (size_t k = 0; k < group.size(); ++k)
        if (odd[static_cast<size_t>(group[k])]) start |= 1u << k;
      std::vector<std::uint32_t> masks;
      std::vector<double> costs;
      for (size_t k = 0; k < ids.size(); ++k) {
        std::uint32_t m = 0;
        for (int r : columns[k]) m ^= 1u << r;
        masks.push_back(m);
        costs.push_back(variables[static_cast<size_t>(ids[k])].cost);
      }
      solution = exact_group(static_cast<int>(group.size()), start, masks, costs);
    } else {
      solution = eliminate(group, odd, columns);
      spdlog::warn(
          "parity fix: {} connected panels ({} with an odd total) and curve pieces "
          "shared by more than two panels; the edge-count change is feasible but not "
          "guaranteed minimal",
          group.size(), odd_count);
    }
    if (!solution) {
      if (unfixable)
        for (int c : group)
          if (odd[static_cast<size_t>(c)]) {
            *unfixable = c;
            break;
          }
      return std::nullopt;
    }
    for (int k : *solution) chosen.push_back(ids[static_cast<size_t>(k)]);
  }
  std::sort(chosen.begin(), chosen.end());
  return chosen;
}

EdgeCounts compute_edge_counts(const GarmentRequest& sketch, const CurveNetwork& net,
                               const std::vector<PanelLoop>& loops) {
  const size_t edge_count = net.edges.size();
  EdgeCounts result;
  result.counts.assign(edge_count, 1);
  result.ideal.assign(edge_count, 1.0);

  // Target edge length: the curve's, else the finest of its panels', else the file's.
  std::vector<double> target(edge_count, sketch.edge_length);
  std::vector<bool> panel_set(edge_count, false);
  for (const PanelLoop& loop : loops) {
    const PanelSpec& spec = sketch.panels[static_cast<size_t>(loop.spec)];
    if (!spec.edge_length) continue;
    for (const LoopEdge& e : loop.edges) {
      const size_t o = static_cast<size_t>(net.edges[static_cast<size_t>(e.edge)].orbit);
      target[o] = panel_set[o] ? std::min(target[o], *spec.edge_length) : *spec.edge_length;
      panel_set[o] = true;
    }
  }
  std::vector<bool> fixed(edge_count, false);
  for (const NetworkCurve& curve : net.curves) {
    if (curve.mirror_copy) continue;
    const CurveSpec& spec = sketch.curves[static_cast<size_t>(curve.spec)];
    if (spec.edge_length)
      for (int e : curve.edges) target[static_cast<size_t>(e)] = *spec.edge_length;
    for (int e : curve.edges) {
      const double ideal =
          net.edges[static_cast<size_t>(e)].length / target[static_cast<size_t>(e)];
      result.ideal[static_cast<size_t>(e)] = ideal;
      result.counts[static_cast<size_t>(e)] = std::max(1, static_cast<int>(std::lround(ideal)));
    }
    if (spec.edges) {
      // Share the fixed count among the curve's pieces by length (largest remainder), >= 1 each.
      const int total = *spec.edges;
      const int pieces = static_cast<int>(curve.edges.size());
      if (total < pieces)
        sketch.fail(spec.json_path + "/edges",
                    fmt::format("curve '{}' is cut into {} pieces by junctions, so it needs at "
                                "least {} edges, not {}",
                                spec.id, pieces, pieces, total));
      double length = 0;
      for (int e : curve.edges) length += net.edges[static_cast<size_t>(e)].length;
      std::vector<std::pair<double, int>> remainders;
      int assigned = 0;
      for (int e : curve.edges) {
        const double share =
            1 + (total - pieces) * net.edges[static_cast<size_t>(e)].length / length;
        const int whole = static_cast<int>(std::floor(share));
        result.counts[static_cast<size_t>(e)] = whole;
        assigned += whole;
        remainders.emplace_back(share - whole, e);
      }
      std::sort(remainders.rbegin(), remainders.rend());
      for (int k = 0; assigned < total; ++k, ++assigned)
        ++result.counts[static_cast<size_t>(remainders[static_cast<size_t>(k)].second)];
      for (int e : curve.edges) fixed[static_cast<size_t>(e)] = true;
    }
  }
  for (size_t e = 0; e < edge_count; ++e) {  // copies follow their originals
    const size_t o = static_cast<size_t>(net.edges[e].orbit);
    result.counts[e] = result.counts[o];
    result.ideal[e] = result.ideal[o];
    fixed[e] = fixed[o];
  }

  // Parity: constraints are the original panels (a copy has its original's total), unknowns the
  // original edges; a panel's coefficient for an edge is how often the loop uses it or its
  // copy, mod 2.
  std::vector<int> constraint_of_loop(loops.size(), -1);
  std::vector<int> constraint_loop;
  for (size_t l = 0; l < loops.size(); ++l)
    if (!loops[l].mirror_copy) {
      constraint_of_loop[l] = static_cast<int>(constraint_loop.size());
      constraint_loop.push_back(static_cast<int>(l));
    }
  const int constraints = static_cast<int>(constraint_loop.size());
  std::vector<bool> odd(static_cast<size_t>(constraints), false);
  std::map<int, std::map<int, int>> uses;  // orbit → constraint → occurrences
  for (int c = 0; c < constraints; ++c) {
    int total = 0;
    for (const LoopEdge& e :
         loops[static_cast<size_t>(constraint_loop[static_cast<size_t>(c)])].edges) {
      total += result.counts[static_cast<size_t>(e.edge)];
      ++uses[net.edges[static_cast<size_t>(e.edge)].orbit][c];
    }
    odd[static_cast<size_t>(c)] = total % 2 != 0;
  }
  std::vector<ParityVariable> variables;
  std::vector<int> variable_edge;
  std::vector<int> direction;
  const double epsilon = 0.5 / static_cast<double>(uses.size() + 1);
  for (const auto& [orbit, by_constraint] : uses) {
    if (fixed[static_cast<size_t>(orbit)]) continue;
    ParityVariable v;
    for (const auto& [c, n] : by_constraint)
      if (n % 2 == 1) v.constraints.push_back(c);
    if (v.constraints.empty()) continue;
    const int n = result.counts[static_cast<size_t>(orbit)];
    const double ideal = result.ideal[static_cast<size_t>(orbit)];
    // ±1 towards the ideal length; never down to 0 edges.
    const int step = (n == 1 || ideal >= n) ? +1 : -1;
    // Cost 1 per curve changed, plus a tie-breaker below 1 in total: the resulting deviation
    // from the ideal count (so the curves whose rounding was closest to a half change first).
    v.cost = 1.0 + epsilon * std::min(1.0, std::abs(n + step - ideal));
    variables.push_back(v);
    variable_edge.push_back(orbit);
    direction.push_back(step);
  }
  int unfixable = -1;
  const auto chosen = solve_parity(constraints, odd, variables, &unfixable);
  if (!chosen) {
    const PanelLoop& loop =
        loops[static_cast<size_t>(constraint_loop[static_cast<size_t>(unfixable)])];
    int total = 0;
    for (const LoopEdge& e : loop.edges) total += result.counts[static_cast<size_t>(e.edge)];
    sketch.fail(loop.json_path,
                fmt::format("panel '{}' has an odd number of boundary edges ({}) and no curve "
                            "that could change it is free: every quad mesh needs an even total. "
                            "Remove \"edges\" from one of its curves or make one of them odd/even",
                            loop.id, total));
  }
  for (int v : *chosen) {
    const int orbit = variable_edge[static_cast<size_t>(v)];
    const int step = direction[static_cast<size_t>(v)];
    for (size_t e = 0; e < edge_count; ++e)
      if (net.edges[e].orbit == orbit) result.counts[e] += step;
    result.changed.push_back(orbit);
  }
  spdlog::debug("parity fix changed {} edge(s)", result.changed.size());
  return result;
}

}  // namespace sd::garment
