#include "garment/fold_repair.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <set>
#include <span>
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

Face face(const meshing::QuadMesh& mesh, Eigen::Index f) {
  return {mesh.faces(f, 0), mesh.faces(f, 1), mesh.faces(f, 2), mesh.faces(f, 3)};
}

constexpr double kInf = std::numeric_limits<double>::infinity();

// The corner cross product (m²) and edge lengths at corner k of quad q: e1 runs to the next
// corner, e2 to the previous one (meshing::measure_quality's corner).
struct Corner {
  Eigen::Vector3d e1, e2;
};
template <class At>
Corner corner_at(const At& at, const Face& q, int k) {
  const Eigen::Vector3d p = at(q[static_cast<size_t>(k)]);
  return {at(q[static_cast<size_t>((k + 1) % 4)]) - p, at(q[static_cast<size_t>((k + 3) % 4)]) - p};
}

// What the repair ranks a quad by: its worst scaled corner by meshing::measure_quality's
// definition (against the sum of its vertices' normals), longest / shortest edge, and the
// largest cosine of a corner angle whichever way it turns (the smallest angle, as the gate
// measures it; measure_quality counts a folded corner as reflex instead, and so misses a fold
// traded for a sliver).
struct QuadFigures {
  double worst = kInf;
  double aspect = 0;
  double largest_cosine = -1;
};

template <class At, class NormalAt>
QuadFigures figures_of(const At& at, const NormalAt& normal_at, const Face& q) {
  QuadFigures out;
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (const int v : q) n += normal_at(v);
  if (n.norm() > 0) n.normalize();
  double shortest = kInf, longest = 0;
  for (int k = 0; k < 4; ++k) {
    const Corner c = corner_at(at, q, k);
    const double l1 = c.e1.norm(), l2 = c.e2.norm(), scale = l1 * l2;
    shortest = std::min(shortest, l1);
    longest = std::max(longest, l1);
    out.worst = std::min(out.worst, scale > 0 ? c.e1.cross(c.e2).dot(n) / scale : 0.0);
    if (scale > 0) out.largest_cosine = std::max(out.largest_cosine, c.e1.dot(c.e2) / scale);
  }
  out.aspect = shortest > 0 ? longest / shortest : kInf;
  return out;
}

// The whole mesh's figures the repair ranks by (the gate's order, `rank`).
struct Summary {
  int folded = 0;       // quads whose worst corner is below the fold threshold
  double worst = kInf;  // smallest scaled corner
  double aspect = 0;    // largest aspect ratio
  double largest_cosine = -1;
  double smallest_angle() const {
    return std::acos(std::clamp(largest_cosine, -1.0, 1.0)) * 180 / std::numbers::pi;
  }
};

// The gate's order of two meshes: fewer folded quads, then no sliver, then the better worst
// corner (as garment/panel_fill.cpp ranks its candidates).
auto rank(const Summary& q) {
  return std::tuple(q.folded, q.aspect >= kSliverAspect, -q.worst);
}

// One round's mesh measured once: each vertex's normal (the sum of its corner cross products,
// plus `extra`), each quad's figures, the quads around each vertex, and the quads in the order
// of each figure, so that a candidate that changes a few quads is judged by re-measuring only
// those (the garment's other quads keep their figures). Judging every candidate on the whole
// mesh made a round cost (folded quads) × (candidates per fold) × (all quads): at a 4 mm edge
// length the shirt's back sleeve had 80 folds in 4,000 quads, and validate ran for minutes.
struct Round {
  std::vector<Eigen::Vector3d> normals;
  std::vector<QuadFigures> quads;
  std::vector<std::vector<Eigen::Index>> incident;  // per vertex, ascending quad ids
  std::vector<Eigen::Index> by_worst, by_aspect, by_cosine;
  Summary summary;
};

