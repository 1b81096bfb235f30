#include "meshing/mesh48.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <sstream>
#include <utility>

#include "meshing/check.hpp"
#include "meshing/mesh48_internal.hpp"
#include "meshing/quad_mesh.hpp"

namespace sd::meshing {
namespace {

// A triangle is degenerate when its area is below this fraction of its longest edge squared.
constexpr double kDegenerateAreaRatio = 1e-14;
// Walking around a vertex more than this many triangles means the adjacency is corrupt.
constexpr int kMaxStar = 1 << 16;

double triangle_area(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  return 0.5 * (b - a).cross(c - a).norm();
}

// Vertices, triangles and blocks live in slot vectors: a freed slot goes on a LIFO free list and
// is reused, reset to a fresh record, by the next allocation of its kind. `count` is the number
// of live slots.
template <class Record>
int take_slot(std::vector<Record>& slots, std::vector<int>& free, int& count) {
  ++count;
  int id;
  if (free.empty()) {
    id = static_cast<int>(slots.size());
    slots.emplace_back();
  } else {
    id = free.back();
    free.pop_back();
    slots[id] = Record{};
  }
  slots[id].alive = true;
  return id;
}

template <class Record>
void release_slot(std::vector<Record>& slots, std::vector<int>& free, int& count, int id) {
  slots[id].alive = false;
  free.push_back(id);
  --count;
}

bool degenerate(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const double longest =
      std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
  const double area = triangle_area(a, b, c);
  return !std::isfinite(area) || longest == 0 || area <= kDegenerateAreaRatio * longest;
}

// Smallest interior angle (radians) of a triangle given by its corners: the one opposite the
// shortest edge.
double min_angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const double ab = (b - a).squaredNorm(), bc = (c - b).squaredNorm(), ca = (a - c).squaredNorm();
  const Eigen::Vector3d& p = (bc <= ab && bc <= ca) ? a : (ca <= ab ? b : c);  // opposite corner
  const Eigen::Vector3d& q = (&p == &a) ? b : (&p == &b ? c : a);
  const Eigen::Vector3d& r = (&p == &a) ? c : (&p == &b ? a : b);
  const Eigen::Vector3d u = q - p, w = r - p;
  return std::atan2(u.cross(w).norm(), u.dot(w));
}

}  // namespace

using detail::debug_validate;
using detail::edge_name;
using detail::HalfEdgeIndex;
using detail::kDuplicateEdgeText;

// ---------------------------------------------------------------------------------------------
// Construction

