#include "meshing/patch_relaxation.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
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

// Unit reference normal of each quad: the sum of its vertices' normals (each the sum of the
// corner cross products around the vertex), so that a folded quad among good neighbours shows
// a negative Jacobian even on a curved patch.
std::vector<Eigen::Vector3d> quad_normals(const QuadMesh& mesh,
                                          const std::vector<Eigen::Vector3d>& x) {
  std::vector<Eigen::Vector3d> vertex_normal(x.size(), Eigen::Vector3d::Zero());
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f)
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d& p = x[static_cast<size_t>(mesh.faces(f, k))];
      vertex_normal[static_cast<size_t>(mesh.faces(f, k))] +=
          (x[static_cast<size_t>(mesh.faces(f, (k + 1) % 4))] - p)
              .cross(x[static_cast<size_t>(mesh.faces(f, (k + 3) % 4))] - p);
    }
  for (auto& n : vertex_normal)
    if (n.norm() > 0) n.normalize();
  std::vector<Eigen::Vector3d> normals(static_cast<size_t>(mesh.faces.rows()));
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f) {
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) n += vertex_normal[static_cast<size_t>(mesh.faces(f, k))];
    normals[static_cast<size_t>(f)] = n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : n;
  }
  return normals;
}

// Smallest scaled Jacobian over the four corners of quad f at positions x.
double quad_min_jacobian(const QuadMesh& mesh, Eigen::Index f, const Eigen::Vector3d& normal,
                         const std::vector<Eigen::Vector3d>& x) {
  double worst = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d& p = x[static_cast<size_t>(mesh.faces(f, k))];
    const Eigen::Vector3d e1 = x[static_cast<size_t>(mesh.faces(f, (k + 1) % 4))] - p;
    const Eigen::Vector3d e2 = x[static_cast<size_t>(mesh.faces(f, (k + 3) % 4))] - p;
    const double denom = std::sqrt(e1.squaredNorm() * e2.squaredNorm());
    worst = std::min(worst, denom > 0 ? e1.cross(e2).dot(normal) / denom : -1.0);
  }
  return worst;
}

// Whether every corner of quad f has a scaled Jacobian of at least `bound` (> 0), without
// square roots: c >= bound |e1| |e2|  <=>  c >= 0 and c² >= bound² |e1|² |e2|².
bool quad_at_least(const QuadMesh& mesh, Eigen::Index f, const Eigen::Vector3d& normal,
                   const std::vector<Eigen::Vector3d>& x, double bound) {
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d& p = x[static_cast<size_t>(mesh.faces(f, k))];
    const Eigen::Vector3d e1 = x[static_cast<size_t>(mesh.faces(f, (k + 1) % 4))] - p;
    const Eigen::Vector3d e2 = x[static_cast<size_t>(mesh.faces(f, (k + 3) % 4))] - p;
    const double c = e1.cross(e2).dot(normal);
    if (c < 0 || c * c < bound * bound * e1.squaredNorm() * e2.squaredNorm()) return false;
  }
  return true;
}

}  // namespace

void relax_interior(QuadMesh& mesh, std::span<const char> fixed, int sweeps,
                    const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& project) {
  if (sweeps <= 0 || mesh.faces.rows() == 0) return;
  const Adjacency adj = build_adjacency(mesh);
  const auto nv = static_cast<size_t>(mesh.vertices.rows());
  const auto nf = static_cast<size_t>(mesh.faces.rows());
  std::vector<Eigen::Vector3d> old(nv), next(nv);
  for (size_t v = 0; v < nv; ++v) old[v] = mesh.vertices.row(static_cast<Eigen::Index>(v)).transpose();
  // Reference normals from the starting positions: they only tell a quad's front from its back.
  const std::vector<Eigen::Vector3d> normals = quad_normals(mesh, old);
  constexpr double kAcceptable = 0.05;  // a move may lower a quad's minimum down to this
  // Stop once no vertex moves more than 1e-3 of the mean edge length in a sweep.
  double edge_sum = 0;
  for (size_t f = 0; f < nf; ++f)
    edge_sum += (old[static_cast<size_t>(mesh.faces(static_cast<Eigen::Index>(f), 0))] -
                 old[static_cast<size_t>(mesh.faces(static_cast<Eigen::Index>(f), 1))])
                    .norm();
  const double tolerance = 1e-3 * edge_sum / static_cast<double>(nf);
  std::vector<char> bad(nf, 0);
  std::vector<int> queue, reverted;
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    // Jacobi step: every free vertex to the mean of its neighbours' old positions.
    for (size_t v = 0; v < nv; ++v) {
      next[v] = old[v];
      const int begin = adj.neighbour_start[v], end = adj.neighbour_start[v + 1];
      if (fixed[v] || end == begin) continue;
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (int i = begin; i < end; ++i) mean += old[static_cast<size_t>(adj.neighbours[static_cast<size_t>(i)])];
      mean /= end - begin;
      next[v] = project ? project(mean) : mean;
    }
    // A quad whose smallest scaled Jacobian would fall below min(before, kAcceptable) keeps
    // its free vertices where they were; quads around a kept vertex are checked again.
    auto worse = [&](size_t f) {
      const auto fi = static_cast<Eigen::Index>(f);
      if (quad_at_least(mesh, fi, normals[f], next, kAcceptable)) return false;
      const double after = quad_min_jacobian(mesh, fi, normals[f], next);
      return after < kAcceptable && after < quad_min_jacobian(mesh, fi, normals[f], old) - 1e-12;
    };
    queue.clear();
    for (size_t f = 0; f < nf; ++f)
      if (worse(f)) queue.push_back(static_cast<int>(f));
    while (!queue.empty()) {
      reverted.clear();
      for (const int f : queue)
        for (int k = 0; k < 4; ++k) {
          const auto v = static_cast<size_t>(mesh.faces(f, k));
          if (next[v] != old[v]) {
            next[v] = old[v];
            reverted.push_back(static_cast<int>(v));
          }
        }
      queue.clear();
      for (const int v : reverted)
        for (int c = adj.corner_start[static_cast<size_t>(v)]; c < adj.corner_start[static_cast<size_t>(v) + 1]; ++c) {
          const auto f = static_cast<size_t>(adj.corners[static_cast<size_t>(c)] / 4);
          if (!bad[f] && worse(f)) {
            bad[f] = 1;
            queue.push_back(static_cast<int>(f));
          }
        }
      for (const int f : queue) bad[static_cast<size_t>(f)] = 0;
    }
    double largest_move = 0;
    for (size_t v = 0; v < nv; ++v) largest_move = std::max(largest_move, (next[v] - old[v]).squaredNorm());
    std::swap(old, next);
    if (largest_move < tolerance * tolerance) break;  // converged
  }
  for (size_t v = 0; v < nv; ++v) mesh.vertices.row(static_cast<Eigen::Index>(v)) = old[v].transpose();
}

}  // namespace sd::meshing
