#include "garment/panel_fill.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <optional>
#include <span>
#include <tuple>
#include <utility>

#include "garment/crease_wall.hpp"
#include "garment/fold_repair.hpp"
#include "garment/panel_surface.hpp"
#include "garment/quality_gate.hpp"
#include "garment/surface_relaxation.hpp"
#include "garment/surface_untangle.hpp"
#include "meshing/arm_widening.hpp"
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
// A body panel's start along its normals (fill_panel's `place`): a ray along the panel's
// normal is taken only when it leaves the body within this many times the nearest distance,
// plus an edge length...
constexpr double kAlongReach = 3.0;
// ... and only where the nearest body point's normal turns more than 60° from the panel's
// (where it agrees, the nearest point is on the panel's own side of the body).
constexpr double kAlongCos = 0.5;
// Rings over which the interpolated surface's quad normals are averaged (one quad's normal is
// noisy where the layout's blocks meet).
constexpr int kAlongRings = 2;
// A free panel's membrane over the body (span_over_obstacle): its default round limit, and each
// vertex weighted in its neighbours' means by mean_weights (0 at valence 3, 1 + 2 cos(2π/k) at
// k ≥ 5 with kSpanHighValence), so the ring of quads round an irregular vertex keeps the size of
// the next ring (issue 18, twelfth round: docs/garment.md). Valence 5 and more are weighted here
// though not in the smoothing along the body (SurfaceRelaxationOptions::weigh_high_valence): the
// t-shirts, whose drape that held back, have no free panel and mesh as before.
// kSpanWeighted is off (the membrane uniform, as before): with it the capelet on the Collada
// human's drape no longer comes to rest (its front's edge at the left elbow still moves at 1.7
// cm/s after 7.7 s, where the uniform membrane's drape rests at 2.1 s; Corpus/DesignDrapeTop).
constexpr int kSpanRounds = 30;
constexpr bool kSpanWeighted = false;
constexpr bool kSpanHighValence = true;
// A quad this many times longer than wide is a sliver (the quality gate warns from 10).
constexpr double kSliverAspect = 10;

// m: a vertex this close to the offset surface lies on it (the fill puts a body panel's vertices
// on it to rounding; a free panel's contacts are on it).
constexpr double kOnOffsetSurface = 1e-3;

// Quads of `mesh` whose mean side lies outside the quality gate's size limits (QualityLimits:
// 0.25-2 times `edge`, m).
int quads_off_size(const meshing::QuadMesh& mesh, double edge) {
  const QualityLimits limits;
  int outside = 0;
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
    const double side = meshing::mean_side(mesh, f) / edge;
    outside += side < limits.size_low || side > limits.size_high ? 1 : 0;
  }
  return outside;
}

// Hash of a point's coordinates bit for bit (-0 and 0 are two keys, which only costs a miss).
size_t exact_point_hash(const Eigen::Vector3d& p) {
  size_t h = 0;
  for (int k = 0; k < 3; ++k) {
    std::uint64_t bits = 0;
    std::memcpy(&bits, &p[k], sizeof bits);
    h = (h ^ bits) * 0x100000001b3ULL;
    h ^= h >> 29;
  }
  return h;
}

