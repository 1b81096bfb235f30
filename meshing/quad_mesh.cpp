#include "meshing/quad_mesh.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <span>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace sd::meshing {
namespace {

bool indices_in_range(const QuadMesh& mesh) {
  return mesh.faces.size() == 0 ||
         (mesh.faces.minCoeff() >= 0 && mesh.faces.maxCoeff() < mesh.vertices.rows());
}

}  // namespace

namespace {

// For each vertex v, its face corners' edges in compressed rows, built in O(F): `out` holds the
// vertex each corner's face goes to after v (edge v → out), `in` the one it comes from
// (edge in → v), in the same corner order.
struct CornerEdges {
  std::vector<int> start, out, in;
  std::span<const int> row(const std::vector<int>& targets, int v) const {
    return {targets.data() + start[static_cast<size_t>(v)],
            static_cast<size_t>(start[static_cast<size_t>(v) + 1] - start[static_cast<size_t>(v)])};
  }
  std::span<const int> out_of(int v) const { return row(out, v); }
  std::span<const int> in_of(int v) const { return row(in, v); }
};

CornerEdges corner_edges(const QuadMesh& mesh) {
  CornerEdges edges;
  const auto nv = static_cast<size_t>(mesh.vertices.rows());
  edges.start.assign(nv + 1, 0);
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f)
    for (int k = 0; k < 4; ++k) ++edges.start[static_cast<size_t>(mesh.faces(f, k)) + 1];
  for (size_t v = 0; v < nv; ++v) edges.start[v + 1] += edges.start[v];
  edges.out.resize(static_cast<size_t>(edges.start[nv]));
  edges.in.resize(edges.out.size());
  std::vector<int> fill(edges.start.begin(), edges.start.end() - 1);
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f)
    for (int k = 0; k < 4; ++k) {
      const auto slot = static_cast<size_t>(fill[static_cast<size_t>(mesh.faces(f, k))]++);
      edges.out[slot] = mesh.faces(f, (k + 1) % 4);
      edges.in[slot] = mesh.faces(f, (k + 3) % 4);
    }
  return edges;
}

}  // namespace

Eigen::VectorXi vertex_valences(const QuadMesh& mesh) {
  if (!indices_in_range(mesh)) throw std::invalid_argument("a face refers to a missing vertex");
  const CornerEdges edges = corner_edges(mesh);
  // Distinct neighbours: the vertices v has an edge to or from, each counted once.
  const auto nv = static_cast<int>(mesh.vertices.rows());
  Eigen::VectorXi valence = Eigen::VectorXi::Zero(nv);
  std::vector<int> counted_for(static_cast<size_t>(nv), -1);  // the last v that counted w
  for (int v = 0; v < nv; ++v)
    for (const auto& row : {edges.out_of(v), edges.in_of(v)})
      for (const int w : row)
        if (std::exchange(counted_for[static_cast<size_t>(w)], v) != v) ++valence(v);
  return valence;
}

std::vector<int> boundary_loop(const QuadMesh& mesh) {
  if (!indices_in_range(mesh)) throw std::invalid_argument("a face refers to a missing vertex");
  const CornerEdges edges = corner_edges(mesh);
  const auto nv = static_cast<size_t>(mesh.vertices.rows());
  std::vector<int> next(nv, -1);    // boundary edge from → to, in face orientation
  std::vector<int> enters(nv, -1);  // enters[w] == v: some face has the edge w → v
  size_t boundary_edges = 0;
  for (int v = 0; v < static_cast<int>(nv); ++v) {
    for (const int w : edges.in_of(v)) enters[static_cast<size_t>(w)] = v;
    for (const int w : edges.out_of(v)) {
      if (enters[static_cast<size_t>(w)] == v) continue;  // w → v too: an inner edge
      if (next[static_cast<size_t>(v)] != -1)
        throw std::invalid_argument("the boundary is not a single simple loop");
      next[static_cast<size_t>(v)] = w;
      ++boundary_edges;
    }
  }
  if (boundary_edges == 0) return {};
  std::vector<int> loop;
  int v = static_cast<int>(std::find_if(next.begin(), next.end(), [](int w) { return w >= 0; }) -
                           next.begin());
  do {
    loop.push_back(v);
    v = next[static_cast<size_t>(v)];
    if (v < 0 || loop.size() > boundary_edges)
      throw std::invalid_argument("the boundary is not a single simple loop");
  } while (v != loop.front());
  if (loop.size() != boundary_edges)
    throw std::invalid_argument("the boundary has more than one loop");
  return loop;
}

