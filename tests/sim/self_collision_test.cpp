// Self-collision detection: the exact kernels (segment closest points, coplanarity times, the
// continuous vertex-face and edge-edge tests) on configurations whose answer is known in closed
// form, and the tree's queries against an all-pairs search.

#include "sim/self_collision.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <tuple>

#include "sim/collision_geometry.hpp"
#include "tests/sim/self_contact_helpers.hpp"

namespace sd::sim {
namespace {

using V = Eigen::Vector3d;
using Points = std::array<Eigen::Vector3d, 4>;

TEST(SegmentClosestPoints, SkewSegmentsMeetAtTheCommonPerpendicular) {
  const SegmentClosestPoints cp =
      closest_points_on_segments(V(-1, 0, 0), V(1, 0, 0), V(0.5, -1, 2), V(0.5, 1, 2));
  EXPECT_NEAR(cp.s, 0.75, 1e-15);
  EXPECT_NEAR(cp.t, 0.5, 1e-15);
  EXPECT_NEAR(cp.squared_distance, 4.0, 1e-14);
}

TEST(SegmentClosestPoints, ParallelSegmentsGiveTheirDistance) {
  // Overlapping along x, 0.3 apart in y: any closest pair is 0.3 apart.
  const SegmentClosestPoints overlap =
      closest_points_on_segments(V(0, 0, 0), V(1, 0, 0), V(0.5, 0.3, 0), V(2, 0.3, 0));
  EXPECT_NEAR(std::sqrt(overlap.squared_distance), 0.3, 1e-15);
  // Disjoint along x: end to end, (2 − 1, 0.3).
  const SegmentClosestPoints apart =
      closest_points_on_segments(V(0, 0, 0), V(1, 0, 0), V(2, 0.3, 0), V(3, 0.3, 0));
  EXPECT_NEAR(apart.squared_distance, 1.0 + 0.09, 1e-14);
  EXPECT_EQ(apart.s, 1.0);
  EXPECT_EQ(apart.t, 0.0);
}

TEST(CoplanarTimes, RootsOfAKnownCubic) {
  // A vertex moving from z = 1 to z = −1 over a still triangle in z = 0: one root at t = 1/2.
  // f = orient(p, a, b, c) is negative while p is on the side of the normal (+z) of abc.
  const Points still = {V(0.2, 0.2, 1), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)};
  Points moved = still;
  moved[0] = V(0.2, 0.2, -1);
  const CoplanarTimes times = coplanar_times(still, moved);
  ASSERT_FALSE(times.degenerate);
  ASSERT_EQ(times.roots.size(), 1u);
  EXPECT_NEAR(times.roots[0].t, 0.5, 1e-14);
  EXPECT_EQ(times.roots[0].sign_before, -1);
  EXPECT_EQ(times.sign_at_start, -1);
}

TEST(SelfCollisionKernels, VertexThroughTheFaceMidStep) {
  const Points x0 = {V(0.2, 0.2, 0.5), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)};
  Points x1 = x0;
  x1[0] = V(0.2, 0.2, -0.5);
  SelfPair hit;
  ASSERT_TRUE(vertex_face_collision(x0, x1, 1e-9, hit));
  EXPECT_NEAR(hit.time, 0.5, 1e-12);
  EXPECT_NEAR(hit.normal.z(), 1.0, 1e-12);  // from the face to the side the vertex came from
  EXPECT_NEAR(hit.weights[0], 1.0, 0.0);
  EXPECT_NEAR(hit.weights[1], -0.6, 1e-12);
  EXPECT_NEAR(hit.weights[2], -0.2, 1e-12);
  EXPECT_NEAR(hit.weights[3], -0.2, 1e-12);
}

TEST(SelfCollisionKernels, FaceSweepingOverAStillVertex) {
  // The same collision seen from the face: it rises from below through the vertex.
  const Points x0 = {V(0.2, 0.2, 0.0), V(0, 0, -0.3), V(1, 0, -0.3), V(0, 1, -0.3)};
  Points x1 = {V(0.2, 0.2, 0.0), V(0, 0, 0.1), V(1, 0, 0.1), V(0, 1, 0.1)};
  SelfPair hit;
  ASSERT_TRUE(vertex_face_collision(x0, x1, 1e-9, hit));
  EXPECT_NEAR(hit.time, 0.75, 1e-12);
  EXPECT_NEAR(hit.normal.z(), 1.0, 1e-12);
}

