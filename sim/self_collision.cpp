#include "sim/self_collision.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "sim/collision_geometry.hpp"
#include "sim/parallel.hpp"

namespace sd::sim {
namespace {

// A region whose normal cone is wider than this is not declared safe: 90° is the theorem's
// bound (normals in an open half-space); 3° less leaves room for rounding and for the normals of
// the instants between the two ends of a step, which the cone does not hold exactly.
constexpr double kMaxSafeHalfAngle = 0.5 * 3.14159265358979323846 - 0.05;
// Boundaries longer than this are not checked (the O(b²) crossing test would cost more than the
// tests it saves); their region is simply not culled.
constexpr int kMaxBoundaryEdges = 1500;
constexpr int kLeafSize = 1;
// The refit runs the subtrees below this depth (16 of them) on all threads, for trees of at
// least twice this many nodes (a 500-triangle cloth's tree: about 5 µs a subtree).
constexpr int kRefitSplitDepth = 4;
constexpr int kParallelRefitNodes = 1000;
// Nodes per chunk when each node's boundary is found (a node costs its triangle count).
constexpr int kNodeGrain = 256;
// The query's walk is cut into pieces below this depth (self tests of subtrees and node pairs
// that run on the threads; about 60–200 pieces on a 4,000-triangle garment).
constexpr int kWalkSplitDepth = 5;
// The tree is built with its halves on the threads down to this depth, for halves of at least
// kBuildGrain triangles.
constexpr int kBuildSplitDepth = 3;
constexpr int kBuildGrain = 256;

Eigen::Vector3d row(const Eigen::VectorXd& x, int i) {
  return x.segment<3>(3 * i);
}

// Proper or touching crossing of 2D segments ab and cd.
bool segments_cross_2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                       const Eigen::Vector2d& d) {
  const auto orient = [](const Eigen::Vector2d& p, const Eigen::Vector2d& q,
                         const Eigen::Vector2d& r) {
    return (q.x() - p.x()) * (r.y() - p.y()) - (q.y() - p.y()) * (r.x() - p.x());
  };
  const double d1 = orient(c, d, a), d2 = orient(c, d, b);
  const double d3 = orient(a, b, c), d4 = orient(a, b, d);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0)))
    return true;
  const auto on_segment = [](const Eigen::Vector2d& p, const Eigen::Vector2d& q,
                             const Eigen::Vector2d& r) {
    return std::min(p.x(), q.x()) <= r.x() && r.x() <= std::max(p.x(), q.x()) &&
           std::min(p.y(), q.y()) <= r.y() && r.y() <= std::max(p.y(), q.y());
  };
  return (d1 == 0 && on_segment(c, d, a)) || (d2 == 0 && on_segment(c, d, b)) ||
         (d3 == 0 && on_segment(a, b, c)) || (d4 == 0 && on_segment(a, b, d));
}

std::array<Eigen::Vector3d, 4> at_time(const std::array<Eigen::Vector3d, 4>& x0,
                                       const std::array<Eigen::Vector3d, 4>& x1, double t) {
  std::array<Eigen::Vector3d, 4> x;
  for (int k = 0; k < 4; ++k) x[k] = (1.0 - t) * x0[k] + t * x1[k];
  return x;
}

// Distance and hit data of the pair at one instant (positions x).
struct PairDistance {
  double distance = 0.0;
  Eigen::Vector4d weights = Eigen::Vector4d::Zero();
  Eigen::Vector3d separation = Eigen::Vector3d::Zero();  // Σ w_k x_k
};

PairDistance vertex_face_distance(const std::array<Eigen::Vector3d, 4>& x) {
  const TriangleClosestPoint cp = closest_point_on_triangle(x[0], x[1], x[2], x[3]);
  PairDistance d;
  d.distance = std::sqrt(cp.squared_distance);
  d.weights << 1.0, -cp.barycentric[0], -cp.barycentric[1], -cp.barycentric[2];
  d.separation = x[0] - cp.point;
  return d;
}

PairDistance edge_edge_distance(const std::array<Eigen::Vector3d, 4>& x) {
  const SegmentClosestPoints cp = closest_points_on_segments(x[0], x[1], x[2], x[3]);
  PairDistance d;
  d.distance = std::sqrt(cp.squared_distance);
  d.weights << 1.0 - cp.s, cp.s, -(1.0 - cp.t), -cp.t;
  d.separation = cp.p - cp.q;
  return d;
}

