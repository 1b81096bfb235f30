#include "garment/panel_loop.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <string>

#include "garment/body_landmarks.hpp"
#include "garment/network_faces.hpp"
#include "garment/stroke_projection.hpp"

namespace sd::garment {
namespace {

// Points of a loop edge in traversal order.
Eigen::MatrixX3d ordered_points(const CurveNetwork& net, const LoopEdge& e) {
  const Eigen::MatrixX3d& p = net.edges[static_cast<size_t>(e.edge)].points;
  return e.forward ? p : Eigen::MatrixX3d(p.colwise().reverse());
}

struct Run {
  std::vector<LoopEdge> edges;
  int start = -1, end = -1;
};

// Every contiguous run along curve c starting at node `start` (any node when start < 0), shortest
// first.
std::vector<Run> runs_from(const CurveNetwork& net, int c, int start, int boundary) {
  const NetworkCurve& curve = net.curves[static_cast<size_t>(c)];
  const int m = static_cast<int>(curve.edges.size());
  std::vector<Run> runs;
  const int positions = curve.closed ? m : m + 1;
  for (int s = 0; s < positions; ++s) {
    if (start >= 0 && curve.nodes[static_cast<size_t>(s)] != start) continue;
    for (int dir : {+1, -1}) {
      for (int len = 1; len <= m; ++len) {
        if (!curve.closed && (dir > 0 ? s + len > m : s - len < 0)) break;
        Run run;
        run.start = curve.nodes[static_cast<size_t>(s)];
        for (int k = 0; k < len; ++k) {
          const int edge_pos = dir > 0 ? (s + k) % m : ((s - k - 1) % m + m) % m;
          run.edges.push_back({curve.edges[static_cast<size_t>(edge_pos)], dir > 0, boundary});
        }
        const int end_pos = dir > 0 ? (s + len) % (curve.closed ? m : m + 1)
                                    : (((s - len) % positions) + positions) % positions;
        run.end = curve.nodes[static_cast<size_t>(end_pos)];
        runs.push_back(std::move(run));
        if (curve.closed && len == m && dir < 0) break;
      }
    }
  }
  std::stable_sort(runs.begin(), runs.end(),
                   [](const Run& a, const Run& b) { return a.edges.size() < b.edges.size(); });
  return runs;
}

bool curve_has_node(const CurveNetwork& net, int c, int node) {
  const auto& nodes = net.curves[static_cast<size_t>(c)].nodes;
  return std::find(nodes.begin(), nodes.end(), node) != nodes.end();
}

// The nearest junctions of curves a and b: the gap a designer has to close, where it is.
struct NodeGap {
  double distance = std::numeric_limits<double>::infinity();
  Eigen::Vector3d on_a = Eigen::Vector3d::Zero(), on_b = Eigen::Vector3d::Zero();
};

NodeGap node_gap(const CurveNetwork& net, int a, int b) {
  NodeGap best;
  for (int x : net.curves[static_cast<size_t>(a)].nodes)
    for (int y : net.curves[static_cast<size_t>(b)].nodes) {
      const Eigen::Vector3d& p = net.nodes[static_cast<size_t>(x)];
      const Eigen::Vector3d& q = net.nodes[static_cast<size_t>(y)];
      if ((p - q).norm() < best.distance) best = {(p - q).norm(), p, q};
    }
  return best;
}

// "(0.092, 0.860, -0.132)": a junction where a designer can find it (metres).
std::string at(const Eigen::Vector3d& p) {
  return fmt::format("({:.3f}, {:.3f}, {:.3f})", p.x(), p.y(), p.z());
}

// What to do about a gap between two curve ends, for the sentence that reports it. Curves
// on the body are moved onto it (by `offset`), so an end written where an on-body curve ends
// can miss it by about the offset and the body's curvature; a curve with "on_body": false is
// used as written.
std::string gap_advice(const GarmentRequest& sketch, const std::string& a, const std::string& b) {
  const std::string rest =
      "or give both curves one point for it (a landmark-relative point, or the same [x, y, z]), "
      "or raise junction_tolerance";
  for (const std::string& id : {a, b})
    for (const CurveSpec& c : sketch.curves)
      if (c.id == id && !c.on_body)
        return fmt::format(
            "; curve '{}' has \"on_body\": false and is used exactly as written, while curves "
            "on the body are moved onto it (plus their offset): write its end at the junction "
            "given here, {}",
            id, rest);
  return "; move one end onto the other, " + rest;
}

// Explicit boundary list → loop edges (unoriented), or a SketchError.
std::vector<LoopEdge> resolve_explicit(const GarmentRequest& sketch, const CurveNetwork& net,
                                       const PanelSpec& panel) {
  std::vector<int> curve_ids;
  for (size_t i = 0; i < panel.boundary.size(); ++i) {
    const int c = net.find_curve(panel.boundary[i]);
    if (c < 0)
      sketch.fail(fmt::format("{}/boundary/{}", panel.json_path, i),
                  fmt::format("curve '{}' is not defined", panel.boundary[i]));
    curve_ids.push_back(c);
  }
  const size_t k = curve_ids.size();
  // A curve listed twice would be sewn to itself.
  for (size_t i = 0; i < k; ++i)
    for (size_t j = i + 1; j < k; ++j)
      if (panel.boundary[i] == panel.boundary[j])
        sketch.fail(fmt::format("{}/boundary/{}", panel.json_path, j),
                    fmt::format("curve '{}' is listed twice in panel '{}' (at {} and {}); each "
                                "curve of a panel's boundary is listed once, in order around it",
                                panel.boundary[i], panel.id, i, j));
  // One open curve alone cannot bound a panel: say how far its ends are apart.
  if (k == 1) {
    const NetworkCurve& only = net.curves[static_cast<size_t>(curve_ids[0])];
    if (!only.closed && !only.nodes.empty() && only.nodes.front() != only.nodes.back()) {
      const Eigen::Vector3d& a = net.nodes[static_cast<size_t>(only.nodes.front())];
      const Eigen::Vector3d& b = net.nodes[static_cast<size_t>(only.nodes.back())];
      sketch.fail(fmt::format("{}/boundary", panel.json_path),
                  fmt::format("panel '{}' has one boundary curve, '{}', and it does not close: "
                              "its ends at {} and {} m are {:.1f} cm apart. List the curves that "
                              "close the loop after it, or make '{}' a loop with \"closed\": true",
                              panel.id, only.id, at(a), at(b), 100 * (a - b).norm(), only.id));
    }
  }
  // Neighbours in the list must share a junction; say which pair does not.
  for (size_t i = 0; i < k; ++i) {
    const int a = curve_ids[i], b = curve_ids[(i + 1) % k];
    if (k == 1) break;
    bool meet = false;
    for (int node : net.curves[static_cast<size_t>(a)].nodes)
      meet = meet || curve_has_node(net, b, node);
    if (meet) continue;
    const NodeGap gap = node_gap(net, a, b);
    const std::string& next = panel.boundary[(i + 1) % k];
    // The gap's ends: the end of `a` that does not already meet the curve before it and the end
    // of `b` that does not meet the curve after it (their other ends are taken). The nearest
    // junctions of a and b are often the taken ones (the two sides of a skirt meet the hip
    // curve, 38 cm apart, while the hem that is missing joins their lower ends).
    const auto free_ends = [&](int c, int neighbour) {
      const NetworkCurve& curve = net.curves[static_cast<size_t>(c)];
      std::vector<int> ends;
      if (curve.closed || curve.nodes.empty()) return ends;
      for (const int node : {curve.nodes.front(), curve.nodes.back()})
        if (k < 3 || !curve_has_node(net, neighbour, node)) ends.push_back(node);
      if (ends.empty()) ends = {curve.nodes.front(), curve.nodes.back()};
      return ends;
    };
    const std::vector<int> a_ends = free_ends(a, curve_ids[(i + k - 1) % k]);
    const std::vector<int> b_ends = free_ends(b, curve_ids[(i + 2) % k]);
    int end_a = -1, end_b = -1;
    double gap_length = std::numeric_limits<double>::infinity();
    for (const int x : a_ends)
      for (const int y : b_ends)
        if (const double d =
                (net.nodes[static_cast<size_t>(x)] - net.nodes[static_cast<size_t>(y)]).norm();
            d < gap_length)
          gap_length = d, end_a = x, end_b = y;
    // Curves of the sketch that run from one end to the other (the seam or hem the designer
    // left out), with the panels that already use each: a curve in no panel is the likely one.
    std::vector<std::string> spans;
    std::string missing;
    for (size_t c = 0; end_a >= 0 && c < net.curves.size(); ++c) {
      const int ci = static_cast<int>(c);
      if (std::find(curve_ids.begin(), curve_ids.end(), ci) != curve_ids.end()) continue;
      if (!curve_has_node(net, ci, end_a) || !curve_has_node(net, ci, end_b)) continue;
      std::vector<std::string> users;
      for (const PanelSpec& other : sketch.panels)
        if (std::find(other.boundary.begin(), other.boundary.end(), net.curves[c].id) !=
            other.boundary.end())
          users.push_back("'" + other.id + "'");
      if (users.empty() && missing.empty()) missing = net.curves[c].id;
      spans.push_back(fmt::format("'{}' ({})", net.curves[c].id,
                                  users.empty()
                                      ? std::string("in no panel")
                                      : fmt::format("in panel{} {}", users.size() == 1 ? "" : "s",
                                                    fmt::join(users, " and "))));
    }
    // A curve of this same list that joins the two (the boundary listed out of order:
    // ["hip", "hem", "side", "centre"]): the one listed later first, as moving it is the
    // smaller edit.
    std::string bridge;
    for (size_t n = 0; bridge.empty() && n + 2 < k; ++n) {
      const size_t j = (i + 2 + n) % k;
      const int c = curve_ids[j];
      if (c == a || c == b) continue;
      bool meets_a = false, meets_b = false;
      for (int node : net.curves[static_cast<size_t>(c)].nodes) {
        meets_a = meets_a || curve_has_node(net, a, node);
        meets_b = meets_b || curve_has_node(net, b, node);
      }
      if (meets_a && meets_b)
        bridge = fmt::format("; '{}' ({} in this list) joins them: put it after '{}'?",
                             panel.boundary[j], j > i ? "listed later" : "listed earlier",
                             panel.boundary[i]);
    }
    const std::string where =
        !spans.empty()
            ? fmt::format(
                  "(the gap runs from the end of '{}' at {} m to the end of '{}' at {} m, "
                  "{:.1f} cm apart; {} {} {} from one to the other{})",
                  panel.boundary[i], at(net.nodes[static_cast<size_t>(end_a)]), next,
                  at(net.nodes[static_cast<size_t>(end_b)]), gap_length * 100,
                  spans.size() == 1 ? "curve" : "curves", fmt::join(spans, " and "),
                  spans.size() == 1 ? "runs" : "run",
                  missing.empty()
                      ? std::string()
                      : fmt::format(": is '{}' missing from the list between them?", missing))
            : fmt::format(
                  "(their junctions are {:.1f} cm apart, '{}' at {} m and '{}' at {} m; "
                  "curves meet when their ends are within {:.1f} cm{})",
                  gap.distance * 100, panel.boundary[i], at(gap.on_a), next, at(gap.on_b),
                  sketch.junction_tolerance * 100,
                  bridge.empty() ? gap_advice(sketch, panel.boundary[i], next) : bridge);
    if (i + 1 == k)
      sketch.fail(fmt::format("{}/boundary", panel.json_path),
                  fmt::format("panel '{}' does not close: its last curve '{}' does not meet its "
                              "first curve '{}' {}",
                              panel.id, panel.boundary[i], panel.boundary[0], where));
    sketch.fail(fmt::format("{}/boundary/{}", panel.json_path, i + 1),
                fmt::format("curve '{}' does not meet curve '{}' before it in panel '{}' {}",
                            panel.boundary[i + 1], panel.boundary[i], panel.id, where));
  }
  std::vector<LoopEdge> loop;
  std::vector<int> used(net.edges.size(), 0);
  int budget = 200000;  // depth-first search steps; lists are short in practice
  std::function<bool(size_t, int, int)> search = [&](size_t i, int current, int first) -> bool {
    if (--budget < 0) return false;
    const int c = curve_ids[i];
    for (const Run& run : runs_from(net, c, i == 0 ? -1 : current, static_cast<int>(i))) {
      const bool last = i + 1 == k;
      const int start = i == 0 ? run.start : first;
      if (last ? run.end != start : !curve_has_node(net, curve_ids[i + 1], run.end)) continue;
      bool clash = false;
      for (const LoopEdge& e : run.edges) clash = clash || used[static_cast<size_t>(e.edge)] > 0;
      if (clash) continue;
      for (const LoopEdge& e : run.edges) {
        ++used[static_cast<size_t>(e.edge)];
        loop.push_back(e);
      }
      if (last || search(i + 1, run.end, start)) return true;
      for (const LoopEdge& e : run.edges) {
        --used[static_cast<size_t>(e.edge)];
        loop.pop_back();
      }
    }
    return false;
  };
  if (!search(0, -1, -1))
    sketch.fail(fmt::format("{}/boundary", panel.json_path),
                fmt::format("the curves of panel '{}' do not form one closed loop in the order "
                            "listed (each curve must continue from where the one before it "
                            "ends, and the last must return to the first)",
                            panel.id));
  return loop;
}

// Two different curves of one panel's outline that cross each other seen from outside the body
// (a bow-tie: 'right' drawn from the top-right corner to the bottom-left and 'left' from the
// bottom-right to the top-left): the view of the check of one curve crossing itself, by the same
// segment test (crossing_seen_from_outside, stroke_projection.hpp): segments whose outward
// directions (the body's nearest normals) agree within 60°, crossing in the plane across their
// mean outward direction. Pieces of one curve are left to that check. Two curves drawn on one
// surface cross with no depth between them; the corpus's outlines that come near themselves seen
// from outside pass 2-3.4 cm apart in depth (a hood's face opening in front of the front
// neckline, 3.0 cm; a sleeve's armhole and underarm at the armpit, 2.1 cm), or cross 1.6 mm along
// the outline from the junction where they meet, a little past each other (a dress's hip curve and
// centre back): a bow-tie's strands cross half its outline from each other.
constexpr double kOutlineCrossingDepth = 0.01;  // m

struct OutlineCrossing {
  int curve_a = -1, curve_b = -1;  // network curve indices, in loop order
  Eigen::Vector3d where = Eigen::Vector3d::Zero();
};

// shortest_loop: m, the least outline between the two strands (the panel's edge length: a fold
// shorter than one mesh edge is lost in the fill).
std::optional<OutlineCrossing> find_outline_crossing(const CurveNetwork& net,
                                                     const BodySurface& body,
                                                     const std::vector<LoopEdge>& edges,
                                                     double shortest_loop) {
  std::vector<Eigen::Vector3d> points;
  std::vector<int> curve;  // of the segment starting at each point
  for (const LoopEdge& e : edges) {
    const Eigen::MatrixX3d pts = ordered_points(net, e);
    for (Eigen::Index k = 0; k + 1 < pts.rows(); ++k) {
      points.push_back(pts.row(k).transpose());
      curve.push_back(net.edges[static_cast<size_t>(e.edge)].curve);
    }
  }
  const size_t n = points.size();
  if (n < 4) return std::nullopt;
  std::vector<Eigen::Vector3d> outward(n);
  SurfacePoint near = body.closest_point(points[0]);
  for (size_t k = 0; k < n; ++k) {
    near = body.closest_point(points[k], near);
    outward[k] = near.normal;
  }
  std::vector<double> length(n);
  double perimeter = 0;
  for (size_t k = 0; k < n; ++k) perimeter += length[k] = (points[(k + 1) % n] - points[k]).norm();
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 2; j < n; ++j) {
      if (curve[i] == curve[j] || (i == 0 && j + 1 == n)) continue;
      const Eigen::Vector3d &a = points[i], &b = points[(i + 1) % n], &c = points[j],
                            &d = points[(j + 1) % n];
      if ((0.5 * (a + b - c - d)).norm() > kOutlineCrossingDepth + 0.5 * (length[i] + length[j]))
        continue;
      // A proper crossing: strands that only touch at a junction do not cross.
      const std::optional<Eigen::Vector2d> st = crossing_seen_from_outside(
          a, b, c, d, outward[i] + outward[(i + 1) % n], outward[j] + outward[(j + 1) % n]);
      if (!st) continue;
      const double s = st->x(), t = st->y();
      const Eigen::Vector3d on_ab = a + s * (b - a), on_cd = c + t * (d - c);
      if ((on_ab - on_cd).norm() >= kOutlineCrossingDepth) continue;
      // The outline between the two strands, the shorter way round: a loop shorter than
      // `shortest_loop` is where two curves meet at a junction a little past each other.
      double arc = 0;
      for (size_t k = i; k <= j; ++k) arc += length[k];
      arc -= s * length[i] + (1 - t) * length[j];
      if (std::min(arc, perimeter - arc) < shortest_loop) continue;
      return OutlineCrossing{curve[i], curve[j], 0.5 * (on_ab + on_cd)};
    }
  return std::nullopt;
}

// Fails at the panel's boundary when two of its curves cross each other (find_outline_crossing).
void check_outline_crossing(const GarmentRequest& sketch, const CurveNetwork& net,
                            const BodySurface& body, const PanelSpec& spec,
                            const std::vector<LoopEdge>& edges) {
  const std::optional<OutlineCrossing> crossing =
      find_outline_crossing(net, body, edges, spec.edge_length.value_or(sketch.edge_length));
  if (!crossing) return;
  const std::string& a = net.curves[static_cast<size_t>(crossing->curve_a)].id;
  const std::string& b = net.curves[static_cast<size_t>(crossing->curve_b)].id;
  std::string landmark;
  if (const BodyLandmarks* landmarks = body.landmarks();
      landmarks != nullptr && !landmarks->points.empty())
    landmark = fmt::format(", near the {}", landmarks->nearest(crossing->where).name);
  // To the millimetre, without "-0.000" on the centre line.
  const Eigen::Vector3d rounded =
      (crossing->where * 1000).array().round().matrix() / 1000 + Eigen::Vector3d::Zero();
  sketch.fail(
      spec.json_path + "/boundary",
      fmt::format("curves '{}' and '{}' of panel '{}' cross each other at {} m{}: a panel's "
                  "outline must not cross itself (the panel would be a bow-tie folded over "
                  "itself). Each curve runs from the junction where the one before it in the "
                  "list ends to the junction where the next begins: check that neither is drawn "
                  "to the opposite corner, and that the list goes round the panel in order",
                  a, b, spec.id, at(rounded), landmark));
}

// A panel's own vote on its facing: which side of its boundary it lies on, seen along the body
// normal n. Over its boundary points p (every fourth; c their centroid, t the step to the next
// point) the sum of w (n × t) · (c − p) is positive when the panel lies on the left of its loop,
// i.e. the loop runs counter-clockwise seen from outside. Each term is the area of the triangle
// (p, p + t, c), weighted by w = 1 / (1 + (d / h)²) for a point d from the body (h the panel's
// edge length): a curve on the body knows its normal, a hem hanging 10 cm off it hardly.
// `share` is the sum over its largest possible value (w |t| |c − p| summed): 1 for a flat
// panel, near 0 for a half-tube round a limb, whose boundary says little about its side.
struct FacingVote {
  double sum = 0;
  double most = 0;
  double share() const { return most > 0 ? sum / most : 0; }
};

FacingVote facing_vote(const CurveNetwork& net, const BodySurface& body,
                       const std::vector<LoopEdge>& edges, double edge_length) {
  std::vector<Eigen::Vector3d> boundary;
  for (const LoopEdge& e : edges) {
    const Eigen::MatrixX3d pts = ordered_points(net, e);
    for (Eigen::Index k = 0; k + 1 < pts.rows(); ++k) boundary.push_back(pts.row(k).transpose());
  }
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& q : boundary) centroid += q;
  centroid /= static_cast<double>(boundary.size());
  FacingVote vote;
  for (size_t k = 0; k < boundary.size(); k += 4) {
    const SurfacePoint s = body.closest_point(boundary[k]);
    const Eigen::Vector3d t = boundary[(k + 1) % boundary.size()] - boundary[k];
    const double w = 1 / (1 + std::pow(s.distance / edge_length, 2));
    vote.sum += w * s.normal.cross(t).dot(centroid - boundary[k]);
    vote.most += w * t.norm() * (centroid - boundary[k]).norm();
  }
  return vote;
}

