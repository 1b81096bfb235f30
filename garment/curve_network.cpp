#include "garment/curve_network.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace sd::garment {
namespace {

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(int n) : parent(static_cast<size_t>(n)) {
    std::iota(parent.begin(), parent.end(), 0);
  }
  int find(int a) {
    while (parent[static_cast<size_t>(a)] != a)
      a = parent[static_cast<size_t>(a)] =
          parent[static_cast<size_t>(parent[static_cast<size_t>(a)])];
    return a;
  }
  void unite(int a, int b) { parent[static_cast<size_t>(find(a))] = find(b); }
};

// A place on a curve: segment s, fraction t in [0, 1] (param = s + t).
struct Split {
  double param = 0;
  int node = -1;
};

struct WorkCurve {
  Eigen::MatrixX3d points;
  bool closed = false;
  bool mirrored = false;  // needs a mirror copy
  bool on_plane = false;  // lies on x = 0: its own mirror
  int start_node = -1, end_node = -1;
  std::vector<Split> splits;
};

Eigen::Vector3d point_at(const Eigen::MatrixX3d& pts, bool closed, double param) {
  const Eigen::Index n = pts.rows();
  const Eigen::Index s =
      std::min<Eigen::Index>(static_cast<Eigen::Index>(std::floor(param)), closed ? n - 1 : n - 2);
  const double t = param - static_cast<double>(s);
  return (1 - t) * pts.row(s).transpose() + t * pts.row((s + 1) % n).transpose();
}

// Polyline from param a to param b (a < b; for closed curves b may pass n), with its ends moved
// to `start` and `end` and the displacement blended along the arc length.
Eigen::MatrixX3d extract_piece(const Eigen::MatrixX3d& pts, bool closed, double a, double b,
                               const Eigen::Vector3d& start, const Eigen::Vector3d& end) {
  const Eigen::Index n = pts.rows();
  auto wrap = [&](double p) { return closed ? std::fmod(p, static_cast<double>(n)) : p; };
  std::vector<Eigen::Vector3d> out;
  out.push_back(point_at(pts, closed, wrap(a)));
  for (Eigen::Index k = static_cast<Eigen::Index>(std::floor(a)) + 1; static_cast<double>(k) < b;
       ++k)
    if (static_cast<double>(k) > a + 1e-9 && static_cast<double>(k) < b - 1e-9)
      out.push_back(pts.row(k % n).transpose());
  out.push_back(point_at(pts, closed, wrap(b)));
  const Eigen::Vector3d d0 = start - out.front(), d1 = end - out.back();
  std::vector<double> arc(out.size(), 0.0);
  for (size_t k = 1; k < out.size(); ++k) arc[k] = arc[k - 1] + (out[k] - out[k - 1]).norm();
  const double total = std::max(arc.back(), 1e-12);
  Eigen::MatrixX3d piece(static_cast<Eigen::Index>(out.size()), 3);
  for (size_t k = 0; k < out.size(); ++k) {
    const double w = arc[k] / total;
    piece.row(static_cast<Eigen::Index>(k)) = (out[k] + (1 - w) * d0 + w * d1).transpose();
  }
  piece.row(0) = start.transpose();
  piece.row(piece.rows() - 1) = end.transpose();
  return piece;
}

// Closest place on a polyline to p: (param, distance).
std::pair<double, double> closest_param(const Eigen::MatrixX3d& pts, bool closed,
                                        const Eigen::Vector3d& p) {
  const Eigen::Index n = pts.rows();
  const Eigen::Index segments = closed ? n : n - 1;
  double best_param = 0, best = std::numeric_limits<double>::infinity();
  for (Eigen::Index s = 0; s < segments; ++s) {
    const Eigen::Vector3d a = pts.row(s).transpose(), b = pts.row((s + 1) % n).transpose();
    const Eigen::Vector3d ab = b - a;
    const double t =
        ab.squaredNorm() > 0 ? std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
    const double d = (a + t * ab - p).norm();
    if (d < best) best = d, best_param = static_cast<double>(s) + t;
  }
  return {best_param, best};
}

// Arc length from the start of the polyline to param.
double arc_to(const Eigen::MatrixX3d& pts, bool closed, double param) {
  double length = 0;
  const Eigen::Index whole = static_cast<Eigen::Index>(std::floor(param));
  for (Eigen::Index s = 0; s < whole; ++s)
    length += (pts.row((s + 1) % pts.rows()) - pts.row(s)).norm();
  return length + (point_at(pts, closed, param) - pts.row(whole % pts.rows()).transpose()).norm();
}

