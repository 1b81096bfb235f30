#include "meshing/quad_layout.hpp"

#include <algorithm>
#include <cassert>
#include <stdexcept>
#include <utility>

namespace sd::meshing::detail {

int QuadMeshBuilder::add_vertex(const Eigen::Vector3d& position) {
  positions_.push_back(position);
  return static_cast<int>(positions_.size()) - 1;
}

std::vector<int> QuadMeshBuilder::add_chain(int from, int to, int edges) {
  if (edges < 1) throw std::logic_error("a chain needs at least one edge");
  std::vector<int> chain{from};
  const Eigen::Vector3d a = position(from), b = position(to);
  for (int k = 1; k < edges; ++k) {
    const double t = static_cast<double>(k) / edges;
    chain.push_back(add_vertex((1 - t) * a + t * b));
  }
  chain.push_back(to);
  for (size_t k = 0; k + 1 < chain.size(); ++k) chain_edges_.push_back({chain[k], chain[k + 1]});
  return chain;
}

void QuadMeshBuilder::add_path(std::span<const int> vertices) {
  for (size_t k = 0; k + 1 < vertices.size(); ++k)
    chain_edges_.push_back({vertices[k], vertices[k + 1]});
}

void QuadMeshBuilder::add_grid(std::span<const int> bottom, std::span<const int> right,
                               std::span<const int> top, std::span<const int> left) {
  const auto a = static_cast<int>(bottom.size()) - 1;
  const auto b = static_cast<int>(right.size()) - 1;
  if (a < 1 || b < 1 || static_cast<int>(top.size()) != a + 1 ||
      static_cast<int>(left.size()) != b + 1 || bottom.back() != right.front() ||
      right.back() != top.front() || top.back() != left.front() || left.back() != bottom.front())
    throw std::logic_error("grid block sides do not match");
  // id(i, j), i along bottom (0..a), j along left (0..b).
  std::vector<int> id(static_cast<size_t>((a + 1) * (b + 1)), -1);
  auto at = [&](int i, int j) -> int& { return id[static_cast<size_t>(j * (a + 1) + i)]; };
  for (int i = 0; i <= a; ++i) {
    at(i, 0) = bottom[static_cast<size_t>(i)];
    at(i, b) = top[static_cast<size_t>(a - i)];
  }
  for (int j = 0; j <= b; ++j) {
    at(a, j) = right[static_cast<size_t>(j)];
    at(0, j) = left[static_cast<size_t>(b - j)];
  }
  const Eigen::Vector3d c0 = position(at(0, 0)), c1 = position(at(a, 0));
  const Eigen::Vector3d c2 = position(at(a, b)), c3 = position(at(0, b));
  for (int j = 1; j < b; ++j)
    for (int i = 1; i < a; ++i) {
      const double u = static_cast<double>(i) / a, v = static_cast<double>(j) / b;
      // Bilinearly blended Coons patch of the four sides.
      const Eigen::Vector3d p =
          (1 - v) * position(at(i, 0)) + v * position(at(i, b)) + (1 - u) * position(at(0, j)) +
          u * position(at(a, j)) -
          ((1 - u) * (1 - v) * c0 + u * (1 - v) * c1 + u * v * c2 + (1 - u) * v * c3);
      at(i, j) = add_vertex(p);
    }
  for (int j = 0; j < b; ++j)
    for (int i = 0; i < a; ++i)
      faces_.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
}

std::vector<int> QuadMeshBuilder::valences() const {
  // Every edge in both directions, bucketed by its first vertex (counting sort, O(E)); a
  // vertex's valence is the number of distinct second vertices in its bucket.
  const size_t nv = positions_.size();
  std::vector<int> start(nv + 1, 0);
  auto each_edge = [&](auto&& visit) {
    for (const auto& e : chain_edges_) visit(e[0], e[1]);
    for (const auto& f : faces_)
      for (size_t k = 0; k < 4; ++k) visit(f[k], f[(k + 1) % 4]);
  };
  each_edge([&](int u, int v) {
    ++start[static_cast<size_t>(u) + 1];
    ++start[static_cast<size_t>(v) + 1];
  });
  for (size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
  std::vector<int> target(static_cast<size_t>(start[nv]));
  std::vector<int> fill(start.begin(), start.end() - 1);
  each_edge([&](int u, int v) {
    target[static_cast<size_t>(fill[static_cast<size_t>(u)]++)] = v;
    target[static_cast<size_t>(fill[static_cast<size_t>(v)]++)] = u;
  });
  std::vector<int> valence(nv, 0);
  for (size_t v = 0; v < nv; ++v) {
    const auto begin = target.begin() + start[v], end = target.begin() + start[v + 1];
    std::sort(begin, end);
    valence[v] = static_cast<int>(std::unique(begin, end) - begin);
  }
  return valence;
}

QuadMesh QuadMeshBuilder::build() const {
  QuadMesh mesh;
  mesh.vertices.resize(static_cast<Eigen::Index>(positions_.size()), 3);
  for (size_t v = 0; v < positions_.size(); ++v)
    mesh.vertices.row(static_cast<Eigen::Index>(v)) = positions_[v].transpose();
  mesh.faces.resize(static_cast<Eigen::Index>(faces_.size()), 4);
  for (size_t f = 0; f < faces_.size(); ++f)
    mesh.faces.row(static_cast<Eigen::Index>(f)) << faces_[f][0], faces_[f][1], faces_[f][2],
        faces_[f][3];
  return mesh;
}

}  // namespace sd::meshing::detail
