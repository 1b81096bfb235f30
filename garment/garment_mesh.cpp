#include "garment/garment_mesh.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>
#include <numeric>
#include <optional>
#include <set>
#include <stdexcept>
#include <tuple>
#include <unordered_map>
#include <utility>

#include "garment/body_landmarks.hpp"
#include "garment/curve_network.hpp"
#include "garment/edge_counts.hpp"
#include "garment/fold_repair.hpp"
#include "garment/garment_crossings.hpp"
#include "garment/network_faces.hpp"
#include "garment/panel_fill.hpp"
#include "garment/panel_grain.hpp"
#include "garment/panel_loop.hpp"
#include "garment/panel_surface.hpp"
#include "garment/panel_tasks.hpp"
#include "garment/sketch_ranges.hpp"
#include "garment/stroke_projection.hpp"
#include "garment/surface_relaxation.hpp"
#include "garment/surface_untangle.hpp"
#include "meshing/patch_fill.hpp"
#include "meshing/quad_quality.hpp"

namespace sd::garment {
namespace {

// Global vertices of the garment: node and curve-piece vertices are made once and shared.
struct VertexPool {
  std::vector<Eigen::Vector3d> positions;
  int add(const Eigen::Vector3d& p) {
    positions.push_back(p);
    return static_cast<int>(positions.size()) - 1;
  }
};

// A seam vertex where both panels have a side vertex of valence 2 (the filler may move a corner
// of a region along its boundary, and a mirrored panel and its copy do it at the same place)
// becomes an interior vertex of valence 2: quads F1 = (b, c, x, a) and F2 = (b, a, y, c) folded
// onto each other along a-b-c. Such a doublet is removed by merging them into (c, x, a, y),
// which keeps F1's panel. Returns each one removed; `faces`/`face_panel` are edited.
struct Doublet {
  int vertex = -1;             // b, left in no face
  int neighbour = -1;          // c: b-c is an edge of the seam b was on
  int panel = -1, other = -1;  // of F1 and F2
};
std::vector<Doublet> remove_doublets(std::vector<std::array<int, 4>>& faces,
                                     std::vector<int>& face_panel, size_t vertex_count) {
  std::vector<Doublet> removed;
  for (bool changed = true; changed;) {
    changed = false;
    std::vector<std::vector<int>> incident(vertex_count);
    for (size_t f = 0; f < faces.size(); ++f)
      for (int v : faces[f]) incident[static_cast<size_t>(v)].push_back(static_cast<int>(f));
    for (size_t b = 0; b < vertex_count && !changed; ++b) {
      if (incident[b].size() != 2) continue;
      auto rotated = [&](int f) {  // the face with b first
        std::array<int, 4> q = faces[static_cast<size_t>(f)];
        while (q[0] != static_cast<int>(b)) std::rotate(q.begin(), q.begin() + 1, q.end());
        return q;
      };
      const std::array<int, 4> f1 = rotated(incident[b][0]), f2 = rotated(incident[b][1]);
      if (f2[1] != f1[3] || f2[3] != f1[1]) continue;  // b is a boundary vertex, not a doublet
      removed.push_back({static_cast<int>(b), f1[1],
                         face_panel[static_cast<size_t>(incident[b][0])],
                         face_panel[static_cast<size_t>(incident[b][1])]});
      faces[static_cast<size_t>(incident[b][0])] = {f1[1], f1[2], f1[3], f2[2]};
      faces.erase(faces.begin() + incident[b][1]);
      face_panel.erase(face_panel.begin() + incident[b][1]);
      changed = true;
    }
  }
  return removed;
}

}  // namespace

std::string body_part_name(BodyPart part) {
  switch (part) {
    case BodyPart::kHead:
      return "head";
    case BodyPart::kTorso:
      return "torso";
    case BodyPart::kLeftArm:
      return "left_arm";
    case BodyPart::kRightArm:
      return "right_arm";
    case BodyPart::kLeftLeg:
      return "left_leg";
    case BodyPart::kRightLeg:
      return "right_leg";
  }
  return "torso";
}

BodyPart classify_body_point(const Eigen::Vector3d& p, double height) {
  const double y = p.y() / height, x = p.x() / height;
  if (y > 0.86) return BodyPart::kHead;
  if (y < 0.45) return x >= 0 ? BodyPart::kLeftLeg : BodyPart::kRightLeg;
  if (std::abs(x) > 0.105) return x > 0 ? BodyPart::kLeftArm : BodyPart::kRightArm;
  return BodyPart::kTorso;
}

namespace {

// m: two boundary curves closer than a quarter edge (3 mm .. 1 cm) for longer than this, away
// from their junctions, are drawn over one line (check_overlapping_boundaries).
constexpr double kOverlapRun = 0.03;

// Stage 1, the panels on the curve network: strokes projected on the body, the network (with
// the mirror copies of every curve a mirrored panel uses), the panel loops and the edge count of
// every curve piece, and the panels' sizes checked against the body.
struct PanelNetwork {
  CurveNetwork net;
  std::vector<PanelLoop> loops;
  EdgeCounts counts;
};

// The cause of an error at a junction near `p` when curve ends were joined there to the
// interior of another curve for lying within the junction tolerance of it (trial 44, P1: a
// sleeve hem ending 1.9 cm from the side seam cut it in two, and the errors named only the
// 2.4 cm piece and "two curves along one seam"): a sentence to append, or empty.
std::string t_join_cause(const GarmentRequest& sketch, const CurveNetwork& net,
                         const Eigen::Vector3d& p) {
  const double tol = sketch.junction_tolerance;
  for (const TJoin& join : net.t_joins) {
    if ((net.nodes[static_cast<size_t>(join.node)] - p).norm() > 0.25 * tol) continue;
    std::string ends;  // "the end of 'a', the end of 'b' and the start of 'c'"
    for (size_t k = 0; k < join.ends.size(); ++k)
      ends += (k == 0 ? "" : (k + 1 == join.ends.size() ? " and " : ", ")) + join.ends[k];
    const bool one = join.ends.size() == 1;
    return fmt::format(
        ". The cause: {} at ({:.3f}, {:.3f}, {:.3f}) m {} {:.1f} cm from the interior of curve "
        "'{}', closer than junction_tolerance ({:.1f} cm), so {} joined to it there (a "
        "T-junction, which cuts '{}' in two); if {} not meant to end on '{}', end {} farther "
        "from it or lower junction_tolerance below {:.1f} cm",
        ends, join.from.x(), join.from.y(), join.from.z(), one ? "was" : "were",
        100 * join.distance, join.curve, 100 * tol, one ? "it was" : "they were", join.curve,
        one ? "it is" : "they are", join.curve, one ? "it" : "them",
        std::floor(1000 * join.distance) / 10);
  }
  return "";
}

// Two curve pieces in panels between the same two junctions must not both be one edge: each
// would be the same straight edge between those junctions, one mesh edge for two seams, and the
// panels on them would overlap (a coarse edge_length over a shirt's armhole halves made the
// stitched mesh's seam checks name panels that share no curve). Fails naming both curves, the
// place and the edge_length that gives the shorter two edges.
void check_single_edges_apart(const GarmentRequest& sketch, const BodySurface& body,
                              const CurveNetwork& net, const std::vector<PanelLoop>& loops,
                              const EdgeCounts& counts) {
  std::vector<bool> used(net.edges.size(), false);
  for (const PanelLoop& loop : loops)
    for (const LoopEdge& e : loop.edges) used[static_cast<size_t>(e.edge)] = true;
  std::map<std::pair<int, int>, int> single;  // junction pair → the first one-edge piece
  for (size_t e = 0; e < net.edges.size(); ++e) {
    const NetworkEdge& edge = net.edges[e];
    if (!used[e] || counts.counts[e] != 1 || edge.from == edge.to) continue;
    const auto [it, fresh] =
        single.try_emplace(std::minmax(edge.from, edge.to), static_cast<int>(e));
    if (fresh) continue;
    const NetworkEdge& other = net.edges[static_cast<size_t>(it->second)];
    const NetworkCurve& a = net.curves[static_cast<size_t>(other.curve)];
    const NetworkCurve& b = net.curves[static_cast<size_t>(edge.curve)];
    const Eigen::Vector3d& p = net.nodes[static_cast<size_t>(edge.from)];
    const Eigen::Vector3d& q = net.nodes[static_cast<size_t>(edge.to)];
    std::string landmark;
    if (const BodyLandmarks* landmarks = body.landmarks())
      landmark = fmt::format(", near the {}", landmarks->nearest(0.5 * (p + q)).name);
    const double shorter = std::min(edge.length, other.length);
    std::string cause = t_join_cause(sketch, net, p);
    if (cause.empty()) cause = t_join_cause(sketch, net, q);
    const CurveSpec& spec = sketch.curves[static_cast<size_t>(std::max(a.spec, b.spec))];
    sketch.fail(
        spec.edge_length ? spec.json_path + "/edge_length" : std::string("/edge_length"),
        fmt::format("curves '{}' and '{}' both run between the junctions at ({:.3f}, {:.3f}, "
                    "{:.3f}) and ({:.3f}, {:.3f}, {:.3f}) m{} ({:.1f} and {:.1f} cm long), and at "
                    "this edge length each is a single edge: both become the same straight edge, "
                    "and the panels on them would lie over each other. Give a smaller "
                    "\"edge_length\" (at most {:.3g} m gives each at least two edges), or give "
                    "these two curves their own \"edge_length\"{}",
                    a.id, b.id, p.x(), p.y(), p.z(), q.x(), q.y(), q.z(), landmark,
                    100 * other.length, 100 * edge.length, std::floor(1e3 * shorter / 1.6) / 1e3,
                    cause));
  }
}

// A mirrored panel is one side's half of a piece, its copy the other's: one drawn whole across
// the mirror plane x = 0 (its outline farther than the junction tolerance on both sides) would
// lie over its copy. Fails at its "mirror" naming how far it reaches either side. Before, a front
// drawn whole with "mirror": true was refused as two panels meeting "only at the point" (or, as
// trial 40's P4 made the message, as its hem lying on its own mirror copy). A panel whose
// junctions all lie on one side (or on the plane) is a half with a curve straying across between
// them: one written point typed on the wrong side (trial 42, P12: a side seam's middle point at
// x = -0.165 for 0.165, and the panel was blamed as drawn whole). That fails at the curve's
// written point nearest to where the outline reaches farthest across.
void check_mirrored_halves(const GarmentRequest& sketch, const BodySurface& body,
                           const CurveNetwork& net, const std::vector<PanelLoop>& loops) {
  const double tol = sketch.junction_tolerance;
  for (const PanelLoop& loop : loops) {
    if (loop.mirror_copy || !sketch.panels[static_cast<size_t>(loop.spec)].mirror) continue;
    double low = std::numeric_limits<double>::infinity(), high = -low;
    double junction_low = low, junction_high = high;
    for (const LoopEdge& e : loop.edges) {
      const NetworkEdge& edge = net.edges[static_cast<size_t>(e.edge)];
      low = std::min(low, edge.points.col(0).minCoeff());
      high = std::max(high, edge.points.col(0).maxCoeff());
      for (const int node : {edge.from, edge.to}) {
        junction_low = std::min(junction_low, net.nodes[static_cast<size_t>(node)].x());
        junction_high = std::max(junction_high, net.nodes[static_cast<size_t>(node)].x());
      }
    }
    if (!(low < -tol && high > tol)) continue;
    // The side of x = 0 the junctions are on (+1, -1), or 0 when on both or only on the plane.
    const int side = junction_low >= -tol && junction_high > tol   ? 1
                     : junction_high <= tol && junction_low < -tol ? -1
                                                                   : 0;
    if (side != 0) {
      // The point of the outline farthest across, and its curve.
      double farthest = 0;
      Eigen::Vector3d where = Eigen::Vector3d::Zero();
      const NetworkCurve* stray = nullptr;
      for (const LoopEdge& e : loop.edges) {
        const NetworkEdge& edge = net.edges[static_cast<size_t>(e.edge)];
        for (Eigen::Index k = 0; k < edge.points.rows(); ++k)
          if (-side * edge.points(k, 0) > farthest) {
            farthest = -side * edge.points(k, 0);
            where = edge.points.row(k).transpose();
            stray = &net.curves[static_cast<size_t>(edge.curve)];
          }
      }
      const CurveSpec& spec = sketch.curves[static_cast<size_t>(stray->spec)];
      // A mirror copy's written points are its original's, reflected.
      const Eigen::Vector3d written_where =
          stray->mirror_copy ? Eigen::Vector3d(-where.x(), where.y(), where.z()) : where;
      const std::optional<WrittenPoint> point = nearest_written_point(spec, written_where);
      const std::string key = spec.is_3d() ? "/points3d" : "/points";
      std::string landmark;
      if (const BodyLandmarks* landmarks = body.landmarks())
        landmark = fmt::format(", near the {}", landmarks->nearest(where).name);
      const char* own = side > 0 ? "x > 0" : "x < 0";
      sketch.fail(
          spec.json_path + key + (point ? fmt::format("/{}", point->index) : std::string()),
          fmt::format(
              "curve '{}' of panel '{}' reaches {:.1f} cm across the mirror plane x = 0 at "
              "({:.3f}, {:.3f}, {:.3f}) m{}, while the panel's junctions all lie on the {} side{}: "
              "a sign typed wrong? Panel '{}' has \"mirror\": true, so it is one half of a "
              "piece, on one side of x = 0, and its mirror copy would lie over it there: move "
              "the point to the {} side",
              stray->id, loop.id, 100 * farthest, where.x(), where.y(), where.z(), landmark, own,
              point ? fmt::format("; the curve's written point nearest there is {}, {}{}",
                                  point->index, point->text,
                                  stray->mirror_copy
                                      ? fmt::format(" (of '{}', whose copy it is)", spec.id)
                                      : std::string())
                    : std::string(),
              loop.id, own));
    }
    sketch.fail(loop.json_path + "/mirror",
                fmt::format("panel '{}' has \"mirror\": true but reaches across the mirror plane "
                            "x = 0 (its outline runs from x = {:.3f} to {:.3f} m), so its mirror "
                            "copy would lie over it. A mirrored panel is one half of a piece, on "
                            "one side of x = 0 (its centre curve drawn at x = 0): draw only that "
                            "half, or remove \"mirror\" for a panel drawn whole",
                            loop.id, low, high));
  }
}

PanelNetwork resolve_network(const GarmentRequest& sketch, const BodySurface& body) {
  check_against_body(sketch, body.box());
  const std::vector<ProjectedCurve> projected = project_curves(sketch, body);
  std::set<std::string> mirrored = curves_to_mirror(sketch);
  CurveNetwork net = build_network(sketch, projected, mirrored);
  // A mirrored "auto" panel's curves are known only once its region is found; their copies can
  // change the regions on the other side, so repeat until the set settles (twice in practice).
  for (int pass = 0; pass < 4; ++pass) {
    const size_t before = mirrored.size();
    mirrored.merge(auto_panel_curves_to_mirror(sketch, net, body));
    if (mirrored.size() == before) break;
    net = build_network(sketch, projected, mirrored);
  }
  std::vector<PanelLoop> loops = resolve_panels(sketch, net, body);
  check_mirrored_halves(sketch, body, net, loops);
  EdgeCounts counts = compute_edge_counts(sketch, net, loops);
  check_single_edges_apart(sketch, body, net, loops, counts);
  {
    // Each panel's size from its edge counts and its curves' polylines, before any fill.
    std::vector<PanelSize> sizes;
    for (const PanelLoop& loop : loops) {
      PanelSize& size = sizes.emplace_back();
      size.id = loop.id;
      size.path = loop.json_path;
      size.mirror_copy = loop.mirror_copy;
      std::vector<Eigen::Vector3d> outline;
      for (const LoopEdge& e : loop.edges) {
        const NetworkEdge& edge = net.edges[static_cast<size_t>(e.edge)];
        size.boundary_edges += counts.counts[static_cast<size_t>(e.edge)];
        size.boundary_length += edge.length;
        const int spec = net.curves[static_cast<size_t>(edge.curve)].spec;
        if (spec >= 0 && sketch.curves[static_cast<size_t>(spec)].edges)
          size.fixed.push_back(
              {spec, static_cast<double>(counts.counts[static_cast<size_t>(e.edge)]), edge.length});
        const Eigen::Index n = edge.points.rows();
        for (Eigen::Index j = 0; j + 1 < n; ++j)
          outline.emplace_back(edge.points.row(e.forward ? j : n - 1 - j).transpose());
      }
      size.area = fan_area(outline);
    }
    check_panel_sizes(sketch, sizes);
    // Said before the long fill, once per file and panel: the gate's trials build it again.
    for (const std::string& warning : fine_edge_warnings(sketch, sizes)) {
      static std::mutex mutex;
      static std::set<std::string> said;
      const std::lock_guard lock(mutex);
      if (said.insert(warning.substr(0, warning.find(" has edges of"))).second)
        spdlog::warn("{}", warning);
    }
    double total = 0;
    for (const PanelSize& size : sizes) total += estimated_quads(size);
    spdlog::debug("{}: about {:.0f} quads expected", sketch.file, total);
  }

  return {std::move(net), std::move(loops), std::move(counts)};
}

// Stage 2: which panels use each curve piece (#edges of the network, at most two each).
std::vector<std::vector<int>> seam_users(const GarmentRequest& sketch, const CurveNetwork& net,
                                         const std::vector<PanelLoop>& loops) {
  // A curve piece is a seam between at most two panels.
  std::vector<std::vector<int>> users(net.edges.size());
  for (size_t l = 0; l < loops.size(); ++l)
    for (const LoopEdge& e : loops[l].edges) {
      auto& u = users[static_cast<size_t>(e.edge)];
      if (u.size() == 2) {
        const std::string& curve =
            net.curves[static_cast<size_t>(net.edges[static_cast<size_t>(e.edge)].curve)].id;
        sketch.fail(loops[l].json_path + "/boundary",
                    fmt::format("curve '{}' already joins panels '{}' and '{}'; a seam joins "
                                "exactly two panels, so '{}' cannot use it too",
                                curve, loops[static_cast<size_t>(u[0])].id,
                                loops[static_cast<size_t>(u[1])].id, loops[l].id));
      }
      u.push_back(static_cast<int>(l));
    }

  return users;
}

// Boundary vertices: placed once per curve piece by arc length; a copy's are the exact mirror
// images of its original's (so mirrored panels match bitwise).
class BoundaryVertices {
 public:
  BoundaryVertices(const CurveNetwork& net, const EdgeCounts& counts, VertexPool& pool)
      : net_(net),
        counts_(counts),
        pool_(pool),
        node_vertex_(net.nodes.size(), -1),
        placed_(net.edges.size()),
        edge_ids_(net.edges.size()) {}