// A curve whose every point is written at x = 0 (3D points, or a stroke in the front or back
// view) is meant to lie on the plane of symmetry, however far its snap onto the body strays
// from it: a centre seam snapped into the crotch of a body that is not exactly symmetric (the
// Collada human) lands up to a centimetre to one side, and without its own mirror the panel and
// its copy were not sewn along it (a mesh that touched itself at one vertex).
bool written_on_plane(const GarmentRequest& sketch, const std::string& id) {
  for (const CurveSpec& spec : sketch.curves) {
    if (spec.id != id) continue;
    if (spec.is_3d())
      return std::all_of(spec.points3d.begin(), spec.points3d.end(),
                         [](const Eigen::Vector3d& p) { return p.x() == 0; });
    const bool frontal = spec.view.kind == ViewKind::kFront || spec.view.kind == ViewKind::kBack;
    return frontal && std::all_of(spec.points.begin(), spec.points.end(),
                                  [](const Eigen::Vector2d& p) { return p.x() == 0; });
  }
  return false;
}

}  // namespace

double polyline_length(const Eigen::MatrixX3d& points) {
  double length = 0;
  for (Eigen::Index k = 1; k < points.rows(); ++k)
    length += (points.row(k) - points.row(k - 1)).norm();
  return length;
}

Eigen::Vector3d polyline_end_tangent(const Eigen::MatrixX3d& p, bool at_start, double reach) {
  reach = std::min(reach, polyline_length(p) / 3);
  const Eigen::Index n = p.rows();
  double arc = 0;
  if (at_start) {
    Eigen::Index k = 1;
    for (; k < n - 1; ++k) {
      arc += (p.row(k) - p.row(k - 1)).norm();
      if (arc >= reach) break;
    }
    return (p.row(k) - p.row(0)).transpose().normalized();
  }
  Eigen::Index k = n - 2;
  for (; k > 0; --k) {
    arc += (p.row(k + 1) - p.row(k)).norm();
    if (arc >= reach) break;
  }
  return (p.row(n - 1) - p.row(k)).transpose().normalized();
}

int CurveNetwork::find_curve(const std::string& id) const {
  for (size_t i = 0; i < curves.size(); ++i)
    if (curves[i].id == id) return static_cast<int>(i);
  if (id.ends_with(".mirror")) {  // an on-plane curve is its own copy
    const std::string base = id.substr(0, id.size() - 7);
    for (size_t i = 0; i < curves.size(); ++i)
      if (curves[i].id == base) {
        const bool has_copy = std::any_of(curves.begin(), curves.end(),
                                          [&](const NetworkCurve& c) { return c.id == id; });
        if (!has_copy) return static_cast<int>(i);
      }
  }
  return -1;
}