Mesh48 Mesh48::build(std::vector<Eigen::Vector3d> rest,
                     const std::vector<std::array<int, 3>>& triangles) {
  Mesh48 m;
  const int nv = static_cast<int>(rest.size());
  const int nt = static_cast<int>(triangles.size());
  m.vertices_.resize(rest.size());
  for (int i = 0; i < nv; ++i) {
    if (!rest[i].allFinite())
      throw Mesh48InputError("vertex " + std::to_string(i) +
                             " has a coordinate that is not a finite number");
    m.vertices_[i].rest = rest[i];
    m.vertices_[i].alive = true;
  }
  m.triangles_.resize(triangles.size());
  m.root_normals_.resize(triangles.size());
  m.root_areas_.resize(triangles.size());
  m.root_corners_.resize(triangles.size());

  for (int t = 0; t < nt; ++t) {
    Triangle& tri = m.triangles_[t];
    for (int k = 0; k < 3; ++k) tri.v[k] = VertexId(triangles[t][k]);
    tri.alive = true;
    tri.root = t;
    const Eigen::Vector3d& a = rest[triangles[t][0]];
    const Eigen::Vector3d& b = rest[triangles[t][1]];
    const Eigen::Vector3d& c = rest[triangles[t][2]];
    if (degenerate(a, b, c))
      throw Mesh48InputError("the triangle on vertices " + std::to_string(triangles[t][0]) + ", " +
                             std::to_string(triangles[t][1]) + ", " +
                             std::to_string(triangles[t][2]) +
                             " has (nearly) zero area; remove the collapsed face first");
    m.root_normals_[t] = (b - a).cross(c - a).normalized();
    m.root_areas_[t] = triangle_area(a, b, c);
    m.root_corners_[t] = {a, b, c};
    m.input_area_ += m.root_areas_[t];
  }
  const HalfEdgeIndex index(nv, nt, [&](int f, int k) { return triangles[f][k]; });
  if (const auto [from, to] = index.duplicate(); from >= 0)
    throw Mesh48InputError("the edge " + edge_name(from, to) + kDuplicateEdgeText);
  std::vector<int> incident(rest.size(), 0);
  for (int from = 0; from < nv; ++from) {
    incident[from] = index.out_degree(from);
    for (const HalfEdgeIndex::Entry* h = index.begin(from); h != index.end(from); ++h) {
      if (const HalfEdgeIndex::Entry* back = index.find(h->to, from)) {
        m.triangles_[h->face].adj[h->corner] = TriangleId(back->face);
      } else {
        m.vertices_[from].on_boundary = true;
        m.vertices_[h->to].on_boundary = true;
        m.input_boundary_length_ += (rest[h->to] - rest[from]).norm();
      }
    }
  }
  for (int i = 0; i < nv; ++i)
    if (incident[i] == 0)
      throw Mesh48InputError("vertex " + std::to_string(i) +
                             " is not used by any face; remove unused vertices first");

  // Pair triangles sharing their diagonal (local edge 0) into level-0 blocks.
  for (int t = 0; t < nt; ++t) {
    Triangle& tri = m.triangles_[t];
    for (int k = 0; k < 3; ++k) m.vertices_[tri.v[k].value()].triangle = TriangleId(t);
    if (tri.block.valid()) continue;
    const BlockId k = m.new_block();
    Block& blk = m.blocks_[k.value()];
    blk.diagonal = {tri.v[1], tri.v[2]};
    blk.apex[0] = tri.v[0];
    blk.tri[0] = TriangleId(t);
    blk.level = 0;
    tri.block = k;
    const TriangleId partner = tri.adj[0];
    if (!partner.valid()) continue;
    Triangle& other = m.triangles_[partner.value()];
    if (other.v[1] != tri.v[2] || other.v[2] != tri.v[1])
      throw std::logic_error("Mesh48::build: the triangles across a block diagonal do not pair");
    if (other.v[0] == tri.v[0])
      throw Mesh48InputError(
          "two faces share all three vertices " + std::to_string(tri.v[0].value()) + ", " +
          std::to_string(tri.v[1].value()) + ", " + std::to_string(tri.v[2].value()) +
          " (a closed two-face pillow); such a piece cannot be simulated");
    blk.apex[1] = other.v[0];
    blk.tri[1] = partner;
    other.block = k;
  }
  m.triangle_count_ = nt;
  m.vertex_count_ = nv;

  // Every vertex must have a single fan of triangles (no bow-tie vertex).
  for (int i = 0; i < nv; ++i) {
    int fan = 0;
    m.for_each_triangle_around(VertexId(i), [&](TriangleId, int) { ++fan; });
    if (fan != incident[i])
      throw Mesh48InputError("vertex " + std::to_string(i) +
                             " joins two pieces of surface at a single point (non-manifold "
                             "vertex); split it into one vertex per piece first");
  }
  debug_validate(m, "Mesh48::build");
  return m;
}

