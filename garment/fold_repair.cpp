#include "garment/fold_repair.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <set>
#include <stdexcept>
#include <tuple>
#include <utility>
#include <vector>

#include "meshing/quad_quality.hpp"

namespace sd::garment {
namespace {

using Face = std::array<int, 4>;

// A quad this many times longer than wide is a sliver (the quality gate warns from 10; the
// same bound as garment/panel_fill.cpp ranks fills by).
constexpr double kSliverAspect = 10;
// degrees: the quality gate's smallest corner angle (garment/quality_gate.hpp).
constexpr double kGateAngle = 10;
// Gauss-Seidel sweeps of the local smoothing: the vertices moved are those of one or two quads
// and their neighbours, a few edge lengths across; three sweeps carry a move over them.
constexpr int kSmoothSweeps = 3;
// Share of the smallest-angle floor one step of the repair after stitching may go down to (the
// result keeps the whole floor).
constexpr double kStepAngleShare = 0.5;

// The gate's order of two meshes: fewer folded quads, then no sliver, then the better worst
// corner (as garment/panel_fill.cpp ranks its candidates).
auto rank(const meshing::QuadQuality& q) {
  return std::tuple(q.inverted_quads, q.max_aspect_ratio >= kSliverAspect, -q.scaled_jacobian_min);
}

Face face(const meshing::QuadMesh& mesh, Eigen::Index f) {
  return {mesh.faces(f, 0), mesh.faces(f, 1), mesh.faces(f, 2), mesh.faces(f, 3)};
}

// Each quad's worst scaled corner by meshing::measure_quality's definition (against the sum of
// its vertices' normals, each the sum of the corner cross products around the vertex, plus
// `extra` where given: the rest of the garment's quads at a seam vertex).
std::vector<double> worst_corners(const meshing::QuadMesh& mesh, const Eigen::MatrixX3d& extra) {
  const auto corner = [&](const Face& q, int k) {
    const Eigen::Vector3d p = mesh.vertices.row(q[static_cast<size_t>(k)]).transpose();
    const Eigen::Vector3d e1 =
        mesh.vertices.row(q[static_cast<size_t>((k + 1) % 4)]).transpose() - p;
    const Eigen::Vector3d e2 =
        mesh.vertices.row(q[static_cast<size_t>((k + 3) % 4)]).transpose() - p;
    return std::pair(e1, e2);
  };
  std::vector<Eigen::Vector3d> normals(static_cast<size_t>(mesh.vertex_count()),
                                       Eigen::Vector3d::Zero());
  if (extra.rows() == mesh.vertex_count())
    for (Eigen::Index v = 0; v < extra.rows(); ++v)
      normals[static_cast<size_t>(v)] = extra.row(v).transpose();
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
    const Face q = face(mesh, f);
    for (int k = 0; k < 4; ++k) {
      const auto [e1, e2] = corner(q, k);
      normals[static_cast<size_t>(q[static_cast<size_t>(k)])] += e1.cross(e2);
    }
  }
  std::vector<double> worst(static_cast<size_t>(mesh.face_count()),
                            std::numeric_limits<double>::infinity());
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
    const Face q = face(mesh, f);
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    for (const int v : q) n += normals[static_cast<size_t>(v)];
    if (n.norm() > 0) n.normalize();
    for (int k = 0; k < 4; ++k) {
      const auto [e1, e2] = corner(q, k);
      const double scale = e1.norm() * e2.norm();
      worst[static_cast<size_t>(f)] =
          std::min(worst[static_cast<size_t>(f)], scale > 0 ? e1.cross(e2).dot(n) / scale : 0.0);
    }
  }
  return worst;
}

// degrees: the smallest corner angle over all quads as the gate measures it (the angle between
// a corner's edges, whichever way the corner turns; measure_quality counts a folded corner as
// reflex instead, and so misses a fold traded for a sliver).
double smallest_angle(const meshing::QuadMesh& mesh) {
  double largest_cosine = -1;
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f)
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d p = mesh.vertices.row(mesh.faces(f, k)).transpose();
      const Eigen::Vector3d e1 = mesh.vertices.row(mesh.faces(f, (k + 1) % 4)).transpose() - p;
      const Eigen::Vector3d e2 = mesh.vertices.row(mesh.faces(f, (k + 3) % 4)).transpose() - p;
      const double scale = e1.norm() * e2.norm();
      if (scale > 0) largest_cosine = std::max(largest_cosine, e1.dot(e2) / scale);
    }
  return std::acos(std::clamp(largest_cosine, -1.0, 1.0)) * 180 / std::numbers::pi;
}