TEST(SelfCollisionKernels, VertexReachingTheFaceAtTheLastInstant) {
  // The vertex lands exactly on the face at t = 1 (without crossing): f touches zero at the end.
  const Points x0 = {V(0.25, 0.25, 0.01), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)};
  Points x1 = x0;
  x1[0] = V(0.25, 0.25, 0.0);
  SelfPair hit;
  ASSERT_TRUE(vertex_face_collision(x0, x1, 1e-9, hit));
  EXPECT_EQ(hit.time, 1.0);
  EXPECT_NEAR(hit.normal.z(), 1.0, 1e-12);
  // Stopping 1 µm short of the face is no collision at a 0.1 µm tolerance.
  x1[0] = V(0.25, 0.25, 1e-6);
  EXPECT_FALSE(vertex_face_collision(x0, x1, 1e-7, hit));
}

TEST(SelfCollisionKernels, VertexPassingBesideTheFaceIsNoCollision) {
  const Points x0 = {V(0.8, 0.8, 0.5), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)};
  Points x1 = x0;
  x1[0] = V(0.8, 0.8, -0.5);  // crosses the plane outside the triangle (x + y > 1)
  SelfPair hit;
  EXPECT_FALSE(vertex_face_collision(x0, x1, 1e-6, hit));
}

TEST(SelfCollisionKernels, CrossingEdges) {
  const Points x0 = {V(-1, 0, 1), V(1, 0, 1), V(0, -1, 0), V(0, 1, 0)};
  Points x1 = x0;
  x1[0].z() = x1[1].z() = -1.0;
  SelfPair hit;
  ASSERT_TRUE(edge_edge_collision(x0, x1, 1e-9, hit));
  EXPECT_NEAR(hit.time, 0.5, 1e-12);
  EXPECT_NEAR(hit.normal.z(), 1.0, 1e-12);  // first edge came from above
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(std::abs(hit.weights[k]), 0.5, 1e-12);
  EXPECT_GT(hit.weights[0], 0.0);
  EXPECT_LT(hit.weights[2], 0.0);
}

TEST(SelfCollisionKernels, ParallelEdgesFallingOntoEachOther) {
  // Parallel edges are coplanar at every instant: the cubic vanishes and the distance walk
  // decides. The upper edge meets the lower one when it has fallen 1 of 2 units.
  const Points x0 = {V(0, 0, 1), V(1, 0, 1), V(0.5, 0, 0), V(1.5, 0, 0)};
  Points x1 = x0;
  x1[0].z() = x1[1].z() = -1.0;
  EXPECT_TRUE(coplanar_times(x0, x1).degenerate);
  const double tolerance = 1e-8;
  SelfPair hit;
  ASSERT_TRUE(edge_edge_collision(x0, x1, tolerance, hit));
  EXPECT_LE(hit.time, 0.5);
  EXPECT_GE(hit.time, 0.5 - tolerance);
  EXPECT_NEAR(hit.normal.z(), 1.0, 1e-9);
  // Side by side 0.1 apart (never closer) and end to end apart along x: no collision.
  Points beside = x0, beside1 = x1;
  beside[2].y() = beside[3].y() = beside1[2].y() = beside1[3].y() = 0.1;
  EXPECT_FALSE(edge_edge_collision(beside, beside1, 1e-6, hit));
  Points apart = x0, apart1 = x1;
  apart[2].x() = apart1[2].x() = 1.2;
  apart[3].x() = apart1[3].x() = 2.0;
  EXPECT_FALSE(edge_edge_collision(apart, apart1, 1e-6, hit));
}

TEST(SelfCollisionKernels, CoplanarVertexSlidingIntoTheFace) {
  // Everything in z = 0: the vertex slides along y = 0.2 from x = −1 into the triangle, whose
  // edge x = 0 it meets at t = 1/1.3.
  const Points x0 = {V(-1, 0.2, 0), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)};
  Points x1 = x0;
  x1[0] = V(0.3, 0.2, 0);
  ASSERT_TRUE(coplanar_times(x0, x1).degenerate);
  const double tolerance = 1e-8;
  SelfPair hit;
  ASSERT_TRUE(vertex_face_collision(x0, x1, tolerance, hit));
  EXPECT_LE(hit.time, 1.0 / 1.3 + 1e-12);
  EXPECT_GE(hit.time, 1.0 / 1.3 - tolerance);
  EXPECT_NEAR(hit.normal.x(), -1.0, 1e-6);  // it came from −x
  // Stopping before the edge: no collision.
  x1[0] = V(-0.01, 0.2, 0);
  EXPECT_FALSE(vertex_face_collision(x0, x1, 1e-6, hit));
}