Mesh48 Mesh48::from_quads(const Eigen::MatrixX3d& vertices, const Eigen::MatrixX4i& quads) {
  const Eigen::Index nv = vertices.rows();
  std::vector<Eigen::Vector3d> rest(static_cast<std::size_t>(nv));
  for (Eigen::Index i = 0; i < nv; ++i) rest[i] = vertices.row(i).transpose();
  std::vector<std::array<int, 3>> triangles;
  triangles.reserve(2 * static_cast<std::size_t>(quads.rows()));
  for (Eigen::Index q = 0; q < quads.rows(); ++q) {
    const std::array<int, 4> c = {quads(q, 0), quads(q, 1), quads(q, 2), quads(q, 3)};
    for (int i = 0; i < 4; ++i) {
      if (c[i] < 0 || c[i] >= nv)
        throw Mesh48InputError("quad " + std::to_string(q) + " refers to vertex " +
                               std::to_string(c[i]) + ", outside 0.." + std::to_string(nv - 1));
      for (int j = 0; j < i; ++j)
        if (c[i] == c[j])
          throw Mesh48InputError("quad " + std::to_string(q) + " uses vertex " +
                                 std::to_string(c[i]) + " twice");
    }
    const Eigen::Vector3d& p0 = rest[c[0]];
    const Eigen::Vector3d& p1 = rest[c[1]];
    const Eigen::Vector3d& p2 = rest[c[2]];
    const Eigen::Vector3d& p3 = rest[c[3]];
    // Diagonal 0-2 gives (1, 2, 0) and (3, 0, 2); diagonal 1-3 gives (0, 1, 3) and (2, 3, 1).
    const double angle02 = std::min(min_angle(p1, p2, p0), min_angle(p3, p0, p2));
    const double angle13 = std::min(min_angle(p0, p1, p3), min_angle(p2, p3, p1));
    bool use02 = angle02 > angle13;
    if (std::abs(angle02 - angle13) <= 1e-12)
      use02 = (p2 - p0).squaredNorm() <= (p3 - p1).squaredNorm();
    if (use02) {
      triangles.push_back({c[1], c[2], c[0]});
      triangles.push_back({c[3], c[0], c[2]});
    } else {
      triangles.push_back({c[0], c[1], c[3]});
      triangles.push_back({c[2], c[3], c[1]});
    }
  }
  Mesh48 m = build(std::move(rest), triangles);
  m.root_source_.resize(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) m.root_source_[t] = static_cast<int>(t / 2);
  return m;
}

Mesh48 Mesh48::from_quads(const QuadMesh& mesh) {
  return from_quads(mesh.vertices, mesh.faces);
}

Mesh48 Mesh48::from_triangles_sqrt3(const TriMesh& mesh, Sqrt3Stats* stats) {
  const int nv = static_cast<int>(mesh.vertex_count());
  const int nf = static_cast<int>(mesh.face_count());
  const auto face_slots = static_cast<std::size_t>(std::max(nf, 0));
  std::vector<Eigen::Vector3d> rest(static_cast<std::size_t>(nv + nf));
  for (int i = 0; i < nv; ++i) rest[i] = mesh.vertices.row(i).transpose();
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.faces(f, k);
      if (v < 0 || v >= nv)
        throw Mesh48InputError("face " + std::to_string(f) + " refers to vertex " +
                               std::to_string(v) + ", outside 0.." + std::to_string(nv - 1));
      if (mesh.faces(f, (k + 1) % 3) == v)
        throw Mesh48InputError("face " + std::to_string(f) + " uses vertex " + std::to_string(v) +
                               " twice");
    }
    rest[nv + f] = (rest[mesh.faces(f, 0)] + rest[mesh.faces(f, 1)] + rest[mesh.faces(f, 2)]) / 3;
  }

  // Directed edges of the input; each undirected edge is visited once, from its first face.
  const HalfEdgeIndex index(nv, nf, [&](int f, int k) { return mesh.faces(f, k); });
  if (const auto [from, to] = index.duplicate(); from >= 0)
    throw Mesh48InputError("the edge " + edge_name(from, to) + kDuplicateEdgeText);
  const auto face_across = [&](int from, int to) {
    const HalfEdgeIndex::Entry* back = index.find(to, from);
    return back ? back->face : -1;
  };
  const auto face_normal = [&](int f) {
    const Eigen::Vector3d a = rest[mesh.faces(f, 0)];
    return Eigen::Vector3d((rest[mesh.faces(f, 1)] - a).cross(rest[mesh.faces(f, 2)] - a));
  };

  Sqrt3Stats counts;
  std::vector<std::array<int, 3>> triangles;
  std::vector<int> source;  // input face each triangle is attributed to
  triangles.reserve(6 * face_slots);
  source.reserve(6 * face_slots);
  for (int f = 0; f < nf; ++f) {
    for (int k = 0; k < 3; ++k) {
      const int i = mesh.faces(f, k), j = mesh.faces(f, (k + 1) % 3);
      const int g = face_across(i, j);
      const int cf = nv + f;
      if (g < 0) {  // boundary edge: one triangle, its diagonal is the input edge
        triangles.push_back({cf, i, j});
        source.push_back(f);
        ++counts.blocks;
        ++counts.boundary_blocks;
        continue;
      }
      if (g < f) continue;  // visited from face g already
      const int cg = nv + g;
      ++counts.blocks;
      // Swap the input edge i-j for the centre edge cf-cg unless that folds a triangle over.
      const Eigen::Vector3d reference = face_normal(f) + face_normal(g);
      const auto keeps_side = [&](int a, int b, int c) {
        return !degenerate(rest[a], rest[b], rest[c]) &&
               (rest[b] - rest[a]).cross(rest[c] - rest[a]).dot(reference) > 0;
      };
      if (keeps_side(i, cg, cf) && keeps_side(j, cf, cg)) {
        triangles.push_back({i, cg, cf});
        triangles.push_back({j, cf, cg});
        source.insert(source.end(), {f, g});
      } else {
        triangles.push_back({cf, i, j});
        triangles.push_back({cg, j, i});
        source.insert(source.end(), {f, g});
        ++counts.unswapped_blocks;
      }
    }
  }
  if (stats) *stats = counts;
  Mesh48 m = build(std::move(rest), triangles);
  m.root_source_ = std::move(source);
  debug_validate(m, "Mesh48::from_triangles_sqrt3");
  return m;
}