// Both continuous tests: coplanarity roots checked for proximity, or, where the four points stay
// coplanar, conservative advancement on the distance (which changes at most at the speed bound
// L = max_k |x1_k − x0_k| summed over the two elements' sides, per unit of step time).
template <class Distance>
bool continuous_test(const std::array<Eigen::Vector3d, 4>& x0,
                     const std::array<Eigen::Vector3d, 4>& x1, double tolerance, SelfPairKind kind,
                     Distance distance_at, SelfPair& hit) {
  const auto plane_normal = [&](const std::array<Eigen::Vector3d, 4>& x) -> Eigen::Vector3d {
    // The plane's normal n with f(t) = n·(separation) up to a positive factor, so that f's sign
    // gives the side: f = orient(p, a, b, c) = −((b − a) × (c − a))·(p − a) for VF, and
    // f = ((a1 − a0) × (b1 − b0))·(pa − pb) for EE.
    return kind == SelfPairKind::vertex_face ? Eigen::Vector3d((x[3] - x[1]).cross(x[2] - x[1]))
                                             : Eigen::Vector3d((x[1] - x[0]).cross(x[3] - x[2]));
  };
  const auto report = [&](double t, const PairDistance& d, const Eigen::Vector3d& normal) {
    hit.kind = kind;
    hit.weights = d.weights;
    hit.normal = normal;
    hit.distance = d.distance;
    hit.time = t;
    return true;
  };
  const CoplanarTimes times = coplanar_times(x0, x1);
  if (!times.degenerate) {
    for (const CoplanarTime& root : times.roots) {
      const std::array<Eigen::Vector3d, 4> x = at_time(x0, x1, root.t);
      const PairDistance d = distance_at(x);
      if (d.distance > tolerance) continue;
      int side = root.sign_before;
      if (side == 0) continue;  // coplanar at the start: a contact, not a collision
      const Eigen::Vector3d n = plane_normal(x);
      const double length = n.norm();
      if (!(length > 0.0)) continue;
      return report(root.t, d, (side / length) * n);
    }
    return false;
  }
  // Coplanar throughout: walk the distance conservatively.
  double speed = 0.0;
  for (int k = 0; k < 4; ++k) speed = std::max(speed, (x1[k] - x0[k]).norm());
  speed *= 2.0;  // both elements may move towards each other
  double t = 0.0;
  PairDistance previous = distance_at(x0);
  if (previous.distance <= tolerance) return false;  // already in contact at the start
  // Each advance is safe: the pair cannot close more than speed·Δt. Approaching head-on, the gap
  // halves at worst per iteration, so 200 iterations reach any tolerance above 1e-60 of it;
  // running out of them counts as a collision (conservative).
  for (int iteration = 0; iteration < 200; ++iteration) {
    const double advance = speed > 0.0 ? (previous.distance - tolerance) / speed : 1.0;
    const double next = std::min(1.0, t + advance);
    const PairDistance d = distance_at(at_time(x0, x1, next));
    if (d.distance <= tolerance || (iteration == 199 && next < 1.0)) {
      const double length = previous.separation.norm();
      if (!(length > 0.0)) return false;
      return report(next, d, previous.separation / length);
    }
    if (next >= 1.0) return false;
    t = next;
    previous = d;
  }
  return false;
}

}  // namespace

bool vertex_face_collision(const std::array<Eigen::Vector3d, 4>& x0,
                           const std::array<Eigen::Vector3d, 4>& x1, double tolerance,
                           SelfPair& hit) {
  return continuous_test(x0, x1, tolerance, SelfPairKind::vertex_face, vertex_face_distance, hit);
}

bool edge_edge_collision(const std::array<Eigen::Vector3d, 4>& x0,
                         const std::array<Eigen::Vector3d, 4>& x1, double tolerance,
                         SelfPair& hit) {
  return continuous_test(x0, x1, tolerance, SelfPairKind::edge_edge, edge_edge_distance, hit);
}