// All element pairs of a mesh, brute force: (kind, sorted vertex tuple) of the pairs that
// collide over x0 → x1.
std::set<std::tuple<int, int, int, int, int>> brute_force_collisions(
    const std::vector<std::array<int, 3>>& triangles, const Eigen::VectorXd& x0,
    const Eigen::VectorXd& x1, double tolerance) {
  std::set<std::tuple<int, int, int, int, int>> found;
  std::set<std::pair<int, int>> edges;
  std::set<int> vertices;
  for (const auto& t : triangles)
    for (int k = 0; k < 3; ++k) {
      edges.insert(std::minmax(t[k], t[(k + 1) % 3]));
      vertices.insert(t[k]);
    }
  const auto points = [](const Eigen::VectorXd& x, std::array<int, 4> v) {
    return Points{x.segment<3>(3 * v[0]), x.segment<3>(3 * v[1]), x.segment<3>(3 * v[2]),
                  x.segment<3>(3 * v[3])};
  };
  for (int v : vertices)
    for (const auto& t : triangles) {
      if (v == t[0] || v == t[1] || v == t[2]) continue;
      const std::array<int, 4> ids = {v, t[0], t[1], t[2]};
      SelfPair hit;
      if (vertex_face_collision(points(x0, ids), points(x1, ids), tolerance, hit))
        found.insert({0, v, t[0], t[1], t[2]});
    }
  for (auto a = edges.begin(); a != edges.end(); ++a)
    for (auto b = std::next(a); b != edges.end(); ++b) {
      if (a->first == b->first || a->first == b->second || a->second == b->first ||
          a->second == b->second)
        continue;
      const std::array<int, 4> ids = {a->first, a->second, b->first, b->second};
      SelfPair hit;
      if (edge_edge_collision(points(x0, ids), points(x1, ids), tolerance, hit))
        found.insert({1, std::min(a->first, b->first), std::max(a->first, b->first),
                      std::min(a->second, b->second), std::max(a->second, b->second)});
    }
  return found;
}

std::set<std::tuple<int, int, int, int, int>> keys(const std::vector<SelfPair>& pairs) {
  std::set<std::tuple<int, int, int, int, int>> found;
  for (const SelfPair& p : pairs) {
    const auto& v = p.vertices;
    if (p.kind == SelfPairKind::vertex_face) {
      found.insert({0, v[0], v[1], v[2], v[3]});
    } else {
      const std::pair<int, int> a = std::minmax(v[0], v[1]), b = std::minmax(v[2], v[3]);
      found.insert({1, std::min(a.first, b.first), std::max(a.first, b.first),
                    std::min(a.second, b.second), std::max(a.second, b.second)});
    }
  }
  return found;
}

TEST(SelfCollider, ContinuousQueryFindsWhatAllPairsFind) {
  // A 6×6 and a 16×16 sheet folded over x = 0 and the upper half driven down through the lower
  // one. The larger one's tree (1,023 nodes, 10 levels) is walked to depth 5 and then in pieces
  // on the threads (sim/self_collision.cpp, collect_leaves).
  for (const int cells : {6, 16}) {
    const testing::FoldedSheet sheet = testing::folded_sheet(cells, 0.3, 0.02);
    Eigen::VectorXd x1 = sheet.x;
    for (int i = 0; i < sheet.x.size() / 3; ++i)
      if (sheet.upper[i]) x1[3 * i + 1] -= 0.04;  // 2 cm through the lower layer
    const double tolerance = 1e-6;
    const auto expected = brute_force_collisions(sheet.triangles, sheet.x, x1, tolerance);
    ASSERT_GT(expected.size(), 20u);
    for (bool culling : {false, true}) {
      SelfCollider collider(sheet.triangles, sheet.x);
      collider.set_culling(culling);
      SelfQueryStats stats;
      const std::vector<SelfPair> found = collider.find_collisions(sheet.x, x1, tolerance, &stats);
      EXPECT_EQ(keys(found), expected) << "culling " << culling << ", " << cells << " cells";
      EXPECT_EQ(found.size(), keys(found).size()) << "each pair once";
    }
  }
}