MeshCheck validate(const QuadMesh& mesh) {
  MeshCheck check;
  auto& problems = check.problems;
  if (mesh.faces.rows() == 0) {
    problems.emplace_back("the mesh has no faces");
    return check;
  }
  if (!indices_in_range(mesh)) {
    problems.emplace_back("a face refers to a vertex index out of range");
    return check;
  }
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) {
    const Eigen::RowVector4i q = mesh.faces.row(f);
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b)
        if (q(a) == q(b))
          problems.push_back("face " + std::to_string(f) + " repeats vertex " +
                             std::to_string(q(a)));
  }
  const CornerEdges edges = corner_edges(mesh);
  auto uses = [&](int from, int to) {
    const auto row = edges.out_of(from);
    return static_cast<int>(std::count(row.begin(), row.end(), to));
  };
  int non_manifold = 0, inconsistent = 0;
  Eigen::Index undirected_edges = 0;
  for (int v = 0; v < static_cast<int>(mesh.vertices.rows()); ++v) {
    const auto row = edges.out_of(v);
    for (size_t i = 0; i < row.size(); ++i) {
      const int w = row[i];
      if (std::find(row.begin(), row.begin() + static_cast<std::ptrdiff_t>(i), w) !=
          row.begin() + static_cast<std::ptrdiff_t>(i))
        continue;  // this directed edge was already counted
      const int forward = uses(v, w), backward = uses(w, v);
      if (forward > 1) ++inconsistent;  // two faces traverse it the same way
      if (backward == 0 || v < w) {
        ++undirected_edges;
        if (forward + backward > 2) ++non_manifold;
      }
    }
  }
  if (non_manifold > 0)
    problems.push_back(std::to_string(non_manifold) + " edge(s) have more than two faces");
  if (inconsistent > 0)
    problems.push_back(std::to_string(inconsistent) +
                       " edge(s) are traversed the same way by two faces (inconsistent "
                       "orientation)");
  std::vector<bool> used(static_cast<size_t>(mesh.vertices.rows()), false);
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f)
    for (int k = 0; k < 4; ++k) used[static_cast<size_t>(mesh.faces(f, k))] = true;
  const auto unused = std::count(used.begin(), used.end(), false);
  if (unused > 0) problems.push_back(std::to_string(unused) + " vertex(es) are used by no face");
  if (non_manifold == 0 && inconsistent == 0) {
    try {
      if (boundary_loop(mesh).empty()) problems.emplace_back("the mesh has no boundary");
    } catch (const std::invalid_argument& e) {
      problems.emplace_back(e.what());
    }
  }
  // A fan at every vertex (no two disks touching at a vertex): with one boundary loop and no
  // bad edges, that is the Euler characteristic of a disk, V - E + F = 1.
  if (problems.empty()) {
    const auto euler = mesh.vertices.rows() - undirected_edges + mesh.faces.rows();
    if (euler != 1)
      problems.push_back("Euler characteristic is " + std::to_string(euler) +
                         ", not 1 (not a disk)");
  }
  const Eigen::RowVector3d lo = mesh.vertices.colwise().minCoeff();
  const Eigen::RowVector3d hi = mesh.vertices.colwise().maxCoeff();
  const double diagonal2 = (hi - lo).squaredNorm();
  if (diagonal2 > 0) {
    int degenerate = 0;
    for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) {
      const Eigen::Vector3d p0 = mesh.vertices.row(mesh.faces(f, 0));
      const Eigen::Vector3d p1 = mesh.vertices.row(mesh.faces(f, 1));
      const Eigen::Vector3d p2 = mesh.vertices.row(mesh.faces(f, 2));
      const Eigen::Vector3d p3 = mesh.vertices.row(mesh.faces(f, 3));
      const double area = 0.5 * (p2 - p0).cross(p3 - p1).norm();
      if (area <= 1e-12 * diagonal2) ++degenerate;
    }
    if (degenerate > 0)
      problems.push_back(std::to_string(degenerate) + " face(s) have (almost) zero area");
  }
  return check;
}

std::string to_obj(const QuadMesh& mesh) {
  std::ostringstream out;
  out.precision(17);
  for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v)
    out << "v " << mesh.vertices(v, 0) << ' ' << mesh.vertices(v, 1) << ' ' << mesh.vertices(v, 2)
        << '\n';
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f)
    out << "f " << mesh.faces(f, 0) + 1 << ' ' << mesh.faces(f, 1) + 1 << ' '
        << mesh.faces(f, 2) + 1 << ' ' << mesh.faces(f, 3) + 1 << '\n';
  return out.str();
}

}  // namespace sd::meshing