// The finaliser of splitmix64: every bit of `x` reaches the low bits a table index takes.
std::uint64_t mix_bits(std::uint64_t x) {
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// The last closest body point found in each cell of a grid, by the cell's 64-bit key (two cells
// with one key share an entry, as in the std::unordered_map this replaces: same hints, same
// answers). Open addressing in flat arrays: the map's node per cell and its pointer chase were
// 14 % of a 0.4 cm shirt's validate, and its lookups missed the cache.
class CellHints {
 public:
  CellHints() {
    empty_.position.setZero();
    empty_.normal.setZero();
  }

  // The hint of the cell `key`, a point without a face (no hint) when the cell is new.
  SurfacePoint& operator[](std::int64_t key) {
    if (2 * (size_ + 1) > keys_.size()) grow();
    const size_t mask = keys_.size() - 1;
    for (size_t slot = mix_bits(static_cast<std::uint64_t>(key)) & mask;;
         slot = (slot + 1) & mask) {
      if (!used_[slot]) {
        used_[slot] = 1;
        keys_[slot] = key;
        hints_[slot] = empty_;
        ++size_;
        return hints_[slot];
      }
      if (keys_[slot] == key) return hints_[slot];
    }
  }

 private:
  void grow() {
    std::vector<std::int64_t> keys = std::move(keys_);
    std::vector<char> used = std::move(used_);
    std::vector<SurfacePoint> hints = std::move(hints_);
    const size_t slots = std::max<size_t>(1024, 2 * keys.size());
    keys_.assign(slots, 0);
    used_.assign(slots, 0);
    hints_.assign(slots, empty_);
    size_ = 0;
    for (size_t k = 0; k < keys.size(); ++k)
      if (used[k]) (*this)[keys[k]] = hints[k];
  }

  std::vector<std::int64_t> keys_;
  std::vector<char> used_;
  std::vector<SurfacePoint> hints_;
  size_t size_ = 0;
  SurfacePoint empty_;  // no face: no hint
};

// The answers of recent queries by query point, bit for bit, in a table of fixed size where a
// new answer replaces the one in its slot (a cache, not a record of every query). A fill asks
// again for points it asked shortly before (a vertex whose neighbours did not move, the
// untangling's candidates). A std::unordered_map of every answer held 1.3 million of them
// (about 250 MB) for the back of the long-sleeved tee at 0.4 cm edges and missed the processor's
// cache on most lookups; a lost answer is only asked again, to the same bits (the answers kept
// are those that do not depend on the hint).
template <typename Answer>
class RecentAnswers {
 public:
  // `slots`: a power of two.
  explicit RecentAnswers(size_t slots) : slots_(slots) {}

  const Answer* find(const Eigen::Vector3d& p) const {
    const Slot& slot = slots_[index(p)];
    return slot.used && slot.point == p ? &slot.answer : nullptr;
  }
  void store(const Eigen::Vector3d& p, const Answer& answer) {
    Slot& slot = slots_[index(p)];
    slot.used = true;
    slot.point = p;
    slot.answer = answer;
  }

 private:
  struct Slot {
    Eigen::Vector3d point = Eigen::Vector3d::Zero();
    Answer answer{};
    bool used = false;
  };
  size_t index(const Eigen::Vector3d& p) const {
    return mix_bits(exact_point_hash(p)) & (slots_.size() - 1);
  }
  std::vector<Slot> slots_;
};

// Slots of a panel's RecentAnswers: about 4 per vertex the panel is expected to have (its
// boundary vertices squared over 16, a square's), a power of two between these bounds.
constexpr size_t kLeastAnswerSlots = size_t{1} << 10, kMostAnswerSlots = size_t{1} << 16;

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

// The panel's offset from the body (m: the mean of its on-body curves' offsets) and how many of
// its boundary's pieces lie on the body.
std::pair<double, int> panel_offset(const GarmentRequest& sketch, const PanelLoop& loop,
                                    const CurveNetwork& net) {
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
  return {offset, on_body};
}

}  // namespace

std::function<Eigen::Vector3d(const Eigen::Vector3d&)> panel_projection(
    const GarmentRequest& sketch, const PanelSpec& spec, const PanelLoop& loop,
    const CurveNetwork& net, const BodySurface& body, const std::string& fit) {
  const double offset = panel_offset(sketch, loop, net).first;
  const double reach = spec.edge_length.value_or(sketch.edge_length);
  if (fit == "body")
    return [&body, offset, reach](const Eigen::Vector3d& p) -> Eigen::Vector3d {
      const SurfacePoint s = body.closest_point(p);
      if ((p - s.position).dot(s.normal) < offset + reach) return s.position + offset * s.normal;
      return p;
    };
  return [&body, offset](const Eigen::Vector3d& p) -> Eigen::Vector3d {
    const SurfacePoint s = body.closest_point(p);
    if ((p - s.position).dot(s.normal) >= offset) return p;
    return s.position + offset * s.normal;
  };
}

