#include "garment/network_faces.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "garment/stroke_projection.hpp"

namespace sd::garment {
namespace {

// A seed closer than this to a curve is on it: which side it means is a guess.
constexpr double kSeedOnCurve = 0.002;  // metres
// m: a "point3d" seed deeper inside the body than this is refused; nearer its surface it was
// likely written by eye on the skin.
constexpr double kSeedInsideBody = 0.02;

// A curve end at a junction: edge `edge` leaving node `node` (at its start when at_start).
struct Dart {
  int edge = -1;
  bool at_start = true;
  double angle = 0;  // radians around the node's outward normal
};

// Half-edge run away from the node along a dart: forward when the dart is the edge's start.
int half_edge_of(const Dart& d) {
  return 2 * d.edge + (d.at_start ? 0 : 1);
}

// Orthonormal tangent basis (e1, e2 = n × e1) of a unit normal: angles measured from e1 towards
// e2 turn counter-clockwise seen from outside.
std::pair<Eigen::Vector3d, Eigen::Vector3d> tangent_basis(const Eigen::Vector3d& n) {
  const Eigen::Vector3d helper =
      std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d e1 = (helper - helper.dot(n) * n).normalized();
  return {e1, n.cross(e1)};
}

double angle_in(const std::pair<Eigen::Vector3d, Eigen::Vector3d>& basis,
                const Eigen::Vector3d& d) {
  return std::atan2(d.dot(basis.second), d.dot(basis.first));
}

// Darts around every node, sorted counter-clockwise seen from outside the body.
std::vector<std::vector<Dart>> sorted_darts(
    const CurveNetwork& net, const BodySurface& body,
    std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>& bases) {
  std::vector<std::vector<Dart>> around(net.nodes.size());
  bases.clear();
  for (const Eigen::Vector3d& p : net.nodes)
    bases.push_back(tangent_basis(body.closest_point(p).normal));
  for (size_t e = 0; e < net.edges.size(); ++e) {
    const NetworkEdge& edge = net.edges[e];
    const Eigen::Vector3d out = polyline_end_tangent(edge.points, true, kJunctionTangentArc);
    const Eigen::Vector3d back = -polyline_end_tangent(edge.points, false, kJunctionTangentArc);
    const size_t from = static_cast<size_t>(edge.from), to = static_cast<size_t>(edge.to);
    around[from].push_back({static_cast<int>(e), true, angle_in(bases[from], out)});
    around[to].push_back({static_cast<int>(e), false, angle_in(bases[to], back)});
  }
  for (auto& darts : around)
    std::sort(darts.begin(), darts.end(),
              [](const Dart& a, const Dart& b) { return a.angle < b.angle; });
  return around;
}

std::string curve_name(const CurveNetwork& net, int edge) {
  return net.curves[static_cast<size_t>(net.edges[static_cast<size_t>(edge)].curve)].id;
}

// Connected components of the network's edges (through shared nodes).
std::vector<int> edge_components(const CurveNetwork& net) {
  std::vector<int> parent(net.nodes.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int a) {
    while (parent[static_cast<size_t>(a)] != a)
      a = parent[static_cast<size_t>(a)] =
          parent[static_cast<size_t>(parent[static_cast<size_t>(a)])];
    return a;
  };
  for (const NetworkEdge& e : net.edges) parent[static_cast<size_t>(find(e.from))] = find(e.to);
  std::vector<int> component;
  for (const NetworkEdge& e : net.edges) component.push_back(find(e.from));
  return component;
}

struct Nearest {
  int edge = -1;
  double distance = std::numeric_limits<double>::infinity();
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d tangent = Eigen::Vector3d::Zero();  // of the segment, along the edge
  int node = -1;  // the nearest point is this junction (an edge end)
};

// Nearest point of the network to p, ignoring the edges of component `skip` (-1: none).
Nearest nearest_curve(const CurveNetwork& net, const std::vector<int>& component, int skip,
                      const Eigen::Vector3d& p) {
  Nearest best;
  for (size_t e = 0; e < net.edges.size(); ++e) {
    if (component[e] == skip) continue;
    const Eigen::MatrixX3d& pts = net.edges[e].points;
    for (Eigen::Index s = 0; s + 1 < pts.rows(); ++s) {
      const Eigen::Vector3d a = pts.row(s).transpose(), b = pts.row(s + 1).transpose();
      const Eigen::Vector3d ab = b - a;
      if (ab.squaredNorm() == 0) continue;
      const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
      const Eigen::Vector3d q = a + t * ab;
      const double d = (p - q).norm();
      if (d >= best.distance) continue;
      best.edge = static_cast<int>(e);
      best.distance = d;
      best.point = q;
      best.tangent = ab.normalized();
      best.node = -1;
      if (s == 0 && t == 0) best.node = net.edges[e].from;
      if (s + 2 == pts.rows() && t == 1) best.node = net.edges[e].to;
    }
  }
  return best;
}

// The face containing p: on p's side of the nearest curve, or in the sector between two curves
// when the nearest point is a junction.
int face_at(const CurveNetwork& net, const NetworkFaces& faces, const BodySurface& body,
            const std::vector<std::vector<Dart>>& around,
            const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>& bases,
            const Nearest& near, const Eigen::Vector3d& p) {
  if (near.node >= 0) {
    const std::vector<Dart>& darts = around[static_cast<size_t>(near.node)];
    const double a = angle_in(bases[static_cast<size_t>(near.node)],
                              p - net.nodes[static_cast<size_t>(near.node)]);
    // The sector [dart k, dart k+1) holding a lies on the left of the half-edge leaving along k.
    size_t k = darts.size() - 1;
    for (size_t i = 0; i < darts.size(); ++i)
      if (darts[i].angle <= a) k = i;
    return faces.face_left[static_cast<size_t>(half_edge_of(darts[k]))];
  }
  const Eigen::Vector3d n = body.closest_point(near.point).normal;
  const bool left = (p - near.point).dot(n.cross(near.tangent)) > 0;
  return faces.face_left[static_cast<size_t>(2 * near.edge + (left ? 0 : 1))];
}

}  // namespace

NetworkFaces trace_faces(const CurveNetwork& net, const BodySurface& body) {
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> bases;
  const std::vector<std::vector<Dart>> around = sorted_darts(net, body, bases);
  // Position of each half-edge's arrival dart in the list of its end node.
  std::vector<size_t> arrival(2 * net.edges.size());
  for (const auto& darts : around)
    for (size_t i = 0; i < darts.size(); ++i)
      arrival[static_cast<size_t>(2 * darts[i].edge + (darts[i].at_start ? 1 : 0))] = i;
  NetworkFaces result;
  result.face_left.assign(2 * net.edges.size(), -1);
  for (size_t start = 0; start < result.face_left.size(); ++start) {
    if (result.face_left[start] >= 0) continue;
    const int face = static_cast<int>(result.faces.size());
    std::vector<LoopEdge> loop;
    for (size_t h = start; result.face_left[h] < 0;) {
      result.face_left[h] = face;
      const int e = static_cast<int>(h / 2);
      const bool forward = h % 2 == 0;
      loop.push_back({e, forward, -1});
      // Arrive at the end node, turn onto the next curve clockwise from the one we came along.
      const NetworkEdge& edge = net.edges[static_cast<size_t>(e)];
      const std::vector<Dart>& darts = around[static_cast<size_t>(forward ? edge.to : edge.from)];
      const size_t i = arrival[h];
      h = static_cast<size_t>(half_edge_of(darts[(i + darts.size() - 1) % darts.size()]));
    }
    result.faces.push_back(std::move(loop));
  }
  return result;
}

Eigen::Vector3d seed_position(const GarmentRequest& sketch, const PanelSpec& panel,
                              const BodySurface& body) {
  const SeedSpec& seed = *panel.seed;
  if (seed.point3d) {
    // Deep inside, the body's surface nearest to the seed is no region the designer pointed at
    // (a seed at the torso's centre was said to lie on the centre back, the curve nearest to it:
    // trial 39, P11).
    const double depth = -body.signed_distance(*seed.point3d);
    if (depth > kSeedInsideBody)
      sketch.fail(
          seed.json_path + "/point3d",
          fmt::format("the seed of panel '{}', ({:.3f}, {:.3f}, {:.3f}) m, lies inside the "
                      "body, {:.1f} cm below its surface, so it does not point at a region; "
                      "give a point on the body inside the panel (`info BODY --slice Y` "
                      "prints the body's outlines at height Y)",
                      panel.id, seed.point3d->x(), seed.point3d->y(), seed.point3d->z(),
                      100 * depth));
    return *seed.point3d;
  }
  const ViewFrame frame = view_frame(seed.view);
  Eigen::Vector3d origin, direction;
  frame.ray(*seed.point, 10.0, origin, direction);
  const std::optional<SurfacePoint> hit = body.first_hit(origin, direction);
  if (!hit)
    sketch.fail(seed.json_path + "/point",
                fmt::format("the seed of panel '{}' misses the body in the {} view; put it on the "
                            "body inside the panel, or give it as \"point3d\"",
                            panel.id, seed.view.name()));
  return hit->position;
}

std::vector<LoopEdge> auto_panel_loop(const GarmentRequest& sketch, const CurveNetwork& net,
                                      const NetworkFaces& faces, const BodySurface& body,
                                      const PanelSpec& panel) {
  const Eigen::Vector3d seed = seed_position(sketch, panel, body);
  const std::string& path = panel.seed->json_path;
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> bases;
  const std::vector<std::vector<Dart>> around = sorted_darts(net, body, bases);
  const std::vector<int> component = edge_components(net);
  const Nearest near = nearest_curve(net, component, -1, seed);
  if (near.edge < 0) sketch.fail(path, "there are no curves to find a panel among");
  // Across the curve, in the body's tangent plane (curves sit `offset` off the body, seeds on it).
  const Eigen::Vector3d normal = body.closest_point(near.point).normal;
  const Eigen::Vector3d across = (seed - near.point) - (seed - near.point).dot(normal) * normal;
  if (across.norm() < kSeedOnCurve)
    sketch.fail(path, fmt::format("the seed of panel '{}' lies on curve '{}' ({:.1f} mm from it "
                                  "along the body), so it does not say which side is meant; move "
                                  "it inside the panel",
                                  panel.id, curve_name(net, near.edge), across.norm() * 1000));
  const int face = face_at(net, faces, body, around, bases, near, seed);
  const std::vector<LoopEdge>& loop = faces.faces[static_cast<size_t>(face)];

  // A curve with the face on both sides is not a boundary: it ends inside the region (or only
  // links two loops), and no disk has that boundary.
  for (const LoopEdge& e : loop)
    if (faces.face_left[static_cast<size_t>(2 * e.edge)] ==
        faces.face_left[static_cast<size_t>(2 * e.edge + 1)]) {
      const NetworkEdge& edge = net.edges[static_cast<size_t>(e.edge)];
      const bool free_end = around[static_cast<size_t>(edge.from)].size() == 1 ||
                            around[static_cast<size_t>(edge.to)].size() == 1;
      const Eigen::Vector3d at = net.nodes[static_cast<size_t>(
          around[static_cast<size_t>(edge.from)].size() == 1 ? edge.from : edge.to)];
      sketch.fail(
          path, free_end ? fmt::format("the region around the seed of panel '{}' is not closed: "
                                       "curve '{}' ends inside it at ({:.3f}, {:.3f}, {:.3f}) "
                                       "without meeting another curve; end it on a curve (or "
                                       "remove it), or list the panel's curves",
                                       panel.id, curve_name(net, e.edge), at.x(), at.y(), at.z())
                         : fmt::format("the region around the seed of panel '{}' is not one closed "
                                       "loop: curve '{}' has the region on both of its sides; list "
                                       "the panel's curves instead",
                                       panel.id, curve_name(net, e.edge)));
    }

  // Curves inside the region that do not touch its boundary would make it a disk with holes.
  const int own = component[static_cast<size_t>(loop.front().edge)];
  std::set<int> probed{own};
  for (size_t e = 0; e < net.edges.size(); ++e) {
    if (!probed.insert(component[e]).second) continue;  // one probe per other component
    const Eigen::Vector3d probe = net.nodes[static_cast<size_t>(net.edges[e].from)];
    const Nearest other = nearest_curve(net, component, component[e], probe);
    if (other.edge >= 0 && component[static_cast<size_t>(other.edge)] == own &&
        face_at(net, faces, body, around, bases, other, probe) == face)
      sketch.fail(path, fmt::format("the region around the seed of panel '{}' has curve '{}' "
                                    "inside it, not connected to its boundary; connect the "
                                    "curves or list the panel's curves",
                                    panel.id, curve_name(net, static_cast<int>(e))));
  }
  return loop;
}

std::set<std::string> auto_panel_curves_to_mirror(const GarmentRequest& sketch,
                                                  const CurveNetwork& net,
                                                  const BodySurface& body) {
  std::set<std::string> ids;
  const bool any = std::any_of(sketch.panels.begin(), sketch.panels.end(),
                               [](const PanelSpec& p) { return p.auto_boundary && p.mirror; });
  if (!any) return ids;
  const NetworkFaces faces = trace_faces(net, body);
  for (const PanelSpec& panel : sketch.panels) {
    if (!panel.auto_boundary || !panel.mirror) continue;
    for (const LoopEdge& e : auto_panel_loop(sketch, net, faces, body, panel)) {
      const NetworkCurve& curve =
          net.curves[static_cast<size_t>(net.edges[static_cast<size_t>(e.edge)].curve)];
      ids.insert(sketch.curves[static_cast<size_t>(curve.spec)].id);
    }
  }
  return ids;
}

}  // namespace sd::garment