  // #points by 3: the piece's vertices from its start node to its end node.
  const Eigen::MatrixX3d& points(int e) {
    Eigen::MatrixX3d& p = placed_[static_cast<size_t>(e)];
    if (p.rows() > 0) return p;
    const NetworkEdge& edge = net_.edges[static_cast<size_t>(e)];
    const int orbit = edge.orbit;
    const int n = counts_.counts[static_cast<size_t>(e)];
    if (orbit == e) {
      p = meshing::resample_by_arc_length(edge.points, n);
      if (edge.points.col(0).cwiseAbs().maxCoeff() == 0) p.col(0).setZero();
    } else {
      Eigen::MatrixX3d original =
          meshing::resample_by_arc_length(net_.edges[static_cast<size_t>(orbit)].points, n);
      if (net_.edges[static_cast<size_t>(orbit)].points.col(0).cwiseAbs().maxCoeff() == 0)
        original.col(0).setZero();
      original.col(0) *= -1.0;
      p = original;
    }
    p.row(0) = net_.nodes[static_cast<size_t>(edge.from)].transpose();
    p.row(p.rows() - 1) = net_.nodes[static_cast<size_t>(edge.to)].transpose();
    return p;
  }

  // The pool ids of points(e) if they were placed, else an empty list (adds nothing).
  const std::vector<int>& placed_ids(int e) const { return edge_ids_[static_cast<size_t>(e)]; }

  // The pool ids of points(e), the end nodes shared with the pieces that meet there.
  const std::vector<int>& ids(int e) {
    std::vector<int>& ids = edge_ids_[static_cast<size_t>(e)];
    if (!ids.empty()) return ids;
    const NetworkEdge& edge = net_.edges[static_cast<size_t>(e)];
    const Eigen::MatrixX3d& p = points(e);
    auto node_id = [&](int node) {
      int& v = node_vertex_[static_cast<size_t>(node)];
      if (v < 0) v = pool_.add(net_.nodes[static_cast<size_t>(node)]);
      return v;
    };
    ids.push_back(node_id(edge.from));
    for (Eigen::Index k = 1; k + 1 < p.rows(); ++k) ids.push_back(pool_.add(p.row(k).transpose()));
    ids.push_back(node_id(edge.to));
    return ids;
  }

