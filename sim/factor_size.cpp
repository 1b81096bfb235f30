#include "sim/factor_size.hpp"

#include <cholmod.h>

#include <algorithm>
#include <cstdint>
#include <new>
#include <tuple>
#include <vector>

#include "sim/diamond_membrane.hpp"

namespace sd::sim {
namespace {

// The vertex graph of the system matrix, both triangles of it, as sorted columns with the
// diagonal (CSC arrays; the pattern is symmetric).
struct VertexGraph {
  std::vector<int> outer, inner;
};

// The pairs of `diamonds` (every two of a diamond's 13 vertices, as collect_neighbours in
// sim/cloth_model.cpp couples them) are added to those of the triangles and hinges.
VertexGraph vertex_graph(const Eigen::MatrixX3i& triangles, int n,
                         const std::vector<DiamondElement>& diamonds) {
  // Edges with the corner opposite them, sorted: an edge met twice is a hinge whose two far
  // corners are coupled (a flat sort rather than a map; a 1000×1000 sheet has 6 million).
  struct FaceEdge {
    int low, high, opposite;
  };
  std::vector<FaceEdge> edges;
  edges.reserve(3 * static_cast<std::size_t>(triangles.rows()));
  for (Eigen::Index f = 0; f < triangles.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = triangles(f, k), b = triangles(f, (k + 1) % 3);
      edges.push_back({std::min(a, b), std::max(a, b), triangles(f, (k + 2) % 3)});
    }
  std::sort(edges.begin(), edges.end(), [](const FaceEdge& p, const FaceEdge& q) {
    return std::tie(p.low, p.high, p.opposite) < std::tie(q.low, q.high, q.opposite);
  });
  // Pairs (i, j) in both orders, packed into 64 bits so that one sort groups them by column.
  std::vector<std::uint64_t> pairs;
  constexpr int kDiamondVertices = DiamondElement::kVertices;
  pairs.reserve(2 * edges.size() + static_cast<std::size_t>(n) +
                diamonds.size() * kDiamondVertices * (kDiamondVertices - 1));
  const auto add = [&](int i, int j) {
    pairs.push_back((static_cast<std::uint64_t>(i) << 32) | static_cast<std::uint32_t>(j));
    pairs.push_back((static_cast<std::uint64_t>(j) << 32) | static_cast<std::uint32_t>(i));
  };
  for (int i = 0; i < n; ++i) pairs.push_back((static_cast<std::uint64_t>(i) << 32) | i);
  for (std::size_t begin = 0; begin < edges.size();) {
    std::size_t end = begin + 1;
    while (end < edges.size() && edges[end].low == edges[begin].low &&
           edges[end].high == edges[begin].high)
      ++end;
    add(edges[begin].low, edges[begin].high);
    if (end - begin == 2) add(edges[begin].opposite, edges[begin + 1].opposite);  // a hinge
    begin = end;
  }
  std::vector<FaceEdge>().swap(edges);
  // A missing neighbour's slot holds the centre again: its pairs repeat the centre's.
  for (const DiamondElement& d : diamonds)
    for (int k = 0; k < kDiamondVertices; ++k)
      for (int l = k + 1; l < kDiamondVertices; ++l)
        if (d.vertices[static_cast<std::size_t>(k)] != d.vertices[static_cast<std::size_t>(l)])
          add(d.vertices[static_cast<std::size_t>(k)], d.vertices[static_cast<std::size_t>(l)]);
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  VertexGraph graph;
  graph.outer.assign(static_cast<std::size_t>(n) + 1, 0);
  graph.inner.reserve(pairs.size());
  for (const std::uint64_t p : pairs) {
    ++graph.outer[static_cast<std::size_t>(p >> 32) + 1];
    graph.inner.push_back(static_cast<int>(p & 0xffffffffu));
  }
  for (int j = 0; j < n; ++j) graph.outer[j + 1] += graph.outer[j];
  return graph;
}

// The analysis of the graph of these triangles and diamonds; `bend_model` as below.
FactorSize analyse(const Eigen::MatrixX3i& triangles, int vertex_count,
                   const std::vector<DiamondElement>& diamonds, BendModel bend_model) {
  FactorSize size;
  if (vertex_count <= 0) return size;
  VertexGraph graph = vertex_graph(triangles, vertex_count, diamonds);
  cholmod_sparse pattern{};
  pattern.nrow = pattern.ncol = static_cast<std::size_t>(vertex_count);
  pattern.nzmax = graph.inner.size();
  pattern.p = graph.outer.data();
  pattern.i = graph.inner.data();
  pattern.stype = -1;  // symmetric, the lower part read
  pattern.itype = CHOLMOD_INT;
  pattern.xtype = CHOLMOD_PATTERN;
  pattern.dtype = CHOLMOD_DOUBLE;
  pattern.sorted = 1;
  pattern.packed = 1;

  cholmod_common common;
  cholmod_start(&common);
  // As CholmodSolver: AMD on the vertex graph, a supernodal factor.
  common.nmethods = 1;
  common.method[0].ordering = CHOLMOD_AMD;
  common.supernodal = CHOLMOD_SUPERNODAL;
  cholmod_factor* factor = cholmod_analyze(&pattern, &common);
  if (factor == nullptr) {
    const int status = common.status;
    cholmod_finish(&common);
    if (status == CHOLMOD_OUT_OF_MEMORY || status == CHOLMOD_TOO_LARGE) throw std::bad_alloc();
    return size;  // CHOLMOD refused the pattern: nothing to predict from (never seen)
  }
  const double n = vertex_count;
  // Each vertex entry of L is a 3×3 block, each diagonal one a lower triangle (6 entries);
  // a column of c vertex entries costs about c² flops, its three scalar columns 3·(3c)².
  size.nonzeros = 9.0 * common.lnz - 3.0 * n;
  size.flops = 27.0 * common.fl;
  if (factor->is_super) {
    // Supernodes of k vertex columns and r vertex rows hold k·r values, 9·k·r in scalars; Ls
    // lists r rows per supernode (3r in scalars); the update block C is 3·3 times as large.
    size.bytes =
        8.0 * 9.0 * (static_cast<double>(factor->xsize) + static_cast<double>(factor->maxcsize)) +
        static_cast<double>(sizeof(int)) * 3.0 * static_cast<double>(factor->ssize);
  } else {
    size.bytes = (8.0 + sizeof(int)) * size.nonzeros;  // Lx and Li
  }
  cholmod_free_factor(&factor, &common);
  cholmod_finish(&common);
  if (bend_model == BendModel::quadratic) {
    size.nonzeros *= kQuadraticBendingFactorScale;
    size.flops *= kQuadraticBendingFactorScale * kQuadraticBendingFactorScale;
    size.bytes *= kQuadraticBendingFactorScale;
  }
  return size;
}

}  // namespace

FactorSize predict_factor_size(const Eigen::MatrixX3i& triangles, int vertex_count,
                               BendModel bend_model) {
  return analyse(triangles, vertex_count, {}, bend_model);
}

FactorSize predict_factor_size(const ClothInput& input, const ClothModelOptions& options) {
  const int n = static_cast<int>(input.rest_positions.rows());
  std::vector<DiamondElement> diamonds;
  if (options.diamond_membrane) {
    // make_diamonds reads the triangles' vertices only.
    std::vector<TriangleElement> triangles(static_cast<std::size_t>(input.triangles.rows()));
    for (Eigen::Index f = 0; f < input.triangles.rows(); ++f)
      for (int k = 0; k < 3; ++k)
        triangles[static_cast<std::size_t>(f)].vertices[static_cast<std::size_t>(k)] =
            input.triangles(f, k);
    diamonds = make_diamonds(input.rest_positions, triangles, input.rest_uv.rows() > 0);
  }
  return analyse(input.triangles, n, diamonds, options.bend_model);
}

}  // namespace sd::sim