CurveNetwork build_network(const GarmentRequest& sketch, const std::vector<ProjectedCurve>& curves,
                           const std::set<std::string>& mirrored) {
  const double tol = sketch.junction_tolerance;
  std::vector<WorkCurve> work(curves.size());
  for (size_t c = 0; c < curves.size(); ++c) {
    WorkCurve& w = work[c];
    w.points = curves[c].points;
    w.closed = curves[c].closed;
    w.mirrored = mirrored.contains(curves[c].id);
    // On the plane means within a quarter of the junction tolerance everywhere (a stroke drawn
    // at x = 0 lands within a millimetre or two); a curve near the plane but off it (an inseam
    // along the inner thigh) keeps its own mirror copy.
    if (w.mirrored && (w.points.col(0).cwiseAbs().maxCoeff() < kOnPlaneFraction * tol ||
                       written_on_plane(sketch, curves[c].id))) {
      w.on_plane = true;
      w.points.col(0).setZero();
    }
  }

  // 1. Endpoints within the tolerance become one node (single-link clustering).
  std::vector<std::pair<int, int>> ends;  // (curve, 0 = start / 1 = end)
  std::vector<Eigen::Vector3d> end_points;
  for (size_t c = 0; c < work.size(); ++c) {
    if (work[c].closed) continue;
    ends.emplace_back(static_cast<int>(c), 0);
    end_points.push_back(work[c].points.row(0).transpose());
    ends.emplace_back(static_cast<int>(c), 1);
    end_points.push_back(work[c].points.row(work[c].points.rows() - 1).transpose());
  }
  UnionFind clusters(static_cast<int>(ends.size()));
  for (size_t a = 0; a < ends.size(); ++a)
    for (size_t b = a + 1; b < ends.size(); ++b)
      if ((end_points[a] - end_points[b]).norm() < tol)
        clusters.unite(static_cast<int>(a), static_cast<int>(b));
  CurveNetwork net;
  std::vector<int> node_of_cluster(ends.size(), -1);
  std::vector<int> members;
  std::vector<std::vector<int>> node_members;
  for (size_t a = 0; a < ends.size(); ++a) {
    const int root = clusters.find(static_cast<int>(a));
    int& node = node_of_cluster[static_cast<size_t>(root)];
    if (node < 0) {
      node = static_cast<int>(net.nodes.size());
      net.nodes.emplace_back(Eigen::Vector3d::Zero());
      node_members.emplace_back();
    }
    node_members[static_cast<size_t>(node)].push_back(static_cast<int>(a));
    const auto [c, which] = ends[a];
    (which == 0 ? work[static_cast<size_t>(c)].start_node : work[static_cast<size_t>(c)].end_node) =
        node;
  }
  std::vector<bool> node_mirrored(net.nodes.size(), false);
  for (size_t node = 0; node < net.nodes.size(); ++node) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int a : node_members[node]) {
      sum += end_points[static_cast<size_t>(a)];
      if (work[static_cast<size_t>(ends[static_cast<size_t>(a)].first)].mirrored)
        node_mirrored[node] = true;
    }
    net.nodes[node] = sum / static_cast<double>(node_members[node].size());
  }
  for (size_t c = 0; c < work.size(); ++c)
    if (!work[c].closed && work[c].start_node == work[c].end_node)
      sketch.fail(
          curves[c].json_path,
          polyline_length(curves[c].points) < 2 * tol
              ? fmt::format("curve '{}' is {:.1f} mm long, too short to have two ends: "
                            "ends closer than the junction tolerance ({:.1f} mm) are one "
                            "junction. Draw it longer (coordinates are in metres), or "
                            "lower \"junction_tolerance\"",
                            curves[c].id, 1e3 * polyline_length(curves[c].points), 1e3 * tol)
              : fmt::format("curve '{}' ends where it starts; set \"closed\": true for a "
                            "loop",
                            curves[c].id));

  // 2. A node on the interior of another curve splits it (T-junction); the node moves onto it.
  for (size_t node = 0; node < net.nodes.size(); ++node) {
    for (size_t c = 0; c < work.size(); ++c) {
      WorkCurve& w = work[c];
      if (w.start_node == static_cast<int>(node) || w.end_node == static_cast<int>(node)) continue;
      const auto [param, distance] = closest_param(w.points, w.closed, net.nodes[node]);
      if (distance >= tol) continue;
      if (!w.closed) {
        const double along = arc_to(w.points, false, param);
        const double length = polyline_length(w.points);
        if (along < tol || length - along < tol) continue;  // near an end: clustering's job
      }
      w.splits.push_back({param, static_cast<int>(node)});
      TJoin join;
      join.node = static_cast<int>(node);
      join.from = net.nodes[node];
      join.distance = distance;
      join.curve = curves[c].id;
      for (const int a : node_members[node]) {
        const auto [end_curve, which] = ends[static_cast<size_t>(a)];
        join.ends.push_back(fmt::format("the {} of '{}'", which == 0 ? "start" : "end",
                                        curves[static_cast<size_t>(end_curve)].id));
      }
      net.t_joins.push_back(std::move(join));
      net.nodes[node] = point_at(w.points, w.closed, param);
      if (w.mirrored) node_mirrored[node] = true;
    }
  }

  // 3. Nodes of mirrored curves near the plane go onto it, so the copies meet the originals.
  for (size_t node = 0; node < net.nodes.size(); ++node) {
    if (!node_mirrored[node] || std::abs(net.nodes[node].x()) >= tol) continue;
    if (2 * std::abs(net.nodes[node].x()) >= tol) {
      PlaneSnap snap;
      snap.from_plane = std::abs(net.nodes[node].x());
      for (const int a : node_members[node]) {
        const auto [c, which] = ends[static_cast<size_t>(a)];
        snap.ends.push_back(fmt::format("the {} of '{}'", which == 0 ? "start" : "end",
                                        curves[static_cast<size_t>(c)].id));
      }
      snap.at = Eigen::Vector3d(0, net.nodes[node].y(), net.nodes[node].z());
      net.plane_snaps.push_back(std::move(snap));
    }
    net.nodes[node].x() = 0;
  }

  // Closed curves without junctions get one node at their first point.
  for (WorkCurve& w : work)
    if (w.closed && w.splits.empty()) {
      w.splits.push_back({0.0, static_cast<int>(net.nodes.size())});
      net.nodes.emplace_back(w.points.row(0).transpose());
      node_mirrored.push_back(w.mirrored);
    }

  // 4. Mirror nodes: on the plane a node is its own image; otherwise an existing node at the
  // image position is paired with it (and moved there exactly), or a new node is made.
  std::vector<int> mirror_node(net.nodes.size(), -1);
  const size_t original_nodes = net.nodes.size();
  for (size_t node = 0; node < original_nodes; ++node) {
    if (!node_mirrored[node] || mirror_node[node] >= 0) continue;
    if (net.nodes[node].x() == 0) {
      mirror_node[node] = static_cast<int>(node);
      continue;
    }
    const Eigen::Vector3d image = mirror_point(net.nodes[node]);
    int match = -1;
    for (size_t other = 0; other < original_nodes; ++other)
      if (other != node && (net.nodes[other] - image).norm() < tol) match = static_cast<int>(other);
    if (match >= 0) {
      net.nodes[static_cast<size_t>(match)] = image;
      mirror_node[node] = match;
      mirror_node[static_cast<size_t>(match)] = static_cast<int>(node);
    } else {
      mirror_node[node] = static_cast<int>(net.nodes.size());
      net.nodes.push_back(image);
    }
  }

  // 5. Edges of the original curves, between consecutive junctions.
  for (size_t c = 0; c < work.size(); ++c) {
    WorkCurve& w = work[c];
    NetworkCurve curve;
    curve.id = curves[c].id;
    curve.spec = static_cast<int>(c);
    curve.closed = w.closed;
    std::vector<Split> splits = w.splits;
    std::sort(splits.begin(), splits.end(),
              [](const Split& a, const Split& b) { return a.param < b.param; });
    const double n = static_cast<double>(w.points.rows());
    if (!w.closed) {
      splits.insert(splits.begin(), {0.0, w.start_node});
      splits.push_back({n - 1.0, w.end_node});
    } else {
      splits.push_back({splits.front().param + n, splits.front().node});
    }
    for (size_t k = 0; k + 1 < splits.size(); ++k) {
      const Split& a = splits[k];
      const Split& b = splits[k + 1];
      if (a.node == b.node && !(w.closed && splits.size() == 2))
        sketch.fail(curves[c].json_path,
                    fmt::format("curve '{}' meets the same junction twice in a row; draw the two "
                                "curves so they meet once",
                                curves[c].id));
      NetworkEdge edge;
      edge.curve = static_cast<int>(net.curves.size());
      edge.from = a.node;
      edge.to = b.node;
      edge.points = extract_piece(w.points, w.closed, a.param, b.param,
                                  net.nodes[static_cast<size_t>(a.node)],
                                  net.nodes[static_cast<size_t>(b.node)]);
      if (w.on_plane) edge.points.col(0).setZero();
      edge.length = polyline_length(edge.points);
      if (edge.length < 1e-4)
        sketch.fail(
            curves[c].json_path,
            fmt::format("two junctions on curve '{}' are closer than 0.1 mm", curves[c].id));
      edge.orbit = static_cast<int>(net.edges.size());
      curve.nodes.push_back(a.node);
      curve.edges.push_back(static_cast<int>(net.edges.size()));
      net.edges.push_back(std::move(edge));
    }
    curve.nodes.push_back(splits.back().node);
    net.curves.push_back(std::move(curve));
  }

  // 6. Mirror copies of the mirrored curves that are not on the plane.
  const size_t original_curves = net.curves.size();
  for (size_t c = 0; c < original_curves; ++c) {
    if (!work[c].mirrored || work[c].on_plane) continue;
    NetworkCurve copy;
    copy.id = net.curves[c].id + ".mirror";
    copy.spec = net.curves[c].spec;
    copy.mirror_copy = true;
    copy.closed = net.curves[c].closed;
    for (int node : net.curves[c].nodes)
      copy.nodes.push_back(mirror_node[static_cast<size_t>(node)]);
    for (int e : net.curves[c].edges) {
      const NetworkEdge& original = net.edges[static_cast<size_t>(e)];
      NetworkEdge edge;
      edge.curve = static_cast<int>(net.curves.size());
      edge.from = mirror_node[static_cast<size_t>(original.from)];
      edge.to = mirror_node[static_cast<size_t>(original.to)];
      edge.points = original.points;
      edge.points.col(0) *= -1.0;
      edge.length = original.length;
      edge.orbit = e;
      copy.edges.push_back(static_cast<int>(net.edges.size()));
      net.edges.push_back(std::move(edge));
    }
    net.curves.push_back(std::move(copy));
  }
  return net;
}

}  // namespace sd::garment
