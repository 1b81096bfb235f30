#include "garment/panel_surface.hpp"

#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <Eigen/SparseLU>
#include <algorithm>
#include <stdexcept>
#include <vector>

namespace sd::garment {
namespace {

// Unique undirected quad edges (a < b).
std::vector<std::pair<int, int>> quad_edges(const meshing::QuadMesh& mesh) {
  std::vector<std::pair<int, int>> edges;
  edges.reserve(static_cast<size_t>(4 * mesh.face_count()));
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f)
    for (int k = 0; k < 4; ++k) {
      const int a = mesh.faces(f, k), b = mesh.faces(f, (k + 1) % 4);
      edges.emplace_back(std::min(a, b), std::max(a, b));
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return edges;
}

// Solves L x = 0 for the unmarked vertices with the marked ones as boundary values: each at the
// mean of its edge neighbours, neighbour u weighing weight[u] (empty: every one 1). A vertex whose
// neighbours all weigh 0 takes their plain mean. Uniform weights make L symmetric (LDLT); others
// do not (LU).
void solve_harmonic(meshing::QuadMesh& mesh, const std::vector<std::pair<int, int>>& edges,
                    const std::vector<char>& held, std::span<const double> weight = {}) {
  const auto nv = static_cast<size_t>(mesh.vertex_count());
  std::vector<int> unknown(nv, -1);
  int n = 0;
  for (size_t v = 0; v < nv; ++v)
    if (!held[v]) unknown[v] = n++;
  if (n == 0) return;
  // Every unknown's neighbours' total weight: a row whose total is 0 falls back to weights 1.
  const auto weight_of = [&](int u) {
    return weight.empty() ? 1.0 : weight[static_cast<size_t>(u)];
  };
  std::vector<double> total(static_cast<size_t>(n), 0.0);
  for (const auto& [a, b] : edges) {
    if (const int ia = unknown[static_cast<size_t>(a)]; ia >= 0)
      total[static_cast<size_t>(ia)] += weight_of(b);
    if (const int ib = unknown[static_cast<size_t>(b)]; ib >= 0)
      total[static_cast<size_t>(ib)] += weight_of(a);
  }
  const auto in_row = [&](int i, int u) {
    return total[static_cast<size_t>(i)] > 0 ? weight_of(u) : 1.0;
  };
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(edges.size() * 4);
  Eigen::MatrixX3d rhs = Eigen::MatrixX3d::Zero(n, 3);
  std::vector<double> diagonal(static_cast<size_t>(n), 0.0);
  const auto add = [&](int i, int to) {  // row i gains the neighbour `to`
    const double w = in_row(i, to);
    diagonal[static_cast<size_t>(i)] += w;
    if (const int j = unknown[static_cast<size_t>(to)]; j >= 0)
      triplets.emplace_back(i, j, -w);
    else
      rhs.row(i) += w * mesh.vertices.row(to);
  };
  for (const auto& [a, b] : edges) {
    if (const int ia = unknown[static_cast<size_t>(a)]; ia >= 0) add(ia, b);
    if (const int ib = unknown[static_cast<size_t>(b)]; ib >= 0) add(ib, a);
  }
  for (int i = 0; i < n; ++i) triplets.emplace_back(i, i, diagonal[static_cast<size_t>(i)]);
  Eigen::SparseMatrix<double> laplacian(n, n);
  laplacian.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::MatrixX3d x;
  if (weight.empty()) {
    const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(laplacian);
    if (solver.info() != Eigen::Success)
      throw std::invalid_argument(
          "span_harmonic: a part of the free vertices touches no fixed one");
    x = solver.solve(rhs);
  } else {
    laplacian.makeCompressed();
    Eigen::SparseLU<Eigen::SparseMatrix<double>> solver;
    solver.compute(laplacian);
    if (solver.info() != Eigen::Success)
      throw std::invalid_argument(
          "span_harmonic: a part of the free vertices touches no fixed one");
    x = solver.solve(rhs);
  }
  for (size_t v = 0; v < nv; ++v)
    if (unknown[v] >= 0) mesh.vertices.row(static_cast<Eigen::Index>(v)) = x.row(unknown[v]);
}

}  // namespace

void span_harmonic(meshing::QuadMesh& mesh, std::span<const char> fixed) {
  if (static_cast<Eigen::Index>(fixed.size()) != mesh.vertex_count())
    throw std::invalid_argument("span_harmonic: one fixed flag per vertex is needed");
  solve_harmonic(mesh, quad_edges(mesh), std::vector<char>(fixed.begin(), fixed.end()));
}

std::array<Eigen::Vector3d, 9> quad_samples(const meshing::QuadMesh& mesh, Eigen::Index f) {
  std::array<Eigen::Vector3d, 4> c;
  for (int k = 0; k < 4; ++k)
    c[static_cast<size_t>(k)] = mesh.vertices.row(mesh.faces(f, k)).transpose();
  const Eigen::Vector3d centre = 0.25 * (c[0] + c[1] + c[2] + c[3]);
  std::array<Eigen::Vector3d, 9> out;
  out[0] = centre;
  for (size_t k = 0; k < 4; ++k) {
    out[1 + k] = 0.5 * (c[k] + c[(k + 1) % 4]);
    out[5 + k] = (centre + c[k] + c[(k + 1) % 4]) / 3.0;
  }
  return out;
}

SpannedSurface span_over_obstacle(meshing::QuadMesh& mesh, std::span<const char> fixed,
                                  const PushOut& push_out, int max_rounds,
                                  std::span<const double> weights) {
  return span_over_obstacle(
      mesh, fixed,
      [&push_out](const Eigen::Vector3d& p, const Eigen::Vector3d&) { return push_out(p); }, false,
      max_rounds, weights);
}

SpannedSurface span_over_obstacle(meshing::QuadMesh& mesh, std::span<const char> fixed,
                                  const PushAlong& push_along, bool release, int max_rounds,
                                  std::span<const double> weights) {
  if (static_cast<Eigen::Index>(fixed.size()) != mesh.vertex_count() ||
      (!weights.empty() && static_cast<Eigen::Index>(weights.size()) != mesh.vertex_count()))
    throw std::invalid_argument(
        "span_over_obstacle: one fixed flag (and one weight, if any) per vertex is needed");
  const std::vector<std::pair<int, int>> edges = quad_edges(mesh);
  std::vector<char> held(fixed.begin(), fixed.end());
  std::vector<char> lifted_hold(fixed.size(), 0);  // held by a quad's sample, never released
  solve_harmonic(mesh, edges, held, weights);
  SpannedSurface result;
  std::vector<Eigen::Vector3d> normals;
  std::vector<std::vector<int>> neighbours(static_cast<size_t>(release ? mesh.vertex_count() : 0));
  if (release)
    for (const auto& [a, b] : edges) {
      neighbours[static_cast<size_t>(a)].push_back(b);
      neighbours[static_cast<size_t>(b)].push_back(a);
    }
  for (;;) {
    normals.assign(static_cast<size_t>(mesh.vertex_count()), Eigen::Vector3d::Zero());
    for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
      const Eigen::Vector3d n =
          (mesh.vertices.row(mesh.faces(f, 2)) - mesh.vertices.row(mesh.faces(f, 0)))
              .transpose()
              .cross((mesh.vertices.row(mesh.faces(f, 3)) - mesh.vertices.row(mesh.faces(f, 1)))
                         .transpose());
      for (int k = 0; k < 4; ++k) normals[static_cast<size_t>(mesh.faces(f, k))] += n;
    }
    for (Eigen::Vector3d& n : normals)
      if (n.norm() > 0) n.normalize();
    int pushed = 0;
    for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v) {
      if (held[static_cast<size_t>(v)]) continue;
      if (const auto out =
              push_along(mesh.vertices.row(v).transpose(), normals[static_cast<size_t>(v)])) {
        mesh.vertices.row(v) = out->transpose();
        held[static_cast<size_t>(v)] = 1;
        ++pushed;
      }
    }
    // With `release`: a held vertex whose neighbours' mean lies outside the obstacle is let go
    // (the membrane there would lift off the body; held, it pulls its free neighbours in after
    // it: a skirt's front held on the inner curve of both thighs sags into the gap between them).
    int released = 0;
    if (release && pushed == 0) {
      for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v) {
        if (!held[static_cast<size_t>(v)] || fixed[static_cast<size_t>(v)] ||
            lifted_hold[static_cast<size_t>(v)])
          continue;
        const std::vector<int>& around = neighbours[static_cast<size_t>(v)];
        if (around.empty()) continue;
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        for (const int u : around) mean += mesh.vertices.row(u).transpose();
        mean /= static_cast<double>(around.size());
        if (!push_along(mean, normals[static_cast<size_t>(v)])) {
          held[static_cast<size_t>(v)] = 0;
          ++released;
        }
      }
    }
    // Then the cloth between the vertices: a quad with a sample inside is moved out whole.
    // Each corner moves by the largest push among its quads' (not their sum: a corner shared by
    // four quads inside would go four times as far), once: a quad beside the fixed boundary
    // moves only in part, and pushing its free corners again each round would raise a spike.
    int lifted = 0;
    if (pushed == 0 && released == 0) {
      std::vector<Eigen::Vector3d> moves(static_cast<size_t>(mesh.vertex_count()),
                                         Eigen::Vector3d::Zero());
      for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
        Eigen::Vector3d move = Eigen::Vector3d::Zero();
        for (const Eigen::Vector3d& x : quad_samples(mesh, f))
          if (const auto out = push_along(x, Eigen::Vector3d::Zero());
              out && (*out - x).norm() > move.norm())
            move = *out - x;
        if (move.norm() == 0) continue;
        for (int k = 0; k < 4; ++k) {
          Eigen::Vector3d& m = moves[static_cast<size_t>(mesh.faces(f, k))];
          if (move.norm() > m.norm()) m = move;
        }
      }
      for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v) {
        const Eigen::Vector3d& m = moves[static_cast<size_t>(v)];
        if (fixed[static_cast<size_t>(v)] || lifted_hold[static_cast<size_t>(v)] || m.norm() == 0)
          continue;
        mesh.vertices.row(v) += m.transpose();
        held[static_cast<size_t>(v)] = 1;
        lifted_hold[static_cast<size_t>(v)] = 1;
        ++lifted;
      }
    }
    result.contacts += pushed;
    if (pushed == 0 && released == 0 && lifted == 0) break;
    if (result.rounds == max_rounds) {
      result.settled = false;
      break;
    }
    solve_harmonic(mesh, edges, held, weights);
    ++result.rounds;
  }
  return result;
}

}  // namespace sd::garment
