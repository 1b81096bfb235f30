#include "sim/contact_response.hpp"

#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <tuple>
#include <utility>

#include "sim/collision_geometry.hpp"
#include "sim/parallel.hpp"

namespace sd::sim {

namespace {
// m: a start deeper than this moves its inside regions out as one piece (plan_start_repair with
// the cloth's triangles); shallower starts push each vertex alone. 2 cm is where `validate` used
// to say a start was not known to recover (garment/quality_gate.cpp).
constexpr double kRegionRepairDepth = 0.02;
constexpr double kNoImpulse = std::numeric_limits<double>::quiet_NaN();
// A contact of the last step is kept while its vertex is within (1 + kHoldMargin)·thickness:
// a vertex held at exactly `thickness` ends a step on the tangent plane, a hair farther from a
// curved body, and without this hysteresis it would drop out, fall back in and be pushed out
// again every other step (measured on a sheet draped on a sphere: ~25 of 60 contacts flickering
// each step, with a position correction each time, and the drape never came to rest).
constexpr double kHoldMargin = 0.25;
// m/s: the fastest a vertex starting inside the body is pushed out (a push of 1 mm per step of
// 1/60 s is 6 cm/s; the bound only binds on steps retried below 1.5 ms).
constexpr double kRepairMaxSpeed = 1.0;
// A contact is released when its constraint pulled the vertex towards the body with more than
// this fraction of the vertex's weight. At the line where a draped cloth leaves the body the
// contact force is about zero and changes sign from step to step; releasing at any pull made
// those vertices switch between held and free every other step, and the switching shook the
// whole (stiff) sheet in a period-2 oscillation that never came to rest.
constexpr double kReleaseFraction = 0.1;
// Rounds of re-projection for a vertex whose projected position is still inside (a concave
// spot where the pushed point lands inside another part of the body).
constexpr int kProjectionRounds = 3;
// A cloth triangle a body vertex pokes through is pushed until the vertex is this fraction of
// the thickness behind it: clear, but not so far that the triangle's own vertices (held at the
// thickness by their contacts) are pulled back through the vertex at the next step.
constexpr double kPiercingClearance = 0.5;
// Body vertices farther than this many thicknesses (at least kMinPiercingReach) through the
// cloth are not looked for: the broad phase grows every triangle's box by this reach.
constexpr double kPiercingReachThicknesses = 4.0;
constexpr double kMinPiercingReach = 0.01;  // m
// Heights above this fraction of the reach count only when the triangle's closest point lies
// inside the body (BodyCollider::find_piercings: a cloth triangle beyond a thin body part is
// not pierced by it). Below, heights count as they are, so only a body part thinner than
// about this (6 mm at the default thickness) could be taken for a tip through the cloth. Not
// the thickness: when the cloth folds over a tip at one of its vertices, that vertex is held
// outside by its own contact, and a tip sliding out beside it (measured on the cone test:
// 3.3 mm, then 8.6 mm the next step) has that vertex as its closest point, outside the body.
constexpr double kPiercingUncheckedFraction = 0.5;
// A body vertex with a spring last step keeps it while the triangle's point over the vertex would
// end the step within the clearance plus this many thicknesses in front of it (the same
// hysteresis as kHoldMargin for contacts: without it a triangle resting on a tip at the
// clearance drops out as soon as it ends a hair farther, falls back and is pushed again).
constexpr double kPiercingHoldMargin = 0.25;
// Held springs per chunk when a renumbered cloth's triangles are searched for them (each tests
// every triangle's box: about 5 µs on a 4,000-triangle garment).
constexpr int kHeldSpringGrain = 16;
// With ContactSettings::spring_band a held spring is kept while its point is within this many
// thicknesses past the clearance in front of the body vertex (a real separation; otherwise
// kPiercingHoldMargin, a 0.75 mm band narrower than the cycles it met: on the flat capelet's
// neckline a spring pushed its point out past it, was dropped, the cloth fell back through and
// was caught again every 9 steps, 39 <-> 40 springs, a 5 mm cycle), and until its force turns
// adhesive. Off by default: measured, it fails two smooth-body tests (docs/collision.md).
constexpr double kPiercingReleaseBand = 1.0;
// A spring's stiffness and damping are those of its point's effective
// mass m (1/Σ w_k²/m_k over the free corners) oscillating at this angular frequency, critically
// damped: k = m ω², c = 2 m ω. Resolution independent, and at any step size a physical
// oscillator rather than a jump: a 1 cm gap closes at most at about ω·1 cm/e = 1.5 m/s, however
// small step control makes the step (a constraint's correction Δx became Δx/h). Measured on the
// examples (docs/collision.md): at 120 rad/s springs too soft for a waistband pressed on the
// hips left 5 body vertices 1.7 mm through the A-line skirt; 400 and 1,000 rad/s left none, and
// 400 the least motion at the end.
constexpr double kSpringFrequency = 400.0;  // rad/s
// The force a spring carries to the next step (and raises in a re-solve) is capped at this many
// times the whole cloth's weight: a tip can hold up a hanging sheet (or a waistband pressed on a
// hip), but a squeeze that no motion of the cloth can clear (two body parts closing on it)
// cannot build up an unbounded push. Measured: a cap of 100 times the point's own weight
// (resolution dependent: a point of a finer mesh weighs less) left a body vertex 1.03 mm
// through the t-shirt adapted to level 2.
constexpr double kMaxSpringLoadClothWeights = 2.0;
// ContactSettings::pinch_budget: a body surface facing a contact's (normals more than
// kPinchFacingCos apart) closer than this many thicknesses along the contact's normal makes a
// pinch, and each side's contact keeps a third of the gap g: the bands [0, g/3] of the two
// sides never overlap, and the middle third is free (a vertex there is held by neither, and two
// layers of cloth have room). Measured on the arms-lowering t-shirt's armpits, where the gap
// is 5.8-6.0 mm: a vertex of the back, released and caught again every other step, moved at
// 0.11 m/s to 6 s; with the budget it rests at 3.2 s (self-collision and the body-vertex check
// off). Probing 3 thicknesses out also caught the rims of the Collada human's seat cleft under
// the tee dress and kept it from resting; at 2.5 the armpits are still caught.
constexpr double kPinchGapThicknesses = 2.5;
constexpr double kPinchFacingCos = -0.5;
// A pinch holds the cloth only where the gap crosses it: the segment between the two facing
// surfaces within this cosine (60°) of the cloth's normal. Beside it (a cleft the cloth bridges,
// its rims under the cloth) the cloth is not squeezed and keeps the full thickness.
constexpr double kPinchAcrossCos = 0.5;

class Stopwatch {
 public:
  explicit Stopwatch(double& total) : total_(total), start_(std::chrono::steady_clock::now()) {}
  ~Stopwatch() {
    total_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  Stopwatch(const Stopwatch&) = delete;
  Stopwatch& operator=(const Stopwatch&) = delete;

 private:
  double& total_;
  std::chrono::steady_clock::time_point start_;
};

// A piercing's height over its triangle at the end of the step (the body already at its end
// pose): if the triangle moved along n with the body vertex, and if it kept its start
// velocity v0 (3n), β the step's position factor.
struct EndHeights {
  double with_body = 0.0;
  double coasting = 0.0;
};

EndHeights end_heights(const BodyPiercing& p, const std::array<int, 3>& triangle,
                       const Eigen::VectorXd& v0, double beta) {
  double point_velocity = 0.0;
  for (int k = 0; k < 3; ++k)
    point_velocity += p.barycentric[k] * v0.segment<3>(3 * triangle[k]).dot(p.normal);
  return {p.height - beta * p.body_velocity.dot(p.normal), p.height - beta * point_velocity};
}

void require(bool ok, const char* message) {
  if (!ok) throw InvalidContactSettingsError(message);
}

}  // namespace

void ContactSettings::validate() const {
  const auto finite_at_least = [](double value, double low) {
    return std::isfinite(value) && value >= low;
  };
  require(std::isfinite(thickness) && thickness > 0.0,
          "the contact thickness must be a positive distance in metres");
  require(std::isfinite(penetration_tolerance) && penetration_tolerance > 0.0,
          "the penetration tolerance must be a positive distance in metres");
  require(!static_friction || finite_at_least(*static_friction, 0.0),
          "the static friction coefficient must be zero or more");
  require(!kinetic_friction || finite_at_least(*kinetic_friction, 0.0),
          "the kinetic friction coefficient must be zero or more");
  require(!static_friction || !kinetic_friction || *static_friction >= *kinetic_friction,
          "the static friction coefficient must not be smaller than the kinetic one");
  require(max_resolves >= 0, "the number of contact re-solves must be zero or more");
  require(repair_steps >= 1, "the start repair needs at least one step");
  require(finite_at_least(search_margin, 0.0), "the contact search margin must be zero or more");
  require(std::isfinite(max_substep_motion) && max_substep_motion > 0.0,
          "the swept check's sub-step motion must be positive");
  require(std::isfinite(stick_speed) && stick_speed > 0.0,
          "the friction stick speed must be positive");
  require(std::isfinite(pinch_floor) && pinch_floor > 0.0 && pinch_floor <= 1.0,
          "the least share of a pinch must be more than zero and at most one thickness");
}

ContactResponse::ContactResponse(const meshing::TriMesh& body, ContactSettings settings)
    : settings_(std::move(settings)), collider_(body) {
  settings_.validate();
}

ContactResponse::ContactResponse(PoseSequence motion, double start_time, ContactSettings settings)
    : settings_(std::move(settings)), collider_(motion.mesh_at(start_time)) {
  settings_.validate();
  collider_.set_pose(motion.vertices_at(start_time), motion.velocity_at(start_time));
  motion_ = std::move(motion);
  body_time_ = start_time;
}

ContactQuery ContactResponse::query() const {
  ContactQuery q;
  q.thickness = settings_.thickness;
  q.search_margin = settings_.search_margin;
  q.max_substep_motion = settings_.max_substep_motion;
  return q;
}

void ContactResponse::set_cloth_triangles(const ClothModel& model) {
  std::vector<std::array<int, 3>> triangles;
  triangles.reserve(model.triangles.size());
  for (const TriangleElement& t : model.triangles) triangles.push_back(t.vertices);
  cloth_ = ClothTriangles(std::move(triangles));
  piercings_.clear();
}

double ContactResponse::piercing_reach() const {
  return std::max(kPiercingReachThicknesses * settings_.thickness, kMinPiercingReach);
}

std::vector<BodyPiercing> ContactResponse::find_piercings(const Eigen::VectorXd& x1,
                                                          double min_height,
                                                          bool every_triangle) const {
  if (!settings_.check_body_vertices) return {};
  return piercings_of(x1, min_height, every_triangle);
}

std::vector<BodyPiercing> ContactResponse::piercings_of(const Eigen::VectorXd& x, double min_height,
                                                        bool every_triangle) const {
  if (cloth_.triangles.empty()) return {};
  const double reach = piercing_reach();
  return collider_.find_piercings(x, cloth_, min_height, reach, kPiercingUncheckedFraction * reach,
                                  nullptr, every_triangle);
}

void ContactResponse::reset_cloth(const Eigen::VectorXd& x, const Eigen::VectorXd& mass,
                                  double gravity) {
  stats_ = ContactStepStats{};
  Stopwatch watch(stats_.collision_seconds);
  const int n = static_cast<int>(x.size() / 3);
  release_force_ = (kReleaseFraction * gravity) * mass;
  mass_ = mass;
  gravity_ = gravity;
  cache_.reset();
  last_normal_force_.assign(n, kNoImpulse);
  active_index_.assign(n, -1);
  active_.clear();
  too_deep_.clear();
  end_contacts_.clear();
  accepted_contacts_.clear();
  // A body vertex's spring force is its load and carries over to a new cloth; the pairs it was
  // held by were the old cloth's triangles.
  if (last_piercing_force_.size() != static_cast<std::size_t>(collider_.vertex_count()))
    last_piercing_force_.assign(static_cast<std::size_t>(collider_.vertex_count()), kNoImpulse);
  spring_body_vertex_.clear();
  spring_past_clearance_.clear();
  spring_ends_.clear();
  // A renumbered cloth (adaptive detail's splits and merges): the held pairs named the old
  // triangles. Each follows its point on the cloth to the new triangles that hold it (a split's
  // children hold it exactly, a merged parent within the merge error), and
  // spring_start_piercings keeps or drops it by its height as it does any held pair. Without
  // this a pair in front of a cloth edge, which find_piercings does not report, lost its
  // spring at every split or merge, and the cloth fell onto the body vertex: a loose strapless
  // top resting on the hip's vertices lost 11 of its 18 springs at each late split, dropped
  // 2 mm and moved at up to 27 cm/s (docs/garment.md, "Seventh round").
  std::vector<SpringEnd> followed;
  const double follow = kPiercingHoldMargin * settings_.thickness;
  // A triangle whose bounding box lies farther than `follow` from the point cannot hold it (the
  // closest point is inside the box), so the exact test runs only on the few triangles near
  // it. The box test errs to the safe side by a relative 1e-6, far above rounding: the same
  // triangles pass as when every triangle was tested (the held springs × all triangles had
  // been 3 % of an adaptive garment drape's CPU).
  std::vector<Eigen::AlignedBox3d> boxes;
  if (!held_springs_.empty()) {
    boxes.resize(cloth_.triangles.size());
    for (std::size_t t = 0; t < cloth_.triangles.size(); ++t)
      for (int k : cloth_.triangles[t]) boxes[t].extend(x.segment<3>(3 * k));
  }
  const double reach = follow * (1.0 + 1e-6);
  // Each held spring on its own, on the threads; joined in the held springs' order.
  const int held_count = static_cast<int>(held_springs_.size());
  std::vector<std::vector<SpringEnd>> found(
      static_cast<std::size_t>(chunk_count(held_count, kHeldSpringGrain)));
  parallel_chunks(held_count, kHeldSpringGrain, [&](int chunk, int first, int last) {
    for (int h = first; h < last; ++h) {
      const SpringEnd& held = held_springs_[static_cast<std::size_t>(h)];
      for (std::size_t t = 0; t < cloth_.triangles.size(); ++t) {
        if (boxes[t].squaredExteriorDistance(held.point) > reach * reach) continue;
        const std::array<int, 3>& c = cloth_.triangles[t];
        const TriangleClosestPoint q = closest_point_on_triangle(
            held.point, x.segment<3>(3 * c[0]), x.segment<3>(3 * c[1]), x.segment<3>(3 * c[2]));
        if (q.squared_distance <= follow * follow) {
          SpringEnd next = held;
          next.triangle = static_cast<int>(t);
          found[static_cast<std::size_t>(chunk)].push_back(next);
        }
      }
    }
  });
  for (const std::vector<SpringEnd>& chunk : found)
    followed.insert(followed.end(), chunk.begin(), chunk.end());
  held_springs_ = std::move(followed);
  // Plan the push-out on the first cloth, or again (over the remaining steps) when the cloth
  // is renumbered in the middle of one.
  if (!repair_planned_ || repairing()) {
    const int steps = repair_planned_ ? repair_.steps - repair_step_ : settings_.repair_steps;
    StartRepairOptions options;
    options.thickness = settings_.thickness;
    options.steps = std::max(1, steps);
    // Each vertex pushed alone to its nearest skin (the repair every example and design has
    // rested with) unless the cloth starts deeper than kRegionRepairDepth: then the regions inside
    // move out as one piece with the cloth round them (cloth drawn centimetres into the legs,
    // which the vertex-by-vertex push left caught round a leg). The region move changed the
    // Collada tee's shaped drape, whose two vertices start 1.2 mm inside, so that it no longer
    // came to rest: kept for the deep starts it was built for.
    repair_ = plan_start_repair(collider_, x, options);
    if (repair_.max_depth > kRegionRepairDepth)
      repair_ = plan_start_repair(collider_, x, options, &cloth_);
    repair_step_ = 0;
    if (!repair_planned_ && !repair_.empty() && repair_.regions == 0)
      spdlog::warn(
          "sim: {} cloth vertices start inside the body (deepest {:.1f} mm); pushing them out "
          "over {} steps",
          repair_.pushed.size(), 1e3 * repair_.max_depth, repair_.steps);
    else if (!repair_planned_ && !repair_.empty())
      spdlog::warn(
          "sim: {} cloth vertices start inside the body (deepest {:.1f} mm); pushing them out "
          "over {} steps ({} regions moved out as one, {} vertices with the cloth round them, "
          "{:.1f} mm at most)",
          repair_.pushed.size(), 1e3 * repair_.max_depth, repair_.steps, repair_.regions,
          repair_.moved.size(), 1e3 * repair_.max_push);
    repair_planned_ = true;
  }
  in_repair_.assign(n, 0);
  for (const RepairMove& m : repair_.moved) in_repair_[m.vertex] = 1;
}

void ContactResponse::restore_normal_forces(std::vector<double> forces) {
  if (forces.size() != last_normal_force_.size())
    throw std::invalid_argument("restore_normal_forces needs one force per cloth vertex");
  last_normal_force_ = std::move(forces);
}

void ContactResponse::move_body_to(double t, double h) {
  stats_ = ContactStepStats{};
  if (!motion_) return;
  Stopwatch watch(stats_.collision_seconds);
  // A retried step starts again from t: put the body back first, so that the step's sweep
  // starts where the cloth's does.
  if (body_time_ != t) collider_.set_pose(motion_->vertices_at(t), motion_->velocity_at(t));
  move_body(collider_, *motion_, t, t + h);
  body_time_ = t + h;
}

Eigen::Vector3d ContactResponse::cloth_vertex_normal(int v, const Eigen::VectorXd& x) const {
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  if (v < 0 || static_cast<std::size_t>(v) + 1 >= cloth_.vertex_offsets.size()) return normal;
  for (int k = cloth_.vertex_offsets[v]; k < cloth_.vertex_offsets[v + 1]; ++k) {
    const std::array<int, 3>& t = cloth_.triangles[cloth_.vertex_triangles[k]];
    const Eigen::Vector3d a = x.segment<3>(3 * t[0]);
    normal += (x.segment<3>(3 * t[1]) - a).cross(x.segment<3>(3 * t[2]) - a);
  }
  return normal;
}

std::optional<double> ContactResponse::pinch_gap(const Eigen::Vector3d& point,
                                                 const Eigen::Vector3d& normal,
                                                 const Eigen::Vector3d& cloth_normal) const {
  // The other side of a pinch: the body's closest point to the point kPinchGapThicknesses
  // thicknesses out along the normal. Its own surface (flat) is exactly that far; a facing
  // surface nearer (or the point inside the facing part, a negative distance) gives the gap
  // along the normal, g = reach + distance (exact for parallel surfaces, smaller for tilted
  // ones).
  const double reach = kPinchGapThicknesses * settings_.thickness;
  const std::optional<BodyProximity> other = collider_.closest_point(point + reach * normal, reach);
  if (!other || other->normal.dot(normal) > kPinchFacingCos) return std::nullopt;
  // Inside the gap, or bridging its opening? Cloth inside a gap lies between the two surfaces:
  // the segment from one to the other crosses the cloth, along its normal (the armpit's layer
  // between arm and torso). Cloth over a cleft's opening has both surfaces on its body side and
  // the segment runs along the cloth, beside it (the back of a skirt over the seat's cleft,
  // whose rims hold it). Such cloth is not squeezed: its contacts keep the full thickness, as
  // everywhere else (measured: budgeting them started a new cycle under the shaped tee dress).
  const Eigen::Vector3d across = other->point - point;
  const double scale = across.norm() * cloth_normal.norm();
  if (!(scale > 0.0) || std::abs(across.dot(cloth_normal)) < kPinchAcrossCos * scale)
    return std::nullopt;
  return reach + other->distance;
}

double ContactResponse::contact_thickness(const BodyContact& contact,
                                          const Eigen::VectorXd& x) const {
  const double thickness = settings_.thickness;
  if (!settings_.pinch_budget) return thickness;
  const std::optional<double> gap =
      pinch_gap(contact.point, contact.normal, cloth_vertex_normal(contact.vertex, x));
  if (!gap) return thickness;
  return std::clamp(*gap / 3.0, settings_.pinch_floor * thickness, thickness);
}

double ContactResponse::spring_clearance(const BodyPiercing& p, const Eigen::VectorXd& x) const {
  const double clearance = kPiercingClearance * settings_.thickness;
  if (!settings_.pinch_budget) return clearance;
  // The body vertex, from the triangle's point under it and its height along the normal.
  const std::array<int, 3>& t = cloth_.triangles[p.cloth_triangle];
  Eigen::Vector3d vertex = p.height * p.normal;
  for (int k = 0; k < 3; ++k) vertex += p.barycentric[k] * x.segment<3>(3 * t[k]);
  // The same budget as the contacts: a third of the gap to a facing body part across the
  // cloth, so that the springs of the two sides do not ask for the same cloth twice.
  const std::optional<double> gap = pinch_gap(vertex, p.normal, p.normal);
  if (!gap) return clearance;
  return std::clamp(*gap / 3.0, std::min(settings_.pinch_floor * settings_.thickness, clearance),
                    clearance);
}

int ContactResponse::add_contact(const BodyContact& contact, double thickness,
                                 const Eigen::VectorXd& x_hat, double beta,
                                 ConstraintFilter& filter, Eigen::VectorXd& y, bool allow_release) {
  const int i = contact.vertex;
  const Eigen::Vector3d& n = contact.normal;
  const double body_normal_velocity = contact.body_velocity.dot(n);
  // Distance above `thickness` the vertex would end at if it moved with the body along n:
  // x1 = x̂ + y + β v1 against the surface at its end-of-step pose.
  const Eigen::Vector3d start = x_hat.segment<3>(3 * i) + y.segment<3>(3 * i);
  const double gap = (start - contact.point).dot(n) + beta * body_normal_velocity - thickness;
  // Too close: move the start out (position correction, no velocity). Farther (a vertex that
  // ended too deep after an unconstrained solve): a normal velocity that lands it at thickness.
  if (gap < 0.0) y.segment<3>(3 * i) -= gap * n;
  const double normal_velocity = body_normal_velocity - std::max(gap, 0.0) / beta;
  // Its constraint pulled the cloth towards the body last step: let it leave.
  const bool released = allow_release && last_normal_force_[i] < -release_force_[i];
  if (!released) filter.constrain_direction(i, n, normal_velocity);
  ActiveContact active{contact, normal_velocity, released};
  if (active_index_[i] >= 0) {
    // Its friction is already in the solve.
    const ActiveContact& old = active_[active_index_[i]];
    active.stuck = old.stuck;
    active.friction_in_solve = old.friction_in_solve;
    active.slide_direction = old.slide_direction;
    active_[active_index_[i]] = active;
  } else {
    active_index_[i] = static_cast<int>(active_.size());
    active_.push_back(active);
  }
  return active_index_[i];
}

void ContactResponse::constrain_start(const Eigen::VectorXd& x_hat, const Eigen::VectorXd& v0,
                                      double beta, ConstraintFilter& filter, Eigen::VectorXd& y,
                                      StepForces& extra) {
  Stopwatch watch(stats_.collision_seconds);
  const int n = static_cast<int>(x_hat.size() / 3);
  y.setZero(3 * n);
  extra.clear();
  std::vector<VertexDamping>& friction = extra.drags;
  beta_ = beta;
  for (const ActiveContact& a : active_) active_index_[a.contact.vertex] = -1;
  active_.clear();
  too_deep_.clear();
  end_contacts_.clear();

  // Vertices being pushed out of an intersecting start (and the cloth round them) move along
  // their push to this step's goal; ordinary contacts leave them alone until the repair is over.
  const bool repair = repairing();
  if (repair) {
    for (const RepairMove& m : repair_.moved) {
      const int i = m.vertex;
      BodyContact c;  // the push as a constraint along its direction
      c.vertex = i;
      c.normal = m.direction;
      c.point = repair_.target.segment<3>(3 * i);
      if (filter.is_pinned(i)) continue;
      const Eigen::Vector3d goal = repair_.goal(i, repair_step_ + 1);
      // At most kRepairMaxSpeed: the push is planned per step, so a step retried shorter and
      // shorter asked for the same millimetres in less time (1.46 mm in the minimum step of
      // 16 µs was 90 m/s, past the speed limit, and the drape failed at the wrist where the
      // cause was a stretched elbow). A slower push catches up in the next steps (the goal is
      // absolute), and after the repair the ordinary contact finishes it.
      const double normal_velocity = std::clamp(
          (goal - x_hat.segment<3>(3 * i)).dot(c.normal) / beta, -kRepairMaxSpeed, kRepairMaxSpeed);
      filter.constrain_direction(i, c.normal, normal_velocity);
      active_index_[i] = static_cast<int>(active_.size());
      ActiveContact pushed{c, normal_velocity};
      pushed.repair = true;
      active_.push_back(pushed);
      ++stats_.repairing;
    }
  }
  ContactQuery hold = query();
  hold.thickness *= 1.0 + kHoldMargin;
  for (const BodyContact& c : collider_.find_contacts(x_hat, hold, &cache_)) {
    if (filter.is_pinned(c.vertex) || (repair && in_repair_[c.vertex])) continue;
    // Farther than thickness: only a contact of the last step is held (and pulled back to the
    // thickness; if that pulls, it is released next step).
    // (A vertex placed at exactly the thickness counts as a contact despite rounding.)
    const double thickness = contact_thickness(c, x_hat);
    if (c.distance >= thickness * (1.0 + 1e-9) && std::isnan(last_normal_force_[c.vertex]))
      continue;
    // A pinched contact's band is its own (the query's covers the full thickness).
    if (thickness < settings_.thickness && c.distance >= thickness * (1.0 + kHoldMargin)) continue;
    ActiveContact& a = active_[add_contact(c, thickness, x_hat, beta, filter, y, true)];
    // Friction inside the solve for a contact pressed last step (λ > 0), relative to the body:
    //  * slower than ε = stick_speed at the start: a drag C = μ_s λ / ε on the tangential
    //    velocity; it holds the vertex (creeping at most at ε) while the pull stays below
    //    μ_s λ, and lets it go beyond;
    //  * sliding along t̂: Coulomb's force −μ_k λ t̂, linearised at the start velocity: constant
    //    along t̂, a drag μ_k λ / |v_t0| across it (the direction turns with the velocity).
    // Implicit, so the cloth around it responds, and the same for PCG and CHOLMOD.
    const double lambda = last_normal_force_[c.vertex];
    if (a.released || !(lambda > 0.0)) continue;
    const Eigen::Vector3d& normal = c.normal;
    const Eigen::Matrix3d tangent_projector =
        Eigen::Matrix3d::Identity() - normal * normal.transpose();
    const Eigen::Vector3d relative =
        tangent_projector * (v0.segment<3>(3 * c.vertex) - c.body_velocity);
    const double speed = relative.norm();
    VertexDamping term{c.vertex, Eigen::Matrix3d::Zero(), c.body_velocity, Eigen::Vector3d::Zero()};
    if (speed < settings_.stick_speed) {
      term.coefficient = (static_friction() * lambda / settings_.stick_speed) * tangent_projector;
      a.stuck = true;
    } else {
      a.slide_direction = relative / speed;
      term.coefficient = (kinetic_friction() * lambda / speed) *
                         (tangent_projector - a.slide_direction * a.slide_direction.transpose());
      term.force = -kinetic_friction() * lambda * a.slide_direction;
    }
    a.friction_in_solve = true;
    friction.push_back(term);
  }
  // After the contacts: the springs start from the corrected start x̂ + y.
  spring_start_piercings(x_hat + y, v0, beta, filter, extra);
}

double ContactResponse::point_mass(const BodyPiercing& p) const {
  const std::array<int, 3>& t = cloth_.triangles[p.cloth_triangle];
  double mass = 0.0;
  for (int k = 0; k < 3; ++k) mass += p.barycentric[k] * mass_[t[k]];
  return mass;
}

PointSpring ContactResponse::piercing_spring(const BodyPiercing& p, const Eigen::VectorXd& x,
                                             const std::vector<unsigned char>& pinned,
                                             double preload, double clearance) const {
  const std::array<int, 3>& t = cloth_.triangles[p.cloth_triangle];
  PointSpring spring;
  spring.triangle = p.cloth_triangle;
  spring.weights = p.barycentric;
  spring.normal = p.normal;
  double inverse_mass = 0.0;
  for (int k = 0; k < 3; ++k)
    if (pinned.empty() || pinned[t[k]] == 0)
      inverse_mass += p.barycentric[k] * p.barycentric[k] / mass_[t[k]];
  // The body vertex is the height above the point; the point must end the clearance in front of
  // it.
  // With the band a point already farther than that keeps its distance: the spring
  // starts the step pushing (its preload) or not at all, never pulling the cloth back onto the
  // vertex (which, released at the band's edge, fell back through and was caught again).
  const double push = p.height + clearance;
  spring.target = settings_.spring_band ? along_spring_normal(spring, t, x) + std::max(push, 0.0)
                                        : along_spring_normal(spring, t, x) + p.height + clearance;
  spring.reference_velocity = p.body_velocity;
  if (!(inverse_mass > 0.0)) return spring;  // all corners pinned: nothing can move
  const double mass = 1.0 / inverse_mass;
  spring.stiffness = mass * kSpringFrequency * kSpringFrequency;
  spring.damping = 2.0 * mass * kSpringFrequency;
  spring.preload = std::min(preload, max_spring_preload());
  return spring;
}

double ContactResponse::target_past_clearance(const BodyPiercing& p, double clearance) const {
  return settings_.spring_band ? std::max(-(p.height + clearance), 0.0) : 0.0;
}

double ContactResponse::max_spring_preload() const {
  return kMaxSpringLoadClothWeights * gravity_ * mass_.sum();
}

void ContactResponse::spring_start_piercings(const Eigen::VectorXd& start,
                                             const Eigen::VectorXd& v0, double beta,
                                             const ConstraintFilter& filter, StepForces& extra) {
  spring_body_vertex_.clear();
  spring_past_clearance_.clear();
  if (!settings_.check_body_vertices || cloth_.triangles.empty() || repairing()) return;
  const int n = static_cast<int>(start.size() / 3);
  const double clearance = kPiercingClearance * settings_.thickness;
  const double margin =
      (settings_.spring_band ? kPiercingReleaseBand : kPiercingHoldMargin) * settings_.thickness;
  const double hold = clearance + margin;
  pinned_.assign(static_cast<std::size_t>(n), 0);
  for (int i = 0; i < n; ++i) pinned_[i] = filter.is_pinned(i);
  // Every triangle near a body vertex, not only the highest: a vertex under a cloth edge is
  // under both triangles, and a spring on one let the other end the step through it (measured:
  // a re-solve in 106 of the t-shirt's 120 steps).
  std::vector<BodyPiercing> candidates = find_piercings(start, -piercing_reach(), true);
  // The pairs that had springs last step, whether or not the search reports them now (in front
  // of the cloth, find_piercings keeps only a vertex over a triangle's face; one in front of a
  // cloth edge that the last step pushed back came through again every step, measured: a
  // re-solve in 114 of the t-shirt's 120 steps).
  std::sort(candidates.begin(), candidates.end(), [](const BodyPiercing& a, const BodyPiercing& b) {
    return std::tie(a.body_vertex, a.cloth_triangle) < std::tie(b.body_vertex, b.cloth_triangle);
  });
  for (const SpringEnd& held : held_springs_) {
    const int body_vertex = held.body_vertex, triangle = held.triangle;
    const auto found = std::lower_bound(
        candidates.begin(), candidates.end(), std::make_pair(body_vertex, triangle),
        [](const BodyPiercing& a, const std::pair<int, int>& key) {
          return std::tie(a.body_vertex, a.cloth_triangle) < std::tie(key.first, key.second);
        });
    if (found != candidates.end() && found->body_vertex == body_vertex &&
        found->cloth_triangle == triangle)
      continue;
    if (const std::optional<BodyPiercing> p = collider_.piercing_of_pair(
            start, cloth_.triangles[static_cast<std::size_t>(triangle)], triangle, body_vertex))
      candidates.insert(found, *p);
  }
  std::vector<BodyPiercing> springs;
  std::vector<double> clearances;  // per spring, m
  for (const BodyPiercing& p : candidates) {
    const auto [with_body, coasting] = end_heights(p, cloth_.triangles[p.cloth_triangle], v0, beta);
    const double carried = last_piercing_force_[p.body_vertex];
    bool held = !std::isnan(carried);
    // With the band, released by the sign of its force, as a contact is: it ended pulling the
    // point onto the vertex by more than kReleaseFraction of the point's weight. It is caught
    // again only within the clearance.
    if (held && settings_.spring_band && carried < -kReleaseFraction * gravity_ * point_mass(p))
      held = false;
    // A spring only where it would push: the point ends within the clearance of the body vertex
    // (or through), or the vertex had a spring last step and the cloth has not left its reach
    // (the same hysteresis as contacts: dropping a spring as soon as it ended a hair beyond the
    // clearance let the cloth fall back through the next step, and a sheet on a sphere
    // re-solved every step).
    if (held ? with_body <= -hold : std::max(with_body, coasting) <= -clearance) continue;
    // Inside a pinch (pinch_budget) the clearance is the vertex's share of the gap, held like
    // a pinched contact up to (1 + kHoldMargin) times it: the two sides' bands stay apart.
    const double own = spring_clearance(p, start);
    if (own < clearance &&
        (held ? with_body <= -(1.0 + kHoldMargin) * own : std::max(with_body, coasting) <= -own))
      continue;
    springs.push_back(p);
    clearances.push_back(own);
  }
  // The load a body vertex carried last step is shared by its springs (sorted by body vertex),
  // and so are the stiffness and damping: a vertex under a cloth edge pushes no harder than one
  // under a face (with full springs on both triangles the pair overshot past the hold distance,
  // was dropped and fell back, and the sheet on the sphere never settled).
  for (std::size_t first = 0, last = 0; first < springs.size(); first = last) {
    while (last < springs.size() && springs[last].body_vertex == springs[first].body_vertex) ++last;
    const double force = last_piercing_force_[springs[first].body_vertex];
    const double share = std::isnan(force) ? 0.0 : std::max(force, 0.0) / (last - first);
    for (std::size_t k = first; k < last; ++k) {
      spring_body_vertex_.push_back(springs[k].body_vertex);
      spring_past_clearance_.push_back(target_past_clearance(springs[k], clearances[k]));
      PointSpring spring = piercing_spring(springs[k], start, pinned_, share, clearances[k]);
      spring.stiffness /= static_cast<double>(last - first);
      spring.damping /= static_cast<double>(last - first);
      extra.springs.push_back(spring);
    }
  }
  stats_.piercings_held = static_cast<int>(extra.springs.size());
}

int ContactResponse::spring_end_piercings(const Eigen::VectorXd& x1, StepForces& extra) {
  int changed = 0;
  const std::size_t springs = extra.springs.size();
  for (const BodyPiercing& p : piercings_) {
    // The body vertex's springs: the load they end with at x1, and the one on p's triangle.
    double carried = 0.0;
    std::size_t match = springs;
    for (std::size_t s = 0; s < springs; ++s) {
      if (spring_body_vertex_[s] != p.body_vertex) continue;
      const PointSpring& spring = extra.springs[s];
      const double along = along_spring_normal(spring, cloth_.triangles[spring.triangle], x1);
      carried += std::max(0.0, spring.preload + spring.stiffness * (spring.target - along));
      if (spring.triangle == p.cloth_triangle) match = s;
    }
    if (match < springs) {
      // Still through its spring's triangle: carry what the vertex's springs ended pushing with
      // as this one's preload (an augmented-Lagrangian update), so the next solve pushes harder
      // where the spring alone is too soft.
      PointSpring& spring = extra.springs[match];
      const double preload = std::min(carried, max_spring_preload());
      if (preload <= spring.preload) continue;
      spring.preload = preload;
    } else {
      // New, or through another triangle (the cloth slid over the vertex): a spring for that
      // triangle, carrying the load. The old springs stay (their triangles may still rest on
      // the vertex).
      const double own = spring_clearance(p, x1);
      spring_body_vertex_.push_back(p.body_vertex);
      spring_past_clearance_.push_back(target_past_clearance(p, own));
      extra.springs.push_back(piercing_spring(p, x1, pinned_, carried, own));
    }
    ++changed;
  }
  return changed;
}

void ContactResponse::record_spring_forces(const Eigen::VectorXd& x, const StepForces& extra) {
  spring_ends_.clear();
  const double margin =
      (settings_.spring_band ? kPiercingReleaseBand : kPiercingHoldMargin) * settings_.thickness;
  for (std::size_t s = 0; s < spring_body_vertex_.size(); ++s) {
    const PointSpring& spring = extra.springs[s];
    const double along = along_spring_normal(spring, cloth_.triangles[spring.triangle], x);
    double force = spring.preload + spring.stiffness * (spring.target - along);
    // With fade_carried_push the push carried past the clearance fades to nothing across the
    // hold margin, so a spring whose point leaves the hold is released at no load
    // (docs/collision.md, "The hem's cycle, traced"). Carried in full, the push that built up
    // while the cloth was caught is still there when it is dropped (15 mN of the hand's 45 at
    // the t-shirt's hem): it pushed the cloth out, the cloth fell back free, was caught and
    // pushed again, and every such cycle put energy in.
    const double past = along - (spring.target - spring_past_clearance_[s]);
    if (settings_.fade_carried_push && force > 0.0 && past > 0.0)
      force *= std::max(0.0, 1.0 - past / margin);
    const std::array<int, 3>& c = cloth_.triangles[spring.triangle];
    Eigen::Vector3d point = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) point += spring.weights[k] * x.segment<3>(3 * c[k]);
    spring_ends_.push_back(
        {spring_body_vertex_[s], spring.triangle, std::min(force, max_spring_preload()), point});
  }
}

void ContactResponse::apply_friction(const Eigen::VectorXd& impulse, const Eigen::VectorXd& mass,
                                     const Eigen::VectorXd& x_hat, double beta, Eigen::VectorXd& v,
                                     Eigen::VectorXd& x) {
  stats_.stuck = 0;
  if (impulse.size() != v.size()) return;
  const double mu_static = static_friction();
  const double mu_kinetic = kinetic_friction();
  for (const ActiveContact& a : active_) {
    if (a.released || a.repair) continue;
    if (a.stuck) {  // held by the solve's drag
      ++stats_.stuck;
      continue;
    }
    const int i = a.contact.vertex;
    const Eigen::Vector3d& n = a.contact.normal;
    auto vi = v.segment<3>(3 * i);
    const Eigen::Vector3d relative = vi - a.contact.body_velocity;
    const Eigen::Vector3d tangential = relative - relative.dot(n) * n;
    if (a.friction_in_solve) {
      // Sliding: the solve applied Coulomb's force. If that reversed the motion, friction
      // stopped it within the step (the linearisation cannot know): it stops.
      if (tangential.dot(a.slide_direction) >= 0.0) continue;
      vi -= tangential;
      ++stats_.stuck;
    } else {
      // A new contact: Coulomb's law from this step's normal impulse. Friction changes the
      // relative tangential velocity by at most μ·Δv_n, Δv_n = j_n / m.
      const double normal_dv = std::max(impulse.segment<3>(3 * i).dot(n), 0.0) / mass[i];
      const double speed = tangential.norm();
      if (speed <= mu_static * normal_dv) {
        vi -= tangential;
        ++stats_.stuck;
      } else {
        vi -= (mu_kinetic * normal_dv / speed) * tangential;
      }
    }
    x.segment<3>(3 * i) = x_hat.segment<3>(3 * i) + beta * vi;
  }
}

int ContactResponse::constrain_deep(const Eigen::VectorXd& x0, const Eigen::VectorXd& x1,
                                    const Eigen::VectorXd& x_hat, double beta,
                                    ConstraintFilter& filter, Eigen::VectorXd& y,
                                    StepForces& extra) {
  Stopwatch watch(stats_.collision_seconds);
  end_contacts_ = collider_.find_contacts_swept(x0, x1, query(), &cache_);
  too_deep_.clear();
  const bool repair = repairing();
  for (const BodyContact& c : end_contacts_) {
    if (filter.is_pinned(c.vertex) || (repair && in_repair_[c.vertex])) continue;
    if (c.crossed || c.distance < -settings_.penetration_tolerance) too_deep_.push_back(c);
  }
  // Body vertices more than the tolerance through the cloth. Not any height: over a smooth
  // convex body the cloth's chords pass a fraction of a millimetre under body vertices between
  // cloth vertices held at the thickness; re-solving for those made a sheet on a sphere
  // re-solve every step and never come to rest.
  piercings_ =
      repair ? std::vector<BodyPiercing>{} : find_piercings(x1, settings_.penetration_tolerance);
  if ((too_deep_.empty() && piercings_.empty()) || stats_.resolves >= settings_.max_resolves)
    return 0;
  for (const BodyContact& c : too_deep_)
    add_contact(c, contact_thickness(c, x1), x_hat, beta, filter, y, false);
  const int springs = spring_end_piercings(x1, extra);
  stats_.piercings_resolved += springs;
  const int added = static_cast<int>(too_deep_.size()) + springs;
  if (added > 0) ++stats_.resolves;
  return added;
}

void ContactResponse::finish_step(Eigen::VectorXd& x, Eigen::VectorXd& v, const StepForces& extra) {
  Stopwatch watch(stats_.collision_seconds);
  // Last resort for what the re-solves did not fix: onto the surface, with the body's normal
  // velocity (the approaching part of the relative velocity removed).
  std::vector<unsigned char> projected(x.size() / 3, 0);
  for (const BodyContact& c : too_deep_) {
    const int i = c.vertex;
    Eigen::Vector3d point = c.point;
    Eigen::Vector3d normal = c.normal;
    const double thickness = contact_thickness(c, x);
    for (int round = 0; round < kProjectionRounds; ++round) {
      x.segment<3>(3 * i) = point + thickness * normal;
      const std::optional<BodyProximity> check = collider_.closest_point(x.segment<3>(3 * i));
      if (!check || check->distance >= -settings_.penetration_tolerance) break;
      point = check->point;
      normal = check->normal;
    }
    auto vi = v.segment<3>(3 * i);
    const double approach = (vi - c.body_velocity).dot(normal);
    if (approach < 0.0) vi -= approach * normal;
    projected[i] = 1;
    ++stats_.projected;
  }
  if (stats_.projected > 0)
    spdlog::debug("sim: {} cloth vertices projected out of the body after {} re-solves",
                  stats_.projected, stats_.resolves);
  // Body vertices still through the cloth after the re-solves stay so until the next step's
  // springs (carrying the force they ended with) push them out: nothing is lifted.
  record_spring_forces(x, extra);
  for (const BodyPiercing& p : piercings_) {
    stats_.max_piercing = std::max(stats_.max_piercing, p.height);
    if (p.height > settings_.penetration_tolerance) ++stats_.piercing;
  }
  // Penetration at the end of the step, from the last end check (projected vertices measured
  // again, the repair's vertices excluded while it runs).
  const bool repair = repairing();
  for (const BodyContact& c : end_contacts_) {
    const int i = c.vertex;
    if (repair && in_repair_[i]) continue;
    const double distance =
        projected[i] ? collider_.signed_distance(x.segment<3>(3 * i)) : c.distance;
    if (distance < 0.0) stats_.max_penetration = std::max(stats_.max_penetration, -distance);
    if (distance < -settings_.penetration_tolerance) ++stats_.penetrating;
  }
  for (const ActiveContact& a : active_)
    if (!a.released && !a.repair)
      ++stats_.contacts;
    else if (a.released)
      ++stats_.released;
}

void ContactResponse::record_normal_forces(const Eigen::VectorXd& impulse) {
  std::fill(last_normal_force_.begin(), last_normal_force_.end(), kNoImpulse);
  std::fill(last_piercing_force_.begin(), last_piercing_force_.end(), kNoImpulse);
  if (impulse.size() != static_cast<Eigen::Index>(3 * last_normal_force_.size())) return;
  for (const ActiveContact& a : active_) {
    if (a.released || a.repair) continue;
    const int i = a.contact.vertex;
    last_normal_force_[i] = impulse.segment<3>(3 * i).dot(a.contact.normal) / beta_;
  }
}

void ContactResponse::accept_step(const Eigen::VectorXd& impulse) {
  record_normal_forces(impulse);
  held_springs_ = spring_ends_;
  // A body vertex with several springs (under a cloth edge, or the cloth slid over it) carries
  // the sum of their pushes (or, when none pushed, the least pull: it stays held).
  for (const SpringEnd& end : held_springs_) {
    const double force = end.force;
    double& carried = last_piercing_force_[end.body_vertex];
    if (std::isnan(carried))
      carried = force;
    else if (carried > 0.0 || force > 0.0)
      carried = std::max(carried, 0.0) + std::max(force, 0.0);
    else
      carried = std::max(carried, force);
  }
  accepted_contacts_ = active_;
  if (repairing()) {
    ++repair_step_;
    if (!repairing())
      spdlog::info("sim: start repair done: {} vertices pushed out of the body",
                   repair_.pushed.size());
  }
}

int ContactResponse::count_penetrating(const Eigen::VectorXd& x, double* deepest) const {
  ContactQuery q = query();
  q.thickness = 0.0;  // every vertex inside (or on) the surface
  int count = 0;
  double depth = 0.0;
  for (const BodyContact& c : collider_.find_contacts(x, q)) {
    depth = std::max(depth, -c.distance);
    if (c.distance < -settings_.penetration_tolerance) ++count;
  }
  if (deepest != nullptr) *deepest = depth;
  return count;
}

int ContactResponse::count_piercing(const Eigen::VectorXd& x, double* highest) const {
  // Sided by the cloth's pseudo-normal where the closest point is a corner or an edge: the
  // measure is exact there, where the springs keep the plane of each triangle (conservative: a
  // spring may push where the cloth already covers the vertex; switching the springs too
  // changed the designs' drapes, two of them no longer came to rest in their time).
  std::vector<BodyPiercing> through;
  if (!cloth_.triangles.empty()) {
    const double reach = piercing_reach();
    through = collider_.find_piercings(x, cloth_, settings_.penetration_tolerance, reach,
                                       kPiercingUncheckedFraction * reach, nullptr, false, true);
  }
  double top = 0.0;
  for (const BodyPiercing& p : through) top = std::max(top, p.height);
  if (highest != nullptr) *highest = top;
  return static_cast<int>(through.size());
}

}  // namespace sd::sim