// A panel's vote decides against its oriented neighbours only from this share up: the torso
// panels of the corpus have 0.54-0.61, half a sleeve round a bent elbow -0.18 (the test) and down
// a forearm turned forward -0.04 to 0.15 (repro/long-sleeve-top-human-forearm.json).
constexpr double kClearVote = 0.25;

struct Orientation {
  bool reversed = false;      // the loop runs against the order its boundary lists
  bool against_vote = false;  // ... which its neighbours decided against its own vote
};

// Orients every listed loop (mirror copies follow their originals). Two panels sewn along a
// curve piece run it in opposite directions, so a panel sewn to oriented panels takes the
// orientation that agrees with them (weighted by the length of each seam); the vote of each
// panel (`votes`) decides only where no oriented neighbour does: the first panel of each group of
// sewn panels is the one with the clearest vote, and the others follow along their seams, the
// one with the most seam length to oriented panels first. A panel whose own vote is clear
// (kClearVote) and disagrees with its neighbours keeps its own: one curve given to the wrong
// panel, which the seam check then names.
std::vector<Orientation> orient_loops(const GarmentRequest& sketch, const CurveNetwork& net,
                                      const std::vector<int>& mirror_edge,
                                      const std::vector<PanelLoop>& loops,
                                      const std::vector<FacingVote>& votes) {
  const size_t n = loops.size();
  // Every traversal of a curve piece: by which panel, and whether it runs forward while that
  // panel is as listed (its mirror copy runs the mirrored piece the other way).
  struct Use {
    int panel;
    bool forward;
  };
  std::vector<std::vector<Use>> uses(net.edges.size());
  for (size_t p = 0; p < n; ++p)
    for (const LoopEdge& e : loops[p].edges) {
      uses[static_cast<size_t>(e.edge)].push_back({static_cast<int>(p), e.forward});
      const int image = mirror_edge[static_cast<size_t>(e.edge)];
      if (sketch.panels[p].mirror && image >= 0 && image != e.edge)
        uses[static_cast<size_t>(image)].push_back({static_cast<int>(p), !e.forward});
    }
  // A seam of two panels as listed: when both run it the same way (`same`), exactly one of them
  // is to be reversed; otherwise both or neither.
  struct Seam {
    int other;
    bool same;
    double length;
  };
  std::vector<std::vector<Seam>> seams(n);
  for (size_t e = 0; e < uses.size(); ++e) {
    if (uses[e].size() != 2 || uses[e][0].panel == uses[e][1].panel) continue;
    const Eigen::MatrixX3d& pts = net.edges[e].points;
    double length = 0;
    for (Eigen::Index k = 0; k + 1 < pts.rows(); ++k)
      length += (pts.row(k + 1) - pts.row(k)).norm();
    const Use a = uses[e][0], b = uses[e][1];
    const bool same = a.forward == b.forward;
    seams[static_cast<size_t>(a.panel)].push_back({b.panel, same, length});
    seams[static_cast<size_t>(b.panel)].push_back({a.panel, same, length});
  }
  std::vector<Orientation> result(n);
  std::vector<char> oriented(n, 0);
  for (size_t done = 0; done < n; ++done) {
    // The panel with the most seam length to oriented ones ...
    size_t next = n;
    double linked = 0;
    for (size_t p = 0; p < n; ++p) {
      if (oriented[p]) continue;
      double length = 0;
      for (const Seam& s : seams[p])
        if (oriented[static_cast<size_t>(s.other)]) length += s.length;
      if (length > linked) next = p, linked = length;
    }
    // ... or, when none is sewn to one, the clearest vote.
    if (next == n)
      for (size_t p = 0; p < n; ++p)
        if (!oriented[p] &&
            (next == n || std::abs(votes[p].share()) > std::abs(votes[next].share())))
          next = p;
    const bool own = votes[next].sum < 0;
    // Seam length agreeing with it reversed, and as listed.
    double for_reversed = 0, for_listed = 0;
    for (const Seam& s : seams[next])
      if (oriented[static_cast<size_t>(s.other)])
        (result[static_cast<size_t>(s.other)].reversed != s.same ? for_reversed : for_listed) +=
            s.length;
    bool reverse = own;
    if (for_reversed != for_listed && std::abs(votes[next].share()) < kClearVote)
      reverse = for_reversed > for_listed;
    result[next] = {reverse, reverse != own};
    oriented[next] = 1;
  }
  return result;
}

}  // namespace

