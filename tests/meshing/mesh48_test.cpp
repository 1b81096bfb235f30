#include "meshing/mesh48.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <tuple>

#include "meshing/quad_mesh.hpp"
#include "tests/meshing/mesh48_fixtures.hpp"

namespace sd::meshing {

// Reaches into a mesh to break it on purpose, so that validate() is seen to catch each kind of
// damage (a validate() that always passed would let every other test here pass too).
struct Mesh48TestAccess {
  static void swap_diagonal_ends(Mesh48& m, TriangleId t) {
    std::swap(m.triangles_[t.value()].v[1], m.triangles_[t.value()].v[2]);
  }
  static void set_level(Mesh48& m, TriangleId t, int level) {
    m.triangles_[t.value()].level = level;
  }
  static void clear_neighbor(Mesh48& m, TriangleId t, int k) {
    m.triangles_[t.value()].adj[k] = {};
  }
  static void nudge_rest(Mesh48& m, VertexId v, double dx) {
    m.vertices_[v.value()].rest.x() += dx;
  }
  static void drop_child(Mesh48& m, BlockId k, int i) { m.blocks_[k.value()].child[i] = {}; }
  static void miscount(Mesh48& m) { ++m.triangle_count_; }
  // Removes a triangle cleanly from the slots and its neighbours: leaves a hole in the surface.
  static void cut_out(Mesh48& m, TriangleId t) {
    for (const TriangleId n : m.triangles_[t.value()].adj)
      if (n.valid())
        for (TriangleId& back : m.triangles_[n.value()].adj)
          if (back == t) back = {};
    m.free_triangle(t);
  }
};

namespace {

using testing::icosphere;
using testing::quad_grid;
using testing::triangle_sheet;

std::string joined(const std::vector<std::string>& problems) {
  std::string text;
  for (const std::string& p : problems) text += p + "\n";
  return text;
}

#define EXPECT_VALID(mesh)                               \
  do {                                                   \
    const auto problems_ = (mesh).validate();            \
    EXPECT_TRUE(problems_.empty()) << joined(problems_); \
  } while (false)

// Triangles as (apex, b, c) vertex-id triples and leaf blocks as (level, b, c, A, D), sorted:
// equal snapshots mean equal topology whatever the triangle and block ids are.
struct Snapshot {
  std::vector<std::array<int, 3>> triangles;
  std::vector<std::array<int, 5>> blocks;
  bool operator==(const Snapshot&) const = default;
};

Snapshot snapshot(const Mesh48& mesh) {
  Snapshot s;
  for (const TriangleId t : mesh.live_triangles()) {
    const auto& v = mesh.vertices(t);
    s.triangles.push_back({v[0].value(), v[1].value(), v[2].value()});
  }
  for (const BlockId k : mesh.leaf_blocks()) {
    const auto d = mesh.diagonal(k);
    const auto a = mesh.apexes(k);
    // A block's sides may be listed in either order: normalise on the smaller apex.
    if (a[1].valid() && a[1] < a[0])
      s.blocks.push_back({mesh.level(k), d[1].value(), d[0].value(), a[1].value(), a[0].value()});
    else
      s.blocks.push_back({mesh.level(k), d[0].value(), d[1].value(), a[0].value(), a[1].value()});
  }
  std::sort(s.triangles.begin(), s.triangles.end());
  std::sort(s.blocks.begin(), s.blocks.end());
  return s;
}

Eigen::Vector3d unnormalised_normal(const Mesh48& mesh, TriangleId t) {
  const auto& v = mesh.vertices(t);
  const Eigen::Vector3d a = mesh.rest_position(v[0]);
  return (mesh.rest_position(v[1]) - a).cross(mesh.rest_position(v[2]) - a);
}

// ---------------------------------------------------------------------------------------------
// Construction from quads

TEST(Mesh48Quads, RhombusTakesTheDiagonalWithTheLargerSmallestAngle) {
  // Diagonal along x (length 4) gives 26.6° corners; along y (length 2) the smallest is 53.1°.
  Eigen::MatrixX3d v(4, 3);
  v << -2, 0, 0, 0, -1, 0, 2, 0, 0, 0, 1, 0;
  Eigen::MatrixX4i q(1, 4);
  q << 0, 1, 2, 3;
  const Mesh48 mesh = Mesh48::from_quads(v, q);
  ASSERT_EQ(mesh.block_count(), 1);
  const auto d = mesh.diagonal(BlockId(0));
  EXPECT_EQ((std::set<int>{d[0].value(), d[1].value()}), (std::set<int>{1, 3}));
  EXPECT_VALID(mesh);
  // Rotating the corner order must not change the choice.
  q << 1, 2, 3, 0;
  const auto d2 = Mesh48::from_quads(v, q).diagonal(BlockId(0));
  EXPECT_EQ((std::set<int>{d2[0].value(), d2[1].value()}), (std::set<int>{1, 3}));
}

TEST(Mesh48Quads, GridGivesOneLevelZeroBlockPerQuad) {
  const int nx = 5, ny = 3;
  const auto g = quad_grid(nx, ny, 0.1);
  const Mesh48 mesh = Mesh48::from_quads(g.vertices, g.quads);
  EXPECT_VALID(mesh);
  EXPECT_EQ(mesh.vertex_count(), (nx + 1) * (ny + 1));
  EXPECT_EQ(mesh.triangle_count(), 2 * nx * ny);
  EXPECT_EQ(mesh.block_count(), nx * ny);
  EXPECT_TRUE(mesh.is_compact());
  EXPECT_EQ(mesh.max_level(), 0);
  EXPECT_NEAR(mesh.total_rest_area(), nx * ny * 0.01, 1e-14);
  for (const BlockId k : mesh.leaf_blocks()) {
    EXPECT_EQ(mesh.level(k), 0);
    EXPECT_TRUE(mesh.triangles(k)[1].valid());  // every quad block has both triangles
    EXPECT_FALSE(mesh.is_pending(k));
  }
  for (const TriangleId t : mesh.live_triangles()) {
    // Each triangle lies in its source quad: its centroid is inside the quad's square.
    const int q = mesh.source_face(t);
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const VertexId v : mesh.vertices(t)) centroid += mesh.rest_position(v) / 3;
    EXPECT_NEAR(centroid.x(), (q % nx + 0.5) * 0.1, 0.05);
    EXPECT_NEAR(centroid.y(), (q / nx + 0.5) * 0.1, 0.05);
  }
  const Mesh48Arrays arrays = mesh.arrays();
  EXPECT_EQ(arrays.faces.rows(), 2 * nx * ny);
  EXPECT_EQ(arrays.rest_positions, g.vertices);
  // Interior edges: quad edges between two quads plus one diagonal per quad.
  EXPECT_EQ(arrays.interior_edges.rows(), nx * (ny - 1) + ny * (nx - 1) + nx * ny);
  // Counter-clockwise quads in the xy plane give +z normals.
  for (Eigen::Index f = 0; f < arrays.faces.rows(); ++f) {
    const Eigen::Vector3d a = arrays.rest_positions.row(arrays.faces(f, 0));
    const Eigen::Vector3d b = arrays.rest_positions.row(arrays.faces(f, 1));
    const Eigen::Vector3d c = arrays.rest_positions.row(arrays.faces(f, 2));
    EXPECT_GT((b - a).cross(c - a).z(), 0);
  }
}

TEST(Mesh48Quads, QuadMeshOverloadMatchesArrays) {
  const auto g = quad_grid(3, 2);
  QuadMesh qm{g.vertices, g.quads};
  EXPECT_EQ(snapshot(Mesh48::from_quads(qm)), snapshot(Mesh48::from_quads(g.vertices, g.quads)));
}

TEST(Mesh48Quads, RejectsMeshesThatCannotBeSimulated) {
  const auto g = quad_grid(2, 2);
  const auto expect_error = [&](const Eigen::MatrixX3d& v, const Eigen::MatrixX4i& q,
                                const std::string& fragment) {
    try {
      (void)Mesh48::from_quads(v, q);
      ADD_FAILURE() << "no error, expected one mentioning '" << fragment << "'";
    } catch (const Mesh48InputError& error) {
      EXPECT_NE(std::string(error.what()).find(fragment), std::string::npos) << error.what();
    }
  };
  Eigen::MatrixX4i q = g.quads;
  q(1, 2) = 99;
  expect_error(g.vertices, q, "outside");
  q = g.quads;
  q(0, 2) = q(0, 0);
  expect_error(g.vertices, q, "twice");
  q = g.quads;
  q.row(3) = q.row(3).reverse().eval();  // one quad turned over
  expect_error(g.vertices, q, "consistently oriented");
  Eigen::MatrixX3d v(g.vertices.rows() + 1, 3);
  v << g.vertices, Eigen::RowVector3d(5, 5, 5);
  expect_error(v, g.quads, "not used by any face");
  v = g.vertices;
  v.row(1) = v.row(0);  // quad 0 collapses to a triangle with a zero-area half
  expect_error(v.topRows(g.vertices.rows()), g.quads, "zero area");
  v = g.vertices;
  v(4, 1) = std::nan("");
  expect_error(v, g.quads, "finite");
  // A bow-tie: two quads touching at one vertex only.
  Eigen::MatrixX3d bow(7, 3);
  bow << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 2, 1, 0, 2, 2, 0, 1, 2, 0;
  Eigen::MatrixX4i bq(2, 4);
  bq << 0, 1, 2, 3, 2, 4, 5, 6;
  expect_error(bow, bq, "non-manifold vertex");
}

// ---------------------------------------------------------------------------------------------
// √3 construction

TEST(Mesh48Sqrt3, ClosedSphereHasOneBlockPerEdge) {
  const TriMesh sphere = icosphere(2);
  const int nv = static_cast<int>(sphere.vertex_count()),
            nf = static_cast<int>(sphere.face_count());
  const int ne = 3 * nf / 2;
  Sqrt3Stats stats;
  const Mesh48 mesh = Mesh48::from_triangles_sqrt3(sphere, &stats);
  EXPECT_VALID(mesh);
  EXPECT_EQ(mesh.block_count(), ne);
  EXPECT_EQ(stats.blocks, ne);
  EXPECT_EQ(stats.boundary_blocks, 0);
  EXPECT_EQ(stats.unswapped_blocks, 0);
  EXPECT_EQ(mesh.vertex_count(), nv + nf);
  EXPECT_EQ(mesh.triangle_count(), 2 * ne);
  // The swapped triangles span the dihedral angle at each input edge, so on a curved surface
  // their area is a little smaller than the input's (exactly equal on a flat sheet).
  EXPECT_NEAR(mesh.total_rest_area(), face_areas(sphere).sum(), 0.01 * face_areas(sphere).sum());
  // Swapped: every block's diagonal joins two face centres, its apexes are input vertices.
  for (const BlockId k : mesh.leaf_blocks()) {
    for (const VertexId v : mesh.diagonal(k)) EXPECT_GE(v.value(), nv);
    for (const VertexId v : mesh.apexes(k)) EXPECT_LT(v.value(), nv);
  }
  // A triangle's source face is one whose centre it touches; refinement passes it down.
  Mesh48 refined = mesh;
  for (const BlockId k : refined.leaf_blocks())
    if (refined.can_split(k)) (void)refined.split(k);
  for (const TriangleId t : mesh.live_triangles()) {
    const auto& v = mesh.vertices(t);
    const VertexId centre(nv + mesh.source_face(t));
    EXPECT_TRUE(std::find(v.begin(), v.end(), centre) != v.end());
  }
  std::vector<int> per_face(static_cast<std::size_t>(nf), 0);
  for (const TriangleId t : refined.live_triangles()) ++per_face[refined.source_face(t)];
  for (const int count : per_face) EXPECT_EQ(count, 6);  // 3 triangles per face, each halved
  // Face centres are the centroids and input vertices keep their positions.
  for (int f = 0; f < nf; ++f) {
    const Eigen::Vector3d centre =
        (sphere.vertices.row(sphere.faces(f, 0)) + sphere.vertices.row(sphere.faces(f, 1)) +
         sphere.vertices.row(sphere.faces(f, 2)))
            .transpose() /
        3;
    EXPECT_LT((mesh.rest_position(VertexId(nv + f)) - centre).norm(), 1e-15);
  }
  // Orientation follows the input: outward normals on the sphere.
  for (const TriangleId t : mesh.live_triangles()) {
    const auto& v = mesh.vertices(t);
    EXPECT_GT(unnormalised_normal(mesh, t).dot(mesh.rest_position(v[0])), 0);
  }
}

TEST(Mesh48Sqrt3, OpenSheetGivesBoundaryBlocksWithOneTriangle) {
  const int nx = 4, ny = 3;
  const TriMesh sheet = triangle_sheet(nx, ny);
  const TriMeshTopology topo = analyse_topology(sheet);
  const int nf = static_cast<int>(sheet.face_count());
  const int boundary = static_cast<int>(topo.boundary_edges);
  const int ne = (3 * nf + boundary) / 2;
  Sqrt3Stats stats;
  const Mesh48 mesh = Mesh48::from_triangles_sqrt3(sheet, &stats);
  EXPECT_VALID(mesh);
  EXPECT_EQ(boundary, 2 * (nx + ny));
  EXPECT_EQ(mesh.block_count(), ne);
  EXPECT_EQ(stats.boundary_blocks, boundary);
  EXPECT_EQ(mesh.triangle_count(), 2 * (ne - boundary) + boundary);
  int single = 0;
  for (const BlockId k : mesh.leaf_blocks()) {
    if (mesh.triangles(k)[1].valid()) continue;
    ++single;
    EXPECT_FALSE(mesh.is_pending(k));  // a boundary block, not waiting for a neighbour
    EXPECT_TRUE(mesh.on_boundary(mesh.diagonal(k)[0]));
    EXPECT_TRUE(mesh.on_boundary(mesh.diagonal(k)[1]));
  }
  EXPECT_EQ(single, boundary);
  EXPECT_NEAR(mesh.total_rest_area(), nx * ny, 1e-12);
}

TEST(Mesh48Sqrt3, KeepsTheInputEdgeWhereASwapWouldFold) {
  // Two thin triangles meeting at edge 0-1, both leaning past vertex 1: their centres lie beyond
  // the edge's end, so the centre-to-centre segment misses the edge and a swap would fold.
  TriMesh m;
  m.vertices.resize(4, 3);
  m.vertices << 0, 0, 0, 10, 0, 0, 25, 0.2, 0, 25, -0.2, 0;
  m.faces.resize(2, 3);
  m.faces << 0, 1, 2, 1, 0, 3;
  Sqrt3Stats stats;
  const Mesh48 mesh = Mesh48::from_triangles_sqrt3(m, &stats);
  EXPECT_EQ(stats.blocks, 5);
  EXPECT_EQ(stats.unswapped_blocks, 1);
  EXPECT_VALID(mesh);
  for (const TriangleId t : mesh.live_triangles()) EXPECT_GT(unnormalised_normal(mesh, t).z(), 0);
  // The unswapped block refines like any other.
  Mesh48 refined = mesh;
  for (int round = 0; round < 3; ++round)
    for (const BlockId k : refined.leaf_blocks())
      if (refined.can_split(k)) (void)refined.split(k);
  EXPECT_VALID(refined);
  EXPECT_GE(refined.max_level(), 3);
}

TEST(Mesh48Sqrt3, RejectsInconsistentOrientation) {
  TriMesh sheet = triangle_sheet(2, 2);
  sheet.faces.row(3) = sheet.faces.row(3).reverse().eval();
  EXPECT_THROW((void)Mesh48::from_triangles_sqrt3(sheet), Mesh48InputError);
  TriMesh fin = triangle_sheet(1, 1);  // faces (0,1,3), (0,3,2): a third face on edge 0-3
  fin.vertices.conservativeResize(5, 3);
  fin.vertices.row(4) << 0.5, 0.5, 1;
  fin.faces.conservativeResize(3, 3);
  fin.faces.row(2) << 3, 0, 4;
  EXPECT_THROW((void)Mesh48::from_triangles_sqrt3(fin), Mesh48InputError);
}

TEST(Mesh48Validate, ReportsEachKindOfDamage) {
  const auto g = quad_grid(3, 3);
  Mesh48 base = Mesh48::from_quads(g.vertices, g.quads);
  const auto changes = base.split_edge(VertexId(5), VertexId(9));  // three splits, levels 0-1
  ASSERT_TRUE(base.validate().empty());
  const BlockChange& last = changes.back();
  const auto expect_problem = [](const Mesh48& mesh, const std::string& fragment) {
    const auto problems = mesh.validate();
    const bool found = std::any_of(problems.begin(), problems.end(), [&](const std::string& p) {
      return p.find(fragment) != std::string::npos;
    });
    EXPECT_TRUE(found) << "expected '" << fragment << "' among:\n" << joined(problems);
  };
  {
    Mesh48 m = base;
    Mesh48TestAccess::swap_diagonal_ends(m, last.a10);
    expect_problem(m, "orientation");
    expect_problem(m, "does not have the block's apex and diagonal");
  }
  {
    Mesh48 m = base;
    Mesh48TestAccess::set_level(m, last.a11, 3);
    expect_problem(m, "level rule");
  }
  {
    Mesh48 m = base;
    Mesh48TestAccess::clear_neighbor(m, last.a11, 1);
    expect_problem(m, "records neighbour triangle -1");
  }
  {
    Mesh48 m = base;
    Mesh48TestAccess::cut_out(m, last.a20);
    expect_problem(m, "hanging vertex");
    expect_problem(m, "total rest area");
  }
  {
    Mesh48 m = base;
    Mesh48TestAccess::nudge_rest(m, last.e, 1e-9);
    expect_problem(m, "rest midpoint");
  }
  {
    Mesh48 m = base;
    Mesh48TestAccess::drop_child(m, last.block, 2);
    expect_problem(m, "wrong number of children");
    expect_problem(m, "does not list it");
  }
  {
    Mesh48 m = base;
    Mesh48TestAccess::miscount(m);
    expect_problem(m, "count of live triangles");
  }
}

// ---------------------------------------------------------------------------------------------
// Split

TEST(Mesh48Split, OneBlockBisectsItsDiagonalIntoExactHalves) {
  // A curved (non-planar) quad: children must still lie in their parent's plane.
  const auto g = quad_grid(1, 1, 1.0, 0.8);
  Mesh48 mesh = Mesh48::from_quads(g.vertices, g.quads);
  const BlockId k(0);
  const auto [b, c] = mesh.diagonal(k);
  const auto [a, d] = mesh.apexes(k);
  const auto [t0, t1] = mesh.triangles(k);
  const Eigen::Vector3d n1 = mesh.rest_normal(t0), n2 = mesh.rest_normal(t1);
  const double area1 = mesh.rest_area(t0), area2 = mesh.rest_area(t1);

  const auto changes = mesh.split(k);
  EXPECT_VALID(mesh);
  ASSERT_EQ(changes.size(), 1u);
  const BlockChange& ch = changes[0];
  EXPECT_EQ(ch.kind, BlockChange::Kind::kSplit);
  EXPECT_FALSE(ch.forced);
  EXPECT_EQ(ch.block, k);
  EXPECT_EQ(ch.level, 0);
  EXPECT_EQ(ch.a, a);
  EXPECT_EQ(ch.b, b);
  EXPECT_EQ(ch.c, c);
  EXPECT_EQ(ch.d, d);
  EXPECT_EQ(mesh.rest_position(ch.e), 0.5 * (mesh.rest_position(b) + mesh.rest_position(c)));
  EXPECT_EQ(mesh.level(ch.e), 1);
  EXPECT_EQ(mesh.parent_block(ch.e), k);
  EXPECT_TRUE(mesh.is_split(k));
  EXPECT_EQ(mesh.split_vertex(k), ch.e);
  EXPECT_DOUBLE_EQ(ch.area_a1, area1);
  EXPECT_DOUBLE_EQ(ch.area_a2, area2);
  for (const double half : {ch.area_a10, ch.area_a11}) EXPECT_NEAR(half, area1 / 2, 1e-15);
  for (const double half : {ch.area_a20, ch.area_a21}) EXPECT_NEAR(half, area2 / 2, 1e-15);
  // The input face of each side, as the children carry it.
  EXPECT_EQ(ch.source_a1, 0);
  EXPECT_EQ(ch.source_a2, 0);
  for (const TriangleId t : {ch.a10, ch.a11}) EXPECT_EQ(mesh.source_face(t), ch.source_a1);
  for (const TriangleId t : {ch.a20, ch.a21}) EXPECT_EQ(mesh.source_face(t), ch.source_a2);
  // Children as named in DESIGN.md, counter-clockwise like their parents.
  const auto same_cycle = [&](TriangleId t, std::array<VertexId, 3> expected) {
    auto v = mesh.vertices(t);
    for (int r = 0; r < 3; ++r) {
      if (v == expected) return true;
      std::rotate(v.begin(), v.begin() + 1, v.end());
    }
    return false;
  };
  EXPECT_TRUE(same_cycle(ch.a10, {a, ch.e, c}));
  EXPECT_TRUE(same_cycle(ch.a11, {a, b, ch.e}));
  EXPECT_TRUE(same_cycle(ch.a20, {d, ch.e, b}));
  EXPECT_TRUE(same_cycle(ch.a21, {d, c, ch.e}));
  EXPECT_GT(mesh.rest_normal(ch.a10).dot(n1), 1 - 1e-12);
  EXPECT_GT(mesh.rest_normal(ch.a11).dot(n1), 1 - 1e-12);
  EXPECT_GT(mesh.rest_normal(ch.a20).dot(n2), 1 - 1e-12);
  EXPECT_GT(mesh.rest_normal(ch.a21).dot(n2), 1 - 1e-12);
  // The single quad's edges are boundary: its four children are boundary blocks of level 1.
  EXPECT_EQ(mesh.block_count(), 5);
  for (const BlockId child : mesh.children(k)) {
    EXPECT_EQ(mesh.level(child), 1);
    EXPECT_FALSE(mesh.is_pending(child));
    EXPECT_TRUE(mesh.can_split(child));
  }
  EXPECT_EQ(mesh.valence(ch.e), 4);
  EXPECT_TRUE(mesh.can_merge(k));
}

TEST(Mesh48Split, RefusesSplitBlocksAndDeadIds) {
  const auto g = quad_grid(2, 2);
  Mesh48 mesh = Mesh48::from_quads(g.vertices, g.quads);
  (void)mesh.split(BlockId(0));
  EXPECT_FALSE(mesh.can_split(BlockId(0)));
  EXPECT_THROW((void)mesh.split(BlockId(0)), Mesh48OperationError);
  EXPECT_FALSE(mesh.can_split(BlockId(999)));
  EXPECT_THROW((void)mesh.split(BlockId(999)), Mesh48OperationError);
  EXPECT_THROW((void)mesh.split(BlockId{}), Mesh48OperationError);
  EXPECT_THROW((void)mesh.rest_position(VertexId(999)), Mesh48OperationError);
  EXPECT_THROW((void)mesh.split_edge(VertexId(0), VertexId(999)), Mesh48OperationError);
  EXPECT_VALID(mesh);
}

TEST(Mesh48Split, PendingBlockForcesTheCoarserNeighbourFirst) {
  const auto g = quad_grid(2, 1);
  Mesh48 mesh = Mesh48::from_quads(g.vertices, g.quads);
  // The shared quad edge is 1-4. Split the left quad; its child across 1-4 is pending.
  const BlockId left = mesh.triangles(BlockId(0))[0].valid() ? BlockId(0) : BlockId(1);
  const auto first = mesh.split(left);
  ASSERT_EQ(first.size(), 1u);
  BlockId pending;
  for (const BlockId child : mesh.children(left))
    if (mesh.is_pending(child)) pending = child;
  ASSERT_TRUE(pending.valid());
  const auto diag = mesh.diagonal(pending);
  EXPECT_EQ((std::set<int>{diag[0].value(), diag[1].value()}), (std::set<int>{1, 4}));
  EXPECT_VALID(mesh);

  const auto changes = mesh.split(pending);
  EXPECT_VALID(mesh);
  ASSERT_EQ(changes.size(), 2u);
  EXPECT_TRUE(changes[0].forced);
  EXPECT_EQ(changes[0].block, BlockId(1 - left.value()));
  EXPECT_EQ(changes[0].level, 0);
  EXPECT_FALSE(changes[1].forced);
  EXPECT_EQ(changes[1].block, pending);
  EXPECT_EQ(changes[1].level, 1);
  EXPECT_TRUE(changes[1].d.valid());  // completed by the neighbour's child before its split
  EXPECT_EQ(mesh.rest_position(changes[1].e), Eigen::Vector3d(1, 0.5, 0));
  EXPECT_EQ(mesh.max_level(), 2);
}

TEST(Mesh48Split, SplitEdgeOfAQuadEdgeSplitsBothQuadsFirst) {
  const auto g = quad_grid(3, 3);
  Mesh48 mesh = Mesh48::from_quads(g.vertices, g.quads);
  // Interior vertical quad edge between vertices 5 and 9 (x = 1, y in [1, 2]).
  const auto changes = mesh.split_edge(VertexId(5), VertexId(9));
  EXPECT_VALID(mesh);
  ASSERT_EQ(changes.size(), 3u);
  EXPECT_TRUE(changes[0].forced);
  EXPECT_TRUE(changes[1].forced);
  EXPECT_FALSE(changes[2].forced);
  EXPECT_EQ(mesh.rest_position(changes[2].e), Eigen::Vector3d(1, 1.5, 0));
  // Splitting an edge that already is a block diagonal takes one split.
  const auto [b, c] = mesh.diagonal(BlockId(0));
  EXPECT_EQ(mesh.split_edge(b, c).size(), 1u);
  EXPECT_THROW((void)mesh.split_edge(VertexId(0), VertexId(15)), Mesh48OperationError);
  EXPECT_VALID(mesh);
  // A boundary quad edge (vertices 2-3, y = 0): the quad, then the boundary block it leaves.
  const auto boundary = mesh.split_edge(VertexId(2), VertexId(3));
  ASSERT_EQ(boundary.size(), 2u);
  EXPECT_TRUE(boundary[0].forced);
  EXPECT_FALSE(boundary[1].d.valid());
  EXPECT_TRUE(mesh.on_boundary(boundary[1].e));
  EXPECT_EQ(mesh.rest_position(boundary[1].e), Eigen::Vector3d(2.5, 0, 0));
  EXPECT_EQ(mesh.valence(boundary[1].e), 3);
  EXPECT_VALID(mesh);
}

TEST(Mesh48Split, DeepRefinementAtACornerKeepsAdjacentLevelsWithinOne) {
  const auto g = quad_grid(4, 4, 0.25);
  Mesh48 mesh = Mesh48::from_quads(g.vertices, g.quads);
  // Keep splitting the block of the triangle at the centre vertex (12) until level 14.
  int forced = 0;
  while (mesh.max_level() < 14) {
    TriangleId finest;
    for (const TriangleId t : mesh.live_triangles()) {
      const auto& v = mesh.vertices(t);
      if (std::find(v.begin(), v.end(), VertexId(12)) == v.end()) continue;
      if (!finest.valid() || mesh.level(t) > mesh.level(finest)) finest = t;
    }
    const auto changes = mesh.split(mesh.block(finest));
    for (const BlockChange& ch : changes) forced += ch.forced ? 1 : 0;
    ASSERT_TRUE(mesh.validate().empty()) << joined(mesh.validate());
  }
  EXPECT_GT(forced, 10);  // the level rule had to pull neighbours along
  for (const TriangleId t : mesh.live_triangles())
    for (int k = 0; k < 3; ++k) {
      if (mesh.neighbor(t, k).valid()) {
        EXPECT_LE(std::abs(mesh.level(t) - mesh.level(mesh.neighbor(t, k))), 1);
      }
    }
}

// ---------------------------------------------------------------------------------------------
// Merge

TEST(Mesh48Merge, SplitThenMergeRestoresTheExactTopology) {
  const auto g = quad_grid(4, 4);
  Mesh48 mesh = Mesh48::from_quads(g.vertices, g.quads);
  std::mt19937 rng(7);
  // Build some irregular state first, then round-trip blocks at several levels.
  for (int i = 0; i < 40; ++i) {
    const auto leaves = mesh.leaf_blocks();
    (void)mesh.split(leaves[rng() % leaves.size()]);
  }
  ASSERT_TRUE(mesh.validate().empty());
  int round_trips = 0, with_forced = 0;
  for (const BlockId k : mesh.leaf_blocks()) {
    const Snapshot before = snapshot(mesh);
    const double area = mesh.total_rest_area();
    const auto changes = mesh.split(k);
    ASSERT_TRUE(mesh.validate().empty());
    with_forced += changes.size() > 1 ? 1 : 0;
    for (auto it = changes.rbegin(); it != changes.rend(); ++it) {
      ASSERT_TRUE(mesh.can_merge(it->block));
      EXPECT_EQ(mesh.child_triangles(it->block),
                (std::array<TriangleId, 4>{it->a11, it->a10, it->a21, it->a20}));
      const BlockChange undo = mesh.merge(it->block);
      EXPECT_EQ(undo.kind, BlockChange::Kind::kMerge);
      EXPECT_EQ(undo.e, it->e);
      EXPECT_EQ(undo.a, it->a);
      EXPECT_EQ(undo.d, it->d);
      EXPECT_EQ((std::set<VertexId>{undo.b, undo.c}), (std::set<VertexId>{it->b, it->c}));
      ASSERT_TRUE(mesh.validate().empty()) << joined(mesh.validate());
    }
    EXPECT_EQ(snapshot(mesh), before);
    EXPECT_NEAR(mesh.total_rest_area(), area, 1e-12 * area);
    ++round_trips;
  }
  EXPECT_GT(round_trips, 50);
  EXPECT_GT(with_forced, 5);
}

TEST(Mesh48Merge, OnlyWhenNoChildIsSplit) {
  const auto g = quad_grid(3, 3);
  Mesh48 mesh = Mesh48::from_quads(g.vertices, g.quads);
  EXPECT_FALSE(mesh.can_merge(BlockId(4)));  // never split
  EXPECT_THROW((void)mesh.merge(BlockId(4)), Mesh48OperationError);
  const auto first = mesh.split(BlockId(4));  // the centre quad
  const VertexId e = first[0].e;
  EXPECT_TRUE(mesh.can_merge(BlockId(4)));
  // Split one of its children (forcing the neighbour quad): the parent must stay split.
  const BlockId child = mesh.children(BlockId(4))[0];
  (void)mesh.split(child);
  EXPECT_VALID(mesh);
  EXPECT_GT(mesh.valence(e), 4);
  EXPECT_FALSE(mesh.can_merge(BlockId(4)));
  EXPECT_FALSE(mesh.child_triangles(BlockId(4))[0].valid());  // the split child
  EXPECT_TRUE(mesh.child_triangles(BlockId(4))[1].valid());
  EXPECT_THROW((void)mesh.merge(BlockId(4)), Mesh48OperationError);
  // Undo the child's split: the parent is mergeable again.
  (void)mesh.merge(child);
  EXPECT_EQ(mesh.valence(e), 4);
  EXPECT_TRUE(mesh.can_merge(BlockId(4)));
  (void)mesh.merge(BlockId(4));
  EXPECT_VALID(mesh);
  EXPECT_FALSE(mesh.alive(e));
}

// The merge rule in words: a split block merges iff its vertex E has valence 4 (3 on the
// boundary), i.e. no finer block depends on it.
TEST(Mesh48Merge, MergeableExactlyWhenTheSplitVertexHasItsOriginalValence) {
  const auto g = quad_grid(4, 4);
  Mesh48 mesh = Mesh48::from_quads(g.vertices, g.quads);
  std::mt19937 rng(11);
  for (int i = 0; i < 120; ++i) {
    const auto leaves = mesh.leaf_blocks();
    (void)mesh.split(leaves[rng() % leaves.size()]);
  }
  int mergeable = 0, blocked = 0;
  for (int k = 0; k < mesh.block_capacity(); ++k) {
    const BlockId id(k);
    if (!mesh.alive(id) || !mesh.is_split(id)) continue;
    const VertexId e = mesh.split_vertex(id);
    const int original = mesh.on_boundary(e) ? 3 : 4;
    EXPECT_EQ(mesh.can_merge(id), mesh.valence(e) == original) << "block " << k;
    (mesh.can_merge(id) ? mergeable : blocked) += 1;
  }
  EXPECT_GT(mergeable, 10);
  EXPECT_GT(blocked, 10);
}

// ---------------------------------------------------------------------------------------------
// Randomised operations

struct StressResult {
  int splits = 0, forced = 0, merges = 0, max_level = 0, max_triangles = 0;
};

// Random splits (with their forced splits) and merges, validating after each, checking that
// each change conserves rest area and that the total stays the input's.
StressResult stress(Mesh48& mesh, int operations, unsigned seed, int max_level, int target_size,
                    int compact_every = 0) {
  StressResult r;
  std::mt19937 rng(seed);
  const double area0 = mesh.total_rest_area();
  for (int op = 0; op < operations; ++op) {
    const bool grow = mesh.triangle_count() < target_size;
    const double p_split = grow ? 0.7 : 0.3;
    const auto mergeable = mesh.mergeable_blocks();
    const bool do_split =
        mergeable.empty() || std::uniform_real_distribution<double>(0, 1)(rng) < p_split;
    std::vector<BlockChange> changes;
    if (do_split) {
      auto leaves = mesh.leaf_blocks();
      std::erase_if(leaves, [&](BlockId k) { return mesh.level(k) >= max_level; });
      if (leaves.empty()) continue;
      changes = mesh.split(leaves[rng() % leaves.size()]);
      for (const BlockChange& ch : changes) (ch.forced ? r.forced : r.splits) += 1;
    } else {
      changes.push_back(mesh.merge(mergeable[rng() % mergeable.size()]));
      ++r.merges;
    }
    for (const BlockChange& ch : changes) {
      const double parents = ch.area_a1 + ch.area_a2;
      const double children = ch.area_a10 + ch.area_a11 + ch.area_a20 + ch.area_a21;
      EXPECT_NEAR(children, parents, 1e-13 * parents) << "operation " << op;
    }
    const auto problems = mesh.validate();
    if (!problems.empty()) {
      ADD_FAILURE() << "after operation " << op << ":\n" << joined(problems);
      return r;
    }
    EXPECT_NEAR(mesh.total_rest_area(), area0, 1e-11 * area0);
    r.max_level = std::max(r.max_level, mesh.max_level());
    r.max_triangles = std::max(r.max_triangles, mesh.triangle_count());
    if (compact_every > 0 && (op + 1) % compact_every == 0) {
      (void)mesh.compact();
      EXPECT_TRUE(mesh.is_compact());
    }
  }
  return r;
}

TEST(Mesh48Random, ThousandsOfSplitsAndMergesOnAQuadGridStayValid) {
  const auto g = quad_grid(4, 4, 0.5, 1.0);
  Mesh48 mesh = Mesh48::from_quads(g.vertices, g.quads);
  const StressResult r = stress(mesh, 4000, 2024, 10, 500, 700);
  EXPECT_GT(r.splits, 1000);
  EXPECT_GT(r.merges, 1000);
  EXPECT_GT(r.forced, 200);
  EXPECT_GE(r.max_level, 6);
  // Merging everything back gives the input's blocks again.
  for (auto m = mesh.mergeable_blocks(); !m.empty(); m = mesh.mergeable_blocks())
    for (const BlockId k : m)
      if (mesh.can_merge(k)) (void)mesh.merge(k);
  EXPECT_VALID(mesh);
  EXPECT_EQ(mesh.triangle_count(), 32);
  EXPECT_EQ(mesh.vertex_count(), 25);
  EXPECT_EQ(snapshot(mesh), snapshot(Mesh48::from_quads(g.vertices, g.quads)));
}

TEST(Mesh48Random, ThousandsOfSplitsAndMergesOnSqrt3MeshesStayValid) {
  {
    Mesh48 sphere = Mesh48::from_triangles_sqrt3(icosphere(1));
    const StressResult r = stress(sphere, 2500, 99, 9, 900, 500);
    EXPECT_GT(r.merges, 500);
    EXPECT_GT(r.forced, 100);
  }
  {
    Mesh48 sheet = Mesh48::from_triangles_sqrt3(triangle_sheet(3, 2));
    const StressResult r = stress(sheet, 2500, 5, 10, 400, 0);
    EXPECT_GT(r.merges, 500);
    EXPECT_GT(r.forced, 100);
  }
}

TEST(Mesh48Random, TinyAndHugeMeshesWorkTheSame) {
  for (const double scale : {1e-4, 1e4}) {
    SCOPED_TRACE(scale);
    const auto g = quad_grid(3, 3, scale, 1.2);
    Mesh48 quads = Mesh48::from_quads(g.vertices, g.quads);
    const StressResult rq = stress(quads, 1200, 3, 12, 400, 300);
    EXPECT_GE(rq.max_level, 8);
    Mesh48 sphere = Mesh48::from_triangles_sqrt3(icosphere(0, scale));
    const StressResult rs = stress(sphere, 1200, 4, 12, 400, 0);
    EXPECT_GE(rs.max_level, 6);
  }
}

// ---------------------------------------------------------------------------------------------
// Export and compaction

TEST(Mesh48Arrays, InteriorEdgesListBothOppositeVertices) {
  const auto g = quad_grid(3, 3);
  Mesh48 mesh = Mesh48::from_quads(g.vertices, g.quads);
  (void)stress(mesh, 300, 17, 6, 300);
  const Mesh48Arrays arrays = mesh.arrays();
  const auto has_cycle = [&](int f, int i, int j, int k) {
    for (int r = 0; r < 3; ++r)
      if (arrays.faces(f, r) == i && arrays.faces(f, (r + 1) % 3) == j &&
          arrays.faces(f, (r + 2) % 3) == k)
        return true;
    return false;
  };
  std::set<std::pair<int, int>> edges;
  for (Eigen::Index e = 0; e < arrays.interior_edges.rows(); ++e) {
    const int i = arrays.interior_edges(e, 0), j = arrays.interior_edges(e, 1);
    EXPECT_TRUE(has_cycle(arrays.edge_faces(e, 0), i, j, arrays.interior_edges(e, 2)));
    EXPECT_TRUE(has_cycle(arrays.edge_faces(e, 1), j, i, arrays.interior_edges(e, 3)));
    EXPECT_TRUE(edges.insert(std::minmax(i, j)).second);
  }
  // Euler: 3F = 2 E_interior + E_boundary.
  int boundary = 0;
  for (Eigen::Index f = 0; f < arrays.faces.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      boundary += mesh.neighbor(arrays.triangle_ids[f], k).valid() ? 0 : 1;
  EXPECT_EQ(3 * arrays.faces.rows(), 2 * arrays.interior_edges.rows() + boundary);
  for (Eigen::Index f = 0; f < arrays.faces.rows(); ++f) {
    EXPECT_EQ(arrays.face_level(f), mesh.level(arrays.triangle_ids[f]));
    EXPECT_EQ(arrays.face_block(f), mesh.block(arrays.triangle_ids[f]).value());
  }
}

TEST(Mesh48Arrays, CompactRenumbersWithoutChangingTheMesh) {
  const auto g = quad_grid(4, 3);
  Mesh48 mesh = Mesh48::from_quads(g.vertices, g.quads);
  (void)stress(mesh, 600, 23, 7, 400);
  ASSERT_FALSE(mesh.is_compact());
  const Mesh48Arrays before = mesh.arrays();
  const Mesh48Remap remap = mesh.compact();
  EXPECT_TRUE(mesh.is_compact());
  EXPECT_VALID(mesh);
  const Mesh48Arrays after = mesh.arrays();
  // Order-preserving: rows keep their order, and ids now equal rows.
  EXPECT_EQ(before.faces, after.faces);
  EXPECT_EQ(before.rest_positions, after.rest_positions);
  EXPECT_EQ(before.interior_edges, after.interior_edges);
  for (std::size_t r = 0; r < after.vertex_ids.size(); ++r) {
    EXPECT_EQ(after.vertex_ids[r].value(), static_cast<int>(r));
    EXPECT_EQ(remap.vertices[before.vertex_ids[r].value()], static_cast<int>(r));
  }
  for (std::size_t f = 0; f < after.triangle_ids.size(); ++f) {
    EXPECT_EQ(remap.triangles[before.triangle_ids[f].value()], static_cast<int>(f));
    EXPECT_EQ(remap.blocks[before.face_block(static_cast<Eigen::Index>(f))],
              after.face_block(static_cast<Eigen::Index>(f)));
  }
  EXPECT_EQ(remap.vertex_count, mesh.vertex_count());
  EXPECT_EQ(remap.triangle_count, mesh.triangle_count());
  EXPECT_EQ(remap.block_count, mesh.block_count());
  // Operations keep working on the compacted mesh.
  (void)stress(mesh, 300, 29, 7, 400);
}

}  // namespace
}  // namespace sd::meshing