SelfCollider::SelfCollider(std::vector<std::array<int, 3>> triangles, const Eigen::VectorXd& x)
    : triangles_(std::move(triangles)) {
  const int n = static_cast<int>(x.size() / 3);
  const int f = static_cast<int>(triangles_.size());
  vertex_owner_.assign(static_cast<std::size_t>(n), -1);
  // Edges numbered in the order they are first met; each vertex lists the edges to its
  // higher-numbered neighbours (a handful), which finds an edge faster than a tree of pairs.
  std::vector<std::vector<std::array<int, 2>>> edges_from(static_cast<std::size_t>(n));
  triangle_edges_.resize(triangles_.size());
  for (int t = 0; t < f; ++t) {
    for (int k = 0; k < 3; ++k) {
      const int v = triangles_[t][k];
      if (v < 0 || v >= n) throw std::invalid_argument("self collision: vertex index out of range");
      if (vertex_owner_[v] < 0) vertex_owner_[v] = t;
      const int w = triangles_[t][(k + 1) % 3];
      if (w < 0 || w >= n) throw std::invalid_argument("self collision: vertex index out of range");
      const auto [low, high] = std::minmax(v, w);
      std::vector<std::array<int, 2>>& from = edges_from[static_cast<std::size_t>(low)];
      auto it = std::find_if(from.begin(), from.end(),
                             [high](const std::array<int, 2>& e) { return e[0] == high; });
      int edge = 0;
      if (it == from.end()) {
        edge = static_cast<int>(edges_.size());
        from.push_back({high, edge});
        edges_.push_back({low, high});
        edge_owner_.push_back(t);
        edge_triangles_.push_back({t, -1});
      } else {
        edge = (*it)[1];
        if (edge_triangles_[edge][1] < 0) edge_triangles_[edge][1] = t;
      }
      triangle_edges_[t][k] = edge;
    }
  }
  order_.resize(triangles_.size());
  std::iota(order_.begin(), order_.end(), 0);
  position_.assign(triangles_.size(), 0);
  // A subtree over m triangles has 2m − 1 nodes (one triangle a leaf), so every node's place in
  // preorder is known before it is built and the top subtrees are built on the threads.
  nodes_.assign(f > 0 ? 2 * static_cast<std::size_t>(f) - 1 : 0, Node{});
  if (f > 0) build(0, 0, f, x, 0);
  for (int i = 0; i < f; ++i) position_[order_[i]] = i;
  // Connectivity and boundary of each node: edges with exactly one of their triangles inside.
  // Each node's own, so the nodes are done on all threads.
  parallel_chunks(static_cast<int>(nodes_.size()), kNodeGrain, [&](int, int first, int last) {
    for (int index = first; index < last; ++index) {
      Node& node = nodes_[static_cast<std::size_t>(index)];
      const auto inside = [&](int t) {
        return t >= 0 && position_[t] >= node.begin && position_[t] < node.end;
      };
      std::vector<int> parent(static_cast<std::size_t>(node.end - node.begin));
      std::iota(parent.begin(), parent.end(), 0);
      const auto find = [&](int i) {
        while (parent[i] != i) i = parent[i] = parent[parent[i]];
        return i;
      };
      int components = node.end - node.begin;
      node.boundary.clear();
      for (int i = node.begin; i < node.end; ++i) {
        const int t = order_[i];
        for (int k = 0; k < 3; ++k) {
          const int e = triangle_edges_[t][k];
          const auto [t0, t1] = edge_triangles_[e];
          const int other = t0 == t ? t1 : t0;
          if (!inside(other)) {
            node.boundary.push_back(e);
          } else if (other > t) {
            const int a = find(i - node.begin), b = find(position_[other] - node.begin);
            if (a != b) {
              parent[a] = b;
              --components;
            }
          }
        }
      }
      node.connected = components == 1;
      if (!node.connected || static_cast<int>(node.boundary.size()) > kMaxBoundaryEdges)
        node.boundary.clear();
    }
  });
}

void SelfCollider::build(int index, int begin, int end, const Eigen::VectorXd& x, int depth) {
  static_assert(kLeafSize == 1, "the preorder places assume single-triangle leaves");
  Node& node = nodes_[static_cast<std::size_t>(index)];
  node.begin = begin;
  node.end = end;
  if (end - begin <= kLeafSize) return;
  // Median split of the centroids along the longest side of their box.
  Eigen::AlignedBox3d box;
  const auto centroid = [&](int t) {
    return Eigen::Vector3d(
        (row(x, triangles_[t][0]) + row(x, triangles_[t][1]) + row(x, triangles_[t][2])) / 3.0);
  };
  for (int i = begin; i < end; ++i) box.extend(centroid(order_[i]));
  int axis = 0;
  box.sizes().maxCoeff(&axis);
  const int middle = begin + (end - begin) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + middle, order_.begin() + end,
                   [&](int a, int b) { return centroid(a)[axis] < centroid(b)[axis]; });
  node.left = index + 1;
  node.right = index + 2 * (middle - begin);
  const int left = node.left, right = node.right;
  // The two halves own disjoint ranges of order_ and of nodes_.
  if (depth < kBuildSplitDepth && end - begin >= 2 * kBuildGrain) {
    parallel_chunks(2, 1, [&](int, int first, int last) {
      for (int half = first; half < last; ++half) {
        if (half == 0)
          build(left, begin, middle, x, depth + 1);
        else
          build(right, middle, end, x, depth + 1);
      }
    });
  } else {
    build(left, begin, middle, x, depth + 1);
    build(right, middle, end, x, depth + 1);
  }
}