// ---------------------------------------------------------------------------------------------
// Slots

VertexId Mesh48::new_vertex() {
  return VertexId(take_slot(vertices_, free_vertices_, vertex_count_));
}
TriangleId Mesh48::new_triangle() {
  return TriangleId(take_slot(triangles_, free_triangles_, triangle_count_));
}
BlockId Mesh48::new_block() {
  return BlockId(take_slot(blocks_, free_blocks_, block_count_));
}

void Mesh48::free_vertex(VertexId v) {
  release_slot(vertices_, free_vertices_, vertex_count_, v.value());
}
void Mesh48::free_triangle(TriangleId t) {
  release_slot(triangles_, free_triangles_, triangle_count_, t.value());
}
void Mesh48::free_block(BlockId k) {
  release_slot(blocks_, free_blocks_, block_count_, k.value());
}

bool Mesh48::is_compact() const {
  return free_vertices_.empty() && free_triangles_.empty() && free_blocks_.empty();
}

int Mesh48::max_level() const {
  int level = 0;
  for (const Triangle& t : triangles_)
    if (t.alive) level = std::max(level, t.level);
  return level;
}

// ---------------------------------------------------------------------------------------------
// Accessors (checked: a dead or out-of-range id is a programming error)

const Mesh48::Vertex& Mesh48::vertex_at(VertexId v) const {
  if (!alive(v)) throw Mesh48OperationError("vertex " + std::to_string(v.value()) + " is not live");
  return vertices_[v.value()];
}
const Mesh48::Triangle& Mesh48::triangle_at(TriangleId t) const {
  if (!alive(t))
    throw Mesh48OperationError("triangle " + std::to_string(t.value()) + " is not live");
  return triangles_[t.value()];
}
const Mesh48::Block& Mesh48::block_at(BlockId k) const {
  if (!alive(k)) throw Mesh48OperationError("block " + std::to_string(k.value()) + " is not live");
  return blocks_[k.value()];
}

bool Mesh48::alive(VertexId v) const {
  return v.valid() && v.value() < vertex_capacity() && vertices_[v.value()].alive;
}
bool Mesh48::alive(TriangleId t) const {
  return t.valid() && t.value() < triangle_capacity() && triangles_[t.value()].alive;
}
bool Mesh48::alive(BlockId k) const {
  return k.valid() && k.value() < block_capacity() && blocks_[k.value()].alive;
}

const Eigen::Vector3d& Mesh48::rest_position(VertexId v) const {
  return vertex_at(v).rest;
}
int Mesh48::level(VertexId v) const {
  return vertex_at(v).level;
}
BlockId Mesh48::parent_block(VertexId v) const {
  return vertex_at(v).parent;
}
bool Mesh48::on_boundary(VertexId v) const {
  return vertex_at(v).on_boundary;
}

int Mesh48::valence(VertexId v) const {
  int fan = 0;
  for_each_triangle_around(v, [&](TriangleId, int) { ++fan; });
  return fan + (vertex_at(v).on_boundary ? 1 : 0);
}