int PanelLoop::side_end(int i) const {
  return i + 1 < side_count() ? side_begin[static_cast<size_t>(i + 1)]
                              : static_cast<int>(edges.size());
}

int loop_start_node(const CurveNetwork& net, const LoopEdge& e) {
  const NetworkEdge& edge = net.edges[static_cast<size_t>(e.edge)];
  return e.forward ? edge.from : edge.to;
}

int loop_end_node(const CurveNetwork& net, const LoopEdge& e) {
  const NetworkEdge& edge = net.edges[static_cast<size_t>(e.edge)];
  return e.forward ? edge.to : edge.from;
}

std::set<std::string> curves_to_mirror(const GarmentRequest& sketch) {
  std::set<std::string> ids;
  for (const PanelSpec& p : sketch.panels)
    for (const std::string& id : p.boundary) {
      const bool copy = id.ends_with(".mirror");
      const std::string base = copy ? id.substr(0, id.size() - 7) : id;
      if (p.mirror || copy) ids.insert(base);
    }
  return ids;
}

std::vector<PanelLoop> resolve_panels(const GarmentRequest& sketch, const CurveNetwork& net,
                                      const BodySurface& body) {
  // Edge mirror map: copies point at their originals and back; on-plane edges at themselves.
  std::vector<int> mirror_edge(net.edges.size(), -1);
  for (size_t e = 0; e < net.edges.size(); ++e) {
    const int o = net.edges[e].orbit;
    if (o != static_cast<int>(e)) {
      mirror_edge[e] = o;
      mirror_edge[static_cast<size_t>(o)] = static_cast<int>(e);
    }
  }
  for (size_t e = 0; e < net.edges.size(); ++e)
    if (mirror_edge[e] < 0 && net.edges[e].points.col(0).cwiseAbs().maxCoeff() == 0)
      mirror_edge[e] = static_cast<int>(e);

  const double corner_cos = std::cos(sketch.corner_angle_degrees * std::numbers::pi / 180);
  std::optional<NetworkFaces> faces;      // traced when a panel is "auto"
  std::map<int, std::string> auto_faces;  // face → the auto panel that picked it
  std::vector<PanelLoop> listed;          // each panel's loop in the order its boundary lists it
  std::vector<FacingVote> votes;
  for (size_t p = 0; p < sketch.panels.size(); ++p) {
    const PanelSpec& spec = sketch.panels[p];
    PanelLoop loop;
    loop.id = spec.id;
    loop.json_path = spec.json_path;
    loop.spec = static_cast<int>(p);
    if (spec.auto_boundary) {
      if (!faces) faces = trace_faces(net, body);
      loop.edges = auto_panel_loop(sketch, net, *faces, body, spec);
      const int face = faces->face_left[static_cast<size_t>(2 * loop.edges.front().edge +
                                                            (loop.edges.front().forward ? 0 : 1))];
      const auto [it, fresh] = auto_faces.try_emplace(face, spec.id);
      if (!fresh)
        sketch.fail(spec.seed->json_path,
                    fmt::format("the seeds of panels '{}' and '{}' lie in the same region of the "
                                "curves; move one of them into the region it is meant for",
                                it->second, spec.id));
    } else {
      loop.edges = resolve_explicit(sketch, net, spec);
      check_outline_crossing(sketch, net, body, spec, loop.edges);
    }
    votes.push_back(
        facing_vote(net, body, loop.edges, spec.edge_length.value_or(sketch.edge_length)));
    listed.push_back(std::move(loop));
  }

  // Every panel's orientation at once: along its seams from its oriented neighbours, from its
  // own vote where it has none (orient_loops above).
  const std::vector<Orientation> orientation =
      orient_loops(sketch, net, mirror_edge, listed, votes);

  std::vector<PanelLoop> loops;
  for (size_t p = 0; p < listed.size(); ++p) {
    const PanelSpec& spec = sketch.panels[p];
    PanelLoop& loop = listed[p];
    const size_t m = loop.edges.size();
    loop.vote = orientation[p].reversed ? -votes[p].share() : votes[p].share();
    loop.turned_by_seams = orientation[p].against_vote;
    if (orientation[p].reversed) {
      std::reverse(loop.edges.begin(), loop.edges.end());
      for (LoopEdge& e : loop.edges) e.forward = !e.forward;
    }

    // Turning angle at the start of each edge.
    loop.turning_deg.resize(m);
    for (size_t k = 0; k < m; ++k) {
      const Eigen::Vector3d in = polyline_end_tangent(
          ordered_points(net, loop.edges[(k + m - 1) % m]), false, kJunctionTangentArc);
      const Eigen::Vector3d out =
          polyline_end_tangent(ordered_points(net, loop.edges[k]), true, kJunctionTangentArc);
      loop.turning_deg[k] = std::acos(std::clamp(in.dot(out), -1.0, 1.0)) * 180 / std::numbers::pi;
    }
    std::vector<bool> corner(m, false);
    if (!spec.corners.empty()) {
      // A listed curve names the junction where it begins in the file's order, i.e. where the
      // curve listed before it ends; that holds whichever way the loop was oriented.
      const int count = static_cast<int>(spec.boundary.size());
      for (size_t k = 0; k < m; ++k) {
        const int a = loop.edges[(k + m - 1) % m].boundary, b = loop.edges[k].boundary;
        if (a == b) continue;  // inside one curve (a T-junction)
        const int later = (a + 1) % count == b ? b : a;
        const std::string& name = spec.boundary[static_cast<size_t>(later)];
        if (std::find(spec.corners.begin(), spec.corners.end(), name) != spec.corners.end())
          corner[k] = true;
      }
    } else {
      for (size_t k = 0; k < m; ++k)
        corner[k] = std::cos(loop.turning_deg[k] * std::numbers::pi / 180) < corner_cos;
    }
    int corners = static_cast<int>(std::count(corner.begin(), corner.end(), true));
    if (static_cast<int>(m) < 3)
      sketch.fail(spec.json_path + "/boundary",
                  fmt::format("panel '{}' has only {} junction(s) on its boundary; a panel needs "
                              "at least 3 corners, so split its boundary into 3 or more curves",
                              spec.id, m));
    while (corners < 3) {  // promote the sharpest remaining junctions
      size_t best = m;
      for (size_t k = 0; k < m; ++k)
        if (!corner[k] && (best == m || loop.turning_deg[k] > loop.turning_deg[best])) best = k;
      corner[best] = true;
      ++corners;
    }
    // Rotate so the loop starts at a corner; sides run between consecutive corners.
    const size_t first =
        static_cast<size_t>(std::find(corner.begin(), corner.end(), true) - corner.begin());
    std::rotate(loop.edges.begin(), loop.edges.begin() + static_cast<long>(first),
                loop.edges.end());
    std::rotate(loop.turning_deg.begin(), loop.turning_deg.begin() + static_cast<long>(first),
                loop.turning_deg.end());
    std::rotate(corner.begin(), corner.begin() + static_cast<long>(first), corner.end());
    for (size_t k = 0; k < m; ++k)
      if (corner[k]) loop.side_begin.push_back(static_cast<int>(k));
    loop.original = static_cast<int>(loops.size());
    loops.push_back(loop);

    if (spec.mirror) {
      PanelLoop copy;
      copy.id = spec.id + ".mirror";
      copy.json_path = spec.json_path;
      copy.spec = static_cast<int>(p);
      copy.mirror_copy = true;
      copy.original = loop.original;
      copy.vote = loop.vote;
      copy.turned_by_seams = loop.turned_by_seams;
      // Mirroring reverses the orientation, so the copy runs the mirrored edges backwards.
      for (size_t k = m; k-- > 0;) {
        const LoopEdge& e = loop.edges[k];
        const int image = mirror_edge[static_cast<size_t>(e.edge)];
        if (image < 0)
          sketch.fail(
              spec.json_path + "/mirror",
              fmt::format(
                  "panel '{}' cannot be mirrored: curve '{}' has no mirror copy", spec.id,
                  net.curves[static_cast<size_t>(net.edges[static_cast<size_t>(e.edge)].curve)]
                      .id));
        copy.edges.push_back({image, !e.forward, e.boundary});
      }
      // Corner at the start of original edge k is at the start of copy edge (m - k) mod m.
      std::vector<bool> copy_corner(m, false);
      for (size_t k = 0; k < m; ++k)
        if (corner[k]) copy_corner[(m - k) % m] = true;
      copy.turning_deg.resize(m);
      for (size_t k = 0; k < m; ++k) copy.turning_deg[(m - k) % m] = loop.turning_deg[k];
      for (size_t k = 0; k < m; ++k)
        if (copy_corner[k]) copy.side_begin.push_back(static_cast<int>(k));
      // Start at a corner.
      const int shift = copy.side_begin.front();
      std::rotate(copy.edges.begin(), copy.edges.begin() + shift, copy.edges.end());
      std::rotate(copy.turning_deg.begin(), copy.turning_deg.begin() + shift,
                  copy.turning_deg.end());
      for (int& s : copy.side_begin) s -= shift;
      loops.push_back(std::move(copy));
    }
  }
  return loops;
}

}  // namespace sd::garment