void SelfCollider::refit(const Eigen::VectorXd& x0, const Eigen::VectorXd& x1, double inflate,
                         bool dirty_only) {
  const Eigen::Vector3d grow = Eigen::Vector3d::Constant(inflate);
  // One pose (the proximity queries): n1 = n0, so a leaf's cone has half-angle atan2(|n0 × n0|,
  // n0 · n0) = atan2(0, 1) = 0 and axis 2 n0 / |2 n0|: the same bits without the second normal
  // and the atan2 (the atan2s were 2.3 % of the 2 cm tee's drape, docs/benchmarks.md).
  const bool one_pose = &x0 == &x1;
  const auto refit_node = [&](int i) {
    // A node without a moved triangle keeps the box and cone of the last refit: they depend
    // only on its triangles' corners at x0 and x1, which are the same.
    if (dirty_only && dirty_[i] == 0) return;
    Node& node = nodes_[i];
    if (node.left < 0) {
      const std::array<int, 3>& t = triangles_[order_[node.begin]];
      node.box.setEmpty();
      for (int k = 0; k < 3; ++k) {
        node.box.extend(row(x0, t[k]));
        if (!one_pose) node.box.extend(row(x1, t[k]));
      }
      node.box.min() -= grow;
      node.box.max() += grow;
      const Eigen::Vector3d n0 = triangle_normal(row(x0, t[0]), row(x0, t[1]), row(x0, t[2]));
      const Eigen::Vector3d n1 =
          one_pose ? n0 : triangle_normal(row(x1, t[0]), row(x1, t[1]), row(x1, t[2]));
      const Eigen::Vector3d sum = n0 + n1;
      if (n0.isZero() || n1.isZero() || !(sum.norm() > 1e-9)) {
        node.axis.setZero();
        node.half_angle = 3.2;  // degenerate or flipped over the step: never safe
      } else {
        node.axis = sum.normalized();
        node.half_angle = one_pose ? 0.0 : 0.5 * std::atan2(n0.cross(n1).norm(), n0.dot(n1));
      }
      return;
    }
    const Node& a = nodes_[node.left];
    const Node& b = nodes_[node.right];
    node.box = a.box.merged(b.box);
    const Eigen::Vector3d sum = (a.end - a.begin) * a.axis + (b.end - b.begin) * b.axis;
    if (a.half_angle > 3.0 || b.half_angle > 3.0 || !(sum.norm() > 1e-9)) {
      node.axis.setZero();
      node.half_angle = 3.2;
      return;
    }
    node.axis = sum.normalized();
    const auto angle = [&](const Eigen::Vector3d& u) {
      return std::atan2(node.axis.cross(u).norm(), node.axis.dot(u));
    };
    node.half_angle = std::max(angle(a.axis) + a.half_angle, angle(b.axis) + b.half_angle);
  };
  // Bottom-up. The nodes are stored in preorder, so a node's subtree is the index range from it
  // to its last descendant, and the subtrees below the top levels are refitted on all threads
  // (each node from its own children only: the same bits in any order), then the top nodes,
  // children before parents (higher index first).
  const int count = static_cast<int>(nodes_.size());
  if (count < 2 * kParallelRefitNodes) {
    for (int i = count - 1; i >= 0; --i) refit_node(i);
    return;
  }
  std::vector<int> subtrees;  // roots at depth kRefitSplitDepth, or leaves above it
  std::vector<int> top;       // inner nodes above that depth, in preorder
  std::vector<std::array<int, 2>> stack{{0, 0}};
  while (!stack.empty()) {
    const auto [i, depth] = stack.back();
    stack.pop_back();
    const Node& node = nodes_[i];
    if (depth == kRefitSplitDepth || node.left < 0) {
      subtrees.push_back(i);
      continue;
    }
    top.push_back(i);
    stack.push_back({node.right, depth + 1});
    stack.push_back({node.left, depth + 1});
  }
  const auto subtree_end = [&](int i) {
    while (nodes_[i].left >= 0) i = nodes_[i].right;
    return i + 1;
  };
  parallel_chunks(static_cast<int>(subtrees.size()), 1, [&](int, int first, int last) {
    for (int s = first; s < last; ++s)
      for (int i = subtree_end(subtrees[s]) - 1; i >= subtrees[s]; --i) refit_node(i);
  });
  for (auto it = top.rbegin(); it != top.rend(); ++it) refit_node(*it);
}

