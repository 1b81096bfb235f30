#include "meshing/patch_relaxation.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>
#include <vector>

namespace sd::meshing {
namespace {

// Compressed adjacency: for each vertex its edge neighbours and its incident (face, corner).
struct Adjacency {
  std::vector<int> neighbour_start, neighbours;
  std::vector<int> corner_start, corners;  // face * 4 + corner index
};

using Quad = std::array<int, 4>;

Adjacency build_adjacency(std::span<const Quad> quads, size_t nv) {
  Adjacency adj;
  adj.corner_start.assign(nv + 1, 0);
  for (const Quad& q : quads)
    for (const int v : q) ++adj.corner_start[static_cast<size_t>(v) + 1];
  for (size_t v = 0; v < nv; ++v) adj.corner_start[v + 1] += adj.corner_start[v];
  adj.corners.resize(static_cast<size_t>(adj.corner_start[nv]));
  std::vector<int> fill(adj.corner_start.begin(), adj.corner_start.end() - 1);
  for (size_t f = 0; f < quads.size(); ++f)
    for (size_t k = 0; k < 4; ++k)
      adj.corners[static_cast<size_t>(fill[static_cast<size_t>(quads[f][k])]++)] =
          static_cast<int>(f * 4 + k);
  // Edge neighbours: the two face neighbours of every corner, each undirected edge seen from
  // both of its faces (once on the boundary), so deduplicated per vertex.
  adj.neighbour_start.assign(nv + 1, 0);
  adj.neighbours.reserve(2 * adj.corners.size());
  std::vector<size_t> listed_for(nv, nv);  // the vertex whose list has w last took w
  for (size_t v = 0; v < nv; ++v) {
    for (int c = adj.corner_start[v]; c < adj.corner_start[v + 1]; ++c) {
      const Quad& q = quads[static_cast<size_t>(adj.corners[static_cast<size_t>(c)] / 4)];
      const auto k = static_cast<size_t>(adj.corners[static_cast<size_t>(c)] % 4);
      for (const int w : {q[(k + 1) % 4], q[(k + 3) % 4]})
        if (std::exchange(listed_for[static_cast<size_t>(w)], v) != v) adj.neighbours.push_back(w);
    }
    adj.neighbour_start[v + 1] = static_cast<int>(adj.neighbours.size());
  }
  return adj;
}

// Unit reference normal of each quad: the sum of its vertices' normals (each the sum of the
// corner cross products around the vertex, averaged over kNormalRings rings of neighbours), so
// that a folded quad among good neighbours shows a negative Jacobian even on a curved patch.
constexpr int kNormalRings = 4;

// Into `normals` (#Q); vertex_normal and averaged are #V scratch buffers (left with
// unspecified contents).
void quad_normals(std::span<const Quad> quads, const Adjacency& adj,
                  const std::vector<Eigen::Vector3d>& x,
                  std::vector<Eigen::Vector3d>& vertex_normal,
                  std::vector<Eigen::Vector3d>& averaged, std::vector<Eigen::Vector3d>& normals) {
  vertex_normal.assign(x.size(), Eigen::Vector3d::Zero());
  for (const Quad& q : quads)
    for (size_t k = 0; k < 4; ++k) {
      const Eigen::Vector3d& p = x[static_cast<size_t>(q[k])];
      vertex_normal[static_cast<size_t>(q[k])] +=
          (x[static_cast<size_t>(q[(k + 1) % 4])] - p)
              .cross(x[static_cast<size_t>(q[(k + 3) % 4])] - p);
    }
  // normalize() and normalized() leave a zero vector as it is.
  for (auto& n : vertex_normal) n.normalize();
  // Averaged over a few rings, so that a cluster of quads that start folded (a Coons block
  // overlapping its neighbour near a reflex corner) cannot turn its own reference around.
  averaged.resize(x.size());
  for (int ring = 0; ring < kNormalRings; ++ring) {
    for (size_t v = 0; v < x.size(); ++v) {
      Eigen::Vector3d sum = vertex_normal[v];
      for (int i = adj.neighbour_start[v]; i < adj.neighbour_start[v + 1]; ++i)
        sum += vertex_normal[static_cast<size_t>(adj.neighbours[static_cast<size_t>(i)])];
      averaged[v] = sum.normalized();
    }
    std::swap(vertex_normal, averaged);
  }
  normals.resize(quads.size());
  for (size_t f = 0; f < quads.size(); ++f) {
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    for (const int v : quads[f]) n += vertex_normal[static_cast<size_t>(v)];
    normals[f] = n.normalized();
  }
}

// The #V and #Q arrays of a relaxation, kept per thread from one call to the next. Allocated
// afresh each time, their pages went back to the kernel after every fill and were faulted in
// again by the next one: about a quarter of a 3,000-quad fill's time (meshing_bench). They never
// leave this struct (results are copied out), so they keep their capacity.
struct RelaxationScratch {
  std::vector<Eigen::Vector3d> x, y, z, normals;
};

// Edges of quad q at positions x: e[k] runs from corner k to corner k+1; the corner k is
// spanned by e[k] and −e[k−1], so its cross product is e[k−1] × e[k].
std::array<Eigen::Vector3d, 4> quad_edges(const Quad& q, const std::vector<Eigen::Vector3d>& x) {
  std::array<Eigen::Vector3d, 4> e;
  for (int k = 0; k < 4; ++k)
    e[static_cast<size_t>(k)] = x[static_cast<size_t>(q[static_cast<size_t>((k + 1) % 4)])] -
                                x[static_cast<size_t>(q[static_cast<size_t>(k)])];
  return e;
}

// Smallest scaled Jacobian over the four corners of quad q at positions x.
double quad_min_jacobian(const Quad& q, const Eigen::Vector3d& normal,
                         const std::vector<Eigen::Vector3d>& x) {
  const auto e = quad_edges(q, x);
  double worst = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < 4; ++k) {
    const Eigen::Vector3d& before = e[(k + 3) % 4];
    const double denom = std::sqrt(before.squaredNorm() * e[k].squaredNorm());
    worst = std::min(worst, denom > 0 ? before.cross(e[k]).dot(normal) / denom : -1.0);
  }
  return worst;
}

// Whether every corner of quad q has a scaled Jacobian of at least `bound` (> 0), without
// square roots: c >= bound |e1| |e2|  <=>  c > 0 and c² >= bound² |e1|² |e2|² (c = 0 is a zero
// angle or a zero-length edge, which quad_min_jacobian counts as 0 or −1).
bool quad_at_least(const Quad& q, const Eigen::Vector3d& normal,
                   const std::vector<Eigen::Vector3d>& x, double bound) {
  const auto e = quad_edges(q, x);
  std::array<double, 4> length2;
  for (size_t k = 0; k < 4; ++k) length2[k] = e[k].squaredNorm();
  for (size_t k = 0; k < 4; ++k) {
    const double c = e[(k + 3) % 4].cross(e[k]).dot(normal);
    if (c <= 0 || c * c < bound * bound * length2[(k + 3) % 4] * length2[k]) return false;
  }
  return true;
}

// quad_min_jacobian(q, normal, x) >= bound, decided without square roots for the quads that clear
// it by more than rounding (most of them).
bool quad_min_jacobian_at_least(const Quad& q, const Eigen::Vector3d& normal,
                                const std::vector<Eigen::Vector3d>& x, double bound) {
  return quad_at_least(q, normal, x, bound * (1 + 1e-12)) ||
         quad_min_jacobian(q, normal, x) >= bound;
}

using Projection = std::function<Eigen::Vector3d(const Eigen::Vector3d&)>;

// Untangling: moves free vertices of quads whose smallest scaled Jacobian is below
// kUntangleTarget (and their free neighbours) one at a time to raise the smallest scaled
// Jacobian over the quads around them (a pattern search in the plane square to their quads'
// reference normals, step halving from half the mean edge length), and accepts a move only when
// that minimum rises. Laplacian smoothing moves a vertex to the mean of its neighbours, which
// near a reflex boundary corner or a strongly graded strip can lie outside the vertex's
// feasible region; this search looks at the quads' orientation itself. Stops when no quad is
// below the target or after kUntanglePasses passes.
constexpr double kUntangleTarget = 0.02;
constexpr int kUntanglePasses = 100;
// A pass that raises no vertex's minimum by more than this is the last one (the search creeps by
// ever smaller steps when a fold cannot be undone).
constexpr double kUntangleProgress = 1e-4;

// `suspects`, when given, are the only quads that can be below kUntangleTarget at the start
// (increasing), so the first pass looks at them alone.
void untangle(std::vector<Eigen::Vector3d>& x, std::span<const Quad> quads,
              const std::vector<Eigen::Vector3d>& normals, const Adjacency& adj,
              std::span<const char> fixed, const Projection& project,
              const std::vector<size_t>* suspects = nullptr) {
  const size_t nf = quads.size(), nv = x.size();
  auto around = [&](size_t v) {  // smallest scaled Jacobian of the quads at v
    double worst = std::numeric_limits<double>::infinity();
    for (int c = adj.corner_start[v]; c < adj.corner_start[v + 1]; ++c) {
      const auto f = static_cast<size_t>(adj.corners[static_cast<size_t>(c)] / 4);
      worst = std::min(worst, quad_min_jacobian(quads[f], normals[f], x));
    }
    return worst;
  };
  std::vector<char> chosen(nv, 0);
  std::vector<size_t> movable;
  for (int pass = 0; pass < kUntanglePasses; ++pass) {
    movable.clear();
    std::fill(chosen.begin(), chosen.end(), 0);
    auto choose = [&](size_t v) {
      if (!fixed[v] && !chosen[v]) {
        chosen[v] = 1;
        movable.push_back(v);
      }
    };
    auto look_at = [&](size_t f) {
      if (quad_min_jacobian_at_least(quads[f], normals[f], x, kUntangleTarget)) return;
      for (const int v : quads[f]) {
        choose(static_cast<size_t>(v));
        for (int i = adj.neighbour_start[static_cast<size_t>(v)]; i < adj.neighbour_start[static_cast<size_t>(v) + 1]; ++i)
          choose(static_cast<size_t>(adj.neighbours[static_cast<size_t>(i)]));
      }
    };
    if (pass == 0 && suspects != nullptr) {
      for (const size_t f : *suspects) look_at(f);
    } else {
      for (size_t f = 0; f < nf; ++f) look_at(f);
    }
    if (movable.empty()) return;
    bool improved = false;
    for (const size_t v : movable) {
      Eigen::Vector3d normal = Eigen::Vector3d::Zero();
      double edge_sum = 0;
      for (int c = adj.corner_start[v]; c < adj.corner_start[v + 1]; ++c)
        normal += normals[static_cast<size_t>(adj.corners[static_cast<size_t>(c)] / 4)];
      const int begin = adj.neighbour_start[v], end = adj.neighbour_start[v + 1];
      for (int i = begin; i < end; ++i)
        edge_sum += (x[static_cast<size_t>(adj.neighbours[static_cast<size_t>(i)])] - x[v]).norm();
      if (normal.norm() == 0 || end == begin) continue;
      normal.normalize();
      const Eigen::Vector3d t1 = normal.unitOrthogonal(), t2 = normal.cross(t1);
      double step = 0.5 * edge_sum / (end - begin);
      double current = around(v);
      // Pattern search in the tangent plane. The candidates are judged where they are, off the
      // projection surface by O(step² · curvature), and only the winner is projected and judged
      // again: one projection per halving instead of eight (projection onto a body is a BVH
      // query, ~90 % of a garment fill's time when every candidate was projected).
      for (int halving = 0; halving < 12; ++halving) {
        const Eigen::Vector3d start = x[v];
        Eigen::Vector3d best_position = start;
        double best = current;
        for (int k = 0; k < 8; ++k) {
          const double angle = k * std::numbers::pi / 4;
          x[v] = start + step * (std::cos(angle) * t1 + std::sin(angle) * t2);
          const double value = around(v);
          if (value > best + 1e-12) {
            best = value;
            best_position = x[v];
          }
        }
        if (project && best > current) {
          best_position = project(best_position);
          x[v] = best_position;
          best = around(v);
        }
        if (best > current) {
          x[v] = best_position;
          improved = improved || best > current + kUntangleProgress;
          current = best;
        } else {
          x[v] = start;
          step *= 0.5;
        }
      }
    }
    if (!improved) return;
  }
}

}  // namespace