 private:
  const CurveNetwork& net_;
  const EdgeCounts& counts_;
  VertexPool& pool_;
  std::vector<int> node_vertex_;
  std::vector<Eigen::MatrixX3d> placed_;
  std::vector<std::vector<int>> edge_ids_;
};

// A panel's sides, corner i to corner i+1: the points of its curve pieces joined (each junction
// once) and, when `ids` is given, their pool ids (which adds the pieces' vertices to the pool).
std::vector<Eigen::MatrixX3d> panel_sides(const PanelLoop& loop, BoundaryVertices& boundary,
                                          std::vector<std::vector<int>>* ids) {
  std::vector<Eigen::MatrixX3d> sides;
  if (ids) ids->clear();
  for (int s = 0; s < loop.side_count(); ++s) {
    std::vector<Eigen::Vector3d> pts;
    std::vector<int> side_ids;
    for (int k = loop.side_begin[static_cast<size_t>(s)]; k < loop.side_end(s); ++k) {
      const LoopEdge& e = loop.edges[static_cast<size_t>(k)];
      const Eigen::MatrixX3d& p = boundary.points(e.edge);
      const Eigen::Index n = p.rows();
      for (Eigen::Index j = 0; j < n; ++j) {
        const Eigen::Index src = e.forward ? j : n - 1 - j;
        if (!pts.empty() && j == 0) continue;  // the junction is already there
        pts.push_back(p.row(src).transpose());
        if (ids) side_ids.push_back(boundary.ids(e.edge)[static_cast<size_t>(src)]);
      }
    }
    Eigen::MatrixX3d m(static_cast<Eigen::Index>(pts.size()), 3);
    for (size_t j = 0; j < pts.size(); ++j)
      m.row(static_cast<Eigen::Index>(j)) = pts[j].transpose();
    sides.push_back(std::move(m));
    if (ids) ids->push_back(std::move(side_ids));
  }
  return sides;
}

// The gate's scaled Jacobian of quad `q` (garment/quality_gate.cpp): its worst corner against the
// sum of its vertices' normals, each the sum of the corner cross products around the vertex over
// the whole garment; below 0 it folds.
double gate_jacobian(const std::array<int, 4>& q, const std::vector<Eigen::Vector3d>& positions,
                     const std::vector<Eigen::Vector3d>& normals) {
  Eigen::Vector3d reference = Eigen::Vector3d::Zero();
  for (const int v : q) reference += normals[static_cast<size_t>(v)];
  if (reference.norm() == 0) return 1;
  reference.normalize();
  double jacobian = 1;
  for (size_t k = 0; k < 4; ++k) {
    const Eigen::Vector3d& p = positions[static_cast<size_t>(q[k])];
    const Eigen::Vector3d e1 = positions[static_cast<size_t>(q[(k + 1) % 4])] - p;
    const Eigen::Vector3d e2 = positions[static_cast<size_t>(q[(k + 3) % 4])] - p;
    const double l1 = e1.norm(), l2 = e2.norm();
    if (l1 > 0 && l2 > 0) jacobian = std::min(jacobian, e1.cross(e2).dot(reference) / (l1 * l2));
  }
  return jacobian;
}

// The corner cross products of `faces` summed at each vertex (#pool): the gate's vertex normals.
std::vector<Eigen::Vector3d> corner_normals(const std::vector<std::array<int, 4>>& faces,
                                            const std::vector<Eigen::Vector3d>& positions) {
  std::vector<Eigen::Vector3d> normals(positions.size(), Eigen::Vector3d::Zero());
  for (const auto& q : faces)
    for (size_t k = 0; k < 4; ++k) {
      const Eigen::Vector3d& b = positions[static_cast<size_t>(q[k])];
      normals[static_cast<size_t>(q[k])] +=
          (positions[static_cast<size_t>(q[(k + 1) % 4])] - b)
              .cross(positions[static_cast<size_t>(q[(k + 3) % 4])] - b);
    }
  return normals;
}

// Stage 3b, folds only the stitched garment shows. The fold repair of fill_panel judges a panel
// by its own quads' normals; the quality gate by the garment's, in which a seam vertex's normal
// also sums the neighbouring panels' quads. At a corner that turns about 200° in one quad on
// the body's saddle (shirt-human's back sleeve at the armpit) the two disagree: the panel alone
// had 2 folds there, the garment 3, and the turn that mended the first did not mend the
// second. Here every original panel that folds by the gate's measure is repaired again with the
// rest of the garment's share of each vertex's normal (fold_repair.hpp, `extra_normals`); its
// mirror copies follow. Kept only when the whole garment then has fewer folded quads (a
// repair moves no seam vertex, but it changes the normals the neighbours are judged by).
// `face_range[l]` are loop l's quads in `faces`, `loop_globals[l]` its patch vertices' pool ids.
// Returns how many panels were repaired.
int repair_stitched_folds(const GarmentRequest& sketch, const CurveNetwork& net,
                          const BodySurface& body, const std::vector<PanelLoop>& loops,
                          const std::vector<std::pair<size_t, size_t>>& face_range,
                          const std::vector<std::vector<int>>& loop_globals,
                          std::map<int, meshing::FilledPatch>& patches,
                          std::vector<std::array<int, 4>>& faces, VertexPool& pool,
                          Garment& garment) {
  const auto folded = [&](const std::vector<Eigen::Vector3d>& normals, size_t begin, size_t end) {
    int count = 0;
    for (size_t f = begin; f < end; ++f)
      if (gate_jacobian(faces[f], pool.positions, normals) < 0) ++count;
    return count;
  };
  int repaired = 0;
  for (auto& [l, patch] : patches) {
    const auto [begin, end] = face_range[static_cast<size_t>(l)];
    std::vector<Eigen::Vector3d> normals = corner_normals(faces, pool.positions);
    if (folded(normals, begin, end) == 0) continue;
    const int before = folded(normals, 0, faces.size());
    const std::vector<int>& og = loop_globals[static_cast<size_t>(l)];
    // The panel's quads on the pool's positions, and the rest of the garment's share of each
    // of its vertices' normals.
    meshing::QuadMesh mesh = patch.mesh;
    for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
      mesh.vertices.row(v) =
          pool.positions[static_cast<size_t>(og[static_cast<size_t>(v)])].transpose();
    const std::vector<std::array<int, 4>> own(faces.begin() + static_cast<std::ptrdiff_t>(begin),
                                              faces.begin() + static_cast<std::ptrdiff_t>(end));
    const std::vector<Eigen::Vector3d> own_normals = corner_normals(own, pool.positions);
    Eigen::MatrixX3d extra(mesh.vertex_count(), 3);
    for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v) {
      const auto g = static_cast<size_t>(og[static_cast<size_t>(v)]);
      extra.row(v) = (normals[g] - own_normals[g]).transpose();
    }
    std::vector<char> fixed(static_cast<size_t>(mesh.vertex_count()), 0);
    for (const auto& side : patch.topology.side_vertices)
      for (const int v : side) fixed[static_cast<size_t>(v)] = 1;
    const std::vector<int> corners = patch.topology.corner_vertices();
    const PanelLoop& loop = loops[static_cast<size_t>(l)];
    const auto project =
        panel_projection(sketch, sketch.panels[static_cast<size_t>(loop.spec)], loop, net, body,
                         garment.panels[static_cast<size_t>(l)].fit);
    const FoldRepairResult result = repair_folds(mesh, fixed, corners, project, 8, extra);
    if (result.edge_turns + result.smoothings == 0) continue;
    // The repaired quads into the garment, and into each mirror copy reflected (faces reversed
    // to stay outward, as build_garment makes them).
    const std::vector<std::array<int, 4>> old_faces = faces;
    const std::vector<Eigen::Vector3d> old_positions = pool.positions;
    const auto write = [&](size_t loop_index, bool mirrored) {
      const std::vector<int>& g = loop_globals[loop_index];
      size_t f = face_range[loop_index].first;
      for (Eigen::Index q = 0; q < mesh.face_count(); ++q, ++f) {
        const auto at = [&](int k) { return g[static_cast<size_t>(mesh.faces(q, k))]; };
        faces[f] = mirrored ? std::array{at(0), at(3), at(2), at(1)}
                            : std::array{at(0), at(1), at(2), at(3)};
      }
      for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v) {
        if (fixed[static_cast<size_t>(v)]) continue;
        const Eigen::Vector3d p = mesh.vertices.row(v).transpose();
        pool.positions[static_cast<size_t>(g[static_cast<size_t>(v)])] =
            mirrored ? mirror_point(p) : p;
      }
    };
    write(static_cast<size_t>(l), false);
    std::vector<size_t> copies;
    for (size_t c = 0; c < loops.size(); ++c)
      if (loops[c].mirror_copy && loops[c].original == l) copies.push_back(c);
    for (const size_t c : copies) write(c, true);
    if (folded(corner_normals(faces, pool.positions), 0, faces.size()) >= before) {
      faces = old_faces;
      pool.positions = old_positions;
      continue;
    }
    ++repaired;
    patch.mesh = std::move(mesh);
    patch.quality = meshing::measure_quality(patch.mesh, corners);
    patch.topology.mesh.faces = patch.mesh.faces;
    patch.topology.distortion = patch.quality.distortion;
    patch.topology.irregular_vertices = patch.quality.irregular_vertices;
    copies.push_back(static_cast<size_t>(l));
    for (const size_t c : copies) {
      GarmentPanel& panel = garment.panels[c];
      panel.quality = patch.quality;
      panel.distortion = patch.topology.distortion;
      panel.irregular_vertices = patch.topology.irregular_vertices;
    }
    spdlog::debug("panel '{}': {} folded quad(s) of the stitched garment repaired, {} left",
                  loop.id, result.folded_before - result.folded_after, result.folded_after);
  }
  return repaired;
}