bool SelfCollider::region_is_safe(const Node& node, const Eigen::VectorXd& x0,
                                  const Eigen::VectorXd& x1) {
  if (!node.connected || node.half_angle >= kMaxSafeHalfAngle || node.boundary.empty())
    return false;
  // Project the boundary on the plane across the cone's axis, at both ends of the step.
  Eigen::Vector3d u = node.axis.unitOrthogonal();
  Eigen::Vector3d w = node.axis.cross(u);
  const int b = static_cast<int>(node.boundary.size());
  std::vector<Eigen::Vector2d> ends(2 * static_cast<std::size_t>(b));
  std::vector<Eigen::AlignedBox2d> boxes(static_cast<std::size_t>(b));
  for (const Eigen::VectorXd* x : {&x0, &x1}) {
    for (int i = 0; i < b; ++i) {
      const std::array<int, 2>& e = edges_[node.boundary[i]];
      for (int k = 0; k < 2; ++k) {
        const Eigen::Vector3d p = row(*x, e[k]);
        ends[2 * i + k] = Eigen::Vector2d(u.dot(p), w.dot(p));
      }
      boxes[i] = Eigen::AlignedBox2d(ends[2 * i].cwiseMin(ends[2 * i + 1]),
                                     ends[2 * i].cwiseMax(ends[2 * i + 1]));
    }
    for (int i = 0; i < b; ++i) {
      const std::array<int, 2>& ei = edges_[node.boundary[i]];
      for (int j = i + 1; j < b; ++j) {
        const std::array<int, 2>& ej = edges_[node.boundary[j]];
        if (ei[0] == ej[0] || ei[0] == ej[1] || ei[1] == ej[0] || ei[1] == ej[1]) continue;
        if (!boxes[i].intersects(boxes[j])) continue;
        if (segments_cross_2d(ends[2 * i], ends[2 * i + 1], ends[2 * j], ends[2 * j + 1]))
          return false;
      }
    }
    if (x == &x1 || &x0 == &x1) break;
  }
  return true;
}

template <class LeafTest>
void SelfCollider::self_test(int index, const Eigen::VectorXd& x0, const Eigen::VectorXd& x1,
                             LeafTest& leaf, SelfQueryStats& stats, int depth,
                             std::vector<WalkPiece>* pieces) {
  const Node& node = nodes_[index];
  if (node.left < 0 || (!dirty_.empty() && dirty_[index] == 0)) return;
  if (pieces != nullptr && depth >= kWalkSplitDepth) {
    pieces->push_back({WalkPiece::Kind::self, index, -1});
    return;
  }
  if (culling_ && region_is_safe(node, x0, x1)) {
    stats.culled_triangles += node.end - node.begin;
    return;
  }
  self_test(node.left, x0, x1, leaf, stats, depth + 1, pieces);
  self_test(node.right, x0, x1, leaf, stats, depth + 1, pieces);
  pair_test(node.left, node.right, leaf, stats, depth + 1, pieces);
}

template <class LeafTest>
void SelfCollider::pair_test(int a, int b, LeafTest& leaf, SelfQueryStats& stats, int depth,
                             std::vector<WalkPiece>* pieces) {
  if (pieces != nullptr && depth >= kWalkSplitDepth) {
    pieces->push_back({WalkPiece::Kind::pair, a, b});
    return;
  }
  if (!dirty_.empty() && dirty_[a] == 0 && dirty_[b] == 0) return;
  ++stats.node_pairs;
  const Node& na = nodes_[a];
  const Node& nb = nodes_[b];
  if (!na.box.intersects(nb.box)) return;
  const bool a_leaf = na.left < 0, b_leaf = nb.left < 0;
  if (a_leaf && b_leaf) {
    ++stats.triangle_pairs;
    leaf(order_[na.begin], order_[nb.begin]);
    return;
  }
  if (b_leaf || (!a_leaf && na.end - na.begin >= nb.end - nb.begin)) {
    pair_test(na.left, b, leaf, stats, depth + 1, pieces);
    pair_test(na.right, b, leaf, stats, depth + 1, pieces);
  } else {
    pair_test(a, nb.left, leaf, stats, depth + 1, pieces);
    pair_test(a, nb.right, leaf, stats, depth + 1, pieces);
  }
}