Round measure(const meshing::QuadMesh& mesh, const Eigen::MatrixX3d& extra, double folded_below) {
  Round r;
  const auto at = [&](int v) { return Eigen::Vector3d(mesh.vertices.row(v).transpose()); };
  r.normals.assign(static_cast<size_t>(mesh.vertex_count()), Eigen::Vector3d::Zero());
  if (extra.rows() == mesh.vertex_count())
    for (Eigen::Index v = 0; v < extra.rows(); ++v)
      r.normals[static_cast<size_t>(v)] = extra.row(v).transpose();
  r.incident.resize(r.normals.size());
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
    const Face q = face(mesh, f);
    for (int k = 0; k < 4; ++k) {
      const Corner c = corner_at(at, q, k);
      r.normals[static_cast<size_t>(q[static_cast<size_t>(k)])] += c.e1.cross(c.e2);
      r.incident[static_cast<size_t>(q[static_cast<size_t>(k)])].push_back(f);
    }
  }
  const auto normal_at = [&](int v) -> const Eigen::Vector3d& {
    return r.normals[static_cast<size_t>(v)];
  };
  r.quads.resize(static_cast<size_t>(mesh.face_count()));
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
    const QuadFigures& q = r.quads[static_cast<size_t>(f)] =
        figures_of(at, normal_at, face(mesh, f));
    r.summary.folded += q.worst < folded_below ? 1 : 0;
    r.summary.worst = std::min(r.summary.worst, q.worst);
    r.summary.aspect = std::max(r.summary.aspect, q.aspect);
    r.summary.largest_cosine = std::max(r.summary.largest_cosine, q.largest_cosine);
  }
  const auto order = [&](auto key) {
    std::vector<Eigen::Index> ids(r.quads.size());
    for (size_t f = 0; f < ids.size(); ++f) ids[f] = static_cast<Eigen::Index>(f);
    std::sort(ids.begin(), ids.end(), [&](Eigen::Index a, Eigen::Index b) {
      return key(r.quads[static_cast<size_t>(a)]) < key(r.quads[static_cast<size_t>(b)]);
    });
    return ids;
  };
  r.by_worst = order([](const QuadFigures& q) { return q.worst; });
  r.by_aspect = order([](const QuadFigures& q) { return -q.aspect; });
  r.by_cosine = order([](const QuadFigures& q) { return -q.largest_cosine; });
  return r;
}

// A candidate change of the round's mesh: a few quads given other corners, a few vertices moved.
class Trial {
 public:
  Trial(const meshing::QuadMesh& mesh, const Round& round) : mesh_(mesh), round_(round) {}

