#include "garment/garment_mesh.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <map>
#include <numeric>
#include <optional>
#include <set>
#include <stdexcept>
#include <unordered_map>

#include "garment/curve_network.hpp"
#include "garment/edge_counts.hpp"
#include "garment/network_faces.hpp"
#include "garment/panel_loop.hpp"
#include "garment/panel_surface.hpp"
#include "garment/sketch_ranges.hpp"
#include "garment/stroke_projection.hpp"
#include "garment/surface_relaxation.hpp"
#include "garment/surface_untangle.hpp"
#include "meshing/patch_fill.hpp"
#include "meshing/quad_quality.hpp"

namespace sd::garment {
namespace {

// Smoothing along the body after the fill (surface_relaxation.hpp): at most this many sweeps
// (the t-shirt's back needs 20 to unfold its crease with steps of half an edge; 10 do not),
// stopped early once no vertex moves more than 1e-2 edge lengths (0.25 mm) in a sweep.
constexpr int kSurfaceSweeps = 20;
constexpr double kSurfaceTolerance = 1e-2;  // edge lengths
constexpr double kSurfaceMaxStep = 0.5;     // edge lengths
// m: an "auto" panel whose spanned surface stands farther than this off the body's offset
// surface spans a hollow and is made "free"; otherwise it lies on the body.
constexpr double kSpanGap = 0.03;
// cos of the angle beyond which a closest body point faces away from its panel (100°): the
// sides of a half-tube are perpendicular to its facing, so only the far side is refused.
constexpr double kAgainstFacing = -0.17;
// ... and the surface seen from the panel's side replaces it only when it is at most this many
// times as far (a point in the middle of a limb is about as far from both sides; a panel that
// wraps over the shoulder to its front has points much nearer the front than the back).
constexpr double kSeenReach = 2.0;
// A quad this many times longer than wide is a sliver (the quality gate warns from 10).
constexpr double kSliverAspect = 10;

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
// which keeps F1's panel. Returns how many were removed; `faces`/`face_panel` are edited.
int remove_doublets(std::vector<std::array<int, 4>>& faces, std::vector<int>& face_panel,
                    size_t vertex_count) {
  int removed = 0;
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
      faces[static_cast<size_t>(incident[b][0])] = {f1[1], f1[2], f1[3], f2[2]};
      faces.erase(faces.begin() + incident[b][1]);
      face_panel.erase(face_panel.begin() + incident[b][1]);
      ++removed;
      changed = true;
    }
  }
  return removed;
}