// Stage 4, one mesh: doublets merged, vertices no face uses dropped (in order), the arrays
// filled. `faces` (pool ids), `face_panel` and `pool` are renumbered in place.
void assemble_mesh(std::vector<std::array<int, 4>>& faces, std::vector<int>& face_panel,
                   VertexPool& pool, Garment& garment) {
  garment.merged_doublets.clear();
  for (const Doublet& d : remove_doublets(faces, face_panel, pool.positions.size())) {
    const auto curve = garment.edge_curve.find(std::minmax(d.vertex, d.neighbour));
    garment.merged_doublets.push_back(
        {pool.positions[static_cast<size_t>(d.vertex)],
         garment.panels[static_cast<size_t>(d.panel)].id,
         garment.panels[static_cast<size_t>(d.other)].id,
         curve == garment.edge_curve.end() ? std::string() : curve->second});
  }
  for (GarmentPanel& p : garment.panels) p.faces = 0;
  for (int p : face_panel) ++garment.panels[static_cast<size_t>(p)].faces;
  // Drop vertices no face uses (the centres of removed doublets), keeping order.
  {
    std::vector<int> remap(pool.positions.size(), -1);
    for (const auto& q : faces)
      for (int v : q) remap[static_cast<size_t>(v)] = 0;
    std::vector<Eigen::Vector3d> kept;
    for (size_t v = 0; v < remap.size(); ++v)
      if (remap[v] == 0) {
        remap[v] = static_cast<int>(kept.size());
        kept.push_back(pool.positions[v]);
      }
    for (auto& q : faces)
      for (int& v : q) v = remap[static_cast<size_t>(v)];
    pool.positions = std::move(kept);
    std::map<std::pair<int, int>, std::string> edge_curve;
    for (const auto& [edge, curve] : garment.edge_curve) {
      const int a = remap[static_cast<size_t>(edge.first)],
                b = remap[static_cast<size_t>(edge.second)];
      if (a >= 0 && b >= 0) edge_curve[std::minmax(a, b)] = curve;
    }
    garment.edge_curve = std::move(edge_curve);
  }
  garment.mesh.vertices.resize(static_cast<Eigen::Index>(pool.positions.size()), 3);
  for (size_t v = 0; v < pool.positions.size(); ++v)
    garment.mesh.vertices.row(static_cast<Eigen::Index>(v)) = pool.positions[v].transpose();
  garment.mesh.faces.resize(static_cast<Eigen::Index>(faces.size()), 4);
  for (size_t f = 0; f < faces.size(); ++f)
    for (int k = 0; k < 4; ++k)
      garment.mesh.faces(static_cast<Eigen::Index>(f), k) = faces[f][static_cast<size_t>(k)];
  garment.face_panel = Eigen::Map<const Eigen::VectorXi>(
      face_panel.data(), static_cast<Eigen::Index>(face_panel.size()));
}

// Stage 4a (crease_wall.hpp): panels that pass through each other (garment_crossings.hpp) take
// their narrow-crease moves (CreaseMoves), each mirror copy its original's reflected. Only
// those: the moves are 1-2 mm where cloth lies in a crease narrower than 2.5 offsets, and
// where no panel crosses another they only change drapes (the t-shirt at 2 cm edges, whose two
// underarm vertices a side moved by 1-2.3 mm, no longer rested in its 10 s).
void settle_crossings_in_creases(const std::vector<PanelLoop>& loops,
                                 const std::vector<std::vector<int>>& loop_globals,
                                 const std::vector<CreaseMoves>& creases,
                                 const std::vector<std::array<int, 4>>& faces,
                                 const std::vector<int>& face_panel, VertexPool& pool,
                                 Garment& garment) {
  if (std::all_of(creases.begin(), creases.end(),
                  [](const CreaseMoves& c) { return c.moves.empty(); }))
    return;
  Garment trial = garment;
  std::vector<std::array<int, 4>> trial_faces = faces;
  std::vector<int> trial_panel = face_panel;
  VertexPool trial_pool = pool;
  assemble_mesh(trial_faces, trial_panel, trial_pool, trial);
  const auto original = [&](int p) {
    const PanelLoop& loop = loops[static_cast<size_t>(p)];
    return loop.mirror_copy ? loop.original : p;
  };
  std::set<int> crossing;
  for (const PanelCrossing& c : find_panel_crossings(trial)) {
    crossing.insert(original(c.panel_a));
    crossing.insert(original(c.panel_b));
  }
  if (crossing.empty()) return;
  const auto move = [&](VertexPool& into, Garment* panels) {
    for (const int l : crossing) {
      const CreaseMoves& crease = creases[static_cast<size_t>(l)];
      if (crease.moves.empty()) continue;
      for (size_t c = 0; c < loops.size(); ++c) {
        const bool own = static_cast<int>(c) == l;
        if (!own && !(loops[c].mirror_copy && loops[c].original == l)) continue;
        for (const auto& [v, position] : crease.moves)
          into.positions[static_cast<size_t>(loop_globals[c][static_cast<size_t>(v)])] =
              own ? position : mirror_point(position);
        if (panels != nullptr) panels->panels[c].quality = crease.quality;
      }
    }
  };
  // Kept only when the garment then crosses itself nowhere: moves that leave a crossing are not
  // what clears it (the t-shirt at 2 cm edges crosses at its sleeves' fronts and backs; with its
  // underarm moves it no longer rested in 10 s).
  VertexPool moved = pool;
  move(moved, nullptr);
  trial = garment;
  trial_faces = faces;
  trial_panel = face_panel;
  assemble_mesh(trial_faces, trial_panel, moved, trial);
  if (!find_panel_crossings(trial).empty()) return;
  spdlog::debug("narrow creases: moved the vertices of {} panel(s) that crossed", crossing.size());
  move(pool, &garment);
}

// Stage 5a, the panels' outlines: a panel whose curves run over each other (three curves along
// one line, or a triangle 1 mm tall) encloses no area. Said as that, before the fan check below
// takes the outline touching itself for two panels that meet at a point (trial 39, P8). Each
// outline vertex's distance to the rest of the outline, leaving out the stretch within two edge
// lengths of it along the outline: the other side of the panel for a panel at least one quad
// wide (an edge length or more), near zero where the outline runs back along itself. Refused
// when that holds for half the outline's vertices: below a tenth of the edge length (a tip or a
// narrow spike of a real panel is a few vertices).
void check_panel_outlines(const GarmentRequest& sketch, const CurveNetwork& net,
                          const std::vector<PanelLoop>& loops) {
  for (const PanelLoop& loop : loops) {
    if (loop.mirror_copy) continue;  // the original's outline, reflected
    // The outline in order, from the curve pieces' polylines (each piece's first point is the
    // previous one's last).
    std::vector<Eigen::Vector3d> outline;
    std::vector<double> along;  // arc length at each point
    for (const LoopEdge& e : loop.edges) {
      const Eigen::MatrixX3d& points = net.edges[static_cast<size_t>(e.edge)].points;
      for (Eigen::Index k = 1; k < points.rows(); ++k) {
        const Eigen::Vector3d p = points.row(e.forward ? k : points.rows() - 1 - k).transpose();
        along.push_back(outline.empty() ? 0.0 : along.back() + (p - outline.back()).norm());
        outline.push_back(p);
      }
    }
    if (outline.size() < 3) continue;
    const size_t n = outline.size();
    const double length = along.back() + (outline.front() - outline.back()).norm();
    const PanelSpec& spec = sketch.panels[static_cast<size_t>(loop.spec)];
    const double target = spec.edge_length.value_or(sketch.edge_length);
    std::vector<double> apart(n, std::numeric_limits<double>::infinity());
    for (size_t i = 0; i < n; ++i)
      for (size_t j = 0; j < n; ++j) {
        const size_t k = (j + 1) % n;
        const auto gap = [&](size_t m) {
          const double d = std::abs(along[m] - along[i]);
          return std::min(d, length - d);
        };
        if (gap(j) <= 2 * target || gap(k) <= 2 * target) continue;
        const Eigen::Vector3d ab = outline[k] - outline[j];
        const double t =
            ab.squaredNorm() > 0
                ? std::clamp((outline[i] - outline[j]).dot(ab) / ab.squaredNorm(), 0.0, 1.0)
                : 0.0;
        apart[i] = std::min(apart[i], (outline[j] + t * ab - outline[i]).norm());
      }
    std::nth_element(apart.begin(), apart.begin() + static_cast<std::ptrdiff_t>(n / 2),
                     apart.end());
    const double typical = apart[n / 2];
    if (!(typical < 0.1 * target)) continue;
    sketch.fail(loop.json_path,
                fmt::format("panel '{}' encloses no area: its curves run over each other (its "
                            "outline, {:.1f} cm long, runs back along itself, {:.1f} mm from its "
                            "other side along half its length). A panel's curves go round the "
                            "piece of cloth it is, like a front's centre front, neckline, "
                            "shoulder, armhole, side and hem: draw them apart",
                            loop.id, 100 * length, 1e3 * typical));
  }
}

// Farthest any point of polyline `a` lies from polyline `b` (m).
double farthest_from(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b) {
  double farthest = 0;
  for (Eigen::Index i = 0; i < a.rows(); ++i) {
    const Eigen::Vector3d p = a.row(i).transpose();
    double nearest = std::numeric_limits<double>::infinity();
    for (Eigen::Index j = 0; j + 1 < b.rows(); ++j) {
      const Eigen::Vector3d s = b.row(j).transpose(), t = b.row(j + 1).transpose();
      const Eigen::Vector3d st = t - s;
      const double u =
          st.squaredNorm() > 0 ? std::clamp((p - s).dot(st) / st.squaredNorm(), 0.0, 1.0) : 0.0;
      nearest = std::min(nearest, (s + u * st - p).norm());
    }
    farthest = std::max(farthest, nearest);
  }
  return farthest;
}

