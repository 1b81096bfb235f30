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
// Once a corner is at most `floor` the others are not looked at: only values above `floor`
// are exact (the untangling's candidates that cannot win).
double quad_min_jacobian(const Quad& q, const Eigen::Vector3d& normal,
                         const std::vector<Eigen::Vector3d>& x,
                         double floor = -std::numeric_limits<double>::infinity()) {
  const auto e = quad_edges(q, x);
  double worst = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < 4; ++k) {
    const Eigen::Vector3d& before = e[(k + 3) % 4];
    const double denom = std::sqrt(before.squaredNorm() * e[k].squaredNorm());
    worst = std::min(worst, denom > 0 ? before.cross(e[k]).dot(normal) / denom : -1.0);
    if (worst <= floor) break;
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
// The pattern search's eight directions (cosine, sine of k·45°), computed once: the sine and
// cosine calls were 4 % of a folding garment fill's time.
const std::array<std::pair<double, double>, 8> kCompass = [] {
  std::array<std::pair<double, double>, 8> directions;
  for (int k = 0; k < 8; ++k) {
    const double angle = k * std::numbers::pi / 4;
    directions[static_cast<size_t>(k)] = {std::cos(angle), std::sin(angle)};
  }
  return directions;
}();
constexpr int kUntanglePasses = 100;
// A pass that raises no vertex's minimum by more than this is the last one (the search creeps by
// ever smaller steps when a fold cannot be undone).
constexpr double kUntangleProgress = 1e-4;

// Untangling moves no vertex farther than this many of the patch's mean edge lengths (at the
// start of the relaxation) from where it began. Without a bound a search can run away: off the
// body the projection leaves a point where it is, a longer step lengthens the vertex's edges, and
// with them its next step (the raglan's back sleeve at 2 cm edges, filled from the start along
// its normals: one vertex 6e8 m away, which the fill then kept for having fewer folded quads).
// Some folds need long moves: a bound of 2 edge lengths changed four fills of the corpus and the
// reproducers (the kimono tee's back: 0 → 2 folded quads); with 10 every garment.obj is the same.
constexpr double kUntangleReach = 10;

// `suspects`, when given, are the only quads that can be below kUntangleTarget at the start
// (increasing), so the first pass looks at them alone. `reach`: kUntangleReach in metres.
void untangle(std::vector<Eigen::Vector3d>& x, std::span<const Quad> quads,
              const std::vector<Eigen::Vector3d>& normals, const Adjacency& adj,
              std::span<const char> fixed, const Projection& project, double reach,
              const std::vector<size_t>* suspects = nullptr) {
  const size_t nf = quads.size(), nv = x.size();
  // Smallest scaled Jacobian of the quads at v; once it is at most `floor` the rest are not
  // looked at (a candidate that cannot win: most of the pattern search's, which was 17 % of
  // a folding garment's meshing time), so only values above `floor` are exact.
  auto around = [&](size_t v, double floor = -std::numeric_limits<double>::infinity()) {
    double worst = std::numeric_limits<double>::infinity();
    for (int c = adj.corner_start[v]; c < adj.corner_start[v + 1]; ++c) {
      const auto f = static_cast<size_t>(adj.corners[static_cast<size_t>(c)] / 4);
      worst = std::min(worst, quad_min_jacobian(quads[f], normals[f], x, floor));
      if (worst <= floor) break;
    }
    return worst;
  };
  std::vector<char> chosen(nv, 0);
  std::vector<size_t> movable;
  const std::vector<Eigen::Vector3d> origin = x;
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
        for (int i = adj.neighbour_start[static_cast<size_t>(v)];
             i < adj.neighbour_start[static_cast<size_t>(v) + 1]; ++i)
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
          const auto& [c, s] = kCompass[static_cast<size_t>(k)];
          x[v] = start + step * (c * t1 + s * t2);
          if ((x[v] - origin[v]).squaredNorm() > reach * reach) continue;
          const double value = around(v, best + 1e-12);
          if (value > best + 1e-12) {
            best = value;
            best_position = x[v];
          }
        }
        if (project && best > current) {
          best_position = project(best_position);
          x[v] = best_position;
          best = (x[v] - origin[v]).squaredNorm() > reach * reach ? current : around(v);
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

RelaxationTally& relaxation_tally() {
  thread_local RelaxationTally tally;
  return tally;
}

void relax_interior(std::vector<Eigen::Vector3d>& positions,
                    std::span<const std::array<int, 4>> quads, std::span<const char> fixed,
                    int sweeps,
                    const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& project,
                    ReferenceNormals reference, RelaxProbe* probe) {
  if (probe != nullptr) *probe = RelaxProbe{probe->stop_at};
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
  const double reach = kUntangleReach * edge_sum / static_cast<double>(nf);
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
  auto largest_move = [&](const std::vector<Eigen::Vector3d>& a,
                          const std::vector<Eigen::Vector3d>& b) {
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
      untangle(x, quads, normals, adj, fixed, project, reach, &suspects);
      positions = x;
      return;
    }
    if (probe != nullptr) {
      for (size_t f = 0; f < nf; ++f)
        probe->folds += quad_min_jacobian(quads[f], normals[f], x) < 0;
      if (probe->folds >= probe->stop_at) {
        probe->stopped = true;
        ++relaxation_tally().stopped;
        positions = x;
        return;
      }
    }
  }
  // The guarded sweeps run between two scratch arrays, from the start again; the result is
  // copied out.
  ++relaxation_tally().guarded;
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
        for (int c = adj.corner_start[static_cast<size_t>(v)];
             c < adj.corner_start[static_cast<size_t>(v) + 1]; ++c) {
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
  untangle(current, quads, normals, adj, fixed, project, reach);
  positions = current;
}

namespace {

// Weight θ of the area term against the shape term: small, since the shape term is what makes
// corners square; it is scale-free, and the area term keeps quads from growing or shrinking
// without bound.
constexpr double kAreaWeight = 0.1;

// χ(d, ε) = (d + √(ε² + d²)) / 2, for d < 0 as ε² / (2 (√(ε² + d²) − d)): the same value
// without the cancellation (a folded corner at small ε has χ ~ ε² / 4|d|, far below |d|, which
// d + √(ε² + d²) would lose to rounding).
double chi(double d, double epsilon) {
  const double root = std::sqrt(epsilon * epsilon + d * d);
  return d >= 0 ? 0.5 * (d + root) : 0.5 * epsilon * epsilon / (root - d);
}

// Smallest det J over all quad corners (ideal square corner: 1).
double smallest_corner(std::span<const Eigen::Vector2d> x, std::span<const Quad> quads, double h) {
  double smallest = std::numeric_limits<double>::infinity();
  for (const Quad& q : quads)
    for (size_t k = 0; k < 4; ++k) {
      const Eigen::Vector2d& p = x[static_cast<size_t>(q[k])];
      const Eigen::Vector2d a = x[static_cast<size_t>(q[(k + 1) % 4])] - p;
      const Eigen::Vector2d b = x[static_cast<size_t>(q[(k + 3) % 4])] - p;
      smallest = std::min(smallest, (a.x() * b.y() - a.y() * b.x()) / (h * h));
    }
  return smallest;
}

// Limited-memory BFGS (Nocedal & Wright 2006, algorithm 7.4) with Armijo backtracking over the
// free coordinates `free` of x, at most `iterations` steps.
void minimise(std::vector<Eigen::Vector2d>& x, std::span<const Quad> quads,
              const std::vector<size_t>& free, double h, double epsilon, int iterations) {
  constexpr int kMemory = 7;
  const auto n = static_cast<Eigen::Index>(2 * free.size());
  std::vector<Eigen::Vector2d> gradient;
  auto evaluate = [&](const std::vector<Eigen::Vector2d>& at, Eigen::VectorXd& g) {
    const double e = detail::untangling_energy(at, quads, h, epsilon, &gradient);
    g.resize(n);
    for (size_t i = 0; i < free.size(); ++i)
      g.segment<2>(static_cast<Eigen::Index>(2 * i)) = gradient[free[i]];
    return e;
  };
  Eigen::VectorXd g, g_next, direction;
  double energy = evaluate(x, g);
  std::vector<Eigen::VectorXd> s_history, y_history;
  std::vector<double> rho;
  std::vector<Eigen::Vector2d> trial = x;
  for (int iteration = 0; iteration < iterations; ++iteration) {
    // Two-loop recursion: direction = −H g.
    direction = -g;
    std::vector<double> alpha(s_history.size());
    for (size_t i = s_history.size(); i-- > 0;) {
      alpha[i] = rho[i] * s_history[i].dot(direction);
      direction -= alpha[i] * y_history[i];
    }
    if (!s_history.empty())
      direction *= s_history.back().dot(y_history.back()) / y_history.back().squaredNorm();
    for (size_t i = 0; i < s_history.size(); ++i) {
      const double beta = rho[i] * y_history[i].dot(direction);
      direction += (alpha[i] - beta) * s_history[i];
    }
    double slope = g.dot(direction);
    if (slope >= 0) {  // not a descent direction: restart from steepest descent
      s_history.clear();
      y_history.clear();
      rho.clear();
      direction = -g;
      slope = -g.squaredNorm();
    }
    if (slope > -1e-30) return;  // stationary
    double step = s_history.empty() ? std::min(1.0, h / std::sqrt(-slope)) : 1.0;
    double next = energy;
    bool accepted = false;
    for (int halving = 0; halving < 40; ++halving, step *= 0.5) {
      for (size_t i = 0; i < free.size(); ++i)
        trial[free[i]] = x[free[i]] + step * direction.segment<2>(static_cast<Eigen::Index>(2 * i));
      next = evaluate(trial, g_next);
      if (next <= energy + 1e-4 * step * slope) {
        accepted = true;
        break;
      }
    }
    if (!accepted) return;
    Eigen::VectorXd s = step * direction, y = g_next - g;
    const double sy = s.dot(y);
    if (sy > 1e-16 * s.norm() * y.norm()) {
      if (static_cast<int>(s_history.size()) == kMemory) {
        s_history.erase(s_history.begin());
        y_history.erase(y_history.begin());
        rho.erase(rho.begin());
      }
      s_history.push_back(std::move(s));
      y_history.push_back(std::move(y));
      rho.push_back(1 / sy);
    }
    for (const size_t v : free) x[v] = trial[v];
    const double decrease = energy - next;
    energy = next;
    g.swap(g_next);
    if (decrease <= 1e-10 * std::abs(energy)) return;
  }
}

}  // namespace

double untangling_energy(std::span<const Eigen::Vector2d> x,
                         std::span<const std::array<int, 4>> quads, double h, double epsilon,
                         std::vector<Eigen::Vector2d>* gradient) {
  if (gradient) gradient->assign(x.size(), Eigen::Vector2d::Zero());
  double energy = 0;
  const double inv_h = 1 / h;
  for (const Quad& q : quads)
    for (size_t k = 0; k < 4; ++k) {
      const auto i = static_cast<size_t>(q[k]), j = static_cast<size_t>(q[(k + 1) % 4]),
                 l = static_cast<size_t>(q[(k + 3) % 4]);
      const Eigen::Vector2d a = (x[j] - x[i]) * inv_h, b = (x[l] - x[i]) * inv_h;
      const double d = a.x() * b.y() - a.y() * b.x();
      const double root = std::sqrt(epsilon * epsilon + d * d);
      const double c = chi(d, epsilon);
      const double numerator =
          (1 - kAreaWeight) * (a.squaredNorm() + b.squaredNorm()) + kAreaWeight * (d * d + 1);
      energy += numerator / c;
      if (!gradient) continue;
      // f = N / c: ∂f = ∂N / c − N c' ∂d / c², c' = (1 + d / root) / 2 = c / root,
      // ∂d/∂a = (b_y, −b_x), ∂d/∂b = (−a_y, a_x).
      const double dc = c / root;
      const double df_dd = (2 * kAreaWeight * d) / c - numerator * dc / (c * c);
      const Eigen::Vector2d ga =
          (2 * (1 - kAreaWeight) / c) * a + df_dd * Eigen::Vector2d(b.y(), -b.x());
      const Eigen::Vector2d gb =
          (2 * (1 - kAreaWeight) / c) * b + df_dd * Eigen::Vector2d(-a.y(), a.x());
      (*gradient)[j] += ga * inv_h;
      (*gradient)[l] += gb * inv_h;
      (*gradient)[i] -= (ga + gb) * inv_h;
    }
  return energy;
}

bool untangle_in_plane(std::vector<Eigen::Vector3d>& positions,
                       std::span<const std::array<int, 4>> quads, std::span<const char> fixed,
                       const Eigen::Vector3d& normal, int rounds, int steps) {
  if (quads.empty()) return true;
  const Eigen::Vector3d u = normal.unitOrthogonal(), w = normal.cross(u);
  std::vector<Eigen::Vector2d> x(positions.size());
  for (size_t v = 0; v < positions.size(); ++v) x[v] = {positions[v].dot(u), positions[v].dot(w)};
  // The quads' signed areas add up to the area the boundary encloses, folded or not.
  double area = 0;
  for (const Quad& q : quads) {
    const Eigen::Vector2d d1 = x[static_cast<size_t>(q[2])] - x[static_cast<size_t>(q[0])];
    const Eigen::Vector2d d2 = x[static_cast<size_t>(q[3])] - x[static_cast<size_t>(q[1])];
    area += 0.5 * (d1.x() * d2.y() - d1.y() * d2.x());
  }
  if (!(area > 0)) return false;  // not counter-clockwise about `normal`
  const double h = std::sqrt(area / static_cast<double>(quads.size()));
  std::vector<size_t> free;
  for (size_t v = 0; v < positions.size(); ++v)
    if (!fixed[v]) free.push_back(v);
  // ε schedule of Garanzha et al.: start at a fraction of the worst corner, then after each
  // minimisation set it so that χ(worst, ε) stays near (1 − σ) of its value, σ the relative
  // decrease of the energy; a small ε once every corner is positive.
  double worst = smallest_corner(x, quads, h);
  double epsilon = std::sqrt(1e-8 + 0.04 * std::pow(std::min(worst, 0.0), 2));
  bool clean = false;
  for (int round = 0; round < rounds; ++round) {
    const double before = untangling_energy(x, quads, h, epsilon);
    minimise(x, quads, free, h, epsilon, steps);
    const double after = untangling_energy(x, quads, h, epsilon);
    worst = smallest_corner(x, quads, h);
    const double sigma = std::max(1 - after / before, 0.1);
    const double mu = (1 - sigma) * chi(worst, epsilon);
    epsilon = worst < mu ? 2 * std::sqrt(mu * (mu - worst)) : 1e-10;
    if (worst > 0) {
      clean = true;
      if (std::abs(before - after) <= 1e-5 * after) break;
    }
  }
  worst = smallest_corner(x, quads, h);
  if (!clean || !(worst > 0)) return false;
  for (const size_t v : free) {
    const Eigen::Vector2d old(positions[v].dot(u), positions[v].dot(w));
    positions[v] += (x[v].x() - old.x()) * u + (x[v].y() - old.y()) * w;
  }
  return true;
}

}  // namespace detail

}  // namespace sd::meshing