// Edge neighbours of every vertex.
std::vector<std::vector<int>> edge_neighbours(const meshing::QuadMesh& mesh) {
  std::vector<std::vector<int>> around(static_cast<size_t>(mesh.vertex_count()));
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f)
    for (int k = 0; k < 4; ++k) {
      const int a = mesh.faces(f, k), b = mesh.faces(f, (k + 1) % 4);
      around[static_cast<size_t>(a)].push_back(b);
      around[static_cast<size_t>(b)].push_back(a);
    }
  for (auto& list : around) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  return around;
}

// The free vertices among `seeds` and their edge neighbours moved towards the mean of their
// own neighbours, lifted onto the surface after each move.
void smooth_around(meshing::QuadMesh& mesh, std::span<const char> fixed,
                   const std::vector<int>& seeds,
                   const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& project) {
  const auto around = edge_neighbours(mesh);
  std::set<int> moving;
  for (const int v : seeds) {
    if (!fixed[static_cast<size_t>(v)]) moving.insert(v);
    for (const int w : around[static_cast<size_t>(v)])
      if (!fixed[static_cast<size_t>(w)]) moving.insert(w);
  }
  for (int sweep = 0; sweep < kSmoothSweeps; ++sweep)
    for (const int v : moving) {
      const auto& list = around[static_cast<size_t>(v)];
      if (list.empty()) continue;
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (const int w : list) mean += mesh.vertices.row(w).transpose();
      mean /= static_cast<double>(list.size());
      mesh.vertices.row(v) = (project ? project(mean) : mean).transpose();
    }
}

}  // namespace

