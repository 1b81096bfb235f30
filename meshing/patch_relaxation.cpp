#include "meshing/patch_relaxation.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <limits>
#include <vector>

namespace sd::meshing {
namespace {

// Compressed adjacency: for each vertex its edge neighbours and its incident (face, corner).
struct Adjacency {
  std::vector<int> neighbour_start, neighbours;
  std::vector<int> corner_start, corners;  // face * 4 + corner index
};

Adjacency build_adjacency(const QuadMesh& mesh) {
  const auto nv = static_cast<size_t>(mesh.vertices.rows());
  std::vector<std::vector<int>> nbr(nv), crn(nv);
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f)
    for (int k = 0; k < 4; ++k) {
      const int v = mesh.faces(f, k);
      crn[static_cast<size_t>(v)].push_back(static_cast<int>(f) * 4 + k);
      // Each undirected edge is seen from both faces (or once on the boundary): deduplicate.
      for (const int w : {mesh.faces(f, (k + 1) % 4), mesh.faces(f, (k + 3) % 4)}) {
        auto& list = nbr[static_cast<size_t>(v)];
        if (std::find(list.begin(), list.end(), w) == list.end()) list.push_back(w);
      }
    }
  Adjacency adj;
  adj.neighbour_start.push_back(0);
  adj.corner_start.push_back(0);
  for (size_t v = 0; v < nv; ++v) {
    adj.neighbours.insert(adj.neighbours.end(), nbr[v].begin(), nbr[v].end());
    adj.corners.insert(adj.corners.end(), crn[v].begin(), crn[v].end());
    adj.neighbour_start.push_back(static_cast<int>(adj.neighbours.size()));
    adj.corner_start.push_back(static_cast<int>(adj.corners.size()));
  }
  return adj;
}

Eigen::MatrixX3d corner_normals(const QuadMesh& mesh) {
  Eigen::MatrixX3d normals = Eigen::MatrixX3d::Zero(mesh.vertices.rows(), 3);
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f)
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d p = mesh.vertices.row(mesh.faces(f, k));
      const Eigen::Vector3d e1 = mesh.vertices.row(mesh.faces(f, (k + 1) % 4)).transpose() - p;
      const Eigen::Vector3d e2 = mesh.vertices.row(mesh.faces(f, (k + 3) % 4)).transpose() - p;
      normals.row(mesh.faces(f, k)) += e1.cross(e2).transpose();
    }
  for (Eigen::Index v = 0; v < normals.rows(); ++v) {
    const double len = normals.row(v).norm();
    if (len > 0) normals.row(v) /= len;
  }
  return normals;
}

// Smallest scaled Jacobian over every corner of the quads around v, with v at position p.
double local_min_jacobian(const QuadMesh& mesh, const Adjacency& adj,
                          const Eigen::MatrixX3d& normals, int v, const Eigen::Vector3d& p) {
  double worst = std::numeric_limits<double>::infinity();
  auto pos = [&](int w) -> Eigen::Vector3d {
    return w == v ? p : Eigen::Vector3d(mesh.vertices.row(w));
  };
  for (int c = adj.corner_start[static_cast<size_t>(v)];
       c < adj.corner_start[static_cast<size_t>(v) + 1]; ++c) {
    const int f = adj.corners[static_cast<size_t>(c)] / 4;
    Eigen::Vector3d n = Eigen::Vector3d::Zero();  // the quad's reference normal
    for (int k = 0; k < 4; ++k) n += normals.row(mesh.faces(f, k)).transpose();
    for (int k = 0; k < 4; ++k) {
      const int a = mesh.faces(f, k);
      const Eigen::Vector3d e1 = pos(mesh.faces(f, (k + 1) % 4)) - pos(a);
      const Eigen::Vector3d e2 = pos(mesh.faces(f, (k + 3) % 4)) - pos(a);
      const double denom = e1.norm() * e2.norm();
      const double jac = denom > 0 ? e1.cross(e2).dot(n) / (denom * n.norm()) : -1.0;
      worst = std::min(worst, jac);
    }
  }
  return worst;
}

}  // namespace

void relax_interior(QuadMesh& mesh, std::span<const char> fixed, int sweeps,
                    const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& project) {
  if (sweeps <= 0) return;
  const Adjacency adj = build_adjacency(mesh);
  constexpr double kAcceptable = 0.05;  // a move may lower the local minimum down to this
  // Stop once no vertex moves more than 1e-3 of the mean edge length in a sweep.
  double edge_sum = 0;
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f)
    edge_sum += (mesh.vertices.row(mesh.faces(f, 0)) - mesh.vertices.row(mesh.faces(f, 1))).norm();
  const double tolerance = 1e-3 * edge_sum / std::max<Eigen::Index>(mesh.faces.rows(), 1);
  const double tolerance2 = tolerance * tolerance;
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    const Eigen::MatrixX3d normals = corner_normals(mesh);
    double largest_move = 0;
    for (Eigen::Index v = 0; v < mesh.vertices.rows(); ++v) {
      if (fixed[static_cast<size_t>(v)]) continue;
      const int begin = adj.neighbour_start[static_cast<size_t>(v)];
      const int end = adj.neighbour_start[static_cast<size_t>(v) + 1];
      if (end == begin) continue;
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (int i = begin; i < end; ++i)
        mean += mesh.vertices.row(adj.neighbours[static_cast<size_t>(i)]).transpose();
      mean /= end - begin;
      if (project) mean = project(mean);
      const Eigen::Vector3d old = mesh.vertices.row(v);
      const double after = local_min_jacobian(mesh, adj, normals, static_cast<int>(v), mean);
      if (after < kAcceptable &&
          after < local_min_jacobian(mesh, adj, normals, static_cast<int>(v), old) - 1e-12)
        continue;
      largest_move = std::max(largest_move, (mean - old).squaredNorm());
      mesh.vertices.row(v) = mean.transpose();
    }
    if (largest_move < tolerance2) break;  // converged
  }
}

}  // namespace sd::meshing