void SelfCollider::collect_leaves(const Eigen::VectorXd& x0, const Eigen::VectorXd& x1,
                                  std::vector<std::array<int, 2>>& leaves, SelfQueryStats& stats) {
  // The traversal's top levels, serially: it stops at kWalkSplitDepth and lists the calls below
  // (and the triangle pairs it met above) in its order, which then run on the threads.
  if (nodes_.empty()) return;
  std::vector<WalkPiece> pieces;
  auto met = [&pieces](int ta, int tb) { pieces.push_back({WalkPiece::Kind::triangles, ta, tb}); };
  self_test(0, x0, x1, met, stats, 0, &pieces);
  std::vector<std::vector<std::array<int, 2>>> found(pieces.size());
  std::vector<SelfQueryStats> counts(pieces.size());
  parallel_chunks(static_cast<int>(pieces.size()), 1, [&](int, int first, int last) {
    for (int k = first; k < last; ++k) {
      const WalkPiece& piece = pieces[static_cast<std::size_t>(k)];
      std::vector<std::array<int, 2>>& out = found[static_cast<std::size_t>(k)];
      auto collect = [&out](int ta, int tb) { out.push_back({ta, tb}); };
      SelfQueryStats& count = counts[static_cast<std::size_t>(k)];
      if (piece.kind == WalkPiece::Kind::self)
        self_test(piece.a, x0, x1, collect, count);
      else if (piece.kind == WalkPiece::Kind::pair)
        pair_test(piece.a, piece.b, collect, count);
      else
        out.push_back({piece.a, piece.b});
    }
  });
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    leaves.insert(leaves.end(), found[k].begin(), found[k].end());
    stats.culled_triangles += counts[k].culled_triangles;
    stats.node_pairs += counts[k].node_pairs;
    stats.triangle_pairs += counts[k].triangle_pairs;
  }
}

namespace {

// Triangle pairs per chunk at least: each costs up to 15 element tests (a few microseconds).
constexpr int kLeafGrain = 256;

// The triangle pairs the traversal reached, tested by `leaf(ta, tb, found, tests)` in chunks on
// the simulator's threads; the chunks' element pairs are joined in traversal order, so the list
// (and the order) is the same on any thread count as on one, and as testing each leaf during the
// traversal gave. The traversal itself (box tests, the curvature culling) stays serial.
template <class Leaf>
void test_leaves(const std::vector<std::array<int, 2>>& leaves, const Leaf& leaf,
                 std::vector<SelfPair>& pairs, long long& element_tests) {
  const int n = static_cast<int>(leaves.size());
  const int chunks = chunk_count(n, kLeafGrain);
  std::vector<std::vector<SelfPair>> found(static_cast<std::size_t>(chunks));
  std::vector<long long> tests(static_cast<std::size_t>(chunks), 0);
  parallel_chunks(n, kLeafGrain, [&](int chunk, int first, int last) {
    const auto c = static_cast<std::size_t>(chunk);
    for (int i = first; i < last; ++i) {
      const std::array<int, 2>& l = leaves[static_cast<std::size_t>(i)];
      leaf(l[0], l[1], found[c], tests[c]);
    }
  });
  for (std::size_t c = 0; c < found.size(); ++c) {
    pairs.insert(pairs.end(), found[c].begin(), found[c].end());
    element_tests += tests[c];
  }
}

}  // namespace