// Two curves drawn along one seam, each used by one of its two panels (`panels`: "panels 'a' and
// 'b'"): the network pieces of two different curves between the same two junctions, one of
// them at `p` (a place where the panels meet only at a point), lying within the junction
// tolerance of each other all along. The JSON path of the curve to delete and the sentence that
// names both, how far they run together and which to keep; nothing when there are none
// (trial 40, P4: 'right2' drawn with exactly the points of 'right' was reported as panels meeting
// "only at the point" where the two curves lay on each other over all of their 20 cm).
std::optional<std::pair<std::string, std::string>> coinciding_curves(const GarmentRequest& sketch,
                                                                     const CurveNetwork& net,
                                                                     const Eigen::Vector3d& p,
                                                                     const std::string& panels) {
  const double tol = sketch.junction_tolerance;
  for (size_t i = 0; i < net.edges.size(); ++i) {
    const NetworkEdge& a = net.edges[i];
    if (a.from == a.to) continue;
    const double from_a = std::min((net.nodes[static_cast<size_t>(a.from)] - p).norm(),
                                   (net.nodes[static_cast<size_t>(a.to)] - p).norm());
    if (from_a > tol) continue;
    for (size_t j = 0; j < net.edges.size(); ++j) {
      const NetworkEdge& b = net.edges[j];
      if (j == i || b.curve == a.curve || std::minmax(a.from, a.to) != std::minmax(b.from, b.to))
        continue;
      const double apart =
          std::max(farthest_from(a.points, b.points), farthest_from(b.points, a.points));
      if (apart > tol) continue;
      const NetworkCurve& ca = net.curves[static_cast<size_t>(a.curve)];
      const NetworkCurve& cb = net.curves[static_cast<size_t>(b.curve)];
      // A curve beside its own mirror copy was meant to lie on the plane x = 0 (a centre seam)
      // but runs off it: "name 'cb_top.mirror' in both lists and delete 'cb_top'" asked for a
      // curve shared with itself (trial 43, P5). Say how far off it is and what puts it on.
      if (ca.id + ".mirror" == cb.id || cb.id + ".mirror" == ca.id) {
        const NetworkCurve& original = ca.mirror_copy ? cb : ca;
        const NetworkEdge& own = ca.mirror_copy ? b : a;
        Eigen::Index far = 0;
        const double off = own.points.col(0).cwiseAbs().maxCoeff(&far);
        return std::pair{
            original.spec < 0 ? std::string("/panels")
                              : sketch.curves[static_cast<size_t>(original.spec)].json_path,
            fmt::format(
                "curve '{}' and its own mirror copy '{}' lie within {:.0f} mm of each other: the "
                "curve is meant to lie on the mirror plane x = 0 (a centre seam of {}), but as "
                "projected onto the body it runs more than {:.1f} mm (a quarter of "
                "junction_tolerance) off it{}, so it is not its own mirror, and the two panels "
                "each have their own copy of the seam and meet only at its ends: write its "
                "points at x = 0 (a curve whose every point is written at x = 0 is its own "
                "mirror), or relative to a landmark on the plane (neck_base, chest, waist, hips, "
                "crotch) with an offset of 0 across",
                original.id, original.id + ".mirror", std::max(1.0, 1e3 * apart), panels,
                1e3 * kOnPlaneFraction * tol,
                off >= 5e-4
                    ? fmt::format(" (meshed, up to {:.1f} mm, at ({:.3f}, {:.3f}, {:.3f}) m)",
                                  1e3 * off, own.points(far, 0), own.points(far, 1),
                                  own.points(far, 2))
                    : std::string())};
      }
      // Keep a mirror copy (the curve a mirrored garment already has), else the first drawn;
      // the other is the one to delete.
      const bool a_kept = ca.mirror_copy != cb.mirror_copy ? ca.mirror_copy : ca.spec <= cb.spec;
      const NetworkCurve& kept = a_kept ? ca : cb;
      const NetworkCurve& extra = a_kept ? cb : ca;
      const bool whole = ca.edges.size() == 1 && cb.edges.size() == 1;
      const Eigen::Vector3d& s = net.nodes[static_cast<size_t>(a.from)];
      const Eigen::Vector3d& t = net.nodes[static_cast<size_t>(a.to)];
      const std::string run =
          whole ? fmt::format("over their whole length ({:.1f} cm)", 100 * a.length)
                : fmt::format(
                      "for {:.1f} cm, from ({:.3f}, {:.3f}, {:.3f}) to ({:.3f}, {:.3f}, "
                      "{:.3f}) m",
                      100 * a.length, s.x(), s.y(), s.z(), t.x(), t.y(), t.z());
      const std::string how = apart < 0.001
                                  ? "lie on each other"
                                  : fmt::format("lie within {:.0f} mm of each other", 1e3 * apart);
      // The copy of a mirrored curve is named in a boundary list as '<curve>.mirror'; the curve
      // drawn again instead is in the file (a copy's own path is its original's).
      return std::pair{
          extra.mirror_copy || extra.spec < 0
              ? std::string("/panels")
              : sketch.curves[static_cast<size_t>(extra.spec)].json_path,
          fmt::format(
              "curves '{}' and '{}' {} {}: {} each have their own copy of one seam, "
              "so they meet only at its ends. Give both panels the same curve (name "
              "'{}' in both boundary lists{})",
              ca.id, cb.id, how, run, panels, kept.id,
              (extra.mirror_copy ? std::string() : fmt::format(" and delete '{}'", extra.id)) +
                  (whole ? "" : "; a panel takes the piece of a curve between its junctions"))};
    }
  }
  return std::nullopt;
}

// Stage 5, the seams checked: every vertex's quads form one fan.
void check_fans(const GarmentRequest& sketch, const CurveNetwork& net, const Garment& garment,
                const std::vector<std::array<int, 4>>& faces, const std::vector<int>& face_panel,
                const VertexPool& pool) {
  // Every vertex's quads must form one fan (joined through edges at the vertex): panels that
  // touch only at a point are two curves drawn along one seam (the right side of a mirrored
  // garment drawn again instead of naming the copy 'side.mirror'), and the mesh would not be a
  // surface there.
  {
    std::vector<std::vector<int>> around(pool.positions.size());
    for (size_t f = 0; f < faces.size(); ++f)
      for (int v : faces[f]) around[static_cast<size_t>(v)].push_back(static_cast<int>(f));
    for (size_t v = 0; v < around.size(); ++v) {
      const std::vector<int>& fan = around[v];
      if (fan.size() < 2) continue;
      // The two neighbours of v in face f.
      auto sides = [&](int f) {
        const auto& q = faces[static_cast<size_t>(f)];
        const size_t k =
            static_cast<size_t>(std::find(q.begin(), q.end(), static_cast<int>(v)) - q.begin());
        return std::pair(q[(k + 1) % 4], q[(k + 3) % 4]);
      };
      std::vector<int> component(fan.size(), -1);
      int components = 0;
      for (size_t start = 0; start < fan.size(); ++start) {
        if (component[start] >= 0) continue;
        std::vector<size_t> stack{start};
        component[start] = components;
        while (!stack.empty()) {
          const size_t a = stack.back();
          stack.pop_back();
          const auto [a1, a2] = sides(fan[a]);
          for (size_t b = 0; b < fan.size(); ++b) {
            if (component[b] >= 0) continue;
            const auto [b1, b2] = sides(fan[b]);
            if (a1 == b1 || a1 == b2 || a2 == b1 || a2 == b2) {
              component[b] = components;
              stack.push_back(b);
            }
          }
        }
        ++components;
      }
      if (components < 2) continue;
      std::set<std::string> names;
      for (int f : fan)
        names.insert(garment.panels[static_cast<size_t>(face_panel[static_cast<size_t>(f)])].id);
      std::string list;
      for (const std::string& name : names) list += (list.empty() ? "'" : ", '") + name + "'";
      // One panel touching itself: its outline passes through the point twice.
      list = names.size() == 1 ? "panel " + list + " meets itself" : "panels " + list + " meet";
      const Eigen::Vector3d& p = pool.positions[v];
      // Curve ends moved onto the mirror plane there, each near enough to it, but farther from
      // their own mirror copies than the tolerance (culottes' inner hems ending 1.2 cm either
      // side of x = 0): the point is of the program's making, and the message says so.
      for (const PlaneSnap& snap : net.plane_snaps) {
        const double tol = sketch.junction_tolerance;
        if ((snap.at - p).norm() > 0.25 * tol) continue;  // the node's vertex, however moved
        // To the millimetre, so that the distance to the copy reads as twice it (1.2, 2.4 cm).
        const double from_plane = std::round(1000 * snap.from_plane) / 1000;
        std::string ends;  // "the end of 'a', the end of 'b' and the start of 'c'"
        for (size_t k = 0; k < snap.ends.size(); ++k)
          ends += (k == 0 ? "" : (k + 1 == snap.ends.size() ? " and " : ", ")) + snap.ends[k];
        sketch.fail(
            "/panels",
            fmt::format(
                "{} only at the point ({:.3f}, {:.3f}, {:.3f}) m, not along a seam: "
                "{} {} {:.1f} cm from the mirror plane x = 0, closer than junction_tolerance "
                "({:.1f} cm), so {} moved onto it and joined to {} mirror copy, {:.1f} cm away. "
                "To keep the two sides apart, end the curves at least {:.1f} cm from x = 0 or "
                "lower junction_tolerance to {:.1f} cm or less; for a seam on the plane (a centre "
                "front), draw the curve at x = 0",
                list, p.x(), p.y(), p.z(), ends, snap.ends.size() == 1 ? "was" : "were",
                100 * from_plane, 100 * tol, snap.ends.size() == 1 ? "it was" : "they were",
                snap.ends.size() == 1 ? "its" : "their", 200 * from_plane, 100 * tol,
                std::floor(1000 * snap.from_plane) / 10));  // below |x|: no longer moved
      }
      if (names.size() == 2)
        if (const auto twice = coinciding_curves(
                sketch, net, p,
                fmt::format("panels '{}' and '{}'", *names.begin(), *names.rbegin())))
          sketch.fail(twice->first, twice->second);
      // Curve ends joined to another curve's interior there, for lying near it: the point is
      // of the program's making too (trial 44, P1), and the cause is said instead.
      if (const std::string cause = t_join_cause(sketch, net, p); !cause.empty())
        sketch.fail("/panels", fmt::format("{} only at the point ({:.3f}, {:.3f}, {:.3f}) m, not "
                                           "along a seam{}",
                                           list, p.x(), p.y(), p.z(), cause));
      sketch.fail(
          "/panels",
          fmt::format("{} only at the point ({:.3f}, {:.3f}, {:.3f}) m, not along "
                      "a seam: two curves there run along one seam without being one curve. "
                      "Give both panels the same curve (on the other side of a mirrored "
                      "garment, the copy '<curve>.mirror')",
                      list, p.x(), p.y(), p.z()));
    }
  }
}