FoldRepairResult repair_folds(meshing::QuadMesh& mesh, std::span<const char> fixed,
                              std::span<const int> corner_vertices,
                              const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& project,
                              int rounds, const Eigen::MatrixX3d& extra_normals) {
  FoldRepairResult result;
  const bool stitched = extra_normals.rows() > 0;
  if (stitched && extra_normals.rows() != mesh.vertex_count())
    throw std::invalid_argument("repair_folds: one extra normal per vertex is needed");
  // measure_quality's figures, with the folds and the worst corner against the whole garment's
  // normals when the rest of it is given (a fold there is a corner below 0, as the gate counts).
  const double folded_below = stitched ? 0.0 : -1e-9;
  const auto judge = [&](const meshing::QuadMesh& m) {
    meshing::QuadQuality q = meshing::measure_quality(m, corner_vertices);
    if (stitched) {
      const std::vector<double> worst = worst_corners(m, extra_normals);
      q.inverted_quads = static_cast<int>(
          std::count_if(worst.begin(), worst.end(), [&](double w) { return w < folded_below; }));
      q.scaled_jacobian_min = *std::min_element(worst.begin(), worst.end());
    }
    return q;
  };
  const meshing::QuadQuality start = judge(mesh);
  meshing::QuadQuality quality = start;
  const double start_angle = smallest_angle(mesh);
  // A fold is not traded for a sharper corner or a longer sliver than the gate already warned
  // about (the tank top's back: 3 folds for a 0.7° corner where it had 3.0°): the result keeps
  // its smallest angle at min(10°, before) or more. Judged by the garment's normals, one step
  // may pass through a sharper corner that a later turn widens again (shirt-human's armpit: 3
  // folds at 7.9°, then 2 at 7.6°, then 1 with no corner below 10°), so there a step may go
  // down to kStepAngleShare of that floor, and the best state that keeps the floor is returned.
  const double floor_angle = std::min(kGateAngle, start_angle);
  const double step_floor = stitched ? kStepAngleShare * floor_angle : floor_angle;
  meshing::QuadMesh kept = mesh;
  meshing::QuadQuality kept_quality = quality;
  FoldRepairResult kept_result = result;
  result.folded_before = result.folded_after = quality.inverted_quads;
  kept_result = result;
  for (int round = 0; round < rounds && quality.inverted_quads > 0; ++round) {
    const std::vector<double> worst = worst_corners(mesh, extra_normals);
    std::set<std::pair<int, int>> edges;
    std::vector<int> valence(static_cast<size_t>(mesh.vertex_count()), 0);
    for (Eigen::Index f = 0; f < mesh.face_count(); ++f)
      for (int k = 0; k < 4; ++k) {
        const int a = mesh.faces(f, k), b = mesh.faces(f, (k + 1) % 4);
        edges.emplace(std::min(a, b), std::max(a, b));
        ++valence[static_cast<size_t>(a)];
      }
    // The quad on the other side of each directed edge: edge a -> b of one quad is b -> a of
    // its neighbour.
    std::vector<std::pair<std::pair<int, int>, Eigen::Index>> directed;
    for (Eigen::Index f = 0; f < mesh.face_count(); ++f)
      for (int k = 0; k < 4; ++k)
        directed.push_back({{mesh.faces(f, k), mesh.faces(f, (k + 1) % 4)}, f});
    std::sort(directed.begin(), directed.end());
    const auto across = [&](int a, int b) -> std::optional<Eigen::Index> {
      const auto it = std::lower_bound(directed.begin(), directed.end(),
                                       std::pair(std::pair(b, a), Eigen::Index{0}));
      if (it == directed.end() || it->first != std::pair(b, a)) return std::nullopt;
      return it->second;
    };

    std::optional<meshing::QuadMesh> best;
    meshing::QuadQuality best_quality = quality;
    bool best_is_turn = false;
    const auto consider = [&](meshing::QuadMesh&& candidate, bool turn) {
      const meshing::QuadQuality q = judge(candidate);
      if (smallest_angle(candidate) < step_floor ||
          q.max_aspect_ratio > std::max(kSliverAspect, start.max_aspect_ratio))
        return;
      if (rank(q) < rank(best_quality)) {
        best = std::move(candidate);
        best_quality = q;
        best_is_turn = turn;
      }
    };
    for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
      if (worst[static_cast<size_t>(f)] >= folded_below) continue;
      const Face q = face(mesh, f);
      // The interior around the fold smoothed.
      {
        meshing::QuadMesh candidate = mesh;
        smooth_around(candidate, fixed, std::vector<int>(q.begin(), q.end()), project);
        consider(std::move(candidate), false);
      }
      // Each inner edge of the quad turned: with the quad rotated to (s, x1, x2, t) and its
      // neighbour across t -> s to (t, y1, y2, s), the hexagon s x1 x2 t y1 y2 is split along
      // x1-y1 or x2-y2 instead of s-t (both quads keep the counter-clockwise order).
      for (int k = 0; k < 4; ++k) {
        const int t = q[static_cast<size_t>(k)], s = q[static_cast<size_t>((k + 1) % 4)];
        const auto g = across(t, s);
        if (!g) continue;
        const int x1 = q[static_cast<size_t>((k + 2) % 4)],
                  x2 = q[static_cast<size_t>((k + 3) % 4)];
        Face other = face(mesh, *g);
        const int at = static_cast<int>(std::find(other.begin(), other.end(), s) - other.begin());
        const int y1 = other[static_cast<size_t>((at + 2) % 4)],
                  y2 = other[static_cast<size_t>((at + 3) % 4)];
        // other = (s, t, y1, y2) from s, i.e. (t, y1, y2, s) from t.
        const std::array<int, 6> hexagon = {s, x1, x2, t, y1, y2};
        std::set<int> distinct(hexagon.begin(), hexagon.end());
        if (distinct.size() != 6) continue;
        // s and t each lose a quad: an interior vertex keeps at least 3, a boundary vertex 1.
        const auto keeps = [&](int v) {
          return valence[static_cast<size_t>(v)] - 1 >= (fixed[static_cast<size_t>(v)] ? 1 : 3);
        };
        if (!keeps(s) || !keeps(t)) continue;
        for (const auto& [u, w, first, second] :
             {std::tuple(x1, y1, Face{x1, x2, t, y1}, Face{y1, y2, s, x1}),
              std::tuple(x2, y2, Face{x2, t, y1, y2}, Face{y2, s, x1, x2})}) {
          if (edges.count({std::min(u, w), std::max(u, w)})) continue;  // the diagonal exists
          // A chord between two boundary vertices would cut the panel; two on one seam (a
          // centre seam shared with the mirror copy) would read as a seam edge used twice.
          if (fixed[static_cast<size_t>(u)] && fixed[static_cast<size_t>(w)]) continue;
          meshing::QuadMesh candidate = mesh;
          for (int c = 0; c < 4; ++c) {
            candidate.faces(f, c) = first[static_cast<size_t>(c)];
            candidate.faces(*g, c) = second[static_cast<size_t>(c)];
          }
          smooth_around(candidate, fixed, std::vector<int>(hexagon.begin(), hexagon.end()),
                        project);
          consider(std::move(candidate), true);
        }
      }
    }
    if (!best) break;
    mesh = std::move(*best);
    quality = best_quality;
    ++(best_is_turn ? result.edge_turns : result.smoothings);
    if (rank(quality) < rank(kept_quality) && smallest_angle(mesh) >= floor_angle) {
      kept = mesh;
      kept_quality = quality;
      kept_result = result;
    }
  }
  // Without the garment's normals every step keeps the floor, so `kept` is the last state.
  mesh = std::move(kept);
  kept_result.folded_after = kept_quality.inverted_quads;
  return kept_result;
}

}  // namespace sd::garment