std::vector<SelfPair> SelfCollider::find_proximities(const Eigen::VectorXd& x, double distance,
                                                     SelfQueryStats* stats) {
  SelfQueryStats local;
  SelfQueryStats& s = stats != nullptr ? *stats : local;
  s = SelfQueryStats{};
  s.triangles = triangle_count();
  std::vector<SelfPair> pairs;
  if (nodes_.empty()) return pairs;
  refit(x, x, 0.5 * distance);
  const double limit2 = distance * distance;
  const auto vertex_face = [&](int v, int t, std::vector<SelfPair>& out, long long& tests) {
    const std::array<int, 3>& f = triangles_[t];
    if (v == f[0] || v == f[1] || v == f[2]) return;
    ++tests;
    const std::array<Eigen::Vector3d, 4> p = {row(x, v), row(x, f[0]), row(x, f[1]), row(x, f[2])};
    const TriangleClosestPoint cp = closest_point_on_triangle(p[0], p[1], p[2], p[3]);
    if (cp.squared_distance >= limit2) return;
    SelfPair pair;
    pair.kind = SelfPairKind::vertex_face;
    pair.vertices = {v, f[0], f[1], f[2]};
    pair.weights << 1.0, -cp.barycentric[0], -cp.barycentric[1], -cp.barycentric[2];
    pair.distance = std::sqrt(cp.squared_distance);
    const Eigen::Vector3d face_normal = triangle_normal(p[1], p[2], p[3]);
    if (pair.distance > 1e-9 * distance + 1e-15) {
      pair.normal = (p[0] - cp.point) / pair.distance;
    } else if (!face_normal.isZero()) {
      pair.normal = face_normal;  // on the face: push to the side of the face's normal
    } else {
      return;
    }
    out.push_back(pair);
  };
  const auto edge_edge = [&](int e, int g, std::vector<SelfPair>& out, long long& tests) {
    const std::array<int, 2>& a = edges_[e];
    const std::array<int, 2>& b = edges_[g];
    if (a[0] == b[0] || a[0] == b[1] || a[1] == b[0] || a[1] == b[1]) return;
    ++tests;
    const SegmentClosestPoints cp =
        closest_points_on_segments(row(x, a[0]), row(x, a[1]), row(x, b[0]), row(x, b[1]));
    // Closest points at an end are a vertex's contact, found by the vertex-face test.
    if (cp.squared_distance >= limit2 || cp.s <= 0.0 || cp.s >= 1.0 || cp.t <= 0.0 || cp.t >= 1.0)
      return;
    SelfPair pair;
    pair.kind = SelfPairKind::edge_edge;
    pair.vertices = {a[0], a[1], b[0], b[1]};
    pair.weights << 1.0 - cp.s, cp.s, -(1.0 - cp.t), -cp.t;
    pair.distance = std::sqrt(cp.squared_distance);
    if (pair.distance > 1e-9 * distance + 1e-15) {
      pair.normal = (cp.p - cp.q) / pair.distance;
    } else {
      const Eigen::Vector3d n = (row(x, a[1]) - row(x, a[0])).cross(row(x, b[1]) - row(x, b[0]));
      if (!(n.norm() > 0.0)) return;
      pair.normal = n.normalized();
    }
    out.push_back(pair);
  };
  const auto leaf = [&](int ta, int tb, std::vector<SelfPair>& out, long long& tests) {
    for_each_owned_element_pair(
        ta, tb, [&](int v, int t) { vertex_face(v, t, out, tests); },
        [&](int e, int g) { edge_edge(e, g, out, tests); });
  };
  std::vector<std::array<int, 2>> leaves;
  collect_leaves(x, x, leaves, s);
  test_leaves(leaves, leaf, pairs, s.element_tests);
  s.pairs_found = static_cast<int>(pairs.size());
  return pairs;
}

std::vector<SelfPair> SelfCollider::find_collisions(const Eigen::VectorXd& x0,
                                                    const Eigen::VectorXd& x1, double tolerance,
                                                    SelfQueryStats* stats,
                                                    const std::vector<unsigned char>* moved) {
  SelfQueryStats local;
  SelfQueryStats& s = stats != nullptr ? *stats : local;
  s = SelfQueryStats{};
  s.triangles = triangle_count();
  std::vector<SelfPair> pairs;
  if (nodes_.empty()) return pairs;
  if (moved != nullptr) {
    // Every element pair with a moved vertex is tested at a triangle pair holding a moved
    // triangle (an element's owner holds the element), so pruning node pairs with none is exact.
    // The same flags restrict the refit: the tree was last refitted at (x0, x1) as the last
    // query saw them, which differ only at the moved vertices.
    dirty_.assign(nodes_.size(), 0);
    for (int i = static_cast<int>(nodes_.size()) - 1; i >= 0; --i) {
      const Node& node = nodes_[i];
      if (node.left < 0) {
        for (int v : triangles_[order_[node.begin]]) dirty_[i] |= (*moved)[v];
      } else {
        dirty_[i] = dirty_[node.left] | dirty_[node.right];
      }
    }
  }
  refit(x0, x1, 0.5 * tolerance, moved != nullptr);
  const auto gather = [&](const std::array<int, 4>& v, const Eigen::VectorXd& x) {
    return std::array<Eigen::Vector3d, 4>{row(x, v[0]), row(x, v[1]), row(x, v[2]), row(x, v[3])};
  };
  // Each element's own swept box, to skip most element pairs of a triangle pair cheaply.
  const auto swept = [&](std::initializer_list<int> vertices) {
    Eigen::AlignedBox3d box;
    for (int v : vertices) {
      box.extend(row(x0, v));
      box.extend(row(x1, v));
    }
    box.min().array() -= 0.5 * tolerance;
    box.max().array() += 0.5 * tolerance;
    return box;
  };
  const auto vertex_face = [&](int v, int t, std::vector<SelfPair>& out, long long& tests) {
    const std::array<int, 3>& f = triangles_[t];
    if (v == f[0] || v == f[1] || v == f[2]) return;
    if (!swept({v}).intersects(swept({f[0], f[1], f[2]}))) return;
    ++tests;
    SelfPair hit;
    hit.vertices = {v, f[0], f[1], f[2]};
    if (vertex_face_collision(gather(hit.vertices, x0), gather(hit.vertices, x1), tolerance, hit))
      out.push_back(hit);
  };
  const auto edge_edge = [&](int e, int g, std::vector<SelfPair>& out, long long& tests) {
    const std::array<int, 2>& a = edges_[e];
    const std::array<int, 2>& b = edges_[g];
    if (a[0] == b[0] || a[0] == b[1] || a[1] == b[0] || a[1] == b[1]) return;
    if (!swept({a[0], a[1]}).intersects(swept({b[0], b[1]}))) return;
    ++tests;
    SelfPair hit;
    hit.vertices = {a[0], a[1], b[0], b[1]};
    if (edge_edge_collision(gather(hit.vertices, x0), gather(hit.vertices, x1), tolerance, hit))
      out.push_back(hit);
  };
  const auto leaf = [&](int ta, int tb, std::vector<SelfPair>& out, long long& tests) {
    for_each_owned_element_pair(
        ta, tb, [&](int v, int t) { vertex_face(v, t, out, tests); },
        [&](int e, int g) { edge_edge(e, g, out, tests); });
  };
  std::vector<std::array<int, 2>> leaves;
  collect_leaves(x0, x1, leaves, s);
  test_leaves(leaves, leaf, pairs, s.element_tests);
  dirty_.clear();
  s.pairs_found = static_cast<int>(pairs.size());
  return pairs;
}