void relax_interior(QuadMesh& mesh, std::span<const char> fixed, int sweeps,
                    const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& project) {
  if (sweeps <= 0 || mesh.faces.rows() == 0) return;
  const auto nv = static_cast<size_t>(mesh.vertices.rows());
  const auto nf = static_cast<size_t>(mesh.faces.rows());
  std::vector<Quad> quads(nf);
  for (size_t f = 0; f < nf; ++f)
    for (int k = 0; k < 4; ++k)
      quads[f][static_cast<size_t>(k)] = mesh.faces(static_cast<Eigen::Index>(f), k);
  std::vector<Eigen::Vector3d> positions(nv);
  for (size_t v = 0; v < nv; ++v)
    positions[v] = mesh.vertices.row(static_cast<Eigen::Index>(v)).transpose();
  detail::relax_interior(positions, quads, fixed, sweeps, project);
  for (size_t v = 0; v < nv; ++v)
    mesh.vertices.row(static_cast<Eigen::Index>(v)) = positions[v].transpose();
}

namespace detail {

void relax_interior(std::vector<Eigen::Vector3d>& positions,
                    std::span<const std::array<int, 4>> quads, std::span<const char> fixed,
                    int sweeps,
                    const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& project,
                    ReferenceNormals reference) {
  if (sweeps <= 0 || quads.empty()) return;
  const size_t nv = positions.size(), nf = quads.size();
  const Adjacency adj = build_adjacency(quads, nv);
  const std::vector<Eigen::Vector3d>& old = positions;  // the start; the result is copied in
  // Reference normals (they only tell a quad's front from its back) and their scratch
  // buffers, which become the sweeps' buffers.
  thread_local RelaxationScratch scratch;
  auto& [x, y, z, normals] = scratch;
  if (reference == ReferenceNormals::kStart) quad_normals(quads, adj, old, x, y, normals);
  constexpr double kAcceptable = 0.05;  // a move may lower a quad's minimum down to this
  static_assert(kAcceptable > kUntangleTarget);
  // Stop once no vertex moves more than 1e-3 of the mean edge length in a sweep.
  double edge_sum = 0;
  for (const Quad& q : quads)
    edge_sum += (old[static_cast<size_t>(q[0])] - old[static_cast<size_t>(q[1])]).norm();
  const double tolerance = 1e-3 * edge_sum / static_cast<double>(nf);
  // The vertices a sweep moves; every other entry of the position buffers keeps its start.
  std::vector<size_t> movers;
  for (size_t v = 0; v < nv; ++v)
    if (!fixed[v] && adj.neighbour_start[v + 1] > adj.neighbour_start[v]) movers.push_back(v);
  // Jacobi step: every free vertex of `from` to the mean of its neighbours, into `to`.
  auto laplacian_step = [&](const std::vector<Eigen::Vector3d>& from,
                            std::vector<Eigen::Vector3d>& to) {
    for (const size_t v : movers) {
      const int begin = adj.neighbour_start[v], end = adj.neighbour_start[v + 1];
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (int i = begin; i < end; ++i)
        mean += from[static_cast<size_t>(adj.neighbours[static_cast<size_t>(i)])];
      mean /= end - begin;
      to[v] = project ? project(mean) : mean;
    }
  };
  auto largest_move = [&](const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
    double largest = 0;
    for (const size_t v : movers) largest = std::max(largest, (a[v] - b[v]).squaredNorm());
    return largest;
  };
  {
    // Optimistic pass: all sweeps unguarded, then one check of every quad. On most patches no
    // quad ends below min(its start, kAcceptable) and this is the result, at a tenth of the
    // checks; otherwise start again with the guarded sweeps below.
    x = old;
    y = old;
    for (int sweep = 0; sweep < sweeps; ++sweep) {
      laplacian_step(x, y);
      const double move = largest_move(x, y);
      std::swap(x, y);
      if (move < tolerance * tolerance) break;
    }
    if (reference == ReferenceNormals::kAfterSweeps) quad_normals(quads, adj, x, y, z, normals);
    // Quads at kAcceptable or above are far above untangling's target too: the others are its
    // only suspects.
    bool acceptable = true;
    std::vector<size_t> suspects;
    for (size_t f = 0; f < nf && acceptable; ++f) {
      if (quad_at_least(quads[f], normals[f], x, kAcceptable)) continue;
      suspects.push_back(f);
      acceptable = quad_min_jacobian(quads[f], normals[f], x) >=
                   quad_min_jacobian(quads[f], normals[f], old) - 1e-12;
    }
    if (acceptable) {
      untangle(x, quads, normals, adj, fixed, project, &suspects);
      positions = x;
      return;
    }
  }
  // The guarded sweeps run between two scratch arrays, from the start again; the result is
  // copied out.
  std::vector<Eigen::Vector3d>& current = y;
  std::vector<Eigen::Vector3d>& next = x;
  current = old;
  next = old;
  std::vector<char> bad(nf, 0);
  std::vector<int> queue, reverted;
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    laplacian_step(current, next);
    // A quad whose smallest scaled Jacobian would fall below min(before, kAcceptable) keeps
    // its free vertices where they were; quads around a kept vertex are checked again.
    // (A reference, not the structured binding itself: clang 14, the fuzz build's compiler,
    // cannot capture structured bindings in a lambda.)
    const std::vector<Eigen::Vector3d>& face_normals = normals;
    auto worse = [&](size_t f) {
      if (quad_at_least(quads[f], face_normals[f], next, kAcceptable)) return false;
      return quad_min_jacobian(quads[f], face_normals[f], next) <
             quad_min_jacobian(quads[f], face_normals[f], current) - 1e-12;
    };
    queue.clear();
    for (size_t f = 0; f < nf; ++f)
      if (worse(f)) queue.push_back(static_cast<int>(f));
    while (!queue.empty()) {
      reverted.clear();
      for (const int f : queue)
        for (const int corner : quads[static_cast<size_t>(f)]) {
          const auto v = static_cast<size_t>(corner);
          if (next[v] != current[v]) {
            next[v] = current[v];
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
    const double move = largest_move(current, next);
    std::swap(current, next);
    if (move < tolerance * tolerance) break;  // converged
  }
  untangle(current, quads, normals, adj, fixed, project);
  positions = current;
}

}  // namespace detail

}  // namespace sd::meshing