TEST(SelfCollider, QueryOfMovedVerticesFindsWhatAFullQueryFindsThere) {
  // The fail-safe's later rounds: a full query over x0 → x1, then some vertices moved at the
  // end of the step (x1 → x2) and a query restricted to them, which refits only the tree's
  // nodes holding a moved vertex. The moved ones (every third upper vertex, another third
  // than the first lowering) go 2 cm through the lower layer, outside every box the first
  // query fitted: a node not refitted would miss their pairs. The 20-cell sheet's tree (3,199
  // nodes) is refitted on the threads. The expected pairs are the full query's at x2 with a
  // moved vertex (the full query is checked against all pairs above).
  for (const int cells : {6, 20}) {
    const testing::FoldedSheet sheet = testing::folded_sheet(cells, 0.3, 0.02);
    const int n = static_cast<int>(sheet.x.size() / 3);
    Eigen::VectorXd x1 = sheet.x;
    for (int i = 0; i < n; ++i)
      if (sheet.upper[i] && i % 3 == 0) x1[3 * i + 1] -= 0.04;
    Eigen::VectorXd x2 = x1;
    std::vector<unsigned char> moved(static_cast<std::size_t>(n), 0);
    for (int i = 0; i < n; ++i)
      if (sheet.upper[i] && i % 3 == 1) {
        x2[3 * i + 1] -= 0.04;
        moved[i] = 1;
      }
    const double tolerance = 1e-6;
    for (bool culling : {false, true}) {
      SelfCollider full(sheet.triangles, sheet.x);
      full.set_culling(culling);
      const auto with_moved = [&](const std::set<std::tuple<int, int, int, int, int>>& all) {
        std::set<std::tuple<int, int, int, int, int>> kept;
        for (const auto& key : all) {
          const auto [kind, a, b, c, d] = key;
          if (moved[a] || moved[b] || moved[c] || moved[d]) kept.insert(key);
        }
        return kept;
      };
      const auto everything = keys(full.find_collisions(sheet.x, x2, tolerance));
      const auto expected = with_moved(everything);
      ASSERT_GT(expected.size(), 20u);
      SelfCollider restricted(sheet.triangles, sheet.x);
      restricted.set_culling(culling);
      ASSERT_FALSE(restricted.find_collisions(sheet.x, x1, tolerance).empty());
      const auto found = keys(restricted.find_collisions(sheet.x, x2, tolerance, nullptr, &moved));
      // It may also report pairs without a moved vertex (met in a triangle pair with one), but
      // only true ones.
      EXPECT_EQ(with_moved(found), expected) << "culling " << culling << ", " << cells << " cells";
      EXPECT_TRUE(std::includes(everything.begin(), everything.end(), found.begin(), found.end()))
          << "culling " << culling << ", " << cells << " cells";
    }
  }
}

TEST(SelfCollider, ProximityBetweenTheLayersOfAFold) {
  const double thickness = 0.005;
  for (double gap : {0.004, 0.006}) {
    const testing::FoldedSheet sheet = testing::folded_sheet(8, 0.4, gap);
    SelfCollider collider(sheet.triangles, sheet.x);
    const std::vector<SelfPair> pairs = collider.find_proximities(sheet.x, thickness);
    int across = 0;
    for (const SelfPair& p : pairs) {
      // Never adjacent elements: no shared vertex.
      const std::set<int> unique(p.vertices.begin(), p.vertices.end());
      EXPECT_EQ(unique.size(), 4u);
      EXPECT_LT(p.distance, thickness);
      // The separation the weights and normal describe is the reported distance.
      double separation = 0.0;
      for (int k = 0; k < 4; ++k)
        separation += p.weights[k] * p.normal.dot(sheet.x.segment<3>(3 * p.vertices[k]));
      EXPECT_NEAR(separation, p.distance, 1e-12);
      across += sheet.upper[p.vertices[0]] != sheet.upper[p.vertices[3]];
    }
    if (gap < thickness) {
      // Every upper vertex away from the crease (|x| > 2 gaps) sits over the lower layer.
      EXPECT_GT(across, 8 * 8 / 2);
    } else {
      // Only the crease's own tight turn may be closer than the thickness.
      EXPECT_EQ(across, 0);
    }
  }
}

TEST(SelfCollider, FlatSheetIsCulledWhole) {
  const testing::FoldedSheet sheet = testing::folded_sheet(10, 0.5, -1.0);  // flat: no fold
  SelfCollider collider(sheet.triangles, sheet.x);
  SelfQueryStats stats;
  EXPECT_TRUE(collider.find_proximities(sheet.x, 0.005, &stats).empty());
  EXPECT_EQ(stats.culled_triangles, stats.triangles);
  EXPECT_EQ(stats.triangle_pairs, 0);
  // Folded, the root's normals span 180°: the two halves are not culled together, each is.
  const testing::FoldedSheet folded = testing::folded_sheet(10, 0.5, 0.02);
  SelfCollider folded_collider(folded.triangles, folded.x);
  folded_collider.find_proximities(folded.x, 0.005, &stats);
  EXPECT_LT(stats.culled_triangles, stats.triangles);
  EXPECT_GT(stats.triangle_pairs, 0);
}

}  // namespace
}  // namespace sd::sim
