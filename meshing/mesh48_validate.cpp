// Mesh48::validate: every invariant of the 4-8 mesh checked from scratch.

#include <Eigen/Geometry>
#include <algorithm>
#include <string>
#include <vector>

#include "meshing/mesh48.hpp"
#include "meshing/mesh48_internal.hpp"

namespace sd::meshing {

using detail::edge_name;
using detail::HalfEdgeIndex;

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