  void set_face(Eigen::Index f, const Face& q) { faces_[f] = q; }
  Face face_of(Eigen::Index f) const {
    const auto it = faces_.find(f);
    return it != faces_.end() ? it->second : face(mesh_, f);
  }
  Eigen::Vector3d at(int v) const {
    const auto it = moved_.find(v);
    return it != moved_.end() ? it->second : Eigen::Vector3d(mesh_.vertices.row(v).transpose());
  }
  // The quads around v after the change, ascending (the order the normals are summed in).
  std::vector<Eigen::Index> incident(int v) const {
    std::vector<Eigen::Index> out;
    for (const Eigen::Index f : round_.incident[static_cast<size_t>(v)])
      if (!faces_.count(f)) out.push_back(f);
    for (const auto& [f, q] : faces_)
      if (std::find(q.begin(), q.end(), v) != q.end()) out.push_back(f);
    std::sort(out.begin(), out.end());
    return out;
  }
  // The free vertices among `seeds` and their edge neighbours moved towards the mean of their
  // own neighbours, lifted onto the surface after each move.
  void smooth_around(std::span<const char> fixed, const std::vector<int>& seeds,
                     const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& project) {
    std::map<int, std::vector<int>> around;
    const auto neighbours = [&](int v) -> const std::vector<int>& {
      auto it = around.find(v);
      if (it != around.end()) return it->second;
      std::vector<int> list;
      for (const Eigen::Index f : incident(v)) {
        const Face q = face_of(f);
        const auto k = static_cast<size_t>(std::find(q.begin(), q.end(), v) - q.begin());
        list.push_back(q[(k + 1) % 4]);
        list.push_back(q[(k + 3) % 4]);
      }
      std::sort(list.begin(), list.end());
      list.erase(std::unique(list.begin(), list.end()), list.end());
      return around.emplace(v, std::move(list)).first->second;
    };
    std::set<int> moving;
    for (const int v : seeds) {
      if (!fixed[static_cast<size_t>(v)]) moving.insert(v);
      for (const int w : neighbours(v))
        if (!fixed[static_cast<size_t>(w)]) moving.insert(w);
    }
    for (int sweep = 0; sweep < kSmoothSweeps; ++sweep)
      for (const int v : moving) {
        const auto& list = neighbours(v);
        if (list.empty()) continue;
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        for (const int w : list) mean += at(w);
        mean /= static_cast<double>(list.size());
        moved_[v] = project ? project(mean) : mean;
      }
  }
  // The mesh's figures after the change: the quads whose corners or vertex normals the change
  // reaches measured again (`measured` counts them), the others taken from the round.
  Summary judge(const Eigen::MatrixX3d& extra, double folded_below, long& measured) const {
    std::set<int> touched;  // vertices whose corner cross products change
    for (const auto& [v, p] : moved_) {
      for (const Eigen::Index f : incident(v))
        for (const int w : face_of(f)) touched.insert(w);
    }
    for (const auto& [f, q] : faces_) {
      touched.insert(q.begin(), q.end());
      const Face old = face(mesh_, f);
      touched.insert(old.begin(), old.end());
    }
    std::map<int, Eigen::Vector3d> normals;
    std::set<Eigen::Index> quads;
    const auto pos = [&](int v) { return at(v); };
    for (const int v : touched) {
      Eigen::Vector3d n =
          extra.rows() > 0 ? Eigen::Vector3d(extra.row(v).transpose()) : Eigen::Vector3d::Zero();
      for (const Eigen::Index f : incident(v)) {
        const Face q = face_of(f);
        const int k = static_cast<int>(std::find(q.begin(), q.end(), v) - q.begin());
        const Corner c = corner_at(pos, q, k);
        n += c.e1.cross(c.e2);
        quads.insert(f);
      }
      normals[v] = n;
    }
    const auto normal_at = [&](int v) -> const Eigen::Vector3d& {
      const auto it = normals.find(v);
      return it != normals.end() ? it->second : round_.normals[static_cast<size_t>(v)];
    };
    Summary s = round_.summary;
    s.worst = kInf, s.aspect = 0, s.largest_cosine = -1;
    for (const Eigen::Index f : quads) {
      const QuadFigures& was = round_.quads[static_cast<size_t>(f)];
      const QuadFigures now = figures_of(pos, normal_at, face_of(f));
      ++measured;
      s.folded += (now.worst < folded_below ? 1 : 0) - (was.worst < folded_below ? 1 : 0);
      s.worst = std::min(s.worst, now.worst);
      s.aspect = std::max(s.aspect, now.aspect);
      s.largest_cosine = std::max(s.largest_cosine, now.largest_cosine);
    }
    // The extremes of the quads the change does not reach: the first in each order that is
    // not among the re-measured ones.
    const auto first_other = [&](const std::vector<Eigen::Index>& order) -> const QuadFigures* {
      for (const Eigen::Index f : order)
        if (!quads.count(f)) return &round_.quads[static_cast<size_t>(f)];
      return nullptr;
    };
    if (const QuadFigures* q = first_other(round_.by_worst)) s.worst = std::min(s.worst, q->worst);
    if (const QuadFigures* q = first_other(round_.by_aspect))
      s.aspect = std::max(s.aspect, q->aspect);
    if (const QuadFigures* q = first_other(round_.by_cosine))
      s.largest_cosine = std::max(s.largest_cosine, q->largest_cosine);
    return s;
  }
  // The change written into `mesh`.
  void apply(meshing::QuadMesh& mesh) const {
    for (const auto& [f, q] : faces_)
      for (int c = 0; c < 4; ++c) mesh.faces(f, c) = q[static_cast<size_t>(c)];
    for (const auto& [v, p] : moved_) mesh.vertices.row(v) = p.transpose();
  }

 private:
  const meshing::QuadMesh& mesh_;
  const Round& round_;
  std::map<Eigen::Index, Face> faces_;
  std::map<int, Eigen::Vector3d> moved_;
};

}  // namespace