const std::array<VertexId, 3>& Mesh48::vertices(TriangleId t) const {
  return triangle_at(t).v;
}
TriangleId Mesh48::neighbor(TriangleId t, int k) const {
  return triangle_at(t).adj.at(k);
}
BlockId Mesh48::block(TriangleId t) const {
  return triangle_at(t).block;
}
int Mesh48::level(TriangleId t) const {
  return triangle_at(t).level;
}
int Mesh48::source_face(TriangleId t) const {
  return root_source_[triangle_at(t).root];
}
int Mesh48::root(TriangleId t) const {
  return triangle_at(t).root;
}
const std::array<Eigen::Vector3d, 3>& Mesh48::root_corners(int r) const {
  return root_corners_.at(static_cast<std::size_t>(r));
}
int Mesh48::root_source(int r) const {
  return root_source_.at(static_cast<std::size_t>(r));
}

double Mesh48::rest_area(TriangleId t) const {
  const Triangle& tri = triangle_at(t);
  return triangle_area(vertices_[tri.v[0].value()].rest, vertices_[tri.v[1].value()].rest,
                       vertices_[tri.v[2].value()].rest);
}

Eigen::Vector3d Mesh48::rest_normal(TriangleId t) const {
  const Triangle& tri = triangle_at(t);
  const Eigen::Vector3d& a = vertices_[tri.v[0].value()].rest;
  return (vertices_[tri.v[1].value()].rest - a)
      .cross(vertices_[tri.v[2].value()].rest - a)
      .normalized();
}

int Mesh48::level(BlockId k) const {
  return block_at(k).level;
}
bool Mesh48::is_split(BlockId k) const {
  return block_at(k).split.valid();
}
std::array<VertexId, 2> Mesh48::diagonal(BlockId k) const {
  return block_at(k).diagonal;
}
std::array<VertexId, 2> Mesh48::apexes(BlockId k) const {
  return block_at(k).apex;
}
std::array<TriangleId, 2> Mesh48::triangles(BlockId k) const {
  return block_at(k).tri;
}
std::array<BlockId, 2> Mesh48::parents(BlockId k) const {
  return block_at(k).parent;
}
std::array<BlockId, 4> Mesh48::children(BlockId k) const {
  return block_at(k).child;
}
VertexId Mesh48::split_vertex(BlockId k) const {
  return block_at(k).split;
}

std::array<TriangleId, 4> Mesh48::child_triangles(BlockId k) const {
  std::array<TriangleId, 4> out;
  const Block& blk = block_at(k);
  for (int i = 0; i < 4; ++i) {
    const BlockId child = blk.child[i];
    if (!alive(child)) continue;
    const Block& cb = blocks_[child.value()];
    for (int s = 0; s < 2; ++s)
      if (cb.parent[s] == k && alive(cb.tri[s])) out[i] = cb.tri[s];
  }
  return out;
}

bool Mesh48::is_pending(BlockId k) const {
  const Block& blk = block_at(k);
  return !blk.split.valid() && !blk.tri[1].valid() && triangles_[blk.tri[0].value()].adj[0].valid();
}

std::vector<TriangleId> Mesh48::live_triangles() const {
  std::vector<TriangleId> out;
  out.reserve(static_cast<std::size_t>(triangle_count_));
  for (int t = 0; t < triangle_capacity(); ++t)
    if (triangles_[t].alive) out.emplace_back(t);
  return out;
}

std::vector<BlockId> Mesh48::leaf_blocks() const {
  std::vector<BlockId> out;
  for (int k = 0; k < block_capacity(); ++k)
    if (blocks_[k].alive && !blocks_[k].split.valid()) out.emplace_back(k);
  return out;
}

std::vector<BlockId> Mesh48::mergeable_blocks() const {
  std::vector<BlockId> out;
  for (int k = 0; k < block_capacity(); ++k)
    if (can_merge(BlockId(k))) out.emplace_back(k);
  return out;
}

double Mesh48::total_rest_area() const {
  double sum = 0;
  for (int t = 0; t < triangle_capacity(); ++t)
    if (triangles_[t].alive) sum += rest_area(TriangleId(t));
  return sum;
}

