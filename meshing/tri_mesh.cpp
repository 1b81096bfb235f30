#include "meshing/tri_mesh.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace sd::meshing {
namespace {

// Union-find over vertex indices, for counting connected components.
class DisjointSets {
 public:
  explicit DisjointSets(Eigen::Index n) : parent_(static_cast<size_t>(n)) {
    std::iota(parent_.begin(), parent_.end(), Eigen::Index{0});
  }
  Eigen::Index find(Eigen::Index i) {
    while (parent_[i] != i) i = parent_[i] = parent_[parent_[i]];
    return i;
  }
  void unite(Eigen::Index a, Eigen::Index b) { parent_[find(a)] = find(b); }

 private:
  std::vector<Eigen::Index> parent_;
};

}  // namespace

BoundingBox bounding_box(const TriMesh& mesh) {
  BoundingBox box;
  if (mesh.vertex_count() == 0) return box;
  box.min = mesh.vertices.colwise().minCoeff().transpose();
  box.max = mesh.vertices.colwise().maxCoeff().transpose();
  return box;
}

TriMeshTopology analyse_topology(const TriMesh& mesh) {
  const Eigen::Index nv = mesh.vertex_count();
  if (mesh.faces.size() > 0 && (mesh.faces.minCoeff() < 0 || mesh.faces.maxCoeff() >= nv))
    throw std::invalid_argument("a face refers to a vertex index outside 0.." +
                                std::to_string(nv - 1));

  TriMeshTopology topo;
  const double diag = bounding_box(mesh).extent().norm();
  const double min_area = 1e-12 * diag * diag;

  // Directed half-edges sorted by their undirected key; a run of equal keys is one edge.
  struct HalfEdge {
    int lo, hi;
    bool forward;  // traversed lo -> hi
  };
  std::vector<HalfEdge> half_edges;
  half_edges.reserve(static_cast<size_t>(mesh.face_count()) * 3);
  std::vector<bool> used(static_cast<size_t>(nv), false);
  DisjointSets sets(nv);
  const Eigen::VectorXd areas = face_areas(mesh);
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
    const Eigen::Vector3i t = mesh.faces.row(f);
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || !(areas[f] > min_area))
      ++topo.degenerate_faces;
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      used[a] = true;
      sets.unite(a, b);
      if (a != b) half_edges.push_back({std::min(a, b), std::max(a, b), a < b});
    }
  }
  std::sort(half_edges.begin(), half_edges.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return x.lo != y.lo ? x.lo < y.lo : x.hi < y.hi;
  });
  for (size_t i = 0; i < half_edges.size();) {
    size_t j = i;
    int forward = 0;
    while (j < half_edges.size() && half_edges[j].lo == half_edges[i].lo &&
           half_edges[j].hi == half_edges[i].hi)
      forward += half_edges[j++].forward ? 1 : 0;
    const size_t count = j - i;
    if (count == 1) ++topo.boundary_edges;
    if (count > 2) ++topo.non_manifold_edges;
    if (count == 2 && forward != 1) ++topo.inconsistent_edges;
    i = j;
  }
  for (Eigen::Index v = 0; v < nv; ++v) {
    if (!used[v])
      ++topo.isolated_vertices;
    else if (sets.find(v) == v)
      ++topo.components;
  }
  return topo;
}

Eigen::VectorXd face_areas(const TriMesh& mesh) {
  Eigen::VectorXd areas(mesh.face_count());
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.faces(f, 0));
    const Eigen::Vector3d b = mesh.vertices.row(mesh.faces(f, 1));
    const Eigen::Vector3d c = mesh.vertices.row(mesh.faces(f, 2));
    areas[f] = 0.5 * (b - a).cross(c - a).norm();
  }
  return areas;
}

Eigen::MatrixX3d vertex_normals(const TriMesh& mesh) {
  Eigen::MatrixX3d normals = Eigen::MatrixX3d::Zero(mesh.vertex_count(), 3);
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.faces(f, 0));
    const Eigen::Vector3d b = mesh.vertices.row(mesh.faces(f, 1));
    const Eigen::Vector3d c = mesh.vertices.row(mesh.faces(f, 2));
    const Eigen::RowVector3d n = (b - a).cross(c - a).transpose();  // length = 2 * area
    for (int k = 0; k < 3; ++k) normals.row(mesh.faces(f, k)) += n;
  }
  for (Eigen::Index v = 0; v < normals.rows(); ++v) {
    const double len = normals.row(v).norm();
    if (len > 0) normals.row(v) /= len;
  }
  return normals;
}

TriMesh icosphere(double radius, int subdivisions, const Eigen::Vector3d& centre) {
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0},
                                    {0, -1, g}, {0, 1, g}, {0, -1, -g}, {0, 1, -g},
                                    {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  std::vector<Eigen::Vector3i> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                    {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                    {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                    {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (Eigen::Vector3d& p : v) p.normalize();
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> midpoint;
    const auto mid = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      if (const auto it = midpoint.find(key); it != midpoint.end()) return it->second;
      v.push_back((v[static_cast<size_t>(a)] + v[static_cast<size_t>(b)]).normalized());
      return midpoint[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<Eigen::Vector3i> next;
    next.reserve(4 * f.size());
    for (const Eigen::Vector3i& t : f) {
      const int a = mid(t[0], t[1]), b = mid(t[1], t[2]), c = mid(t[2], t[0]);
      next.insert(next.end(), {{t[0], a, c}, {t[1], b, a}, {t[2], c, b}, {a, b, c}});
    }
    f = std::move(next);
  }
  TriMesh mesh;
  mesh.vertices.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (size_t i = 0; i < v.size(); ++i)
    mesh.vertices.row(static_cast<Eigen::Index>(i)) = (centre + radius * v[i]).transpose();
  mesh.faces.resize(static_cast<Eigen::Index>(f.size()), 3);
  for (size_t i = 0; i < f.size(); ++i)
    mesh.faces.row(static_cast<Eigen::Index>(i)) = f[i].transpose();
  return mesh;
}

}  // namespace sd::meshing