FoldRepairResult repair_folds(meshing::QuadMesh& mesh, std::span<const char> fixed,
                              std::span<const int> corner_vertices,
                              const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& project,
                              int rounds, const Eigen::MatrixX3d& extra_normals) {
  (void)corner_vertices;  // valence figures do not enter the ranking
  FoldRepairResult result;
  const bool stitched = extra_normals.rows() > 0;
  if (stitched && extra_normals.rows() != mesh.vertex_count())
    throw std::invalid_argument("repair_folds: one extra normal per vertex is needed");
  // measure_quality's figures, with the folds and the worst corner against the whole garment's
  // normals when the rest of it is given (a fold there is a corner below 0, as the gate counts).
  const double folded_below = stitched ? 0.0 : -1e-9;
  Round round = measure(mesh, extra_normals, folded_below);
  const Summary start = round.summary;
  Summary quality = start;
  const double start_angle = start.smallest_angle();
  // A fold is not traded for a sharper corner or a longer sliver than the gate already warned
  // about (the tank top's back: 3 folds for a 0.7° corner where it had 3.0°): the result keeps
  // its smallest angle at min(10°, before) or more. Judged by the garment's normals, one step
  // may pass through a sharper corner that a later turn widens again (shirt-human's armpit: 3
  // folds at 7.9°, then 2 at 7.6°, then 1 with no corner below 10°), so there a step may go
  // down to kStepAngleShare of that floor, and the best state that keeps the floor is returned.
  const double floor_angle = std::min(kGateAngle, start_angle);
  const double step_floor = stitched ? kStepAngleShare * floor_angle : floor_angle;
  meshing::QuadMesh kept = mesh;
  Summary kept_quality = quality;
  result.folded_before = result.folded_after = quality.folded;
  FoldRepairResult kept_result = result;
  for (int r = 0; r < rounds && quality.folded > 0; ++r) {
    if (r > 0) round = measure(mesh, extra_normals, folded_below);
    std::set<std::pair<int, int>> edges;
    for (Eigen::Index f = 0; f < mesh.face_count(); ++f)
      for (int k = 0; k < 4; ++k) {
        const int a = mesh.faces(f, k), b = mesh.faces(f, (k + 1) % 4);
        edges.emplace(std::min(a, b), std::max(a, b));
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

    std::optional<Trial> best;
    Summary best_quality = quality;
    bool best_is_turn = false;
    const auto consider = [&](Trial&& candidate, bool turn) {
      ++result.candidates;
      const Summary q = candidate.judge(extra_normals, folded_below, result.quads_measured);
      if (q.smallest_angle() < step_floor || q.aspect > std::max(kSliverAspect, start.aspect))
        return;
      if (rank(q) < rank(best_quality)) {
        best.emplace(std::move(candidate));
        best_quality = q;
        best_is_turn = turn;
      }
    };
    for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
      if (round.quads[static_cast<size_t>(f)].worst >= folded_below) continue;
      const Face q = face(mesh, f);
      // The interior around the fold smoothed.
      {
        Trial candidate(mesh, round);
        candidate.smooth_around(fixed, std::vector<int>(q.begin(), q.end()), project);
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
          return static_cast<int>(round.incident[static_cast<size_t>(v)].size()) - 1 >=
                 (fixed[static_cast<size_t>(v)] ? 1 : 3);
        };
        if (!keeps(s) || !keeps(t)) continue;
        for (const auto& [u, w, first, second] :
             {std::tuple(x1, y1, Face{x1, x2, t, y1}, Face{y1, y2, s, x1}),
              std::tuple(x2, y2, Face{x2, t, y1, y2}, Face{y2, s, x1, x2})}) {
          if (edges.count({std::min(u, w), std::max(u, w)})) continue;  // the diagonal exists
          // A chord between two boundary vertices would cut the panel; two on one seam (a
          // centre seam shared with the mirror copy) would read as a seam edge used twice.
          if (fixed[static_cast<size_t>(u)] && fixed[static_cast<size_t>(w)]) continue;
          Trial candidate(mesh, round);
          candidate.set_face(f, first);
          candidate.set_face(*g, second);
          candidate.smooth_around(fixed, std::vector<int>(hexagon.begin(), hexagon.end()), project);
          consider(std::move(candidate), true);
        }
      }
    }
    if (!best) break;
    best->apply(mesh);
    quality = best_quality;
    ++(best_is_turn ? result.edge_turns : result.smoothings);
    if (rank(quality) < rank(kept_quality) && quality.smallest_angle() >= floor_angle) {
      kept = mesh;
      kept_quality = quality;
      kept_result = result;
    }
  }
  // Without the garment's normals every step keeps the floor, so `kept` is the last state.
  mesh = std::move(kept);
  kept_result.folded_after = kept_quality.folded;
  kept_result.candidates = result.candidates;
  kept_result.quads_measured = result.quads_measured;
  return kept_result;
}

}  // namespace sd::garment