// ... and no two curves run along each other with their panels on one side: a back hem drawn
// over the front hem puts the back panel over the front one, which the drape cannot separate.
// Each boundary edge's quad points from it into its panel (the same measure as the folds below,
// independent of the loops' orientation); edges of two different curves closer than `near`
// whose quads point the same way (within 60°) overlap. Fails when such edges, away from the
// network's junctions (where curves meet by design), add up to more than kOverlapRun for one pair
// of curves, naming both curves, both panels and the place. Two curves side by side with their
// panels on either side (a slit's two edges below its top) are an opening, not an overlap.
// Which curve is drawn in the wrong place: the one whose panel lies on the other side of the body
// from the overlap (its quads' area vectors summed, against the overlapping quads' normal), more
// than kOverlapBlameMargin apart; else both are named. Trial 42 (P12): a front waist seam whose
// middle point was typed at the back was told to move the back's waist seam, the later curve of
// the file, and the error now points at the front's and its written point nearest the overlap.
constexpr double kOverlapBlameMargin = 0.2;  // in cosines: the panels' facings must differ so much
void check_overlapping_boundaries(const GarmentRequest& sketch, const BodySurface& body,
                                  const CurveNetwork& net, const VertexPool& pool,
                                  const std::vector<std::array<int, 4>>& faces,
                                  const std::vector<int>& face_panel, const Garment& garment) {
  struct CurveEdge {
    Eigen::Vector3d middle, inward, normal;  // normal: of the edge's quad, unit
    double length = 0;
    const std::string* curve = nullptr;
    int panel = -1;
  };
  const double near = std::clamp(0.25 * sketch.edge_length, 0.003, 0.01);
  const double around_junction = 0.02;  // m from a junction, where curves meet by design
  std::vector<CurveEdge> edges;
  for (size_t f = 0; f < faces.size(); ++f)
    for (int k = 0; k < 4; ++k) {
      const int a = faces[f][static_cast<size_t>(k)],
                b = faces[f][static_cast<size_t>((k + 1) % 4)];
      const auto it = garment.edge_curve.find(std::minmax(a, b));
      if (it == garment.edge_curve.end()) continue;
      const Eigen::Vector3d& p = pool.positions[static_cast<size_t>(a)];
      const Eigen::Vector3d& q = pool.positions[static_cast<size_t>(b)];
      CurveEdge e;
      e.middle = 0.5 * (p + q);
      bool at_junction = false;
      for (const Eigen::Vector3d& node : net.nodes)
        at_junction = at_junction || (node - e.middle).norm() < around_junction;
      if (at_junction) continue;
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (int v : faces[f]) c += pool.positions[static_cast<size_t>(v)] / 4;
      const Eigen::Vector3d along = (q - p).normalized();
      e.inward = c - e.middle;
      e.inward = (e.inward - e.inward.dot(along) * along).normalized();
      e.length = (q - p).norm();
      const auto corner = [&](size_t i) -> const Eigen::Vector3d& {
        return pool.positions[static_cast<size_t>(faces[f][i])];
      };
      e.normal = (corner(2) - corner(0)).cross(corner(3) - corner(1)).normalized();
      e.curve = &it->second;
      e.panel = face_panel[f];
      edges.push_back(e);
    }
  // Per (curve, panel, curve, panel): the length of the first curve's edges over the second,
  // their mean place and their quads' normals summed (weighted by length).
  struct Overlap {
    double length = 0;
    Eigen::Vector3d where = Eigen::Vector3d::Zero();
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  };
  std::map<std::tuple<std::string, int, std::string, int>, Overlap> overlaps;
  for (const CurveEdge& a : edges)
    for (const CurveEdge& b : edges) {
      if (*a.curve == *b.curve || (a.middle - b.middle).norm() >= near ||
          a.inward.dot(b.inward) <= 0.5)
        continue;
      Overlap& o = overlaps[{*a.curve, a.panel, *b.curve, b.panel}];
      o.where = (o.length * o.where + a.length * a.middle) / (o.length + a.length);  // their mean
      o.length += a.length;
      o.normal += a.length * a.normal;
    }
  const std::pair<const std::tuple<std::string, int, std::string, int>, Overlap>* worst = nullptr;
  for (const auto& entry : overlaps) {
    spdlog::debug(
        "curves '{}' and '{}' run within {:.1f} mm of each other, their panels on one "
        "side, for {:.1f} cm",
        std::get<0>(entry.first), std::get<2>(entry.first), 1e3 * near, 1e2 * entry.second.length);
    if (!worst || entry.second.length > worst->second.length) worst = &entry;
  }
  if (!worst || worst->second.length <= kOverlapRun) return;
  const auto& [curve_a, panel_a, curve_b, panel_b] = worst->first;
  const auto base = [](const std::string& id) {
    return id.ends_with(".mirror") ? id.substr(0, id.size() - 7) : id;
  };
  const Eigen::Vector3d& where = worst->second.where;
  // How far each panel faces the way the overlap does: its quads' area vectors summed, over their
  // areas (1 for a flat panel, near 0 for one wrapped round a limb), against the overlap's normal
  // (both curves' quads, which point the same way there).
  Eigen::Vector3d facing = worst->second.normal;
  if (const auto it = overlaps.find({curve_b, panel_b, curve_a, panel_a}); it != overlaps.end())
    facing += it->second.normal;
  facing.normalize();
  const auto faces_here = [&](int panel) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double area = 0;
    for (size_t f = 0; f < faces.size(); ++f) {
      if (face_panel[f] != panel) continue;
      const auto corner = [&](size_t i) -> const Eigen::Vector3d& {
        return pool.positions[static_cast<size_t>(faces[f][i])];
      };
      const Eigen::Vector3d vector_area =
          0.5 * (corner(2) - corner(0)).cross(corner(3) - corner(1));
      sum += vector_area;
      area += vector_area.norm();
    }
    return area > 0 ? sum.dot(facing) / area : 0.0;
  };
  const double facing_a = faces_here(panel_a), facing_b = faces_here(panel_b);
  const std::string& panel_name_a = garment.panels[static_cast<size_t>(panel_a)].id;
  const std::string& panel_name_b = garment.panels[static_cast<size_t>(panel_b)].id;
  spdlog::debug("overlap of '{}' and '{}': their panels face its way by {:.2f} and {:.2f}", curve_a,
                curve_b, facing_a, facing_b);
  // The curve drawn away from its panel, when one panel faces the overlap's way much less.
  const std::string* stray = nullptr;
  if (std::abs(facing_a - facing_b) > kOverlapBlameMargin)
    stray = facing_a < facing_b ? &curve_a : &curve_b;
  const CurveSpec* spec = nullptr;  // the stray's, else the later of the two in the file
  for (const CurveSpec& c : sketch.curves)
    if (stray ? c.id == base(*stray) : c.id == base(curve_a) || c.id == base(curve_b)) spec = &c;
  std::string landmark;
  if (const BodyLandmarks* landmarks = body.landmarks())
    landmark = fmt::format(", near the {}", landmarks->nearest(where).name);
  std::string advice;
  std::string path = "/panels";
  if (stray != nullptr && spec != nullptr) {
    const std::string& own_panel = stray == &curve_a ? panel_name_a : panel_name_b;
    const std::string& other_panel = stray == &curve_a ? panel_name_b : panel_name_a;
    // A mirror copy's written points are its original's, reflected.
    const Eigen::Vector3d written_where =
        *stray == spec->id ? where : Eigen::Vector3d(-where.x(), where.y(), where.z());
    const std::optional<WrittenPoint> point = nearest_written_point(*spec, written_where);
    path = spec->json_path + (spec->is_3d() ? "/points3d" : "/points") +
           (point ? fmt::format("/{}", point->index) : std::string());
    advice = fmt::format(
        "Panel '{}' lies mostly on the other side of the body from here, panel '{}' on this "
        "side, so '{}' is likely drawn in the wrong place{}: move its points there to where "
        "panel '{}' is; if the two panels meet along this line, they must lie on either side of "
        "it: give both the same curve",
        own_panel, other_panel, *stray,
        point ? fmt::format(
                    " (its written point nearest here is {}, {}{})", point->index, point->text,
                    *stray == spec->id ? std::string()
                                       : fmt::format(" of '{}', whose copy it is", spec->id))
              : std::string(),
        own_panel);
  } else {
    if (spec != nullptr) path = spec->json_path + (spec->is_3d() ? "/points3d" : "/points");
    advice = fmt::format(
        "One of the two is likely drawn in the wrong place (a back curve drawn on the front?): "
        "'{}' or '{}', move its points to where its panel is; if the two panels meet along this "
        "line, they must lie on either side of it: give both the same curve",
        curve_a, curve_b);
  }
  sketch.fail(path,
              fmt::format("curves '{}' (panel '{}') and '{}' (panel '{}') run along each other for "
                          "{:.1f} cm around ({:.3f}, {:.3f}, {:.3f}) m{}, with both panels on the "
                          "same side of them: the panels lie over each other there, which the "
                          "drape cannot separate. {}",
                          curve_a, panel_name_a, curve_b, panel_name_b, 1e2 * worst->second.length,
                          where.x(), where.y(), where.z(), landmark, advice));
}

