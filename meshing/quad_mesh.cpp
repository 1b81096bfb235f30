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
  const auto nv = static_cast<int>(mesh.vertices.rows());
  return (mesh.faces.array() >= 0).all() && (mesh.faces.array() < nv).all();
}

}  // namespace

namespace {

// For each vertex, the vertices its faces' edges leave it for (v → next in some face):
// compressed rows, built in O(F).
struct OutgoingEdges {
  std::vector<int> start, target;
  std::span<const int> of(int v) const {
    return {target.data() + start[static_cast<size_t>(v)],
            static_cast<size_t>(start[static_cast<size_t>(v) + 1] - start[static_cast<size_t>(v)])};
  }
  bool has(int from, int to) const {
    const auto row = of(from);
    return std::find(row.begin(), row.end(), to) != row.end();
  }
};

OutgoingEdges outgoing_edges(const QuadMesh& mesh) {
  OutgoingEdges out;
  const auto nv = static_cast<size_t>(mesh.vertices.rows());
  out.start.assign(nv + 1, 0);
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f)
    for (int k = 0; k < 4; ++k) ++out.start[static_cast<size_t>(mesh.faces(f, k)) + 1];
  for (size_t v = 0; v < nv; ++v) out.start[v + 1] += out.start[v];
  out.target.resize(static_cast<size_t>(out.start[nv]));
  std::vector<int> fill(out.start.begin(), out.start.end() - 1);
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f)
    for (int k = 0; k < 4; ++k)
      out.target[static_cast<size_t>(fill[static_cast<size_t>(mesh.faces(f, k))]++)] =
          mesh.faces(f, (k + 1) % 4);
  return out;
}

}  // namespace

Eigen::VectorXi vertex_valences(const QuadMesh& mesh) {
  if (!indices_in_range(mesh)) throw std::invalid_argument("a face refers to a missing vertex");
  const OutgoingEdges out = outgoing_edges(mesh);
  // Distinct neighbours: every outgoing target, plus every vertex with an edge into v that v
  // has no edge back to (only boundary edges, on a good mesh).
  Eigen::VectorXi valence = Eigen::VectorXi::Zero(mesh.vertices.rows());
  for (int v = 0; v < static_cast<int>(mesh.vertices.rows()); ++v) {
    const auto row = out.of(v);
    for (size_t i = 0; i < row.size(); ++i) {
      if (std::find(row.begin(), row.begin() + static_cast<std::ptrdiff_t>(i), row[i]) !=
          row.begin() + static_cast<std::ptrdiff_t>(i))
        continue;  // repeated target (non-manifold input)
      ++valence(v);
      if (!out.has(row[i], v)) ++valence(row[i]);
    }
  }
  return valence;
}

std::vector<int> boundary_loop(const QuadMesh& mesh) {
  if (!indices_in_range(mesh)) throw std::invalid_argument("a face refers to a missing vertex");
  const OutgoingEdges out = outgoing_edges(mesh);
  const auto nv = static_cast<size_t>(mesh.vertices.rows());
  std::vector<int> next(nv, -1);  // boundary edge from → to, in face orientation
  size_t edges = 0;
  for (int v = 0; v < static_cast<int>(nv); ++v)
    for (const int w : out.of(v)) {
      if (out.has(w, v)) continue;
      if (next[static_cast<size_t>(v)] != -1)
        throw std::invalid_argument("the boundary is not a single simple loop");
      next[static_cast<size_t>(v)] = w;
      ++edges;
    }
  if (edges == 0) return {};
  std::vector<int> loop;
  int v = static_cast<int>(std::find_if(next.begin(), next.end(), [](int w) { return w >= 0; }) -
                           next.begin());
  do {
    loop.push_back(v);
    v = next[static_cast<size_t>(v)];
    if (v < 0 || loop.size() > edges)
      throw std::invalid_argument("the boundary is not a single simple loop");
  } while (v != loop.front());
  if (loop.size() != edges) throw std::invalid_argument("the boundary has more than one loop");
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
          problems.push_back("face " + std::to_string(f) + " repeats vertex " + std::to_string(q(a)));
  }
  const OutgoingEdges out = outgoing_edges(mesh);
  auto uses = [&](int from, int to) {
    const auto row = out.of(from);
    return static_cast<int>(std::count(row.begin(), row.end(), to));
  };
  int non_manifold = 0, inconsistent = 0;
  Eigen::Index undirected_edges = 0;
  for (int v = 0; v < static_cast<int>(mesh.vertices.rows()); ++v) {
    const auto row = out.of(v);
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
      problems.push_back("Euler characteristic is " + std::to_string(euler) + ", not 1 (not a disk)");
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
