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
#include "meshing/quad_mesh.hpp"

namespace sd::meshing {
namespace {

// Child slots of a split block, in the order of Block::child (DESIGN.md names in brackets).
constexpr int kChildAB = 0;  // (A, B, E) = A11, diagonal AB
constexpr int kChildAC = 1;  // (A, E, C) = A10, diagonal CA
constexpr int kChildDC = 2;  // (D, C, E) = A21, diagonal DC
constexpr int kChildDB = 3;  // (D, E, B) = A20, diagonal BD

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

// Debug builds check every invariant of the mesh after each factory and each split or merge.
void debug_validate([[maybe_unused]] const Mesh48& m, [[maybe_unused]] const char* after) {
#ifndef NDEBUG
  const std::vector<std::string> problems = m.validate();
  SD_DCHECK(problems.empty(), std::string("after ") + after + ": " + problems.front());
#endif
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

std::string edge_name(int u, int v) {
  return std::to_string(u) + "-" + std::to_string(v);
}

// Directed edges of a triangle list grouped by their start vertex (compressed rows), so that an
// edge's reverse is found in O(valence) without sorting.
class HalfEdgeIndex {
 public:
  struct Entry {
    int to;
    int face;
    int corner;  // local index of the face's vertex opposite the edge
  };

  // corner_vertex(f, k): vertex k of face f, for 0 <= f < face_count, in 0..vertex_count-1.
  template <class CornerVertex>
  HalfEdgeIndex(int vertex_count, int face_count, CornerVertex corner_vertex)
      : start_(static_cast<std::size_t>(vertex_count) + 1, 0),
        entries_(3 * static_cast<std::size_t>(face_count)) {
    for (int f = 0; f < face_count; ++f)
      for (int k = 0; k < 3; ++k) ++start_[corner_vertex(f, (k + 1) % 3) + 1];
    for (int v = 0; v < vertex_count; ++v) start_[v + 1] += start_[v];
    std::vector<int> fill(start_.begin(), start_.end() - 1);
    for (int f = 0; f < face_count; ++f)
      for (int k = 0; k < 3; ++k)
        entries_[fill[corner_vertex(f, (k + 1) % 3)]++] = {corner_vertex(f, (k + 2) % 3), f, k};
  }

  int vertex_count() const { return static_cast<int>(start_.size()) - 1; }
  int out_degree(int v) const { return start_[v + 1] - start_[v]; }
  const Entry* begin(int v) const { return entries_.data() + start_[v]; }
  const Entry* end(int v) const { return entries_.data() + start_[v + 1]; }
  const Entry* find(int from, int to) const {
    for (const Entry* e = begin(from); e != end(from); ++e)
      if (e->to == to) return e;
    return nullptr;
  }
  // A directed edge listed twice (inconsistent orientation or a non-manifold edge), else
  // {-1, -1}.
  std::pair<int, int> duplicate() const {
    for (int v = 0; v < vertex_count(); ++v)
      for (const Entry* e = begin(v); e != end(v); ++e)
        for (const Entry* g = e + 1; g != end(v); ++g)
          if (e->to == g->to) return {v, e->to};
    return {-1, -1};
  }

 private:
  std::vector<int> start_;
  std::vector<Entry> entries_;
};

const char* const kDuplicateEdgeText =
    " is traversed in the same direction by two faces: the faces are not consistently "
    "oriented or the edge is shared by more than two faces";

}  // namespace

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
BlockId Mesh48::new_block() { return BlockId(take_slot(blocks_, free_blocks_, block_count_)); }

void Mesh48::free_vertex(VertexId v) {
  release_slot(vertices_, free_vertices_, vertex_count_, v.value());
}
void Mesh48::free_triangle(TriangleId t) {
  release_slot(triangles_, free_triangles_, triangle_count_, t.value());
}
void Mesh48::free_block(BlockId k) { release_slot(blocks_, free_blocks_, block_count_, k.value()); }

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

// ---------------------------------------------------------------------------------------------
// Split

bool Mesh48::can_split(BlockId k) const {
  return alive(k) && !blocks_[k.value()].split.valid();
}

std::vector<BlockChange> Mesh48::split(BlockId k) {
  if (!can_split(k))
    throw Mesh48OperationError("block " + std::to_string(k.value()) +
                               (alive(k) ? " is already split" : " is not live"));
  std::vector<BlockChange> changes;
  split_recursive(k, false, changes);
  debug_validate(*this, "Mesh48::split");
  return changes;
}

void Mesh48::split_recursive(BlockId k, bool forced, std::vector<BlockChange>& changes) {
  const Block& blk = blocks_[k.value()];
  if (!blk.tri[1].valid()) {
    const TriangleId across = triangles_[blk.tri[0].value()].adj[0];
    if (across.valid()) {
      // Pending block: the coarser block across the diagonal must be split first. Each step
      // goes one level coarser, so the recursion ends by level 0.
      const BlockId coarser = triangles_[across.value()].block;
      if (blocks_[coarser.value()].level != blk.level - 1)
        throw std::logic_error("Mesh48: a pending block's neighbour is not one level coarser");
      split_recursive(coarser, true, changes);
    }
  }
  changes.push_back(split_complete(k, forced));
}

BlockChange Mesh48::split_complete(BlockId k, bool forced) {
  const Block blk = blocks_[k.value()];
  const TriangleId t0 = blk.tri[0], t1 = blk.tri[1];
  const Triangle old0 = triangles_[t0.value()];
  if (!t1.valid() && old0.adj[0].valid())
    throw std::logic_error("Mesh48: splitting a pending block");
  const bool has_d = t1.valid();
  const Triangle old1 = has_d ? triangles_[t1.value()] : Triangle{};

  BlockChange ch;
  ch.kind = BlockChange::Kind::kSplit;
  ch.forced = forced;
  ch.block = k;
  ch.level = blk.level;
  ch.a = blk.apex[0];
  ch.b = blk.diagonal[0];
  ch.c = blk.diagonal[1];
  ch.d = blk.apex[1];
  ch.a1 = t0;
  ch.a2 = t1;
  ch.area_a1 = rest_area(t0);
  ch.area_a2 = has_d ? rest_area(t1) : 0.0;
  ch.source_a1 = source_face(t0);
  ch.source_a2 = has_d ? source_face(t1) : -1;

  const VertexId e = new_vertex();
  {
    Vertex& ve = vertices_[e.value()];
    ve.rest = 0.5 * (vertices_[ch.b.value()].rest + vertices_[ch.c.value()].rest);
    ve.level = blk.level + 1;
    ve.parent = k;
    ve.on_boundary = !has_d;
  }
  ch.e = e;

  // Free the parents first so that the children reuse their slots.
  if (has_d) free_triangle(t1);
  free_triangle(t0);
  const TriangleId c_ab = new_triangle(), c_ac = new_triangle();
  const TriangleId c_dc = has_d ? new_triangle() : TriangleId{};
  const TriangleId c_db = has_d ? new_triangle() : TriangleId{};
  const auto make = [&](TriangleId id, VertexId p, VertexId q, TriangleId outer, TriangleId left,
                        TriangleId right, int root) {
    Triangle& tri = triangles_[id.value()];
    tri.v = {e, p, q};
    tri.adj = {outer, left, right};
    tri.level = blk.level + 1;
    tri.root = root;
  };
  const TriangleId n_ab = old0.adj[2], n_ca = old0.adj[1];
  const TriangleId n_dc = has_d ? old1.adj[2] : TriangleId{};
  const TriangleId n_bd = has_d ? old1.adj[1] : TriangleId{};
  make(c_ab, ch.a, ch.b, n_ab, c_db, c_ac, old0.root);  // (E, A, B)
  make(c_ac, ch.c, ch.a, n_ca, c_ab, c_dc, old0.root);  // (E, C, A)
  if (has_d) {
    make(c_dc, ch.d, ch.c, n_dc, c_ac, c_db, old1.root);  // (E, D, C)
    make(c_db, ch.b, ch.d, n_bd, c_dc, c_ab, old1.root);  // (E, B, D)
  }
  if (n_ab.valid()) replace_neighbor(n_ab, c_ab);
  if (n_ca.valid()) replace_neighbor(n_ca, c_ac);
  if (n_dc.valid()) replace_neighbor(n_dc, c_dc);
  if (n_bd.valid()) replace_neighbor(n_bd, c_db);

  Block& split_block = blocks_[k.value()];
  split_block.split = e;
  split_block.tri = {TriangleId{}, TriangleId{}};
  attach_child(k, kChildAB, c_ab);
  attach_child(k, kChildAC, c_ac);
  if (has_d) {
    attach_child(k, kChildDC, c_dc);
    attach_child(k, kChildDB, c_db);
  }

  vertices_[e.value()].triangle = c_ab;
  vertices_[ch.a.value()].triangle = c_ab;
  vertices_[ch.b.value()].triangle = c_ab;
  vertices_[ch.c.value()].triangle = c_ac;
  if (has_d) vertices_[ch.d.value()].triangle = c_dc;

  ch.a11 = c_ab;
  ch.a10 = c_ac;
  ch.a21 = c_dc;
  ch.a20 = c_db;
  ch.area_a11 = rest_area(c_ab);
  ch.area_a10 = rest_area(c_ac);
  ch.area_a21 = has_d ? rest_area(c_dc) : 0.0;
  ch.area_a20 = has_d ? rest_area(c_db) : 0.0;
  return ch;
}

std::vector<BlockChange> Mesh48::split_edge(VertexId u, VertexId v) {
  if (!alive(u) || !alive(v))
    throw Mesh48OperationError("split_edge: vertex " + std::to_string(u.value()) + " or " +
                               std::to_string(v.value()) + " is not live");
  std::vector<BlockChange> changes;
  // At most two rounds: a leg of a leaf block becomes a diagonal once that block is split.
  for (int round = 0; round < 3; ++round) {
    int local = -1;
    const TriangleId t = find_triangle_with_edge(u, v, &local);
    if (!t.valid())
      throw Mesh48OperationError("split_edge: vertices " + std::to_string(u.value()) + " and " +
                                 std::to_string(v.value()) + " share no edge");
    const BlockId k = triangles_[t.value()].block;
    split_recursive(k, local != 0, changes);
    if (local == 0) return changes;
  }
  throw std::logic_error("Mesh48::split_edge: the edge did not become a block diagonal");
}

// ---------------------------------------------------------------------------------------------
// Merge

bool Mesh48::can_merge(BlockId k) const {
  if (!alive(k)) return false;
  const Block& blk = blocks_[k.value()];
  if (!blk.split.valid()) return false;
  for (const BlockId child : blk.child)
    if (child.valid() && (!alive(child) || blocks_[child.value()].split.valid())) return false;
  return true;
}

BlockChange Mesh48::merge(BlockId k) {
  if (!can_merge(k))
    throw Mesh48OperationError("block " + std::to_string(k.value()) +
                               (!alive(k) ? " is not live"
                                : !blocks_[k.value()].split.valid()
                                    ? " is not split"
                                    : " has a split child and cannot merge"));
  const Block blk = blocks_[k.value()];
  const bool has_d = blk.apex[1].valid();

  BlockChange ch;
  ch.kind = BlockChange::Kind::kMerge;
  ch.block = k;
  ch.level = blk.level;
  ch.e = blk.split;
  ch.a = blk.apex[0];
  ch.b = blk.diagonal[0];
  ch.c = blk.diagonal[1];
  ch.d = blk.apex[1];

  // Each child triangle sits on the side of its block whose parent is k.
  std::array<TriangleId, 4> child_tri;
  std::array<int, 4> child_side{};
  for (int i = 0; i < 4; ++i) {
    const BlockId child = blk.child[i];
    if (!child.valid()) continue;
    const Block& cb = blocks_[child.value()];
    child_side[i] = cb.parent[0] == k ? 0 : 1;
    if (cb.parent[child_side[i]] != k)
      throw std::logic_error("Mesh48::merge: a child block does not list its parent");
    child_tri[i] = cb.tri[child_side[i]];
  }
  ch.a11 = child_tri[kChildAB];
  ch.a10 = child_tri[kChildAC];
  ch.a21 = child_tri[kChildDC];
  ch.a20 = child_tri[kChildDB];
  ch.area_a11 = rest_area(ch.a11);
  ch.area_a10 = rest_area(ch.a10);
  ch.area_a21 = has_d ? rest_area(ch.a21) : 0.0;
  ch.area_a20 = has_d ? rest_area(ch.a20) : 0.0;
  const TriangleId n_ab = triangles_[ch.a11.value()].adj[0];
  const TriangleId n_ca = triangles_[ch.a10.value()].adj[0];
  const TriangleId n_dc = has_d ? triangles_[ch.a21.value()].adj[0] : TriangleId{};
  const TriangleId n_bd = has_d ? triangles_[ch.a20.value()].adj[0] : TriangleId{};
  const int root0 = triangles_[ch.a11.value()].root;
  const int root1 = has_d ? triangles_[ch.a21.value()].root : -1;

  // Take the children out of their blocks; a block left empty disappears, a block that keeps
  // only its second side moves it to side 0.
  for (int i = 0; i < 4; ++i) {
    const BlockId child = blk.child[i];
    if (!child.valid()) continue;
    Block& cb = blocks_[child.value()];
    const int s = child_side[i];
    cb.tri[s] = TriangleId{};
    cb.apex[s] = VertexId{};
    cb.parent[s] = BlockId{};
    if (!cb.tri[0].valid() && !cb.tri[1].valid()) {
      free_block(child);
    } else if (s == 0) {
      cb.tri = {cb.tri[1], TriangleId{}};
      cb.apex = {cb.apex[1], VertexId{}};
      cb.parent = {cb.parent[1], BlockId{}};
      cb.diagonal = {cb.diagonal[1], cb.diagonal[0]};
    }
  }
  if (has_d) {
    free_triangle(ch.a20);
    free_triangle(ch.a21);
  }
  free_triangle(ch.a10);
  free_triangle(ch.a11);
  free_vertex(ch.e);

  const TriangleId t0 = new_triangle();
  const TriangleId t1 = has_d ? new_triangle() : TriangleId{};
  {
    Triangle& tri = triangles_[t0.value()];
    tri.v = {ch.a, ch.b, ch.c};
    tri.adj = {t1, n_ca, n_ab};
    tri.block = k;
    tri.level = blk.level;
    tri.root = root0;
  }
  if (has_d) {
    Triangle& tri = triangles_[t1.value()];
    tri.v = {ch.d, ch.c, ch.b};
    tri.adj = {t0, n_bd, n_dc};
    tri.block = k;
    tri.level = blk.level;
    tri.root = root1;
  }
  if (n_ab.valid()) replace_neighbor(n_ab, t0);
  if (n_ca.valid()) replace_neighbor(n_ca, t0);
  if (n_dc.valid()) replace_neighbor(n_dc, t1);
  if (n_bd.valid()) replace_neighbor(n_bd, t1);

  Block& merged = blocks_[k.value()];
  merged.tri = {t0, t1};
  merged.split = VertexId{};
  merged.child = {BlockId{}, BlockId{}, BlockId{}, BlockId{}};
  vertices_[ch.a.value()].triangle = t0;
  vertices_[ch.b.value()].triangle = t0;
  vertices_[ch.c.value()].triangle = t0;
  if (has_d) vertices_[ch.d.value()].triangle = t1;

  ch.a1 = t0;
  ch.a2 = t1;
  ch.area_a1 = rest_area(t0);
  ch.area_a2 = has_d ? rest_area(t1) : 0.0;
  ch.source_a1 = source_face(t0);
  ch.source_a2 = has_d ? source_face(t1) : -1;
  debug_validate(*this, "Mesh48::merge");
  return ch;
}

// ---------------------------------------------------------------------------------------------
// Export and compaction

Mesh48Arrays Mesh48::arrays() const {
  Mesh48Arrays out;
  std::vector<int> vertex_row(vertices_.size(), -1), triangle_row(triangles_.size(), -1);
  out.vertex_ids.reserve(static_cast<std::size_t>(vertex_count_));
  out.rest_positions.resize(vertex_count_, 3);
  out.vertex_level.resize(vertex_count_);
  for (int v = 0; v < vertex_capacity(); ++v) {
    if (!vertices_[v].alive) continue;
    const int row = static_cast<int>(out.vertex_ids.size());
    vertex_row[v] = row;
    out.vertex_ids.emplace_back(v);
    out.rest_positions.row(row) = vertices_[v].rest.transpose();
    out.vertex_level(row) = vertices_[v].level;
  }
  out.triangle_ids.reserve(static_cast<std::size_t>(triangle_count_));
  out.faces.resize(triangle_count_, 3);
  out.face_block.resize(triangle_count_);
  out.face_level.resize(triangle_count_);
  int interior = 0;
  for (int t = 0; t < triangle_capacity(); ++t) {
    const Triangle& tri = triangles_[t];
    if (!tri.alive) continue;
    const int row = static_cast<int>(out.triangle_ids.size());
    triangle_row[t] = row;
    out.triangle_ids.emplace_back(t);
    for (int k = 0; k < 3; ++k) {
      out.faces(row, k) = vertex_row[tri.v[k].value()];
      if (tri.adj[k].valid() && t < tri.adj[k].value()) ++interior;
    }
    out.face_block(row) = tri.block.value();
    out.face_level(row) = tri.level;
  }
  out.interior_edges.resize(interior, 4);
  out.edge_faces.resize(interior, 2);
  int e = 0;
  for (int t = 0; t < triangle_capacity(); ++t) {
    const Triangle& tri = triangles_[t];
    if (!tri.alive) continue;
    for (int k = 0; k < 3; ++k) {
      const TriangleId n = tri.adj[k];
      if (!n.valid() || n.value() < t) continue;
      const VertexId i = tri.v[(k + 1) % 3], j = tri.v[(k + 2) % 3];
      const Triangle& other = triangles_[n.value()];
      VertexId l;
      for (const VertexId w : other.v)
        if (w != i && w != j) l = w;
      out.interior_edges.row(e) << vertex_row[i.value()], vertex_row[j.value()],
          vertex_row[tri.v[k].value()], vertex_row[l.value()];
      out.edge_faces.row(e) << triangle_row[t], triangle_row[n.value()];
      ++e;
    }
  }
  return out;
}

Mesh48Remap Mesh48::compact() {
  Mesh48Remap remap;
  const auto ranks = [](const auto& slots, std::vector<int>& map) {
    map.assign(slots.size(), -1);
    int next = 0;
    for (std::size_t i = 0; i < slots.size(); ++i)
      if (slots[i].alive) map[i] = next++;
    return next;
  };
  remap.vertex_count = ranks(vertices_, remap.vertices);
  remap.triangle_count = ranks(triangles_, remap.triangles);
  remap.block_count = ranks(blocks_, remap.blocks);
  const auto map_v = [&](VertexId v) {
    return v.valid() ? VertexId(remap.vertices[v.value()]) : v;
  };
  const auto map_t = [&](TriangleId t) {
    return t.valid() ? TriangleId(remap.triangles[t.value()]) : t;
  };
  const auto map_b = [&](BlockId k) { return k.valid() ? BlockId(remap.blocks[k.value()]) : k; };

  std::vector<Vertex> vertices(static_cast<std::size_t>(remap.vertex_count));
  for (std::size_t i = 0; i < vertices_.size(); ++i) {
    if (!vertices_[i].alive) continue;
    Vertex v = vertices_[i];
    v.parent = map_b(v.parent);
    v.triangle = map_t(v.triangle);
    vertices[remap.vertices[i]] = v;
  }
  std::vector<Triangle> triangles(static_cast<std::size_t>(remap.triangle_count));
  for (std::size_t i = 0; i < triangles_.size(); ++i) {
    if (!triangles_[i].alive) continue;
    Triangle t = triangles_[i];
    for (auto& v : t.v) v = map_v(v);
    for (auto& n : t.adj) n = map_t(n);
    t.block = map_b(t.block);
    triangles[remap.triangles[i]] = t;
  }
  std::vector<Block> blocks(static_cast<std::size_t>(remap.block_count));
  for (std::size_t i = 0; i < blocks_.size(); ++i) {
    if (!blocks_[i].alive) continue;
    Block k = blocks_[i];
    for (auto& v : k.diagonal) v = map_v(v);
    for (auto& v : k.apex) v = map_v(v);
    for (auto& t : k.tri) t = map_t(t);
    for (auto& p : k.parent) p = map_b(p);
    for (auto& c : k.child) c = map_b(c);
    k.split = map_v(k.split);
    blocks[remap.blocks[i]] = k;
  }
  vertices_ = std::move(vertices);
  triangles_ = std::move(triangles);
  blocks_ = std::move(blocks);
  free_vertices_.clear();
  free_triangles_.clear();
  free_blocks_.clear();
  debug_validate(*this, "Mesh48::compact");
  return remap;
}

// ---------------------------------------------------------------------------------------------
// Validation

std::vector<std::string> Mesh48::validate() const {
  std::vector<std::string> problems;
  constexpr std::size_t kMaxProblems = 100;
  const auto report = [&](const std::string& text) {
    if (problems.size() < kMaxProblems) problems.push_back(text);
  };
  const auto vname = [](VertexId v) { return "vertex " + std::to_string(v.value()); };
  const auto tname = [](TriangleId t) { return "triangle " + std::to_string(t.value()); };
  const auto bname = [](BlockId k) { return "block " + std::to_string(k.value()); };

  // Slot bookkeeping.
  {
    const auto check_slots = [&](const auto& slots, const std::vector<int>& free, int count,
                                 const char* what) {
      int live = 0;
      for (const auto& s : slots) live += s.alive ? 1 : 0;
      std::vector<char> is_free(slots.size(), 0);
      for (const int i : free) {
        if (i < 0 || i >= static_cast<int>(slots.size()) || slots[i].alive || is_free[i])
          report(std::string("free list of ") + what + " holds a bad slot " + std::to_string(i));
        else
          is_free[i] = 1;
      }
      if (live != count || live + static_cast<int>(free.size()) != static_cast<int>(slots.size()))
        report(std::string("count of live ") + what + " (" + std::to_string(count) +
               ") does not match the slots (" + std::to_string(live) + " live, " +
               std::to_string(free.size()) + " free of " + std::to_string(slots.size()) + ")");
    };
    check_slots(vertices_, free_vertices_, vertex_count_, "vertices");
    check_slots(triangles_, free_triangles_, triangle_count_, "triangles");
    check_slots(blocks_, free_blocks_, block_count_, "blocks");
  }

  // Conformity: every directed edge once, its reverse (if any) is the recorded neighbour, and
  // edges without a neighbour lie on the input boundary (their total length is the input's:
  // a hanging vertex would add unmatched edges inside).
  std::vector<int> checked;  // live triangles whose vertices and neighbours are live
  checked.reserve(static_cast<std::size_t>(triangle_count_));
  for (int t = 0; t < triangle_capacity(); ++t) {
    const Triangle& tri = triangles_[t];
    if (!tri.alive) continue;
    bool ok = true;
    for (int k = 0; k < 3; ++k) {
      if (!alive(tri.v[k])) {
        report(tname(TriangleId(t)) + " uses dead " + vname(tri.v[k]));
        ok = false;
      }
      if (tri.v[k] == tri.v[(k + 1) % 3]) {
        report(tname(TriangleId(t)) + " repeats " + vname(tri.v[k]));
        ok = false;
      }
      if (tri.adj[k].valid() && !alive(tri.adj[k])) {
        report(tname(TriangleId(t)) + " has dead neighbour " + tname(tri.adj[k]));
        ok = false;
      }
    }
    if (ok) checked.push_back(t);
  }
  const HalfEdgeIndex index(vertex_capacity(), static_cast<int>(checked.size()),
                            [&](int f, int k) { return triangles_[checked[f]].v[k].value(); });
  if (const auto [from, to] = index.duplicate(); from >= 0)
    report("edge " + edge_name(from, to) + " is used twice in the same direction");
  double boundary_length = 0;
  for (int from = 0; from < index.vertex_count(); ++from) {
    for (const HalfEdgeIndex::Entry* h = index.begin(from); h != index.end(from); ++h) {
      const int to = h->to, tri = checked[h->face];
      const TriangleId recorded = triangles_[tri].adj[h->corner];
      if (const HalfEdgeIndex::Entry* back = index.find(to, from)) {
        if (recorded.value() != checked[back->face])
          report(tname(TriangleId(tri)) + " records neighbour " + tname(recorded) + " across " +
                 edge_name(from, to) + " but " + tname(TriangleId(checked[back->face])) +
                 " is there");
      } else {
        if (recorded.valid())
          report(tname(TriangleId(tri)) + " records a neighbour across unmatched edge " +
                 edge_name(from, to));
        if (!vertices_[from].on_boundary || !vertices_[to].on_boundary)
          report("edge " + edge_name(from, to) +
                 " has one triangle but is not on the boundary (hanging vertex)");
        boundary_length += (vertices_[to].rest - vertices_[from].rest).norm();
      }
    }
  }
  const double length_scale = std::max(input_boundary_length_, 1e-300);
  if (std::abs(boundary_length - input_boundary_length_) > 1e-9 * length_scale)
    report("boundary length " + std::to_string(boundary_length) + " differs from the input's " +
           std::to_string(input_boundary_length_) + " (hanging vertex or lost boundary)");

  // Per triangle: level rule (by the role of each shared edge), block membership, exact-halves
  // rest geometry and orientation relative to the level-0 triangle it lies in.
  double area_sum = 0;
  for (int t = 0; t < triangle_capacity(); ++t) {
    const Triangle& tri = triangles_[t];
    if (!tri.alive) continue;
    const TriangleId id(t);
    bool vertices_ok = true;
    for (const VertexId v : tri.v) vertices_ok = vertices_ok && alive(v);
    if (!vertices_ok) continue;
    for (int k = 0; k < 3; ++k) {
      const TriangleId n = tri.adj[k];
      if (!alive(n)) continue;
      const Triangle& other = triangles_[n.value()];
      const bool other_diag = other.v[1] == tri.v[(k + 2) % 3] && other.v[2] == tri.v[(k + 1) % 3];
      int expected;
      if (k == 0)
        expected = other_diag ? tri.level : tri.level - 1;
      else
        expected = other_diag ? tri.level + 1 : tri.level;
      if (other.level != expected || std::abs(other.level - tri.level) > 1)
        report("level rule: " + tname(id) + " (level " + std::to_string(tri.level) + ") and " +
               tname(n) + " (level " + std::to_string(other.level) + ") across edge " +
               edge_name(tri.v[(k + 1) % 3].value(), tri.v[(k + 2) % 3].value()));
      if (k == 0 && other_diag && other.block != tri.block)
        report(tname(id) + " and " + tname(n) + " share their diagonal but not their block");
    }
    if (!alive(tri.block)) {
      report(tname(id) + " belongs to dead " + bname(tri.block));
    } else {
      const Block& blk = blocks_[tri.block.value()];
      if (blk.tri[0] != id && blk.tri[1] != id)
        report(tname(id) + " is not listed by its " + bname(tri.block));
      if (blk.level != tri.level)
        report(tname(id) + " has level " + std::to_string(tri.level) + " but its " +
               bname(tri.block) + " has level " + std::to_string(blk.level));
    }
    const Eigen::Vector3d& a = vertices_[tri.v[0].value()].rest;
    const Eigen::Vector3d& b = vertices_[tri.v[1].value()].rest;
    const Eigen::Vector3d& c = vertices_[tri.v[2].value()].rest;
    const Eigen::Vector3d n2 = (b - a).cross(c - a);
    const double area = 0.5 * n2.norm();
    area_sum += area;
    if (tri.root < 0 || tri.root >= static_cast<int>(root_normals_.size())) {
      report(tname(id) + " has no level-0 ancestor");
      continue;
    }
    const double expected_area = std::ldexp(root_areas_[tri.root], -tri.level);
    if (std::abs(area - expected_area) > 1e-6 * expected_area)
      report(tname(id) + " has rest area " + std::to_string(area) + ", not 2^-" +
             std::to_string(tri.level) + " of its level-0 triangle");
    if (!(n2.dot(root_normals_[tri.root]) > 0.5 * n2.norm()))
      report("orientation: " + tname(id) + " does not face the way its level-0 triangle does");
  }
  if (std::abs(area_sum - input_area_) > 1e-9 * input_area_)
    report("total rest area " + std::to_string(area_sum) + " differs from the input's " +
           std::to_string(input_area_));

  // Blocks: structure, parents and children.
  for (int k = 0; k < block_capacity(); ++k) {
    const Block& blk = blocks_[k];
    if (!blk.alive) continue;
    const BlockId id(k);
    if (!alive(blk.diagonal[0]) || !alive(blk.diagonal[1]) || !alive(blk.apex[0])) {
      report(bname(id) + " refers to a dead vertex");
      continue;
    }
    const int sides = blk.apex[1].valid() ? 2 : 1;
    if (!blk.split.valid()) {
      for (int s = 0; s < 2; ++s) {
        if (blk.tri[s].valid() != blk.apex[s].valid()) {
          report(bname(id) + " side " + std::to_string(s) + " has an apex but no triangle");
          continue;
        }
        if (!blk.tri[s].valid()) continue;
        if (!alive(blk.tri[s])) {
          report(bname(id) + " lists dead " + tname(blk.tri[s]));
          continue;
        }
        const Triangle& tri = triangles_[blk.tri[s].value()];
        const VertexId p = blk.diagonal[s], q = blk.diagonal[1 - s];
        if (tri.v[0] != blk.apex[s] || tri.v[1] != p || tri.v[2] != q)
          report(bname(id) + " side " + std::to_string(s) + ": " + tname(blk.tri[s]) +
                 " does not have the block's apex and diagonal");
        if (tri.block != id) report(tname(blk.tri[s]) + " does not point back to " + bname(id));
      }
      if (sides == 2 && alive(blk.tri[0]) && alive(blk.tri[1]) &&
          (triangles_[blk.tri[0].value()].adj[0] != blk.tri[1] ||
           triangles_[blk.tri[1].value()].adj[0] != blk.tri[0]))
        report(bname(id) + "'s two triangles are not neighbours across the diagonal");
      if (sides == 1 && alive(blk.tri[0])) {
        const TriangleId across = triangles_[blk.tri[0].value()].adj[0];
        if (alive(across) && triangles_[across.value()].level != blk.level - 1)
          report(bname(id) +
                 " has one triangle but the triangle across its diagonal is not "
                 "one level coarser");
      }
    } else {
      const VertexId e = blk.split;
      if (!alive(e)) {
        report("split " + bname(id) + " has dead split " + vname(e));
        continue;
      }
      if (blk.tri[0].valid() || blk.tri[1].valid())
        report("split " + bname(id) + " still lists triangles");
      const Vertex& ve = vertices_[e.value()];
      if (ve.parent != id) report(vname(e) + " does not point back to its " + bname(id));
      if (ve.level != blk.level + 1) report(vname(e) + " has the wrong level");
      const Eigen::Vector3d mid =
          0.5 * (vertices_[blk.diagonal[0].value()].rest + vertices_[blk.diagonal[1].value()].rest);
      if (ve.rest != mid) report(vname(e) + " is not the rest midpoint of its block's diagonal");
      for (int i = 0; i < 4; ++i) {
        const BlockId child = blk.child[i];
        if (child.valid() != (i < 2 * sides)) {
          report(bname(id) + " has a wrong number of children");
          continue;
        }
        if (!child.valid()) continue;
        if (!alive(child)) {
          report(bname(id) + " lists dead child " + bname(child));
          continue;
        }
        const Block& cb = blocks_[child.value()];
        const int s = cb.parent[0] == id ? 0 : (cb.parent[1] == id ? 1 : -1);
        if (s < 0) {
          report("child " + bname(child) + " does not list parent " + bname(id));
          continue;
        }
        if (cb.level != blk.level + 1 || cb.apex[s] != e)
          report("child " + bname(child) + " of " + bname(id) +
                 " is not on the parent's split vertex one level finer");
      }
    }
    for (int s = 0; s < 2; ++s) {
      const BlockId p = blk.parent[s];
      const bool side_present = blk.apex[s].valid();
      if (blk.level == 0) {
        if (p.valid()) report("level-0 " + bname(id) + " has a parent");
        continue;
      }
      if (side_present != p.valid()) {
        report(bname(id) + " side " + std::to_string(s) + " lacks its parent");
        continue;
      }
      if (!p.valid()) continue;
      if (!alive(p) || blocks_[p.value()].split != blk.apex[s] ||
          std::find(blocks_[p.value()].child.begin(), blocks_[p.value()].child.end(), id) ==
              blocks_[p.value()].child.end())
        report(bname(id) + " side " + std::to_string(s) + ": parent " + bname(p) +
               " is not split at that side's apex or does not list it");
    }
  }

  // Vertices: a live incident triangle; inserted vertices hang off a live split block.
  for (int v = 0; v < vertex_capacity(); ++v) {
    const Vertex& vx = vertices_[v];
    if (!vx.alive) continue;
    const VertexId id(v);
    if (!alive(vx.triangle) || std::find(triangles_[vx.triangle.value()].v.begin(),
                                         triangles_[vx.triangle.value()].v.end(),
                                         id) == triangles_[vx.triangle.value()].v.end())
      report(vname(id) + " does not point to a live incident triangle");
    if (vx.level > 0 && (!alive(vx.parent) || blocks_[vx.parent.value()].split != id))
      report(vname(id) + " is not the split vertex of its parent block");
  }
  if (problems.size() == kMaxProblems) problems.push_back("(further problems not listed)");
  return problems;
}

}  // namespace sd::meshing