// The unit vector area of a panel's boundary loop (the sides, corner to corner), or zero.
Eigen::Vector3d loop_facing(const std::vector<Eigen::MatrixX3d>& side_points) {
  std::vector<Eigen::Vector3d> loop;
  for (const auto& side : side_points)
    for (Eigen::Index r = 0; r + 1 < side.rows(); ++r) loop.emplace_back(side.row(r).transpose());
  Eigen::Vector3d area = Eigen::Vector3d::Zero();
  for (size_t k = 0; k < loop.size(); ++k)
    area += (loop[k] - loop.front()).cross(loop[(k + 1) % loop.size()] - loop.front());
  return area.norm() > 0 ? Eigen::Vector3d(area.normalized()) : Eigen::Vector3d::Zero();
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

Garment build_garment(const Sketch& sketch, const BodySurface& body) {
  if (sketch.garment_mesh)
    throw std::logic_error("build_garment: a garment_mesh sketch has no curves to mesh");
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
  const std::vector<PanelLoop> loops = resolve_panels(sketch, net, body);
  EdgeCounts counts = compute_edge_counts(sketch, net, loops);
  {
    std::vector<double> boundary_edges;
    std::vector<std::string> paths, ids;
    for (const PanelLoop& loop : loops) {
      double edges = 0;
      for (const LoopEdge& e : loop.edges) edges += counts.counts[static_cast<size_t>(e.edge)];
      boundary_edges.push_back(edges);
      paths.push_back(loop.json_path);
      ids.push_back(loop.id);
    }
    check_panel_sizes(sketch, boundary_edges, paths, ids);
  }

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

  // Boundary vertices: placed once per curve piece by arc length; a copy's are the exact mirror
  // images of its original's (so mirrored panels match bitwise).
  VertexPool pool;
  std::vector<int> node_vertex(net.nodes.size(), -1);
  std::vector<Eigen::MatrixX3d> placed(net.edges.size());
  std::vector<std::vector<int>> edge_ids(net.edges.size());
  auto placed_points = [&](int e) -> const Eigen::MatrixX3d& {
    Eigen::MatrixX3d& p = placed[static_cast<size_t>(e)];
    if (p.rows() > 0) return p;
    const NetworkEdge& edge = net.edges[static_cast<size_t>(e)];
    const int orbit = edge.orbit;
    const int n = counts.counts[static_cast<size_t>(e)];
    if (orbit == e) {
      p = meshing::resample_by_arc_length(edge.points, n);
      if (edge.points.col(0).cwiseAbs().maxCoeff() == 0) p.col(0).setZero();
    } else {
      Eigen::MatrixX3d original =
          meshing::resample_by_arc_length(net.edges[static_cast<size_t>(orbit)].points, n);
      if (net.edges[static_cast<size_t>(orbit)].points.col(0).cwiseAbs().maxCoeff() == 0)
        original.col(0).setZero();
      original.col(0) *= -1.0;
      p = original;
    }
    p.row(0) = net.nodes[static_cast<size_t>(edge.from)].transpose();
    p.row(p.rows() - 1) = net.nodes[static_cast<size_t>(edge.to)].transpose();
    return p;
  };
  auto ids_of = [&](int e) -> const std::vector<int>& {
    std::vector<int>& ids = edge_ids[static_cast<size_t>(e)];
    if (!ids.empty()) return ids;
    const NetworkEdge& edge = net.edges[static_cast<size_t>(e)];
    const Eigen::MatrixX3d& p = placed_points(e);
    auto node_id = [&](int node) {
      int& v = node_vertex[static_cast<size_t>(node)];
      if (v < 0) v = pool.add(net.nodes[static_cast<size_t>(node)]);
      return v;
    };
    ids.push_back(node_id(edge.from));
    for (Eigen::Index k = 1; k + 1 < p.rows(); ++k) ids.push_back(pool.add(p.row(k).transpose()));
    ids.push_back(node_id(edge.to));
    return ids;
  };

  Garment garment;
  std::vector<std::array<int, 4>> faces;
  std::vector<int> face_panel;
  // Per original loop: patch vertex → global id, kept for its mirror copy.
  std::map<int, std::vector<int>> patch_globals;
  std::map<int, meshing::FilledPatch> patches;

  for (size_t l = 0; l < loops.size(); ++l) {
    const PanelLoop& loop = loops[l];
    const PanelSpec& spec = sketch.panels[static_cast<size_t>(loop.spec)];
    GarmentPanel panel;
    panel.id = loop.id;
    panel.group = loop.id;
    panel.fabric = spec.fabric;
    panel.mirror_copy = loop.mirror_copy;
    panel.ease = spec.ease;
    for (const LoopEdge& e : loop.edges) {
      panel.curves.push_back(
          net.curves[static_cast<size_t>(net.edges[static_cast<size_t>(e.edge)].curve)].id);
      const std::vector<int>& ids = ids_of(e.edge);
      for (size_t j = 0; j + 1 < ids.size(); ++j)
        garment.edge_curve[std::minmax(ids[j], ids[j + 1])] = panel.curves.back();
    }

    // Sides: points and global ids from corner i to corner i+1.
    std::vector<Eigen::MatrixX3d> side_points;
    std::vector<std::vector<int>> side_ids;
    auto build_sides = [&] {
      side_points.clear();
      side_ids.clear();
      panel.side_counts.clear();
      for (int s = 0; s < loop.side_count(); ++s) {
        std::vector<Eigen::Vector3d> pts;
        std::vector<int> ids;
        for (int k = loop.side_begin[static_cast<size_t>(s)]; k < loop.side_end(s); ++k) {
          const LoopEdge& e = loop.edges[static_cast<size_t>(k)];
          const Eigen::MatrixX3d& p = placed_points(e.edge);
          const std::vector<int>& g = ids_of(e.edge);
          const Eigen::Index n = p.rows();
          for (Eigen::Index j = 0; j < n; ++j) {
            const Eigen::Index src = e.forward ? j : n - 1 - j;
            if (!ids.empty() && j == 0) continue;  // the junction is already there
            pts.push_back(p.row(src).transpose());
            ids.push_back(g[static_cast<size_t>(src)]);
          }
        }
        Eigen::MatrixX3d m(static_cast<Eigen::Index>(pts.size()), 3);
        for (size_t j = 0; j < pts.size(); ++j)
          m.row(static_cast<Eigen::Index>(j)) = pts[j].transpose();
        side_points.push_back(std::move(m));
        side_ids.push_back(std::move(ids));
        panel.side_counts.push_back(static_cast<int>(side_ids.back().size()) - 1);
      }
    };
    build_sides();

    const int panel_index = static_cast<int>(garment.panels.size());
    std::vector<int> globals;
    if (!loop.mirror_copy) {
      // Project interior points onto the offset surface where the panel lies on the body:
      // inside it, or less than one edge length outside it; points spanning a hollow (between
      // the legs, under the bust) are left where the relaxation puts them.
      // Any on-body curve makes the panel a body panel; free-hanging parts (a flared hem) are
      // more than `reach` off the body and are not pulled in.
      double offset = 0;
      int on_body = 0;
      for (const LoopEdge& e : loop.edges) {
        const CurveSpec& cs = sketch.curves[static_cast<size_t>(
            net.curves[static_cast<size_t>(net.edges[static_cast<size_t>(e.edge)].curve)].spec)];
        if (!cs.on_body) continue;
        offset += cs.offset;
        ++on_body;
      }
      if (on_body > 0) offset /= on_body;
      const double reach = spec.edge_length.value_or(sketch.edge_length);
      meshing::FillGeometryOptions options;
      options.relax_iterations = sketch.relax_iterations;
      // Each query starts from the last answer found in the same cell of half an edge length: a
      // vertex moves less than that per relaxation sweep, so the hint is usually its own last
      // projection (a hash collision only gives a poorer hint, never another answer).
      std::unordered_map<std::int64_t, SurfacePoint> hints;
      const double cell = 0.5 * reach;
      // The panel faces `facing` (its boundary's vector area: the loop runs counter-clockwise
      // seen from outside). A point whose closest body point faces the other way has crossed
      // the limb or torso it lies on: the interior of a half-sleeve starts on the chord plane
      // through the arm, where the far side of the arm can be nearest (a hole in the back of a
      // long sleeve at the elbow). Such a point goes to the body's first surface seen from the
      // panel's side instead: a ray from outside the body's box along −facing.
      const Eigen::Vector3d facing = loop_facing(side_points);
      const double outside = (body.box().max - body.box().min).norm();
      const auto closest = [&body, &hints, cell, facing, outside](const Eigen::Vector3d& p) {
        const Eigen::Vector3d q = (p / cell).array().floor();
        const std::int64_t key = (static_cast<std::int64_t>(q.x()) * 73856093) ^
                                 (static_cast<std::int64_t>(q.y()) * 19349663) ^
                                 (static_cast<std::int64_t>(q.z()) * 83492791);
        SurfacePoint& hint = hints[key];
        hint = body.closest_point(p, hint);
        if (hint.normal.dot(facing) < kAgainstFacing) {
          if (const auto seen = body.first_hit(p + outside * facing, -facing);
              seen && seen->normal.dot(facing) > 0 &&
              (seen->position - p).norm() < kSeenReach * hint.distance)
            return *seen;
        }
        return hint;
      };
      const SurfaceLift lift = [&closest, offset, reach](const Eigen::Vector3d& p) -> LiftedPoint {
        const SurfacePoint s = closest(p);
        const double signed_distance = (p - s.position).dot(s.normal);
        if (signed_distance < offset + reach) return {s.position + offset * s.normal, s.normal};
        return {p, Eigen::Vector3d::Zero()};
      };
      // The body as an obstacle only: a point inside the offset surface goes to its closest
      // point on it, any other point stays.
      const PushOut push_out =
          [&closest, offset](const Eigen::Vector3d& p) -> std::optional<Eigen::Vector3d> {
        const SurfacePoint s = closest(p);
        if ((p - s.position).dot(s.normal) >= offset) return std::nullopt;
        return s.position + offset * s.normal;
      };
      const auto fill = [&](const meshing::FillGeometryOptions& o) {
        try {
          return meshing::fill_region(side_points, o);
        } catch (const meshing::FillError& e) {
          sketch.fail(loop.json_path,
                      fmt::format("panel '{}' cannot be filled with quads: {}", loop.id, e.what()));
        }
      };
      // The surface spanned by the boundary decides an "auto" panel: where it stays near or
      // inside the body the panel lies on it (a t-shirt's front over the chest); where it
      // stands off by more than kSpanGap it spans a hollow (a skirt across the legs).
      PanelFit fit = spec.fit;
      if (on_body == 0) fit = PanelFit::kFree;
      meshing::FillGeometryOptions free_options = options;
      free_options.project = nullptr;
      std::optional<meshing::FilledPatch> spanned;
      if (fit != PanelFit::kBody) {
        spanned = fill(free_options);
        std::vector<char> boundary(static_cast<size_t>(spanned->mesh.vertex_count()), 0);
        for (const auto& side : spanned->topology.side_vertices)
          for (int v : side) boundary[static_cast<size_t>(v)] = 1;
        meshing::QuadMesh membrane = spanned->mesh;
        span_harmonic(membrane, boundary);
        for (Eigen::Index v = 0; v < membrane.vertex_count(); ++v) {
          if (boundary[static_cast<size_t>(v)]) continue;
          const Eigen::Vector3d p = membrane.vertices.row(v).transpose();
          const SurfacePoint s = body.closest_point(p);
          panel.span_gap = std::max(panel.span_gap, (p - s.position).dot(s.normal) - offset);
        }
        if (fit == PanelFit::kAuto)
          fit = panel.span_gap > kSpanGap ? PanelFit::kFree : PanelFit::kBody;
      }
      panel.fit = fit == PanelFit::kFree ? "free" : "body";
      if (fit == PanelFit::kBody)
        options.project = [&lift](const Eigen::Vector3d& p) { return lift(p).position; };
      else
        options.project = [&push_out](const Eigen::Vector3d& p) { return push_out(p).value_or(p); };
      const auto normal = [&body](const Eigen::Vector3d& p) -> Eigen::Vector3d {
        return body.closest_point(p).normal;
      };
      meshing::FilledPatch patch = fit == PanelFit::kBody ? fill(options) : std::move(*spanned);
      std::vector<char> fixed(static_cast<size_t>(patch.mesh.vertex_count()), 0);
      for (const auto& side : patch.topology.side_vertices)
        for (int v : side) fixed[static_cast<size_t>(v)] = 1;
      if (fit == PanelFit::kFree) {
        // A panel the body does not touch keeps the filler's own interpolation of its boundary
        // (transfinite, then relaxed), which reproduces a ruled surface such as a tube skirt's
        // cylinder exactly; the uniform harmonic membrane would flatten it between its curves.
        // Where the body is in the way, the membrane spans over it.
        bool touches = false;
        for (Eigen::Index v = 0; v < patch.mesh.vertex_count() && !touches; ++v)
          touches = !fixed[static_cast<size_t>(v)] &&
                    push_out(patch.mesh.vertices.row(v).transpose()).has_value();
        if (touches) span_over_obstacle(patch.mesh, fixed, push_out);
        patch.quality = meshing::measure_quality(patch.mesh, patch.topology.corner_vertices());
      }
      // Candidates: the fill, its smoothing along the surface (body panels; see
      // surface_relaxation.hpp), and each of those unfolded against the body's normals when it
      // folds (surface_untangle.hpp). The best by the quality gate's measures wins: fewest folded
      // quads, then no sliver (aspect ratio 10 or more: the t-shirt dress's back at 3 cm had a
      // clean fill with two vertices on one spot at the armpit, and a smoothed mesh with one
      // fold that unfolding removes), then the best worst corner.
      const auto rank = [](const meshing::QuadQuality& q) {
        return std::tuple(q.inverted_quads, q.max_aspect_ratio >= kSliverAspect,
                          -q.scaled_jacobian_min);
      };
      const auto consider = [&](meshing::QuadMesh&& mesh, meshing::FilledPatch& best) {
        const meshing::QuadQuality quality =
            meshing::measure_quality(mesh, patch.topology.corner_vertices());
        if (rank(quality) < rank(best.quality)) {
          best.mesh = std::move(mesh);
          best.quality = quality;
        }
      };
      const auto unfold = [&](const meshing::QuadMesh& mesh) {
        meshing::QuadMesh unfolded = mesh;
        untangle_on_surface(unfolded, fixed, options.project, normal);
        return unfolded;
      };
      meshing::FilledPatch best = patch;
      if (patch.quality.inverted_quads > 0) consider(unfold(patch.mesh), best);
      if (fit == PanelFit::kBody) {
        meshing::QuadMesh relaxed = patch.mesh;
        relax_on_surface(relaxed, fixed, lift,
                         {kSurfaceSweeps, kSurfaceTolerance * reach, kSurfaceMaxStep * reach});
        const meshing::QuadQuality quality =
            meshing::measure_quality(relaxed, patch.topology.corner_vertices());
        if (quality.inverted_quads > 0) consider(unfold(relaxed), best);
        consider(std::move(relaxed), best);
      }
      patch.mesh = std::move(best.mesh);
      patch.quality = best.quality;
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
        const std::vector<int>& ga = ids_of(a.edge);
        const std::vector<int>& gb = ids_of(b->edge);
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
    garment.panels.push_back(std::move(panel));
  }

  garment.merged_doublets = remove_doublets(faces, face_panel, pool.positions.size());
  if (const int doublets = garment.merged_doublets; doublets > 0)
    spdlog::warn(
        "{} seam vertex(es) had only two quads folded onto each other; merged them into "
        "one quad each (the seam steps one vertex aside there)",
        doublets);
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
      const Eigen::Vector3d& p = pool.positions[v];
      sketch.fail(
          "/panels",
          fmt::format("panels {} meet only at the point ({:.3f}, {:.3f}, {:.3f}) m, not along "
                      "a seam: two curves there run along one seam without being one curve. "
                      "Give both panels the same curve (on the other side of a mirrored "
                      "garment, the copy '<curve>.mirror')",
                      list, p.x(), p.y(), p.z()));
    }
  }

  // Seams must be traversed in opposite directions by their two panels.
  std::map<std::pair<int, int>, std::pair<int, int>> directed;  // (a, b) → (face, count)
  for (size_t f = 0; f < faces.size(); ++f)
    for (int k = 0; k < 4; ++k) {
      const int a = faces[f][static_cast<size_t>(k)],
                b = faces[f][static_cast<size_t>((k + 1) % 4)];
      auto [it, inserted] = directed.try_emplace({a, b}, static_cast<int>(f), 0);
      if (!inserted) {
        const GarmentPanel& p1 =
            garment.panels[static_cast<size_t>(face_panel[static_cast<size_t>(it->second.first)])];
        const GarmentPanel& p2 = garment.panels[static_cast<size_t>(face_panel[f])];
        sketch.fail("/panels",
                    fmt::format("panels '{}' and '{}' face opposite ways along their shared seam; "
                                "check that both lie on the same side of the body",
                                p1.id, p2.id));
      }
    }
  for (const auto& [edge, face] : directed)
    if (edge.first < edge.second && directed.contains({edge.second, edge.first}) &&
        face_panel[static_cast<size_t>(face.first)] !=
            face_panel[static_cast<size_t>(directed.at({edge.second, edge.first}).first)])
      ++garment.seam_edges;

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
  garment.parity_changes = static_cast<int>(counts.changed.size());
  for (const auto& u : users) garment.curve_pieces += u.empty() ? 0 : 1;
  return garment;
}

}  // namespace sd::garment