// ... and the two panels of a seam run it in opposite directions; counts the seam edges.
// `curve_of` names the sketch curve a boundary edge (a, b) of the pool lies on, "" if none.
void check_seam_directions(const GarmentRequest& sketch, const BodySurface& body,
                           const VertexPool& pool, const std::vector<std::array<int, 4>>& faces,
                           const std::vector<int>& face_panel,
                           const std::function<std::string(int, int)>& curve_of, Garment& garment) {
  // Seams must be traversed in opposite directions by their two panels. A pair of panels that
  // run one the same way has one surface turned over: every such edge is collected, so that the
  // message names the curves and the place (the mean of their midpoints) for the designer.
  std::map<std::pair<int, int>, std::pair<int, int>> directed;  // (a, b) → (face, count)
  std::optional<std::pair<int, int>> clash;                     // the first panel pair
  std::set<std::string> curves;
  Eigen::Vector3d where = Eigen::Vector3d::Zero();
  int clashing = 0;
  for (size_t f = 0; f < faces.size(); ++f)
    for (int k = 0; k < 4; ++k) {
      const int a = faces[f][static_cast<size_t>(k)],
                b = faces[f][static_cast<size_t>((k + 1) % 4)];
      auto [it, inserted] = directed.try_emplace({a, b}, static_cast<int>(f), 0);
      if (inserted) continue;
      const std::pair<int, int> panels{face_panel[static_cast<size_t>(it->second.first)],
                                       face_panel[f]};
      if (!clash) clash = panels;
      if (panels != *clash) continue;
      const std::string curve = curve_of(a, b);
      if (!curve.empty()) curves.insert(curve);
      where +=
          0.5 * (pool.positions[static_cast<size_t>(a)] + pool.positions[static_cast<size_t>(b)]);
      ++clashing;
    }
  {
    // The usual cause: one curve given to two panels that lie on the same side of it (a front
    // hem listed again as the back's hem: the back then spans from the back hip round to the
    // front hem and turns over). Each seam edge's two quads point from it into their panels; on
    // a seam they point apart, at such a curve the same way (folded flat onto each other).
    // Named when its mean fold is sharp (the inward directions within 60°); the turned-over
    // panel elsewhere (the clash below) is only its consequence.
    std::map<std::pair<int, int>, std::vector<int>> edge_faces;
    for (size_t f = 0; f < faces.size(); ++f)
      for (int k = 0; k < 4; ++k) {
        const int a = faces[f][static_cast<size_t>(k)],
                  b = faces[f][static_cast<size_t>((k + 1) % 4)];
        edge_faces[{std::min(a, b), std::max(a, b)}].push_back(static_cast<int>(f));
      }
    struct Fold {
      double dot = 0.0;
      int edges = 0;
      int panel_a = -1, panel_b = -1;
    };
    std::map<std::string, Fold> folds;               // by curve
    std::map<std::pair<int, int>, Fold> pair_folds;  // by panel pair, over all they share
    const auto inward = [&](int f, const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (int v : faces[static_cast<size_t>(f)]) c += pool.positions[static_cast<size_t>(v)];
      const Eigen::Vector3d along = (q - p).normalized();
      Eigen::Vector3d d = 0.25 * c - 0.5 * (p + q);
      d -= d.dot(along) * along;
      return Eigen::Vector3d(d.normalized());
    };
    for (const auto& [edge, fs] : edge_faces) {
      if (fs.size() != 2) continue;
      const int pa = face_panel[static_cast<size_t>(fs[0])],
                pb = face_panel[static_cast<size_t>(fs[1])];
      if (pa == pb) continue;
      const std::string curve = curve_of(edge.first, edge.second);
      if (curve.empty()) continue;
      const Eigen::Vector3d& p = pool.positions[static_cast<size_t>(edge.first)];
      const Eigen::Vector3d& q = pool.positions[static_cast<size_t>(edge.second)];
      const double dot = inward(fs[0], p, q).dot(inward(fs[1], p, q));
      for (Fold* fold : {&folds[curve], &pair_folds[{std::min(pa, pb), std::max(pa, pb)}]}) {
        fold->dot += dot;
        ++fold->edges;
        fold->panel_a = std::min(pa, pb), fold->panel_b = std::max(pa, pb);
      }
    }
    // The sharpest fold, one between two panels of the file before one with a mirror copy (the
    // copy folds as its original does, and the file names the original).
    const auto rank = [&](const Fold& f) {
      const bool copies = garment.panels[static_cast<size_t>(f.panel_a)].mirror_copy ||
                          garment.panels[static_cast<size_t>(f.panel_b)].mirror_copy;
      // Without a clash the curve folded over the most length: the hem, not a short side seam.
      return std::pair(!copies, clash ? f.dot / f.edges : f.dot);
    };
    // Named where the seam directions clash, or where two panels fold onto each other along
    // everything they share: otherwise a fold this sharp is the mesh's, not the sketch's (the
    // long-sleeved tee at edge_length 0.01 folds its sleeves at the underarm, mean 0.87-1.00,
    // which the quality gate reports, while their top seam opens at -0.96 to -1.00; at 0.025 it
    // is clean). Panels oriented along their seams (panel_loop.hpp) do not clash where one was
    // given the wrong curve: a back given the front's hem folds onto the front along the hem and
    // both sides (mean 0.45-0.99 each).
    const double sharp = 0.5;
    const auto folded_pair = [&](const Fold& f) {
      const Fold& pair = pair_folds.at({f.panel_a, f.panel_b});
      return pair.dot / pair.edges > sharp;
    };
    const std::pair<const std::string, Fold>* sharpest = nullptr;
    for (const auto& entry : folds) {
      spdlog::debug("seam '{}' between panels '{}' and '{}': mean fold {:.2f} over {} edge(s)",
                    entry.first, garment.panels[static_cast<size_t>(entry.second.panel_a)].id,
                    garment.panels[static_cast<size_t>(entry.second.panel_b)].id,
                    entry.second.dot / entry.second.edges, entry.second.edges);
      if (entry.second.edges >= 2 && entry.second.dot / entry.second.edges > sharp &&
          (clash || folded_pair(entry.second)) &&
          (!sharpest || rank(entry.second) > rank(sharpest->second)))
        sharpest = &entry;
    }
    if (sharpest) {
      const std::string& curve = sharpest->first;
      const GarmentPanel& a = garment.panels[static_cast<size_t>(sharpest->second.panel_a)];
      const GarmentPanel& b = garment.panels[static_cast<size_t>(sharpest->second.panel_b)];
      // Curves the sketch draws but no panel uses: often the one meant for the second panel.
      std::vector<std::string> unused;
      for (const CurveSpec& c : sketch.curves) {
        bool used = false;
        for (const PanelSpec& p : sketch.panels)
          used = used || std::find(p.boundary.begin(), p.boundary.end(), c.id) != p.boundary.end();
        if (!used) unused.push_back("'" + c.id + "'");
      }
      std::string hint;
      for (size_t i = 0; i < unused.size(); ++i)
        hint += (i == 0 ? "" : (i + 1 == unused.size() ? " or " : ", ")) + unused[i];
      // Either cause fits a fold: a wrong curve (likelier when a drawn curve is in no panel) or
      // a panel spanning the other side of a limb (a sleeve half); the likelier comes first.
      const std::string wrong_curve = fmt::format(
          "one of them was given the wrong curve (check the boundary lists of '{}' and '{}'{})",
          a.id, b.id,
          hint.empty() ? ""
                       : fmt::format("; drawn but in no panel: {}: is {} meant there instead of "
                                     "'{}'?",
                                     hint, unused.size() == 1 ? "it" : "one of them", curve));
      const std::string other_side =
          "one of them spans the other side of the body from the one meant (a sleeve half "
          "between curves on opposite sides of the arm can span its front or its back: add a "
          "curve along the middle of the side it should cover and split it there)";
      sketch.fail("/panels",
                  fmt::format("curve '{}' bounds both panels '{}' and '{}', but the two lie on the "
                              "same side of it, folded onto each other there ({} seam edge(s)): "
                              "a curve can be the seam of two panels only when they lie on either "
                              "side of it. Either {}, or {}",
                              curve, a.id, b.id, sharpest->second.edges,
                              hint.empty() ? other_side : wrong_curve,
                              hint.empty() ? wrong_curve : other_side));
    }
  }
  if (clash) {
    const GarmentPanel& p1 = garment.panels[static_cast<size_t>(clash->first)];
    const GarmentPanel& p2 = garment.panels[static_cast<size_t>(clash->second)];
    where /= std::max(clashing, 1);
    std::string along = "their shared seam";
    if (!curves.empty()) {
      along = curves.size() == 1 ? "their shared curve " : "their shared curves ";
      bool first = true;
      for (const std::string& c : curves) along += (first ? "'" : ", '") + c + "'", first = false;
    }
    std::string near;
    try {  // a body that is not a standing figure has no landmarks: the point alone then
      near = fmt::format(", near the {}", find_landmarks(body.mesh()).nearest(where).name);
    } catch (const std::exception&) {
    }
    sketch.fail(
        "/panels",
        fmt::format("panels '{}' and '{}' face opposite ways along {} ({} seam edge(s), around "
                    "({:.3f}, {:.3f}, {:.3f}) m{}): one of them covers the other side of the body "
                    "from the one meant (a sleeve half between curves on opposite sides of the "
                    "arm can span its front or its back). Add a curve along the middle of the "
                    "side that panel should cover and split it there (each piece then covers "
                    "less than half the limb), or move its curves",
                    p1.id, p2.id, along, clashing, where.x(), where.y(), where.z(), near));
  }
  for (const auto& [edge, face] : directed)
    if (edge.first < edge.second && directed.contains({edge.second, edge.first}) &&
        face_panel[static_cast<size_t>(face.first)] !=
            face_panel[static_cast<size_t>(directed.at({edge.second, edge.first}).first)])
      ++garment.seam_edges;
}

// Stage 6, what each panel is: its join's group, body part and area.
void label_panels(const GarmentRequest& sketch, const BodySurface& body,
                  const std::vector<std::array<int, 4>>& faces, const std::vector<int>& face_panel,
                  const VertexPool& pool, Garment& garment) {
  // Joins relabel their panels' group.
  for (const JoinSpec& join : sketch.joins)
    for (const std::string& id : join.panels)
      for (GarmentPanel& p : garment.panels)
        if (p.id == id) p.group = join.id;

  // Body part (majority over faces), area, and how far on-body vertices sit from the offset.
  const double height = body.box().max.y() - body.box().min.y();
  for (size_t pi = 0; pi < garment.panels.size(); ++pi) {
    GarmentPanel& panel = garment.panels[pi];
    std::array<int, 6> votes{};
    for (size_t f = 0; f < faces.size(); ++f) {
      if (face_panel[f] != static_cast<int>(pi)) continue;
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (int v : faces[f]) c += pool.positions[static_cast<size_t>(v)];
      c /= 4;
      const Eigen::Vector3d a = pool.positions[static_cast<size_t>(faces[f][0])],
                            b = pool.positions[static_cast<size_t>(faces[f][1])],
                            cc = pool.positions[static_cast<size_t>(faces[f][2])],
                            d = pool.positions[static_cast<size_t>(faces[f][3])];
      panel.area += 0.5 * (cc - a).cross(d - b).norm();
      if (f % 3 == 0)
        ++votes[static_cast<size_t>(classify_body_point(body.closest_point(c).position, height))];
    }
    panel.body_part = body_part_name(
        static_cast<BodyPart>(std::max_element(votes.begin(), votes.end()) - votes.begin()));
  }
}

}  // namespace