namespace {

// Does segment pq cross triangle abc? Orientation signs, with values below 1e-10 of the cube
// of the configuration's size taken as zero (rounding): touching counts, a segment in the
// triangle's plane does not (a flat strip of the cloth is no intersection).
bool segment_crosses_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                              const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                              const Eigen::Vector3d& c) {
  const double size = std::max({(q - p).norm(), (b - a).norm(), (c - a).norm(), (p - a).norm()});
  const double zero = 1e-10 * size * size * size;
  const auto orient = [zero](const Eigen::Vector3d& u, const Eigen::Vector3d& v,
                             const Eigen::Vector3d& w, const Eigen::Vector3d& z) {
    const double value = (v - u).cross(w - u).dot(z - u);
    return std::abs(value) <= zero ? 0.0 : value;
  };
  const double sp = orient(a, b, c, p), sq = orient(a, b, c, q);
  if ((sp > 0 && sq > 0) || (sp < 0 && sq < 0) || (sp == 0 && sq == 0)) return false;
  const double s1 = orient(p, q, a, b), s2 = orient(p, q, b, c), s3 = orient(p, q, c, a);
  if (s1 == 0 && s2 == 0 && s3 == 0) return false;
  return (s1 >= 0 && s2 >= 0 && s3 >= 0) || (s1 <= 0 && s2 <= 0 && s3 <= 0);
}

}  // namespace

std::vector<std::array<int, 2>> SelfCollider::find_intersections(const Eigen::VectorXd& x) {
  std::vector<std::array<int, 2>> pairs;
  if (nodes_.empty()) return pairs;
  refit(x, x, 0.0);
  SelfQueryStats stats;
  auto leaf = [&](int ta, int tb) {
    const std::array<int, 3>& a = triangles_[ta];
    const std::array<int, 3>& b = triangles_[tb];
    int shared = 0;
    for (int i : a)
      for (int j : b) shared += i == j;
    if (shared >= 2) return;  // neighbours across an edge
    const auto crosses = [&](const std::array<int, 3>& s, const std::array<int, 3>& t) {
      for (int k = 0; k < 3; ++k) {
        const int p = s[k], q = s[(k + 1) % 3];
        // An edge through the shared vertex meets the other triangle there by construction.
        if (p == t[0] || p == t[1] || p == t[2] || q == t[0] || q == t[1] || q == t[2]) continue;
        if (segment_crosses_triangle(row(x, p), row(x, q), row(x, t[0]), row(x, t[1]),
                                     row(x, t[2])))
          return true;
      }
      return false;
    };
    if (crosses(a, b) || crosses(b, a)) pairs.push_back({ta, tb});
  };
  const bool culling = culling_;
  culling_ = false;  // a flipped triangle can hide in a flat-looking region
  self_test(0, x, x, leaf, stats);
  culling_ = culling;
  return pairs;
}

}  // namespace sd::sim
