// Mesh48's changes of topology: splitting and merging blocks (4-8 refinement and its inverse),
// exporting the live mesh as arrays and compacting the slot vectors.

#include <Eigen/Geometry>
#include <algorithm>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "meshing/mesh48.hpp"
#include "meshing/mesh48_internal.hpp"

namespace sd::meshing {
namespace {

// Child slots of a split block, in the order of Block::child (DESIGN.md names in brackets).
constexpr int kChildAB = 0;  // (A, B, E) = A11, diagonal AB
constexpr int kChildAC = 1;  // (A, E, C) = A10, diagonal CA
constexpr int kChildDC = 2;  // (D, C, E) = A21, diagonal DC
constexpr int kChildDB = 3;  // (D, E, B) = A20, diagonal BD

}  // namespace

using detail::debug_validate;

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
  ch.root_a1 = root(t0);
  ch.root_a2 = has_d ? root(t1) : -1;

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
  ch.root_a1 = root(t0);
  ch.root_a2 = has_d ? root(t1) : -1;
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

  // Each live slot moved to its rank, its references renamed by `rename`.
  const auto pack = [](auto& slots, const std::vector<int>& map, int count, auto rename) {
    std::remove_reference_t<decltype(slots)> packed(static_cast<std::size_t>(count));
    for (std::size_t i = 0; i < slots.size(); ++i) {
      if (!slots[i].alive) continue;
      auto item = slots[i];
      rename(item);
      packed[map[i]] = item;
    }
    slots = std::move(packed);
  };
  pack(vertices_, remap.vertices, remap.vertex_count, [&](Vertex& v) {
    v.parent = map_b(v.parent);
    v.triangle = map_t(v.triangle);
  });
  pack(triangles_, remap.triangles, remap.triangle_count, [&](Triangle& t) {
    for (auto& v : t.v) v = map_v(v);
    for (auto& n : t.adj) n = map_t(n);
    t.block = map_b(t.block);
  });
  pack(blocks_, remap.blocks, remap.block_count, [&](Block& k) {
    for (auto& v : k.diagonal) v = map_v(v);
    for (auto& v : k.apex) v = map_v(v);
    for (auto& t : k.tri) t = map_t(t);
    for (auto& p : k.parent) p = map_b(p);
    for (auto& c : k.child) c = map_b(c);
    k.split = map_v(k.split);
  });
  free_vertices_.clear();
  free_triangles_.clear();
  free_blocks_.clear();
  debug_validate(*this, "Mesh48::compact");
  return remap;
}
}  // namespace sd::meshing