Garment build_garment(const GarmentRequest& sketch, const BodySurface& body) {
  if (sketch.garment_mesh)
    throw std::logic_error("build_garment: a garment_mesh sketch has no curves to mesh");
  const PanelNetwork network = resolve_network(sketch, body);
  const CurveNetwork& net = network.net;
  const std::vector<PanelLoop>& loops = network.loops;
  const EdgeCounts& counts = network.counts;
  const std::vector<std::vector<int>> users = seam_users(sketch, net, loops);

  VertexPool pool;
  BoundaryVertices boundary(net, counts, pool);
  Garment garment;
  std::vector<std::array<int, 4>> faces;
  std::vector<int> face_panel;
  // Per original loop: patch vertex → global id, kept for its mirror copy.
  std::map<int, std::vector<int>> patch_globals;
  std::map<int, meshing::FilledPatch> patches;
  // Per loop: its quads' range in `faces` and its patch vertices' pool ids (for stage 3b).
  std::vector<std::pair<size_t, size_t>> face_range(loops.size());
  std::vector<std::vector<int>> loop_globals(loops.size());

  // Stage 3, every original panel's quads, on the body or spanning a hollow (panel_fill.hpp), the
  // panels side by side (panel_tasks.hpp): a fill depends on its own sides only, so the garment
  // has the same bits on any number of threads. The sides' points are placed first (they add
  // nothing to the pool, whose numbering below stays that of a fill in the loop's order).
  std::vector<meshing::FilledPatch> filled(loops.size());
  std::vector<GarmentPanel> fits(loops.size());    // each fill's fit and span_gap
  std::vector<CreaseMoves> creases(loops.size());  // each fill's narrow-crease moves
  {
    std::vector<int> originals;
    std::vector<std::vector<Eigen::MatrixX3d>> sides(loops.size());
    for (size_t l = 0; l < loops.size(); ++l)
      if (!loops[l].mirror_copy) {
        originals.push_back(static_cast<int>(l));
        sides[l] = panel_sides(loops[l], boundary, nullptr);
      }
    run_panel_tasks(static_cast<int>(originals.size()), [&](int k) {
      const auto l = static_cast<size_t>(originals[static_cast<size_t>(k)]);
      const PanelSpec& spec = sketch.panels[static_cast<size_t>(loops[l].spec)];
      filled[l] = fill_panel(sketch, spec, loops[l], net, sides[l], body, fits[l], &creases[l]);
    });
  }

  for (size_t l = 0; l < loops.size(); ++l) {
    const PanelLoop& loop = loops[l];
    const PanelSpec& spec = sketch.panels[static_cast<size_t>(loop.spec)];
    GarmentPanel panel;
    panel.id = loop.id;
    panel.group = loop.id;
    panel.fabric = spec.fabric;
    panel.mirror_copy = loop.mirror_copy;
    panel.ease = spec.ease;
    if (spec.corners.empty() && !spec.auto_boundary) {
      // Each corner's name as "corners" gives it: the curve listed later of the two that meet
      // there (docs/sketch-format.md), in the order of the file's list.
      const int count = static_cast<int>(spec.boundary.size());
      const size_t m = loop.edges.size();
      std::vector<std::pair<int, double>> named;
      for (const int k : loop.side_begin) {
        const int a = loop.edges[(static_cast<size_t>(k) + m - 1) % m].boundary;
        const int b = loop.edges[static_cast<size_t>(k)].boundary;
        if (a == b) {  // a corner inside one curve cannot be named
          named.clear();
          break;
        }
        named.emplace_back((a + 1) % count == b ? b : a, loop.turning_deg[static_cast<size_t>(k)]);
      }
      std::sort(named.begin(), named.end());
      for (const auto& [index, turning] : named)
        panel.turning_corners.emplace_back(spec.boundary[static_cast<size_t>(index)], turning);
    } else if (!spec.corners.empty() && !loop.mirror_copy) {
      // Named by the same rule (the curve listed later of the two that meet there).
      const int count = static_cast<int>(spec.boundary.size());
      const size_t m = loop.edges.size();
      std::vector<std::pair<int, GarmentPanel::ListedCorner>> named;
      for (const int k : loop.side_begin) {
        const LoopEdge& e = loop.edges[static_cast<size_t>(k)];
        const int a = loop.edges[(static_cast<size_t>(k) + m - 1) % m].boundary;
        const int b = e.boundary;
        if (a < 0 || b < 0 || a == b) continue;
        const int index = (a + 1) % count == b ? b : a;
        named.emplace_back(index, GarmentPanel::ListedCorner{
                                      spec.boundary[static_cast<size_t>(index)],
                                      net.nodes[static_cast<size_t>(loop_start_node(net, e))],
                                      loop.turning_deg[static_cast<size_t>(k)]});
      }
      std::sort(named.begin(), named.end(),
                [](const auto& x, const auto& y) { return x.first < y.first; });
      for (auto& [index, corner] : named) panel.listed_corners.push_back(std::move(corner));
    }
    for (const LoopEdge& e : loop.edges) {
      panel.curves.push_back(
          net.curves[static_cast<size_t>(net.edges[static_cast<size_t>(e.edge)].curve)].id);
      const std::vector<int>& ids = boundary.ids(e.edge);
      for (size_t j = 0; j + 1 < ids.size(); ++j)
        garment.edge_curve[std::minmax(ids[j], ids[j + 1])] = panel.curves.back();
    }

    // Sides: global ids from corner i to corner i+1 (their points were filled above).
    std::vector<std::vector<int>> side_ids;
    panel_sides(loop, boundary, &side_ids);
    for (const std::vector<int>& ids : side_ids)
      panel.side_counts.push_back(static_cast<int>(ids.size()) - 1);

    const int panel_index = static_cast<int>(garment.panels.size());
    face_range[l].first = faces.size();
    std::vector<int> globals;
    if (!loop.mirror_copy) {
      // Stage 3: the panel's quads, on the body or spanning a hollow (panel_fill.hpp).
      meshing::FilledPatch patch = std::move(filled[static_cast<size_t>(l)]);
      panel.fit = fits[static_cast<size_t>(l)].fit;
      panel.span_gap = fits[static_cast<size_t>(l)].span_gap;
      globals.assign(static_cast<size_t>(patch.mesh.vertex_count()), -1);
      for (size_t s = 0; s < patch.topology.side_vertices.size(); ++s)
        for (size_t j = 0; j < patch.topology.side_vertices[s].size(); ++j)
          globals[static_cast<size_t>(patch.topology.side_vertices[s][j])] = side_ids[s][j];
      for (size_t v = 0; v < globals.size(); ++v)
        if (globals[v] < 0)
          globals[v] = pool.add(patch.mesh.vertices.row(static_cast<Eigen::Index>(v)).transpose());
      for (Eigen::Index f = 0; f < patch.mesh.face_count(); ++f) {
        std::array<int, 4> q;
        for (int k = 0; k < 4; ++k)
          q[static_cast<size_t>(k)] = globals[static_cast<size_t>(patch.mesh.faces(f, k))];
        faces.push_back(q);
        face_panel.push_back(panel_index);
      }
      panel.partition = patch.topology.partition;
      panel.distortion = patch.topology.distortion;
      panel.irregular_vertices = patch.topology.irregular_vertices;
      panel.quality = patch.quality;
      panel.faces = static_cast<int>(patch.mesh.face_count());
      patch_globals[static_cast<int>(l)] = globals;
      patches[static_cast<int>(l)] = std::move(patch);
    } else {
      // Reflect the original's fill: boundary vertices map through the mirrored curve pieces,
      // interior vertices are reflected, and faces are reversed to stay outward.
      const PanelLoop& original = loops[static_cast<size_t>(loop.original)];
      const meshing::FilledPatch& patch = patches.at(loop.original);
      const std::vector<int>& og = patch_globals.at(loop.original);
      std::map<int, int> image;  // original global → copy global, for boundary vertices
      const size_t m = original.edges.size();
      for (size_t k = 0; k < m; ++k) {
        const LoopEdge& a = original.edges[k];
        // The copy runs the mirrored edges in reverse order; find a's image by edge orbit.
        const LoopEdge* b = nullptr;
        for (const LoopEdge& c : loop.edges) {
          const NetworkEdge& ce = net.edges[static_cast<size_t>(c.edge)];
          const NetworkEdge& ae = net.edges[static_cast<size_t>(a.edge)];
          const bool same_orbit = ce.orbit == ae.orbit;
          if (same_orbit && (c.edge != a.edge || ce.points.col(0).cwiseAbs().maxCoeff() == 0))
            b = &c;
        }
        if (b == nullptr)
          throw std::runtime_error("mirror copy lost a boundary edge of " + original.id);
        const std::vector<int>& ga = boundary.ids(a.edge);
        const std::vector<int>& gb = boundary.ids(b->edge);
        for (size_t j = 0; j < ga.size(); ++j) image[ga[j]] = gb[j];
      }
      globals.assign(og.size(), -1);
      for (size_t v = 0; v < og.size(); ++v) {
        const auto it = image.find(og[v]);
        globals[v] = it != image.end()
                         ? it->second
                         : pool.add(mirror_point(
                               patch.mesh.vertices.row(static_cast<Eigen::Index>(v)).transpose()));
      }
      for (Eigen::Index f = 0; f < patch.mesh.face_count(); ++f) {
        const auto& pf = patch.mesh.faces;
        faces.push_back(
            {globals[static_cast<size_t>(pf(f, 0))], globals[static_cast<size_t>(pf(f, 3))],
             globals[static_cast<size_t>(pf(f, 2))], globals[static_cast<size_t>(pf(f, 1))]});
        face_panel.push_back(panel_index);
      }
      const GarmentPanel& op = garment.panels[static_cast<size_t>(loop.original)];
      panel.partition = op.partition;
      panel.distortion = op.distortion;
      panel.irregular_vertices = op.irregular_vertices;
      panel.quality = op.quality;
      panel.faces = op.faces;
      panel.fit = op.fit;
      panel.span_gap = op.span_gap;
    }
    face_range[l].second = faces.size();
    loop_globals[l] = globals;
    garment.panels.push_back(std::move(panel));
  }

  repair_stitched_folds(sketch, net, body, loops, face_range, loop_globals, patches, faces, pool,
                        garment);
  settle_crossings_in_creases(loops, loop_globals, creases, faces, face_panel, pool, garment);
  assemble_mesh(faces, face_panel, pool, garment);
  check_panel_outlines(sketch, net, loops);
  check_fans(sketch, net, garment, faces, face_panel, pool);
  const auto curve_of = [&](int a, int b) -> std::string {
    for (size_t e = 0; e < net.edges.size(); ++e) {
      const std::vector<int>& ids = boundary.placed_ids(static_cast<int>(e));
      for (size_t k = 0; k + 1 < ids.size(); ++k)
        if ((ids[k] == a && ids[k + 1] == b) || (ids[k] == b && ids[k + 1] == a))
          return net.curves[static_cast<size_t>(net.edges[e].curve)].id;
    }
    return "";
  };
  check_overlapping_boundaries(sketch, body, net, pool, faces, face_panel, garment);
  check_seam_directions(sketch, body, pool, faces, face_panel, curve_of, garment);
  label_panels(sketch, body, faces, face_panel, pool, garment);
  // The grain: a panel on a limb may run along it (panel_grain.hpp); the landmarks are found only
  // then (a body that is not a standing figure has none: every panel is vertical).
  {
    bool limbs = false;
    for (const GarmentPanel& panel : garment.panels)
      limbs = limbs || panel.body_part.find("arm") != std::string::npos ||
              panel.body_part.find("leg") != std::string::npos;
    for (const PanelSpec& spec : sketch.panels)
      limbs = limbs || spec.grain.rule == GrainRule::kLimb;
    choose_grain(sketch, body.mesh(), limbs ? body.landmarks() : nullptr, garment);
  }
  garment.parity_changes = static_cast<int>(counts.changed.size());
  for (const auto& u : users) garment.curve_pieces += u.empty() ? 0 : 1;
  return garment;
}

}  // namespace sd::garment