meshing::FilledPatch fill_panel(const GarmentRequest& sketch, const PanelSpec& spec,
                                const PanelLoop& loop, const CurveNetwork& net,
                                const std::vector<Eigen::MatrixX3d>& side_points,
                                const BodySurface& body, GarmentPanel& panel, CreaseMoves* crease) {
  // Project interior points onto the offset surface where the panel lies on the body:
  // inside it, or less than one edge length outside it; points spanning a hollow (between
  // the legs, under the bust) are left where the relaxation puts them.
  // Any on-body curve makes the panel a body panel; free-hanging parts (a flared hem) are
  // more than `reach` off the body and are not pulled in.
  const auto [offset, on_body] = panel_offset(sketch, loop, net);
  const double reach = spec.edge_length.value_or(sketch.edge_length);
  meshing::FillGeometryOptions options;
  options.relax_iterations = sketch.relax_iterations;
  // The fill of a panel with a widening arm cut across the arm is tried below, once the panel
  // is finished, and judged by the finished quads.
  options.widen_arms = false;
  // The boundary turns about the body's normal where it runs near the body (within the offset
  // and two edges): a strap round the back of the neck seen from the front would turn the
  // wrong way; a hem spanning the legs keeps the loop's own normal.
  options.surface_normal = [&body, offset, reach](const Eigen::Vector3d& p) -> Eigen::Vector3d {
    const SurfacePoint s = body.closest_point(p);
    return s.distance <= offset + 2 * reach ? s.normal : Eigen::Vector3d::Zero();
  };
  // Each query starts from the last answer found in the same cell of half an edge length: a
  // vertex moves less than that per relaxation sweep, so the hint is usually its own last
  // projection (a hash collision only gives a poorer hint, never another answer).
  CellHints hints;
  const double cell = 0.5 * reach;
  // The panel faces `facing` (its boundary's vector area: the loop runs counter-clockwise
  // seen from outside). A point whose closest body point faces the other way has crossed
  // the limb or torso it lies on: the interior of a half-sleeve starts on the chord plane
  // through the arm, where the far side of the arm can be nearest (a hole in the back of a
  // long sleeve at the elbow). Such a point goes to the body's first surface seen from the
  // panel's side instead: a ray from outside the body's box along −facing.
  const Eigen::Vector3d facing = loop_facing(side_points);
  const double outside = (body.box().max - body.box().min).norm();
  // Recent answers by query point, bit for bit: 28 % of the raglan's and the shorts' queries
  // repeat one (RecentAnswers). A point with equally near body triangles is not kept (which of
  // them the tree answers may depend on the hint).
  struct Answer {
    SurfacePoint nearest;  // the body's closest point (the hint it leaves)
    SurfacePoint chosen;   // what `closest` returns
  };
  size_t boundary_vertices = 0;
  for (const auto& side : side_points) boundary_vertices += static_cast<size_t>(side.rows());
  RecentAnswers<Answer> answers(std::clamp(std::bit_ceil(boundary_vertices * boundary_vertices / 4),
                                           kLeastAnswerSlots, kMostAnswerSlots));
  const auto closest = [&body, &hints, &answers, cell, facing,
                        outside](const Eigen::Vector3d& p) -> SurfacePoint {
    const Eigen::Vector3d q = (p / cell).array().floor();
    const std::int64_t key = (static_cast<std::int64_t>(q.x()) * 73856093) ^
                             (static_cast<std::int64_t>(q.y()) * 19349663) ^
                             (static_cast<std::int64_t>(q.z()) * 83492791);
    SurfacePoint& hint = hints[key];
    if (const Answer* known = answers.find(p)) {
      hint = known->nearest;
      return known->chosen;
    }
    hint = body.closest_point(p, hint);
    SurfacePoint chosen = hint;
    if (hint.normal.dot(facing) < kAgainstFacing) {
      if (const auto seen = body.first_hit(p + outside * facing, -facing);
          seen && seen->normal.dot(facing) > 0 &&
          (seen->position - p).norm() < kSeenReach * hint.distance)
        chosen = *seen;
    }
    if (!hint.tied) answers.store(p, Answer{hint, chosen});
    return chosen;
  };
  const SurfaceLift lift = [&closest, offset, reach](const Eigen::Vector3d& p) -> LiftedPoint {
    const SurfacePoint s = closest(p);
    const double signed_distance = (p - s.position).dot(s.normal);
    if (signed_distance < offset + reach) return {s.position + offset * s.normal, s.normal};
    return {p, Eigen::Vector3d::Zero()};
  };
  // The body as an obstacle only: a point inside the offset surface goes to its closest
  // point on it, any other point stays.
  const PushOut push_out = [&closest,
                            offset](const Eigen::Vector3d& p) -> std::optional<Eigen::Vector3d> {
    const SurfacePoint s = closest(p);
    if ((p - s.position).dot(s.normal) >= offset) return std::nullopt;
    return s.position + offset * s.normal;
  };
  // push_out along the spanned surface's normal `n` (a unit vector, or zero): a point inside
  // the offset surface goes where the ray along n leaves the body, when that surface faces along
  // n within kAlongReach times the nearest distance plus an edge; otherwise to its nearest point.
  const PushAlong push_along = [&closest, &body, offset, reach](
                                   const Eigen::Vector3d& p,
                                   const Eigen::Vector3d& n) -> std::optional<Eigen::Vector3d> {
    const SurfacePoint s = closest(p);
    if ((p - s.position).dot(s.normal) >= offset) return std::nullopt;
    if (n.norm() > 0.5)
      if (const auto hit = body.first_hit(p, n);
          hit && hit->normal.dot(n) > 0 && hit->distance <= kAlongReach * s.distance + reach)
        return Eigen::Vector3d(hit->position + offset * hit->normal);
    return Eigen::Vector3d(s.position + offset * s.normal);
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
    if (fit == PanelFit::kAuto) fit = panel.span_gap > kSpanGap ? PanelFit::kFree : PanelFit::kBody;
  }
  panel.fit = fit == PanelFit::kFree ? "free" : "body";
  // A body panel's interior starts where the layout's interpolation of its boundary puts
  // it. On a panel that wraps a limb (a raglan sleeve: half a tube from the top of the arm
  // to its underside) that is the plane through the limb's axis, the medial axis of the
  // closest-point map: nearest-point projection scatters the interior over both sides of
  // the arm (the back sleeve's interior landed on the front of the arm, leaving the back
  // bare, with folds and slivers in every plan). `place` starts such a panel along its own
  // normals instead: the interpolated surface's normals, which on the chord plane point to
  // the panel's side of the limb. A point inside the body whose nearest body point turns
  // more than 60° from that normal (kAlongCos) goes to where the ray along the normal leaves
  // the body, when that surface faces along the normal within kAlongReach times the nearest
  // distance plus an edge; every other point goes to its nearest point as before.
  const auto place = [&](std::vector<Eigen::Vector3d>& positions,
                         std::span<const std::array<int, 4>> quads, std::span<const char> fixed) {
    // The interpolated surface's own normals (each quad's diagonal cross product, summed at
    // its corners, then averaged over kAlongRings rings): the quads run counter-clockwise
    // seen from outside, so on a half-tube's chord plane they point to the panel's side.
    std::vector<Eigen::Vector3d> normals(positions.size(), Eigen::Vector3d::Zero());
    for (const auto& q : quads) {
      const Eigen::Vector3d n =
          (positions[static_cast<size_t>(q[2])] - positions[static_cast<size_t>(q[0])])
              .cross(positions[static_cast<size_t>(q[3])] - positions[static_cast<size_t>(q[1])]);
      for (const int v : q) normals[static_cast<size_t>(v)] += n;
    }
    for (int ring = 0; ring < kAlongRings; ++ring) {
      std::vector<Eigen::Vector3d> summed(positions.size(), Eigen::Vector3d::Zero());
      for (const auto& q : quads) {
        Eigen::Vector3d n = Eigen::Vector3d::Zero();
        for (const int v : q) n += normals[static_cast<size_t>(v)];
        for (const int v : q) summed[static_cast<size_t>(v)] += n;
      }
      normals = std::move(summed);
      for (Eigen::Vector3d& n : normals)
        if (n.norm() > 0) n.normalize();
    }
    for (size_t v = 0; v < positions.size(); ++v) {
      if (fixed[v]) continue;
      const Eigen::Vector3d p = positions[v];
      const SurfacePoint s = closest(p);
      const double signed_distance = (p - s.position).dot(s.normal);
      Eigen::Vector3d n = normals[v];
      std::optional<SurfacePoint> hit;
      if (n.norm() > 1e-3 && signed_distance < 0 && s.normal.dot(n) < kAlongCos * n.norm()) {
        n.normalize();
        hit = body.first_hit(p, n);
        if (hit && (hit->normal.dot(n) <= 0 || hit->distance > kAlongReach * s.distance + reach))
          hit.reset();
      }
      positions[v] = hit ? Eigen::Vector3d(hit->position + offset * hit->normal) : lift(p).position;
    }
  };
  if (fit == PanelFit::kBody)
    options.project = [&lift](const Eigen::Vector3d& p) { return lift(p).position; };
  else
    options.project = [&push_out](const Eigen::Vector3d& p) { return push_out(p).value_or(p); };
  const auto normal = [&body](const Eigen::Vector3d& p) -> Eigen::Vector3d {
    return body.closest_point(p).normal;
  };
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
  const auto finish = [&](meshing::FilledPatch patch) {
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
      // ... or the cloth between them (quad_samples, panel_surface.hpp).
      for (Eigen::Index f = 0; f < patch.mesh.face_count() && !touches; ++f)
        for (const Eigen::Vector3d& x : quad_samples(patch.mesh, f))
          touches = touches || push_out(x).has_value();
      if (touches) {
        const meshing::QuadMesh start = patch.mesh;
        const std::vector<double> weights = kSpanWeighted
                                                ? mean_weights(patch.mesh, fixed, kSpanHighValence)
                                                : std::vector<double>{};
        span_over_obstacle(patch.mesh, fixed, push_out, kSpanRounds, weights);
        // Weights move quads towards one size round the irregular vertices but can widen a ring
        // elsewhere past the gate's size limits (the capelet's back at 3 cm: three quads of 0.44
        // edge lengths round a vertex of valence 3 grow to 0.52, and one over the shoulder from
        // 1.87 to 2.09): then the uniform membrane is spanned too and kept when it has fewer.
        if (const int off_size = weights.empty() ? 0 : quads_off_size(patch.mesh, reach);
            off_size > 0) {
          meshing::QuadMesh uniform = start;
          span_over_obstacle(uniform, fixed, push_out);
          if (quads_off_size(uniform, reach) < off_size) patch.mesh = std::move(uniform);
        }
        patch.quality = meshing::measure_quality(patch.mesh, patch.topology.corner_vertices());
        // Folded or a sliver: where the membrane crosses a crease of the body (a one-piece
        // skirt's front over the crotch, its back over the seat), the nearest points gather
        // neighbouring vertices on the crease's floor, down to quads of no area that the
        // simulator refuses. Spanned again, pushed along the membrane's own normals instead
        // (parallel rays keep neighbours apart); the better by the same measures is kept. Only
        // then, so that every panel that came out clean the first way keeps its bits.
        if (patch.quality.inverted_quads > 0 || patch.quality.max_aspect_ratio >= kSliverAspect) {
          meshing::QuadMesh along = start;
          span_over_obstacle(along, fixed, push_along, true, kSpanRounds, weights);
          const meshing::QuadQuality quality =
              meshing::measure_quality(along, patch.topology.corner_vertices());
          if (rank(quality) < rank(patch.quality)) {
            patch.mesh = std::move(along);
            patch.quality = quality;
          }
        }
      } else {
        patch.quality = meshing::measure_quality(patch.mesh, patch.topology.corner_vertices());
      }
    }
    // Among the fill, its smoothing along the body and their unfoldings, the gate's other two
    // warnings on a quad's shape count too before the worst corner: a corner under the gate's
    // 10°, then quads off its size band (0.25-2 × the edge). The smoothing evens out the quads
    // that a layout fans where the region widens (the one-piece one-shoulder top's back: a
    // valence-6 vertex under the strap, 4 quads up to 2.29 × the edge in the fill, 2 after the
    // smoothing and none after the weighted one below, whose worst corners are poorer: scaled
    // Jacobian 0.35 against 0.46; ranked by that corner alone the fill was kept and warned). A
    // panel whose chosen candidate has no corner under 10° and no quad off size keeps it (it
    // stays first by this order too, and the weighted smoothing is not run).
    const auto gate_rank = [&](const meshing::QuadQuality& q, const meshing::QuadMesh& m) {
      const QualityLimits limits;
      return std::tuple(q.inverted_quads, q.max_aspect_ratio >= kSliverAspect,
                        q.min_angle_deg < limits.min_angle_deg, quads_off_size(m, reach),
                        -q.scaled_jacobian_min);
    };
    const auto consider = [&](meshing::QuadMesh&& mesh, meshing::FilledPatch& best) {
      const meshing::QuadQuality quality =
          meshing::measure_quality(mesh, patch.topology.corner_vertices());
      if (gate_rank(quality, mesh) < gate_rank(best.quality, best.mesh)) {
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
      // Quads still off size: the smoothing once more from the fill with the vertices of
      // valence 5 and more weighted too (SurfaceRelaxationOptions::weigh_high_valence, off by
      // default for the t-shirts' drapes), which keeps the ring round such a vertex the size of
      // the next ring where the uniform mean grows it. Another candidate, judged like the
      // others, so a panel without quads off size is not touched.
      if (quads_off_size(best.mesh, reach) > 0) {
        meshing::QuadMesh weighted = patch.mesh;
        relax_on_surface(
            weighted, fixed, lift,
            {kSurfaceSweeps, kSurfaceTolerance * reach, kSurfaceMaxStep * reach, true});
        const meshing::QuadQuality folds =
            meshing::measure_quality(weighted, patch.topology.corner_vertices());
        if (folds.inverted_quads > 0) consider(unfold(weighted), best);
        consider(std::move(weighted), best);
      }
    }
    patch.mesh = std::move(best.mesh);
    patch.quality = best.quality;
    return patch;
  };
  // A body panel whose every plan folds is finished (smoothed and unfolded along the body,
  // above) before the filler's last resorts (FillGeometryOptions::good_enough: a second search
  // and a second relaxation, each a full relaxation more along the body), because that usually
  // mends what they would: the raglan top's sleeves and the long-sleeved tee's back sleeve come
  // out clean either way, the last resorts being a third of their meshing time. Only when the
  // finished panel still folds or has a sliver does the filler go on to them, and the better of
  // the two finished panels is kept (the thorough one on a tie, which is what every panel got
  // before).
  const auto clean = [](const meshing::QuadQuality& q) {
    return q.inverted_quads == 0 && q.max_aspect_ratio < kSliverAspect;
  };
  const auto fill_on_body = [&](meshing::FillGeometryOptions o) {
    std::optional<meshing::FilledPatch> quick;  // the search's best, finished
    Eigen::MatrixX3d offered;                   // ... as the search left it
    o.good_enough = [&](const meshing::FilledPatch& searched) {
      offered = searched.mesh.vertices;
      quick = finish(searched);
      return clean(quick->quality);
    };
    meshing::FilledPatch filled = fill(o);
    if (!quick) return finish(std::move(filled));
    // The last resorts changed nothing (the panel was finished already) or did not come out
    // better once finished.
    if (clean(quick->quality) ||
        (filled.mesh.vertices.rows() == offered.rows() &&
         filled.mesh.faces.rows() == quick->mesh.faces.rows() &&
         filled.mesh.faces == quick->mesh.faces && filled.mesh.vertices == offered))
      return std::move(*quick);
    meshing::FilledPatch thorough = finish(std::move(filled));
    if (rank(quick->quality) < rank(thorough.quality)) return std::move(*quick);
    return thorough;
  };
  meshing::FilledPatch patch =
      fit == PanelFit::kBody ? fill_on_body(options) : finish(std::move(*spanned));
  // Interior vertices of a body panel whose own normal (the quads' diagonal cross products
  // summed) turns against the body's normal at their nearest point: the panel lies there on
  // the far side of a limb, wound the wrong way round it.
  const auto far_side = [&](const meshing::FilledPatch& filled) {
    std::vector<Eigen::Vector3d> normals(static_cast<size_t>(filled.mesh.vertex_count()),
                                         Eigen::Vector3d::Zero());
    std::vector<char> boundary(normals.size(), 0);
    for (const auto& side : filled.topology.side_vertices)
      for (const int v : side) boundary[static_cast<size_t>(v)] = 1;
    const auto& m = filled.mesh;
    for (Eigen::Index f = 0; f < m.face_count(); ++f) {
      const Eigen::Vector3d n =
          (m.vertices.row(m.faces(f, 2)) - m.vertices.row(m.faces(f, 0)))
              .transpose()
              .cross((m.vertices.row(m.faces(f, 3)) - m.vertices.row(m.faces(f, 1))).transpose());
      for (int k = 0; k < 4; ++k) normals[static_cast<size_t>(m.faces(f, k))] += n;
    }
    int count = 0;
    for (size_t v = 0; v < normals.size(); ++v)
      if (!boundary[v] &&
          closest(m.vertices.row(static_cast<Eigen::Index>(v)).transpose()).normal.dot(normals[v]) <
              0)
        ++count;
    return count;
  };
  // A body panel that still folds or has a sliver, with part of it on the far side of a
  // limb: filled again from the start along the panel's own normals (`place` above), and
  // the better of the two by the same measures kept. Only then: on the examples and the
  // design corpus the nearest-point start is as good or better wherever it comes out clean
  // (a t-shirt's back over the shoulder, whose interpolated surface faces back where the
  // body faces up), and a fold without a far side (the shorts' back at the crotch) is not
  // what the other start mends (all four plans filled again cost the shorts 3 times the
  // meshing time for one fold less).
  if (fit == PanelFit::kBody &&
      (patch.quality.inverted_quads > 0 || patch.quality.max_aspect_ratio >= kSliverAspect) &&
      far_side(patch) > 0) {
    meshing::FillGeometryOptions along = options;
    along.place = place;
    meshing::FilledPatch other = fill_on_body(along);
    if (rank(other.quality) < rank(patch.quality)) patch = std::move(other);
  }
  // A panel that runs out into a long thin arm which widens towards the body (a one-piece
  // halter's strap) keeps the arm as many quads wide as its end all the way to where it joins,
  // so its quads there grow past the gate's size limit and the body's next to them are squeezed
  // (folds, slivers). With such flaws and such an arm (meshing/arm_widening.hpp), the panel is
  // filled again cut across the arm where it joins, each part on its own (the arm gets a
  // valence-3/valence-5 pair that adds quads across it), finished as a whole like any fill, and
  // kept when it has no more folded quads, slivers or quads off size than the first fill and
  // fewer of one of them (docs/meshing.md, "Round 42: an arm that widens"). A panel without them
  // is not touched.
  const auto flaws = [&](const meshing::FilledPatch& filled) {
    return std::array<int, 3>{filled.quality.inverted_quads,
                              filled.quality.max_aspect_ratio >= kSliverAspect ? 1 : 0,
                              quads_off_size(filled.mesh, reach)};
  };
  // Keeps `other` when it has no more folded quads, slivers or quads off size than the panel's
  // fill and fewer of one of them.
  const auto keep_if_fewer_flaws = [&](meshing::FilledPatch&& other,
                                       const std::array<int, 3>& before) {
    const std::array<int, 3> after = flaws(other);
    bool no_worse = true;
    for (size_t k = 0; k < after.size(); ++k) no_worse = no_worse && after[k] <= before[k];
    if (no_worse && after != before) patch = std::move(other);
  };
  if (const std::array<int, 3> before = flaws(patch); before != std::array<int, 3>{})
    if (const std::optional<meshing::ArmCut> cut = meshing::find_arm_cut(side_points)) {
      const meshing::FillGeometryOptions part = fit == PanelFit::kBody ? options : free_options;
      try {
        meshing::FilledPatch widened = finish(meshing::fill_with_arm_cut(
            side_points, *cut,
            [&part](const std::vector<Eigen::MatrixX3d>& points) {
              return meshing::fill_region(points, part);
            },
            part));
        keep_if_fewer_flaws(std::move(widened), before);
      } catch (const meshing::FillError&) {
        // A part that cannot be filled: the panel keeps its fill.
      }
    }
  // Folds that every start, plan, smoothing and unfolding left: mended by local changes of the
  // quads at each fold (fold_repair.hpp), kept only when the gate's measures improve. A clean
  // panel is not touched.
  const auto repair = [&](meshing::FilledPatch& filled) {
    if (filled.quality.inverted_quads == 0) return;
    std::vector<char> fixed(static_cast<size_t>(filled.mesh.vertex_count()), 0);
    for (const auto& side : filled.topology.side_vertices)
      for (const int v : side) fixed[static_cast<size_t>(v)] = 1;
    const std::vector<int> corners = filled.topology.corner_vertices();
    const FoldRepairResult repaired = repair_folds(filled.mesh, fixed, corners, options.project);
    if (repaired.edge_turns + repaired.smoothings > 0) {
      filled.quality = meshing::measure_quality(filled.mesh, corners);
      // The layout's connectivity follows the turned edges; its distortion is the new one.
      filled.topology.mesh.faces = filled.mesh.faces;
      filled.topology.distortion = filled.quality.distortion;
      filled.topology.irregular_vertices = filled.quality.irregular_vertices;
    }
  };
  repair(patch);
  // A body panel that still has such flaws after the fold repair and whose boundary turns one
  // way about the loop's overall normal and the other about the body's (a strap over the shoulder,
  // a neckline cut into a front that wraps the chest): the layout put its single-quad corners and
  // its reflex vertices by the loop's normal, so a corner the body sees as convex may be avoided as
  // "reflex" and the region's narrowing taken up where the boundary does not turn. Filled again
  // with the reflex and flat positions judged about the body's normals (the same turns the layout
  // already ranks by), its folds mended as above, and kept by the same rule as the arm cut
  // (docs/meshing.md, "Round 44").
  // Only for a sliver or quads off size: a fold alone that the repair left is not what the
  // other flags mend (on the Collada shirt's back sleeve the refill without it came out inside
  // the body and turned back on itself, two new gate warnings the panel's measures do not see).
  if (fit == PanelFit::kBody)
    if (const std::array<int, 3> before = flaws(patch); before[1] + before[2] > 0) {
      meshing::FillGeometryOptions about_body = options;
      about_body.flags_about_surface = true;
      meshing::FilledPatch other = fill_on_body(about_body);
      repair(other);
      // Nor a corner under the gate's limit where the fill had none.
      const double sharp = QualityLimits{}.min_angle_deg;
      if (other.quality.min_angle_deg >= sharp || patch.quality.min_angle_deg < sharp)
        keep_if_fewer_flaws(std::move(other), before);
    }
  // Narrow creases (crease_wall.hpp), once the panel is filled: each vertex that lies on the
  // offset surface (or inside it) would go onto its own wall of a crease, at the offset that
  // fits. After the fill, not in its projection: the fill's choice among plans and smoothings at
  // a four-curve junction changes with any small move of the surface it projects on (the
  // jacket's back sleeve came out with slivers and quads 2 cm inside the arm). Not kept if it
  // folds a quad or makes a sliver; returned, not applied (CreaseMoves).
  if (crease != nullptr) {
    std::vector<char> fixed(static_cast<size_t>(patch.mesh.vertex_count()), 0);
    for (const auto& side : patch.topology.side_vertices)
      for (const int v : side) fixed[static_cast<size_t>(v)] = 1;
    const std::vector<SeamSide> seams = seam_sides(side_points, body, offset);
    meshing::QuadMesh moved = patch.mesh;
    std::vector<std::pair<int, Eigen::Vector3d>> moves;
    for (Eigen::Index v = 0; v < patch.mesh.vertex_count(); ++v) {
      if (fixed[static_cast<size_t>(v)]) continue;
      const Eigen::Vector3d p = patch.mesh.vertices.row(v).transpose();
      const SurfacePoint s = closest(p);
      if ((p - s.position).dot(s.normal) > offset + kOnOffsetSurface) continue;
      const CreaseWall w = crease_wall(body, seams, p, s, offset, reach);
      if (!w.moved) continue;
      moves.emplace_back(static_cast<int>(v), w.point.position + w.offset * w.point.normal);
      moved.vertices.row(v) = moves.back().second.transpose();
    }
    if (!moves.empty()) {
      const meshing::QuadQuality quality =
          meshing::measure_quality(moved, patch.topology.corner_vertices());
      if (quality.inverted_quads <= patch.quality.inverted_quads &&
          (quality.max_aspect_ratio < kSliverAspect ||
           patch.quality.max_aspect_ratio >= kSliverAspect))
        *crease = {std::move(moves), quality};
    }
  }
  return patch;
}

}  // namespace sd::garment
