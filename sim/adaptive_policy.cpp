#include "sim/adaptive_policy.hpp"

#include <algorithm>
#include <cmath>

#include "sim/adaptive_estimate.hpp"
#include "sim/element_forces.hpp"

namespace sd::sim {
namespace {

using meshing::BlockId;
using meshing::TriangleId;
using meshing::VertexId;

Eigen::Vector3d row3(const Eigen::VectorXd& flat, int i) {
  return flat.segment<3>(3 * i);
}

// The hinge of two triangles that share an edge, in element_forces' convention: triangles
// (x0, x1, x2) and (x1, x0, x3). Empty if they share no edge.
std::optional<std::array<int, 4>> hinge_between(const meshing::Mesh48& mesh, TriangleId t1,
                                                TriangleId t2) {
  const auto& a = mesh.vertices(t1);
  const auto& b = mesh.vertices(t2);
  for (int k = 0; k < 3; ++k)
    for (int m = 0; m < 3; ++m)
      if (b[m] == a[(k + 1) % 3] && b[(m + 1) % 3] == a[k])
        return std::array<int, 4>{a[k].value(), a[(k + 1) % 3].value(), a[(k + 2) % 3].value(),
                                  b[(m + 2) % 3].value()};
  return std::nullopt;
}

// A triangle made less than min_lifetime ago (may not be merged away yet).
bool is_young(const MergeInputs& in, TriangleId t) {
  return t.valid() &&
         in.birth[static_cast<std::size_t>(t.value())] > in.now - in.settings.min_lifetime + 1e-12;
}

// Whether a hinge (bending's vertex order) sags less than the coarsen threshold, and, for
// hinge_is_quiet, also turns slower than steady_rate (dθ/dt = Σ ∂θ/∂x_i · v_i).
bool hinge_is_flat(const MergeInputs& in, const std::array<int, 4>& hinge) {
  const Eigen::VectorXd& x = in.x;
  const double theta =
      dihedral_angle(row3(x, hinge[0]), row3(x, hinge[1]), row3(x, hinge[2]), row3(x, hinge[3]));
  return hinge_sag(in.mesh, in.bend_rest, hinge, theta) < in.settings.coarsen_threshold;
}

bool hinge_is_quiet(const MergeInputs& in, const std::array<int, 4>& hinge) {
  const Eigen::VectorXd& x = in.x;
  const Condition<12> theta = dihedral_angle_condition(row3(x, hinge[0]), row3(x, hinge[1]),
                                                       row3(x, hinge[2]), row3(x, hinge[3]), false);
  double rate = 0.0;
  for (int m = 0; m < 4; ++m) rate += theta.gradient.segment<3>(3 * m).dot(row3(in.v, hinge[m]));
  return std::abs(rate) < in.settings.steady_rate &&
         hinge_sag(in.mesh, in.bend_rest, hinge, theta.value) < in.settings.coarsen_threshold;
}

// No body bulging under the chord b–c (always true without a body).
bool flat_body_under(const MergeInputs& in, VertexId b, VertexId c) {
  return !in.body_sag ||
         in.body_sag(row3(in.x, b.value()), row3(in.x, c.value())) < in.settings.coarsen_threshold;
}

// Even levels: blocks at an even level that can merge together with their split children (two
// levels at once, so no odd triangles are left but the strips next to finer ones), each with the
// larger of its own and its children's merge errors. A child is judged as any merge; the block
// itself as it will be once its children are merged: its split vertex E, diagonal B-C and apexes
// A, D stay, so the hinges around E and across its outer edges are known before.
std::vector<std::pair<double, BlockId>> even_level_merges(const MergeInputs& in) {
  const meshing::Mesh48& mesh = in.mesh;
  const Eigen::VectorXd& x = in.x;
  std::vector<BlockId> candidates;
  for (BlockId k : mesh.mergeable_blocks()) {
    if (mesh.level(k) % 2 == 0) {
      candidates.push_back(k);
      continue;
    }
    for (BlockId parent : mesh.parents(k))
      if (parent.valid()) candidates.push_back(parent);
  }
  std::sort(candidates.begin(), candidates.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());

  std::vector<std::pair<double, BlockId>> out;
  for (BlockId k : candidates) {
    if (!mesh.alive(k) || !mesh.is_split(k) || mesh.level(k) < in.settings.min_level) continue;
    const auto [b, c] = mesh.diagonal(k);
    const auto [a, d] = mesh.apexes(k);
    const VertexId e = mesh.split_vertex(k);
    double error = (row3(x, e.value()) - 0.5 * (row3(x, b.value()) + row3(x, c.value()))).norm();
    bool keep = error < in.settings.coarsen_threshold;
    // The children: merged first if split (each a merge of its own), or leaves whose triangle
    // on this side is old enough.
    const std::array<BlockId, 4> children = mesh.children(k);
    for (BlockId child : children) {
      if (!keep || !child.valid() || !mesh.alive(child)) continue;
      if (mesh.is_split(child)) {
        const std::optional<double> child_error =
            mesh.can_merge(child) ? merge_error(in, child) : std::nullopt;
        keep = child_error.has_value();
        if (keep) error = std::max(error, *child_error);
      } else {
        for (TriangleId t : mesh.triangles(child))
          if (is_young(in, t)) keep = false;
      }
    }
    if (!keep) continue;
    // The hinges around E after the children's merges, between (A, B, E), (A, E, C), (D, C, E)
    // and (D, E, B) (bending's order: (x0, x1, x2) and (x1, x0, x3), x0 -> x1 along the first).
    const int ia = a.value(), ib = b.value(), ic = c.value(), ie = e.value();
    keep = hinge_is_quiet(in, {ia, ie, ic, ib});
    if (d.valid()) {
      const int id = d.value();
      keep = keep && hinge_is_quiet(in, {ie, ic, ia, id}) && hinge_is_quiet(in, {ie, id, ic, ib}) &&
             hinge_is_quiet(in, {ie, ib, id, ia});
    }
    // The outer edges of the merged triangles (A, B, C) and (D, C, B), children() order AB, AC,
    // DC, DB: the hinge to whatever lies across, the child's other apex (or, across a pending
    // child, the coarser neighbour's third vertex).
    const std::array<std::array<VertexId, 3>, 4> sides{
        {{a, b, c}, {c, a, b}, {d, c, b}, {b, d, c}}};
    for (int i = 0; i < 4 && keep; ++i) {
      const BlockId child = children[static_cast<std::size_t>(i)];
      if (!child.valid() || !mesh.alive(child)) continue;
      VertexId across;
      for (VertexId apex : mesh.apexes(child))
        if (apex.valid() && apex != e) across = apex;
      if (!across.valid() && !mesh.is_split(child)) {
        const TriangleId t = mesh.triangles(child)[0];
        const TriangleId beyond = t.valid() ? mesh.neighbor(t, 0) : TriangleId();
        if (beyond.valid())
          for (VertexId corner : mesh.vertices(beyond))
            if (corner != sides[static_cast<std::size_t>(i)][0] &&
                corner != sides[static_cast<std::size_t>(i)][1])
              across = corner;
      }
      if (!across.valid()) continue;  // the cloth's border
      const auto& [u, w, third] = sides[static_cast<std::size_t>(i)];
      keep = hinge_is_flat(in, {u.value(), w.value(), third.value(), across.value()});
    }
    if (keep) keep = flat_body_under(in, b, c);
    if (keep) out.emplace_back(error, k);
  }
  return out;
}

}  // namespace

std::optional<double> merge_error(const MergeInputs& in, BlockId k) {
  const meshing::Mesh48& mesh = in.mesh;
  const Eigen::VectorXd& x = in.x;
  const std::array<TriangleId, 4> children = mesh.child_triangles(k);
  for (TriangleId t : children)
    if (is_young(in, t)) return std::nullopt;
  const auto [b, c] = mesh.diagonal(k);
  const VertexId e = mesh.split_vertex(k);
  const double error =
      (row3(x, e.value()) - 0.5 * (row3(x, b.value()) + row3(x, c.value()))).norm();
  if (!(error < in.settings.coarsen_threshold)) return std::nullopt;
  // Every hinge around E: steady (|dθ/dt| below steady_rate) and with a sag estimate below
  // coarsen_threshold. E–B and E–C have the width of the parent's diagonal BC, so their sag
  // is what BC's estimate would be after the merge: a block split for a fold along its
  // diagonal is not merged back while the fold is there.
  bool keep = true;
  for (int p = 0; p < 4 && keep; ++p)
    for (int q = p + 1; q < 4 && keep; ++q) {
      if (!children[p].valid() || !children[q].valid()) continue;
      if (const auto hinge = hinge_between(mesh, children[p], children[q]))
        keep = hinge_is_quiet(in, *hinge);
    }
  // The block's outer edges after the merge: the parent triangles are twice the children,
  // so a bend across an outer edge that was fine for the children can have twice their
  // sag. Below coarsen_threshold too, or a merge next to a fold is split again at once and
  // the mesh churns every min_lifetime.
  for (TriangleId t : children) {
    if (!keep || !t.valid()) continue;
    const auto& corners = mesh.vertices(t);
    const int at_e =
        static_cast<int>(std::find(corners.begin(), corners.end(), e) - corners.begin());
    if (at_e > 2) continue;
    const TriangleId across = mesh.neighbor(t, at_e);
    if (!across.valid()) continue;  // a boundary edge: no hinge
    const VertexId u = corners[static_cast<std::size_t>((at_e + 1) % 3)];
    const VertexId w = corners[static_cast<std::size_t>((at_e + 2) % 3)];
    const VertexId third = (u == b || w == b) ? c : b;  // of the parent triangle
    VertexId opposite;
    for (VertexId corner : mesh.vertices(across))
      if (corner != u && corner != w) opposite = corner;
    // Element_forces' hinge order: (x0, x1, x2) and (x1, x0, x3) with x0 → x1 along t.
    keep = hinge_is_flat(in, {u.value(), w.value(), third.value(), opposite.value()});
  }
  // The body sag under the parent's diagonal: merging next to a curved body would make the
  // next split.
  if (keep) keep = flat_body_under(in, b, c);
  if (!keep) return std::nullopt;
  return error;
}

std::vector<std::pair<double, BlockId>> merge_candidates(const MergeInputs& in) {
  std::vector<std::pair<double, BlockId>> merges;
  if (in.settings.even_levels) {
    merges = even_level_merges(in);
  } else {
    for (BlockId k : in.mesh.mergeable_blocks())
      if (in.mesh.level(k) >= in.settings.min_level)
        if (const std::optional<double> error = merge_error(in, k)) merges.emplace_back(*error, k);
  }
  std::sort(merges.begin(), merges.end());
  return merges;
}

std::size_t merge_count(const meshing::Mesh48& mesh, const AdaptiveSettings& settings,
                        const std::vector<std::pair<double, BlockId>>& merges) {
  std::size_t count = merges.size();
  if (settings.even_levels)
    for (const auto& [error, k] : merges)
      for (BlockId child : mesh.children(k))
        if (child.valid() && mesh.alive(child) && mesh.is_split(child)) ++count;
  return count;
}

std::vector<std::pair<double, int>> refine_candidates(const Eigen::VectorXd& errors,
                                                      const meshing::Mesh48Arrays& arrays,
                                                      const AdaptiveSettings& settings) {
  std::vector<std::pair<double, int>> refinements;
  for (Eigen::Index r = 0; r < errors.size(); ++r)
    if (errors(r) > settings.refine_threshold && edge_refinable(arrays, r, settings.max_level))
      refinements.emplace_back(errors(r), static_cast<int>(r));
  std::sort(refinements.begin(), refinements.end(), std::greater<>());
  return refinements;
}

std::vector<BlockId> odd_level_blocks(const meshing::Mesh48& mesh,
                                      const AdaptiveSettings& settings) {
  std::vector<BlockId> odd_blocks;
  for (BlockId k : mesh.leaf_blocks())
    if (mesh.level(k) % 2 != 0 && mesh.level(k) < settings.max_level && !mesh.is_pending(k))
      odd_blocks.push_back(k);
  return odd_blocks;
}

}  // namespace sd::sim