// ---------------------------------------------------------------------------------------------
// Adjacency helpers

template <class Visit>
void Mesh48::for_each_triangle_around(VertexId v, Visit visit) const {
  const TriangleId start = vertices_[v.value()].triangle;
  if (!alive(start)) return;
  const auto corner_of = [&](TriangleId t) {
    const Triangle& tri = triangles_[t.value()];
    for (int i = 0; i < 3; ++i)
      if (tri.v[i] == v) return i;
    throw std::logic_error("Mesh48: a vertex's star walk left the vertex");
  };
  // Counter-clockwise: across the outgoing edge (v, v[i+1]), opposite corner i+2.
  TriangleId t = start;
  int steps = 0;
  do {
    const int i = corner_of(t);
    visit(t, i);
    t = triangles_[t.value()].adj[(i + 2) % 3];
    if (++steps > kMaxStar) throw std::logic_error("Mesh48: vertex star does not close");
  } while (t.valid() && t != start);
  if (t == start) return;
  // Open fan: walk clockwise from the start across the incoming edge (v[i+2], v), corner i+1.
  t = triangles_[start.value()].adj[(corner_of(start) + 1) % 3];
  while (t.valid()) {
    const int i = corner_of(t);
    visit(t, i);
    t = triangles_[t.value()].adj[(i + 1) % 3];
    if (++steps > kMaxStar) throw std::logic_error("Mesh48: vertex star does not close");
  }
}

TriangleId Mesh48::find_triangle_with_edge(VertexId u, VertexId v, int* local_edge) const {
  TriangleId found;
  for_each_triangle_around(u, [&](TriangleId t, int i) {
    if (found.valid()) return;
    const Triangle& tri = triangles_[t.value()];
    if (tri.v[(i + 1) % 3] == v) {
      found = t;
      *local_edge = (i + 2) % 3;
    } else if (tri.v[(i + 2) % 3] == v) {
      found = t;
      *local_edge = (i + 1) % 3;
    }
  });
  return found;
}

// Points t's neighbour entry across the edge it shares with new_neighbor at new_neighbor. The
// entry is found by the edge's vertices, since the ids of removed triangles may be reused.
void Mesh48::replace_neighbor(TriangleId t, TriangleId new_neighbor) {
  const Triangle& nt = triangles_[new_neighbor.value()];
  Triangle& tri = triangles_[t.value()];
  for (int k = 0; k < 3; ++k) {
    const VertexId p = tri.v[(k + 1) % 3], q = tri.v[(k + 2) % 3];
    for (int j = 0; j < 3; ++j)
      if (nt.v[(j + 1) % 3] == q && nt.v[(j + 2) % 3] == p) {
        tri.adj[k] = new_neighbor;
        return;
      }
  }
  throw std::logic_error("Mesh48: replace_neighbor found no shared edge");
}

// Puts a new child triangle (apex E, diagonal p-q) of block `parent` into the level-l+1 block
// with diagonal p-q: the one already holding the neighbour across p-q, or a new block.
void Mesh48::attach_child(BlockId parent, int child_index, TriangleId child) {
  const Triangle c = triangles_[child.value()];
  const TriangleId across = c.adj[0];
  BlockId k;
  if (across.valid() && triangles_[across.value()].v[1] == c.v[2] &&
      triangles_[across.value()].v[2] == c.v[1]) {
    k = triangles_[across.value()].block;
    Block& blk = blocks_[k.value()];
    if (blk.tri[1].valid() || blk.split.valid() || blk.level != c.level)
      throw std::logic_error("Mesh48: the block to complete is not a pending block of the level");
    blk.apex[1] = c.v[0];
    blk.tri[1] = child;
    blk.parent[1] = parent;
  } else {
    k = new_block();
    Block& blk = blocks_[k.value()];
    blk.diagonal = {c.v[1], c.v[2]};
    blk.apex[0] = c.v[0];
    blk.tri[0] = child;
    blk.parent[0] = parent;
    blk.level = c.level;
  }
  triangles_[child.value()].block = k;
  blocks_[parent.value()].child[child_index] = k;
}

}  // namespace sd::meshing
