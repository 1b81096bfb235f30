#include "sim/adaptive_detail.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>

#include <Eigen/Geometry>
#include <spdlog/spdlog.h>

#include "meshing/mesh48_transfer.hpp"
#include "sim/element_forces.hpp"

namespace sd::sim {
namespace {

using meshing::BlockChange;
using meshing::BlockId;
using meshing::TriangleId;
using meshing::VertexId;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

void require(bool ok, const std::string& message) {
  if (!ok) throw InvalidAdaptiveSettingsError(message);
}

// θ − θ0 wrapped into (−π, π].
double angle_difference(double theta, double rest) {
  return std::remainder(theta - rest, 2.0 * std::numbers::pi);
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

Eigen::Vector3d row3(const Eigen::VectorXd& flat, int i) { return flat.segment<3>(3 * i); }

// How far a split vertex at `e` (on the diagonal b–c) may be lifted off the body. Lifting E by δ
// changes each child triangle (E, apex, b or c) by δ against its height from E, the distance
// from E to the opposite side: a lift square to the cloth stretches it by sqrt(1 + (δ/h)²) − 1,
// 4.4 % at 0.3 × the smallest height (the usual case: the body's normal is near the cloth's),
// a lift along it by up to δ/h, 30 %. A flat parent (an apex near the diagonal) has small
// heights: lifted without this bound, a t-shirt split under the arm was moved 14 mm off the body
// and its children stretched by 340 %.
double safe_lift(const Eigen::Vector3d& e, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                 std::initializer_list<const Eigen::Vector3d*> apexes) {
  constexpr double kMaxLiftPerHeight = 0.3;
  const auto height = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
    const Eigen::Vector3d side = q - p;
    const double length = side.norm();
    return length > 0.0 ? side.cross(e - p).norm() / length : 0.0;
  };
  double shortest = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d* apex : apexes)
    if (apex != nullptr) shortest = std::min({shortest, height(*apex, b), height(*apex, c)});
  return kMaxLiftPerHeight * shortest;
}

}  // namespace

void AdaptiveSettings::validate() const {
  const auto positive = [](double value) { return std::isfinite(value) && value > 0.0; };
  require(positive(refine_threshold), "the refine threshold must be a positive length in metres");
  require(positive(coarsen_threshold) && coarsen_threshold < refine_threshold,
          "the coarsen threshold must be positive and below the refine threshold (metres)");
  require(std::isfinite(steady_rate) && steady_rate >= 0.0,
          "the steady hinge rate must be zero or more radians per second");
  require(std::isfinite(min_lifetime) && min_lifetime >= 0.0,
          "the minimum triangle lifetime must be zero or more seconds");
  require(min_level >= 0 && max_level >= min_level && max_level <= 30,
          "the adaptive levels must satisfy 0 <= min_level <= max_level <= 30");
  require(max_vertices >= 0, "the particle budget must be zero (none) or a positive count");
  require(std::isfinite(merge_batch) && merge_batch >= 0.0 && merge_batch < 1.0,
          "the merge batch must be a fraction of the particles, at least 0 and below 1");
}

// The state by vertex and triangle id while a batch of splits and merges is applied (ids are
// Mesh48 slots: they stay valid until compact(), rows grow as new vertices appear).
struct AdaptiveCloth::Transfer {
  Eigen::MatrixX3d x, v;
  Eigen::VectorXd m;
  std::vector<double> birth;
  std::vector<PinRecord> pins;
  std::vector<int> pin_of;           // vertex id -> index into pins, or -1
  std::vector<VertexOrigin> origin;  // vertex id -> where it comes from (ids before the batch)
  std::vector<char> touched_blocks;  // made, completed or merged in this batch
  std::vector<char> made_triangles;  // triangle ids made or removed in this batch
  double now = 0.0;
  int moved_off_body = 0;  // split vertices moved out to the contact thickness
  bool changed = false;
  bool measured = false;
  ConservedQuantities before;
};

AdaptiveCloth::AdaptiveCloth(meshing::Mesh48 mesh, AdaptiveMaterial material,
                             Eigen::MatrixX3d positions, std::vector<Pin> pins,
                             SimulationSettings simulation, AdaptiveSettings adaptive)
    : mesh_(std::move(mesh)), material_(std::move(material)), settings_(adaptive) {
  settings_.validate();
  simulation.validate();
  if (!mesh_.is_compact())
    throw std::invalid_argument("the adaptive cloth needs a compact 4-8 mesh (call compact())");
  arrays_ = mesh_.arrays();
  const int n = mesh_.vertex_count();
  if (positions.rows() == 0) positions = arrays_.rest_positions;
  if (positions.rows() != n || !positions.allFinite())
    throw std::invalid_argument("the start positions must be finite, one row per cloth vertex (" +
                                std::to_string(n) + ")");
  for (const Pin& pin : pins) {
    if (pin.vertex < 0 || pin.vertex >= n)
      throw std::invalid_argument("pinned vertex " + std::to_string(pin.vertex) +
                                  " is not a cloth vertex (the cloth has " + std::to_string(n) +
                                  ")");
    pins_.push_back({pin.vertex, pin.path, positions.row(pin.vertex).transpose()});
  }
  birth_.assign(static_cast<std::size_t>(mesh_.triangle_count()), 0.0);

  Transfer state;
  state.x = std::move(positions);
  state.v = Eigen::MatrixX3d::Zero(n, 3);
  state.birth = birth_;
  state.pins = pins_;
  rebuild(state, &simulation);  // the model (with its lumped masses) and the simulation
}

AdaptiveCloth::~AdaptiveCloth() = default;
AdaptiveCloth::AdaptiveCloth(AdaptiveCloth&&) noexcept = default;
AdaptiveCloth& AdaptiveCloth::operator=(AdaptiveCloth&&) noexcept = default;

Eigen::MatrixX3d AdaptiveCloth::positions() const {
  return unflatten_positions(simulation_->positions());
}

Eigen::MatrixX3d AdaptiveCloth::velocities() const {
  return unflatten_positions(simulation_->velocities());
}

Eigen::Vector3d AdaptiveCloth::linear_momentum() const {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  const Eigen::VectorXd& v = simulation_->velocities();
  for (Eigen::Index i = 0; i < masses_.size(); ++i) p += masses_(i) * row3(v, static_cast<int>(i));
  return p;
}

ConservedQuantities AdaptiveCloth::conserved_quantities() const {
  return {masses_.sum(), linear_momentum(), simulation_->energy()};
}

std::vector<int> AdaptiveCloth::pinned_vertices() const {
  std::vector<int> out;
  for (const PinRecord& pin : pins_) out.push_back(pin.vertex);
  std::sort(out.begin(), out.end());
  return out;
}

double AdaptiveCloth::hinge_sag(const std::array<int, 4>& hinge, double theta) const {
  std::array<Eigen::Vector3d, 4> p;
  for (int m = 0; m < 4; ++m) p[m] = mesh_.rest_position(VertexId(hinge[m]));
  const double rest = material_.model_options.bend_rest == BendRestShape::designed
                          ? dihedral_angle(p[0], p[1], p[2], p[3])
                          : 0.0;
  const double areas =
      0.5 * ((p[1] - p[0]).cross(p[2] - p[0]).norm() + (p[3] - p[0]).cross(p[1] - p[0]).norm());
  return std::abs(angle_difference(theta, rest)) * areas / (p[1] - p[0]).norm() / 8.0;
}

Eigen::VectorXd AdaptiveCloth::edge_errors() const {
  const Eigen::VectorXd& x = simulation_->positions();
  const Eigen::MatrixX4i& edges = arrays_.interior_edges;
  Eigen::VectorXd errors(edges.rows());
  for (Eigen::Index r = 0; r < edges.rows(); ++r) {
    const double theta = dihedral_angle(row3(x, edges(r, 0)), row3(x, edges(r, 1)),
                                        row3(x, edges(r, 2)), row3(x, edges(r, 3)));
    errors(r) = std::abs(angle_difference(theta, edge_rest_angle_(r))) * edge_width_(r) / 8.0;
  }
  if (has_body()) errors = errors.cwiseMax(body_sags());
  return errors;
}

Eigen::VectorXd AdaptiveCloth::body_sags() const {
  const Eigen::MatrixX4i& edges = arrays_.interior_edges;
  Eigen::VectorXd sags = Eigen::VectorXd::Zero(edges.rows());
  const ContactResponse* contact = simulation_->contact();
  if (contact == nullptr || !simulation_->settings().contact.enabled) return sags;
  const Eigen::VectorXd& x = simulation_->positions();
  const double reach = body_reach();
  // Three closest-point queries per edge are most of adaptivity's cost on a body, and the sag
  // under an edge depends only on where its two ends are: an edge whose ends (and the body)
  // moved less than `settle` since its sag was found keeps it. A body point then moved as
  // little, so the kept sag is off by about 2·settle, the coarsen threshold. A sag that stays
  // below the refine threshold by more than twice the motion is kept too (below).
  const double settle = 0.5 * settings_.coarsen_threshold;
  const double body_motion = contact->collider().total_motion();
  body_sag_memory_.resize(static_cast<std::size_t>(edges.rows()));
  // Only edges that can still be refined need their sag (a block at the finest level cannot
  // split; merges ask body_sag themselves), only the stale ones a new one, and only their
  // vertices a body point.
  const int n = static_cast<int>(x.size() / 3);
  std::vector<unsigned char> stale(static_cast<std::size_t>(edges.rows()), 0);
  std::vector<unsigned char> needed(static_cast<std::size_t>(n), 0);
  for (Eigen::Index r = 0; r < edges.rows(); ++r) {
    if (!refinable(r)) continue;
    const BodySagMemory& memory = body_sag_memory_[static_cast<std::size_t>(r)];
    const int i = edges(r, 0), j = edges(r, 1);
    if (memory.valid) {
      const double moved =
          std::max({(row3(x, i) - memory.xi).norm(), (row3(x, j) - memory.xj).norm(),
                    body_motion - memory.body_motion});
      // Near enough to where it was found, or so far below the refine threshold that the motion
      // cannot lift it over (the three body points move as little as what they lie under, so
      // the sag changes by at most twice the motion): such a sag cannot decide a split, and the
      // splits and their order are those a fresh one would give.
      if (moved < settle || memory.sag + 2.0 * moved < settings_.refine_threshold) {
        sags(r) = memory.sag;
        ++body_sags_reused_;
        continue;
      }
    }
    ++body_sags_computed_;
    stale[static_cast<std::size_t>(r)] = 1;
    needed[static_cast<std::size_t>(i)] = 1;
    needed[static_cast<std::size_t>(j)] = 1;
  }
  // The body point under each of those vertices within reach (bounded queries: most of a
  // garment is not, and FCL prunes by the bound).
  std::vector<std::optional<BodyProximity>> under(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i)
    if (needed[static_cast<std::size_t>(i)])
      under[static_cast<std::size_t>(i)] = contact->collider().closest_point(row3(x, i), reach);
  for (Eigen::Index r = 0; r < edges.rows(); ++r) {
    if (!stale[static_cast<std::size_t>(r)]) continue;
    const int i = edges(r, 0), j = edges(r, 1);
    const std::optional<BodyProximity>& at_i = under[static_cast<std::size_t>(i)];
    const std::optional<BodyProximity>& at_j = under[static_cast<std::size_t>(j)];
    if (at_i || at_j)
      sags(r) = body_sag(row3(x, i), row3(x, j), at_i ? &*at_i : nullptr, at_j ? &*at_j : nullptr);
    body_sag_memory_[static_cast<std::size_t>(r)] = {row3(x, i), row3(x, j), body_motion, sags(r),
                                                     true};
  }
  return sags;
}

bool AdaptiveCloth::refinable(Eigen::Index edge) const {
  return arrays_.face_level(arrays_.edge_faces(edge, 0)) < settings_.max_level ||
         arrays_.face_level(arrays_.edge_faces(edge, 1)) < settings_.max_level;
}

double AdaptiveCloth::body_reach() const {
  const ContactSettings& contact = simulation_->settings().contact;
  return contact.thickness + contact.search_margin;
}

double AdaptiveCloth::body_sag(const Eigen::Vector3d& xi, const Eigen::Vector3d& xj,
                               const BodyProximity* at_i, const BodyProximity* at_j) const {
  const BodyCollider& body = simulation_->contact()->collider();
  const double reach = body_reach();
  // Body points under the ends not given; beyond reach of both, no sag. The other end and the
  // midpoint are at most the edge's length farther than the near end.
  std::optional<BodyProximity> near_i, near_j;
  if (at_i == nullptr && at_j == nullptr) {
    near_i = body.closest_point(xi, reach);
    near_j = body.closest_point(xj, reach);
    if (!near_i && !near_j) return 0.0;
  }
  const double bound = reach + (xi - xj).norm();
  if (at_i == nullptr && !near_i) near_i = body.closest_point(xi, bound);
  if (at_j == nullptr && !near_j) near_j = body.closest_point(xj, bound);
  if (at_i == nullptr) at_i = near_i ? &*near_i : nullptr;
  if (at_j == nullptr) at_j = near_j ? &*near_j : nullptr;
  const std::optional<BodyProximity> middle = body.closest_point(0.5 * (xi + xj), bound);
  if (at_i == nullptr || at_j == nullptr || !middle) return 0.0;
  return std::max(0.0, (middle->point - 0.5 * (at_i->point + at_j->point)).dot(middle->normal));
}

AdaptiveCloth::Transfer AdaptiveCloth::begin_transfer() const {
  Transfer state;
  state.x = positions();
  state.v = velocities();
  state.m = masses_;
  state.birth = birth_;
  state.pins = pins_;
  state.pin_of.assign(static_cast<std::size_t>(mesh_.vertex_capacity()), -1);
  for (std::size_t k = 0; k < state.pins.size(); ++k)
    state.pin_of[static_cast<std::size_t>(state.pins[k].vertex)] = static_cast<int>(k);
  state.origin.resize(static_cast<std::size_t>(mesh_.vertex_capacity()));
  for (int i = 0; i < mesh_.vertex_capacity(); ++i)
    state.origin[static_cast<std::size_t>(i)] = {i, i};
  state.now = simulation_->time();
  return state;
}

void AdaptiveCloth::apply(const BlockChange& change, Transfer& state) {
  if (!state.changed && settings_.measure_jumps) {
    state.before = conserved_quantities();  // the simulation still holds the old state
    state.measured = true;
  }
  state.changed = true;
  // Mass moves at each triangle's eased density ρ·e². The ease comes from the input faces the
  // change recorded: by the time a forced split of a chain is applied, its child slots may
  // hold the triangles of the next split.
  const double rho = material_.fabric.area_density;
  const double e1 = face_ease(change.source_a1);
  const double e2 = change.source_a2 >= 0 ? face_ease(change.source_a2) : 1.0;
  meshing::transfer_mass_and_velocity(change, {rho * e1 * e1, rho * e2 * e2}, state.m, state.v);
  const auto grow = [](auto& vector, int size, auto fill) {
    if (static_cast<int>(vector.size()) < size) vector.resize(static_cast<std::size_t>(size), fill);
  };
  grow(state.birth, mesh_.triangle_capacity(), 0.0);
  grow(state.touched_blocks, mesh_.block_capacity(), char{0});
  grow(state.made_triangles, mesh_.triangle_capacity(), char{0});
  // Parents and children both: a removed slot may be reused by a later change of the batch.
  for (TriangleId t : {change.a1, change.a2, change.a10, change.a11, change.a20, change.a21})
    if (t.valid()) state.made_triangles[static_cast<std::size_t>(t.value())] = 1;
  grow(state.pin_of, mesh_.vertex_capacity(), -1);
  grow(state.origin, mesh_.vertex_capacity(), VertexOrigin{});
  state.touched_blocks[static_cast<std::size_t>(change.block.value())] = 1;
  const auto pin_index = [&](VertexId v) { return state.pin_of[static_cast<std::size_t>(v.value())]; };

  if (change.kind == BlockChange::Kind::kSplit) {
    // E at the midpoint of BC in world space, as in rest space: each child keeps its parent's
    // deformation gradient, so stretch, shear and the centre of mass are unchanged.
    meshing::place_split_vertex(change, state.x);
    keep_off_body(change.e.value(), state);
    // E comes from the edge BC if both are particles from before the batch.
    const VertexOrigin& from_b = state.origin[static_cast<std::size_t>(change.b.value())];
    const VertexOrigin& from_c = state.origin[static_cast<std::size_t>(change.c.value())];
    state.origin[static_cast<std::size_t>(change.e.value())] =
        from_b.a >= 0 && from_b.a == from_b.b && from_c.a >= 0 && from_c.a == from_c.b
            ? VertexOrigin{from_b.a, from_c.a}
            : VertexOrigin{};
    for (TriangleId t : {change.a10, change.a11, change.a20, change.a21}) {
      if (!t.valid()) continue;
      state.birth[static_cast<std::size_t>(t.value())] = state.now;
      state.touched_blocks[static_cast<std::size_t>(mesh_.block(t).value())] = 1;
    }
    state.pin_of[static_cast<std::size_t>(change.e.value())] = -1;
    // A split edge between two pinned vertices (a pinned border) is pinned at its midpoint,
    // following the two pins' paths.
    const int pb = pin_index(change.b), pc = pin_index(change.c);
    if (pb >= 0 && pc >= 0) {
      const PinRecord b = state.pins[static_cast<std::size_t>(pb)];
      const PinRecord c = state.pins[static_cast<std::size_t>(pc)];
      PinRecord e;
      e.vertex = change.e.value();
      e.fixed = 0.5 * (b.fixed + c.fixed);
      if (b.path || c.path)
        e.path = [b, c](double t) {
          const Eigen::Vector3d xb = b.path ? b.path(t) : b.fixed;
          const Eigen::Vector3d xc = c.path ? c.path(t) : c.fixed;
          return Eigen::Vector3d(0.5 * (xb + xc));
        };
      state.pin_of[static_cast<std::size_t>(e.vertex)] = static_cast<int>(state.pins.size());
      state.pins.push_back(std::move(e));
    }
  } else {
    state.origin[static_cast<std::size_t>(change.e.value())] = VertexOrigin{};  // gone
    for (TriangleId t : {change.a1, change.a2})
      if (t.valid()) state.birth[static_cast<std::size_t>(t.value())] = state.now;
    if (const int pe = pin_index(change.e); pe >= 0) {
      state.pins.erase(state.pins.begin() + pe);
      std::fill(state.pin_of.begin(), state.pin_of.end(), -1);
      for (std::size_t k = 0; k < state.pins.size(); ++k)
        state.pin_of[static_cast<std::size_t>(state.pins[k].vertex)] = static_cast<int>(k);
    }
  }
}

double AdaptiveCloth::ease(TriangleId t) const { return face_ease(mesh_.source_face(t)); }

double AdaptiveCloth::face_ease(int source) const {
  if (material_.source_ease.size() == 0) return 1.0;
  if (source < 0 || source >= material_.source_ease.size())
    throw InvalidClothError("the ease must be given for every input face (" +
                            std::to_string(material_.source_ease.size()) + " given, face " +
                            std::to_string(source) + " needed)");
  return material_.source_ease(source);
}

void AdaptiveCloth::keep_off_body(int e, Transfer& state) const {
  const ContactResponse* contact = simulation_->contact();
  if (contact == nullptr || !simulation_->settings().contact.enabled) return;
  const double thickness = contact->settings().thickness;
  const Eigen::Vector3d x = state.x.row(e).transpose();
  // Unbounded: a chord across a sharp edge can put E deeper inside than the thickness.
  const std::optional<BodyProximity> near = contact->collider().closest_point(x);
  if (!near || near->distance >= thickness) return;
  // adapt() and refine_uniformly() decline splits whose lift would stretch the children, so
  // the whole lift is taken: what remains deeper than the safe lift comes from forced splits,
  // and leaving it inside for the start repair to push out failed worse (the t-shirt at L2:
  // 430 m/s within 5 steps).
  const double lift = thickness - near->distance;
  state.x.row(e) += (lift * near->normal).transpose();
  ++state.moved_off_body;
}

void AdaptiveCloth::carry_body_sag_memory(const Eigen::MatrixX4i& old_edges,
                                          const std::vector<VertexOrigin>& origin) {
  // An edge between two particles that were joined before the change is the same chord, so its
  // body sag is the same; every other edge starts without one.
  const auto key = [](int a, int b) {
    return (static_cast<std::uint64_t>(std::min(a, b)) << 32) |
           static_cast<std::uint32_t>(std::max(a, b));
  };
  std::unordered_map<std::uint64_t, Eigen::Index> before;  // old row of each remembered edge
  for (Eigen::Index r = 0; r < old_edges.rows(); ++r)
    if (static_cast<std::size_t>(r) < body_sag_memory_.size() &&
        body_sag_memory_[static_cast<std::size_t>(r)].valid)
      before.emplace(key(old_edges(r, 0), old_edges(r, 1)), r);
  const Eigen::MatrixX4i& edges = arrays_.interior_edges;
  std::vector<BodySagMemory> after(static_cast<std::size_t>(edges.rows()));
  for (Eigen::Index r = 0; r < edges.rows() && !before.empty(); ++r) {
    const VertexOrigin& i = origin[static_cast<std::size_t>(edges(r, 0))];
    const VertexOrigin& j = origin[static_cast<std::size_t>(edges(r, 1))];
    if (i.a < 0 || i.a != i.b || j.a < 0 || j.a != j.b) continue;  // a new vertex
    const auto found = before.find(key(i.a, j.a));
    if (found == before.end()) continue;
    BodySagMemory memory = body_sag_memory_[static_cast<std::size_t>(found->second)];
    if (old_edges(found->second, 0) != i.a) std::swap(memory.xi, memory.xj);  // ends reversed
    after[static_cast<std::size_t>(r)] = memory;
  }
  body_sag_memory_ = std::move(after);
}

bool AdaptiveCloth::split_stays_off_body(BlockId k, const Eigen::MatrixX3d& x) const {
  const ContactResponse* contact = simulation_->contact();
  if (contact == nullptr || !simulation_->settings().contact.enabled) return true;
  const auto position = [&](VertexId v) -> Eigen::Vector3d { return x.row(v.value()); };
  const auto [b, c] = mesh_.diagonal(k);
  const Eigen::Vector3d xb = position(b), xc = position(c);
  const Eigen::Vector3d middle = 0.5 * (xb + xc);
  const std::optional<BodyProximity> near = contact->collider().closest_point(middle);
  if (!near) return true;
  const double lift = contact->settings().thickness - near->distance;
  if (lift <= 0.0) return true;
  const auto [a, d] = mesh_.apexes(k);
  const Eigen::Vector3d xa = position(a);
  const Eigen::Vector3d xd = d.valid() ? position(d) : Eigen::Vector3d::Zero();
  return lift <= safe_lift(middle, xb, xc, {&xa, d.valid() ? &xd : nullptr});
}

void AdaptiveCloth::set_body(const meshing::TriMesh& body) {
  simulation_->set_body(body);
  body_sag_memory_.clear();
}

void AdaptiveCloth::set_body_motion(PoseSequence motion) {
  simulation_->set_body_motion(std::move(motion));
  body_sag_memory_.clear();
}

void AdaptiveCloth::clear_body() {
  simulation_->clear_body();
  body_sag_memory_.clear();
}

double AdaptiveCloth::rebuild(Transfer& state, const SimulationSettings* first_settings) {
  const auto start = Clock::now();
  const bool first = simulation_ == nullptr;
  ClothModelReuse reuse;
  if (!first) {
    const meshing::Mesh48Remap remap = mesh_.compact();
    state.x = meshing::remap_rows(state.x, remap.vertices, remap.vertex_count);
    state.v = meshing::remap_rows(state.v, remap.vertices, remap.vertex_count);
    state.m = meshing::remap_rows(state.m, remap.vertices, remap.vertex_count);
    std::vector<double> birth(static_cast<std::size_t>(remap.triangle_count), 0.0);
    for (std::size_t t = 0; t < remap.triangles.size() && t < state.birth.size(); ++t)
      if (remap.triangles[t] >= 0) birth[static_cast<std::size_t>(remap.triangles[t])] = state.birth[t];
    state.birth = std::move(birth);
    for (PinRecord& pin : state.pins) pin.vertex = remap.vertices[static_cast<std::size_t>(pin.vertex)];
    std::vector<VertexOrigin> origin(static_cast<std::size_t>(remap.vertex_count));
    for (std::size_t slot = 0; slot < remap.vertices.size() && slot < state.origin.size(); ++slot)
      if (remap.vertices[slot] >= 0)
        origin[static_cast<std::size_t>(remap.vertices[slot])] = state.origin[slot];
    state.origin = std::move(origin);
    // What the model can keep: particles that were there before, triangles no change made.
    reuse.previous_vertex.resize(static_cast<std::size_t>(remap.vertex_count));
    for (std::size_t i = 0; i < reuse.previous_vertex.size(); ++i) {
      const VertexOrigin& from = state.origin[i];
      reuse.previous_vertex[i] = from.a >= 0 && from.a == from.b ? from.a : -1;
    }
    reuse.previous_triangle.resize(static_cast<std::size_t>(remap.triangle_count));
    for (std::size_t t = 0; t < remap.triangles.size(); ++t)
      if (const int row = remap.triangles[t]; row >= 0)
        reuse.previous_triangle[static_cast<std::size_t>(row)] =
            t < state.made_triangles.size() && state.made_triangles[t] ? -1 : static_cast<int>(t);
    const Eigen::MatrixX4i old_edges = arrays_.interior_edges;
    arrays_ = mesh_.arrays();
    carry_body_sag_memory(old_edges, state.origin);
  }

  ClothInput input;
  input.rest_positions = arrays_.rest_positions;
  input.triangles = arrays_.faces;
  input.up = material_.up;
  if (material_.source_warp.rows() > 0) {
    input.warp.resize(arrays_.faces.rows(), 3);
    for (Eigen::Index f = 0; f < arrays_.faces.rows(); ++f) {
      const int source = mesh_.source_face(arrays_.triangle_ids[static_cast<std::size_t>(f)]);
      if (source < 0 || source >= material_.source_warp.rows())
        throw InvalidClothError("the warp directions must be given for every input face (" +
                                std::to_string(material_.source_warp.rows()) + " given, face " +
                                std::to_string(source) + " needed)");
      input.warp.row(f) = material_.source_warp.row(source);
    }
  }
  Eigen::VectorXd ease_scale;  // per face, empty without ease
  if (material_.source_ease.size() > 0) {
    ease_scale.resize(arrays_.faces.rows());
    for (Eigen::Index f = 0; f < ease_scale.size(); ++f)
      ease_scale(f) = ease(arrays_.triangle_ids[static_cast<std::size_t>(f)]);
  }
  ClothModel model;
  if (first) {
    model = build_cloth_model(input, material_.fabric, material_.model_options);
    if (ease_scale.size() > 0) scale_rest_shapes(model, ease_scale);
  } else {
    model = update_cloth_model(simulation_->model(), reuse, input, ease_scale,
                               material_.model_options);
  }
  if (first) {
    state.m = model.mass;
  } else {
    // The carried masses equal the lumped masses ρ·A/3 of the new mesh (4-8 children are exact
    // halves); use the carried ones, which conserve the total exactly.
    const double scale = std::max(1e-300, state.m.cwiseAbs().maxCoeff());
    const double deviation = (model.mass - state.m).cwiseAbs().maxCoeff();
    if (deviation > 1e-9 * scale)
      spdlog::warn("adaptive: carried masses differ from the lumped ones by {:.3g} kg", deviation);
    model.mass = state.m;
  }

  // Per interior edge: rest dihedral angle and mean rest height (A1 + A2)/|e|.
  const Eigen::MatrixX4i& edges = arrays_.interior_edges;
  const Eigen::MatrixX3d& rest = arrays_.rest_positions;
  edge_rest_angle_.resize(edges.rows());
  edge_width_.resize(edges.rows());
  for (Eigen::Index r = 0; r < edges.rows(); ++r) {
    const Eigen::Vector3d p0 = rest.row(edges(r, 0)), p1 = rest.row(edges(r, 1));
    const Eigen::Vector3d p2 = rest.row(edges(r, 2)), p3 = rest.row(edges(r, 3));
    edge_rest_angle_(r) = material_.model_options.bend_rest == BendRestShape::designed
                              ? dihedral_angle(p0, p1, p2, p3)
                              : 0.0;
    const double areas = 0.5 * ((p1 - p0).cross(p2 - p0).norm() + (p3 - p0).cross(p1 - p0).norm());
    edge_width_(r) = areas / (p1 - p0).norm();
  }

  std::vector<Pin> pins;
  for (const PinRecord& pin : state.pins) pins.push_back({pin.vertex, pin.path});
  masses_ = state.m;
  birth_ = std::move(state.birth);
  pins_ = std::move(state.pins);
  if (first) {
    simulation_ = std::make_unique<Simulation>(std::move(model), flatten_positions(state.x),
                                               std::move(pins), *first_settings);
  } else {
    simulation_->replace_model(std::move(model), flatten_positions(state.x),
                               flatten_positions(state.v), std::move(pins), state.origin);
  }
  return seconds_since(start);
}

AdaptStats AdaptiveCloth::finish(Transfer& state, AdaptStats stats,
                                 Clock::time_point operations_start) {
  stats.operations_s = seconds_since(operations_start);
  stats.moved_off_body = state.moved_off_body;
  if (state.changed) {
    stats.rebuild_s = rebuild(state);
    if (state.measured) {
      stats.before = state.before;
      stats.after = conserved_quantities();
    }
  }
  stats.vertices = mesh_.vertex_count();
  stats.triangles = mesh_.triangle_count();
  report_.splits += stats.splits;
  report_.forced_splits += stats.forced_splits;
  report_.merges += stats.merges;
  report_.moved_off_body += stats.moved_off_body;
  report_.splits_declined_on_body += stats.splits_declined_on_body;
  report_.topology_changes += stats.changed() ? 1 : 0;
  report_.estimate_s += stats.estimate_s;
  report_.operations_s += stats.operations_s;
  report_.rebuild_s += stats.rebuild_s;
  return stats;
}

void AdaptiveCloth::count_split(const std::vector<BlockChange>& changes, Transfer& state,
                                AdaptStats& stats) {
  for (const BlockChange& change : changes) {
    apply(change, state);
    ++(change.forced ? stats.forced_splits : stats.splits);
  }
}

bool AdaptiveCloth::is_young(TriangleId t, double now) const {
  return t.valid() &&
         birth_[static_cast<std::size_t>(t.value())] > now - settings_.min_lifetime + 1e-12;
}

bool AdaptiveCloth::hinge_is_flat(const std::array<int, 4>& hinge, const Eigen::VectorXd& x) const {
  const double theta =
      dihedral_angle(row3(x, hinge[0]), row3(x, hinge[1]), row3(x, hinge[2]), row3(x, hinge[3]));
  return hinge_sag(hinge, theta) < settings_.coarsen_threshold;
}

bool AdaptiveCloth::hinge_is_quiet(const std::array<int, 4>& hinge, const Eigen::VectorXd& x,
                                   const Eigen::VectorXd& v) const {
  const Condition<12> theta = dihedral_angle_condition(row3(x, hinge[0]), row3(x, hinge[1]),
                                                       row3(x, hinge[2]), row3(x, hinge[3]), false);
  double rate = 0.0;
  for (int m = 0; m < 4; ++m) rate += theta.gradient.segment<3>(3 * m).dot(row3(v, hinge[m]));
  return std::abs(rate) < settings_.steady_rate &&
         hinge_sag(hinge, theta.value) < settings_.coarsen_threshold;
}

// Whether split block k (children leaves) may merge now, and how far the merge moves the surface:
// old enough, flat (|x_E − (x_B + x_C)/2| and the sag of every hinge around E below the coarsen
// threshold), steady (every hinge around E turns slower than steady_rate), the parent's outer
// edges flat enough, and no body bulging under its diagonal.
std::optional<double> AdaptiveCloth::merge_error(BlockId k, const Eigen::VectorXd& x,
                                                 const Eigen::VectorXd& v, double now) const {
  const std::array<TriangleId, 4> children = mesh_.child_triangles(k);
  for (TriangleId t : children)
    if (is_young(t, now)) return std::nullopt;
  const auto [b, c] = mesh_.diagonal(k);
  const VertexId e = mesh_.split_vertex(k);
  const double error =
      (row3(x, e.value()) - 0.5 * (row3(x, b.value()) + row3(x, c.value()))).norm();
  if (!(error < settings_.coarsen_threshold)) return std::nullopt;
  // Every hinge around E: steady (|dθ/dt| below steady_rate) and with a sag estimate below
  // coarsen_threshold. E–B and E–C have the width of the parent's diagonal BC, so their sag
  // is what BC's estimate would be after the merge: a block split for a fold along its
  // diagonal is not merged back while the fold is there.
  bool keep = true;
  for (int p = 0; p < 4 && keep; ++p)
    for (int q = p + 1; q < 4 && keep; ++q) {
      if (!children[p].valid() || !children[q].valid()) continue;
      if (const auto hinge = hinge_between(mesh_, children[p], children[q]))
        keep = hinge_is_quiet(*hinge, x, v);
    }
  // The block's outer edges after the merge: the parent triangles are twice the children,
  // so a bend across an outer edge that was fine for the children can have twice their
  // sag. Below coarsen_threshold too, or a merge next to a fold is split again at once and
  // the mesh churns every min_lifetime.
  for (TriangleId t : children) {
    if (!keep || !t.valid()) continue;
    const auto& corners = mesh_.vertices(t);
    const int at_e =
        static_cast<int>(std::find(corners.begin(), corners.end(), e) - corners.begin());
    if (at_e > 2) continue;
    const TriangleId across = mesh_.neighbor(t, at_e);
    if (!across.valid()) continue;  // a boundary edge: no hinge
    const VertexId u = corners[static_cast<std::size_t>((at_e + 1) % 3)];
    const VertexId w = corners[static_cast<std::size_t>((at_e + 2) % 3)];
    const VertexId third = (u == b || w == b) ? c : b;  // of the parent triangle
    VertexId opposite;
    for (VertexId corner : mesh_.vertices(across))
      if (corner != u && corner != w) opposite = corner;
    // Element_forces' hinge order: (x0, x1, x2) and (x1, x0, x3) with x0 → x1 along t.
    keep = hinge_is_flat({u.value(), w.value(), third.value(), opposite.value()}, x);
  }
  // The body sag under the parent's diagonal: merging next to a curved body would make the
  // next split.
  if (keep && has_body() && simulation_->settings().contact.enabled)
    keep = body_sag(row3(x, b.value()), row3(x, c.value())) < settings_.coarsen_threshold;
  if (!keep) return std::nullopt;
  return error;
}

// Even levels: blocks at an even level that can merge together with their split children (two
// levels at once, so no odd triangles are left but the strips next to finer ones), each with the
// larger of its own and its children's merge errors. A child is judged as any merge; the block
// itself as it will be once its children are merged: its split vertex E, diagonal B-C and apexes
// A, D stay, so the hinges around E and across its outer edges are known before.
std::vector<std::pair<double, BlockId>> AdaptiveCloth::even_level_merges(const Eigen::VectorXd& x,
                                                                         const Eigen::VectorXd& v,
                                                                         double now) const {
  std::vector<BlockId> candidates;
  for (BlockId k : mesh_.mergeable_blocks()) {
    if (mesh_.level(k) % 2 == 0) {
      candidates.push_back(k);
      continue;
    }
    for (BlockId parent : mesh_.parents(k))
      if (parent.valid()) candidates.push_back(parent);
  }
  std::sort(candidates.begin(), candidates.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());

  std::vector<std::pair<double, BlockId>> out;
  for (BlockId k : candidates) {
    if (!mesh_.alive(k) || !mesh_.is_split(k) || mesh_.level(k) < settings_.min_level) continue;
    const auto [b, c] = mesh_.diagonal(k);
    const auto [a, d] = mesh_.apexes(k);
    const VertexId e = mesh_.split_vertex(k);
    double error = (row3(x, e.value()) - 0.5 * (row3(x, b.value()) + row3(x, c.value()))).norm();
    bool keep = error < settings_.coarsen_threshold;
    // The children: merged first if split (each a merge of its own), or leaves whose triangle
    // on this side is old enough.
    const std::array<BlockId, 4> children = mesh_.children(k);
    for (BlockId child : children) {
      if (!keep || !child.valid() || !mesh_.alive(child)) continue;
      if (mesh_.is_split(child)) {
        const std::optional<double> child_error =
            mesh_.can_merge(child) ? merge_error(child, x, v, now) : std::nullopt;
        keep = child_error.has_value();
        if (keep) error = std::max(error, *child_error);
      } else {
        for (TriangleId t : mesh_.triangles(child))
          if (is_young(t, now)) keep = false;
      }
    }
    if (!keep) continue;
    // The hinges around E after the children's merges, between (A, B, E), (A, E, C), (D, C, E)
    // and (D, E, B) (bending's order: (x0, x1, x2) and (x1, x0, x3), x0 -> x1 along the first).
    const int ia = a.value(), ib = b.value(), ic = c.value(), ie = e.value();
    keep = hinge_is_quiet({ia, ie, ic, ib}, x, v);
    if (d.valid()) {
      const int id = d.value();
      keep = keep && hinge_is_quiet({ie, ic, ia, id}, x, v) &&
             hinge_is_quiet({ie, id, ic, ib}, x, v) && hinge_is_quiet({ie, ib, id, ia}, x, v);
    }
    // The outer edges of the merged triangles (A, B, C) and (D, C, B), children() order AB, AC,
    // DC, DB: the hinge to whatever lies across, the child's other apex (or, across a pending
    // child, the coarser neighbour's third vertex).
    const std::array<std::array<VertexId, 3>, 4> sides{
        {{a, b, c}, {c, a, b}, {d, c, b}, {b, d, c}}};
    for (int i = 0; i < 4 && keep; ++i) {
      const BlockId child = children[static_cast<std::size_t>(i)];
      if (!child.valid() || !mesh_.alive(child)) continue;
      VertexId across;
      for (VertexId apex : mesh_.apexes(child))
        if (apex.valid() && apex != e) across = apex;
      if (!across.valid() && !mesh_.is_split(child)) {
        const TriangleId t = mesh_.triangles(child)[0];
        const TriangleId beyond = t.valid() ? mesh_.neighbor(t, 0) : TriangleId();
        if (beyond.valid())
          for (VertexId corner : mesh_.vertices(beyond))
            if (corner != sides[static_cast<std::size_t>(i)][0] &&
                corner != sides[static_cast<std::size_t>(i)][1])
              across = corner;
      }
      if (!across.valid()) continue;  // the cloth's border
      const auto& [u, w, third] = sides[static_cast<std::size_t>(i)];
      keep = hinge_is_flat({u.value(), w.value(), third.value(), across.value()}, x);
    }
    if (keep && has_body() && simulation_->settings().contact.enabled)
      keep = body_sag(row3(x, ib), row3(x, ic)) < settings_.coarsen_threshold;
    if (keep) out.emplace_back(error, k);
  }
  return out;
}

AdaptStats AdaptiveCloth::adapt() {
  AdaptStats stats;
  if (!settings_.enabled || !(settings_.refine || settings_.coarsen)) {
    stats.vertices = mesh_.vertex_count();
    stats.triangles = mesh_.triangle_count();
    return stats;
  }
  const auto estimate_start = Clock::now();
  const Eigen::VectorXd& x = simulation_->positions();
  const Eigen::VectorXd& v = simulation_->velocities();
  const double now = simulation_->time();

  // Merge candidates: split blocks whose children are leaves, at or above the coarsest level,
  // old enough, flat (merging moves the surface by |x_E − (x_B + x_C)/2|) and steady (every
  // hinge around E turns slower than steady_rate); with even levels, even blocks together with
  // their split children. Flattest first.
  std::vector<std::pair<double, BlockId>> merges;
  if (settings_.coarsen) {
    if (settings_.even_levels) {
      merges = even_level_merges(x, v, now);
    } else {
      for (BlockId k : mesh_.mergeable_blocks())
        if (mesh_.level(k) >= settings_.min_level)
          if (const std::optional<double> error = merge_error(k, x, v, now))
            merges.emplace_back(*error, k);
    }
    std::sort(merges.begin(), merges.end());
  }

  // Refinement candidates: interior edges above the threshold, largest first.
  std::vector<std::pair<double, int>> refinements;
  if (settings_.refine) {
    const Eigen::VectorXd errors = edge_errors();
    for (Eigen::Index r = 0; r < errors.size(); ++r)
      if (errors(r) > settings_.refine_threshold && refinable(r))
        refinements.emplace_back(errors(r), static_cast<int>(r));
    std::sort(refinements.begin(), refinements.end(), std::greater<>());
  }
  // Even levels: every complete odd block (only splits make them then; a pending one is the
  // strip next to a coarser region and stays) is split on this step whatever its estimate.
  std::vector<BlockId> odd_blocks;
  if (settings_.refine && settings_.even_levels)
    for (BlockId k : mesh_.leaf_blocks())
      if (mesh_.level(k) % 2 != 0 && mesh_.level(k) < settings_.max_level && !mesh_.is_pending(k))
        odd_blocks.push_back(k);
  stats.estimate_s = seconds_since(estimate_start);
  // Merges on their own wait until enough of them pay for a rebuild (merge_batch); blocks that
  // stay flat and steady are still candidates on the next step.
  std::size_t merge_count = merges.size();
  if (settings_.even_levels)
    for (const auto& [error, k] : merges)
      for (BlockId child : mesh_.children(k))
        if (child.valid() && mesh_.alive(child) && mesh_.is_split(child)) ++merge_count;
  if (refinements.empty() && odd_blocks.empty() &&
      static_cast<double>(merge_count) < settings_.merge_batch * mesh_.vertex_count())
    merges.clear();

  const auto operations_start = Clock::now();
  Transfer state = begin_transfer();
  const auto touched = [&](BlockId k) {
    const auto i = static_cast<std::size_t>(k.value());
    return i < state.touched_blocks.size() && state.touched_blocks[i] != 0;
  };
  for (const auto& [error, k] : merges) {
    if (!mesh_.alive(k) || touched(k)) continue;
    if (settings_.even_levels) {
      // Its split children first, all or none (a neighbour's merge may have merged one).
      bool ready = true;
      for (BlockId child : mesh_.children(k))
        if (child.valid() && mesh_.alive(child) && mesh_.is_split(child) &&
            (!mesh_.can_merge(child) || touched(child)))
          ready = false;
      if (!ready) continue;
      for (BlockId child : mesh_.children(k))
        if (child.valid() && mesh_.alive(child) && mesh_.is_split(child)) {
          apply(mesh_.merge(child), state);
          ++stats.merges;
        }
    }
    if (!mesh_.can_merge(k)) continue;
    apply(mesh_.merge(k), state);
    ++stats.merges;
  }
  for (const auto& [error, r] : refinements) {
    if (settings_.max_vertices > 0 && mesh_.vertex_count() >= settings_.max_vertices) break;
    const VertexId i(arrays_.interior_edges(r, 0)), j(arrays_.interior_edges(r, 1));
    // The blocks on the two sides of the edge, if the edge still exists (an edge already split
    // or merged away in this batch waits for the next step: one level per block per step).
    std::array<BlockId, 2> blocks;
    for (int side = 0; side < 2; ++side) {
      const TriangleId t = arrays_.triangle_ids[static_cast<std::size_t>(arrays_.edge_faces(r, side))];
      if (!mesh_.alive(t)) continue;
      const auto& corners = mesh_.vertices(t);
      const bool has_edge = std::find(corners.begin(), corners.end(), i) != corners.end() &&
                            std::find(corners.begin(), corners.end(), j) != corners.end();
      if (has_edge) blocks[static_cast<std::size_t>(side)] = mesh_.block(t);
    }
    if (blocks[1] == blocks[0]) blocks[1] = BlockId();
    for (BlockId k : blocks) {
      if (!k.valid() || !mesh_.can_split(k) || touched(k)) continue;
      if (mesh_.level(k) + 1 > settings_.max_level) continue;
      if (!split_stays_off_body(k, state.x)) {
        ++stats.splits_declined_on_body;
        continue;
      }
      count_split(mesh_.split(k), state, stats);
    }
  }
  for (BlockId k : odd_blocks) {
    if (settings_.max_vertices > 0 && mesh_.vertex_count() >= settings_.max_vertices) break;
    // Made or completed by a split above (one level per block per step), or left pending by a
    // merge above (its split would force the merged block's split back).
    if (!mesh_.can_split(k) || mesh_.is_pending(k) || touched(k)) continue;
    if (!split_stays_off_body(k, state.x)) {
      ++stats.splits_declined_on_body;
      continue;
    }
    count_split(mesh_.split(k), state, stats);
  }
  return finish(state, stats, operations_start);
}

AdaptStats AdaptiveCloth::split_blocks(const std::vector<BlockId>& blocks) {
  AdaptStats stats;
  const auto start = Clock::now();
  Transfer state = begin_transfer();
  for (BlockId k : blocks)
    if (mesh_.can_split(k)) count_split(mesh_.split(k), state, stats);
  return finish(state, stats, start);
}

AdaptStats AdaptiveCloth::merge_blocks(const std::vector<BlockId>& blocks) {
  AdaptStats stats;
  const auto start = Clock::now();
  Transfer state = begin_transfer();
  for (BlockId k : blocks)
    if (mesh_.alive(k) && mesh_.can_merge(k)) {
      apply(mesh_.merge(k), state);
      ++stats.merges;
    }
  return finish(state, stats, start);
}

AdaptStats AdaptiveCloth::refine_uniformly(int level) {
  AdaptStats stats;
  const auto start = Clock::now();
  Transfer state = begin_transfer();
  // Blocks whose split would have to stretch the cloth to stay off the body stay coarse, as in
  // adapt(); each is asked once.
  std::vector<char> declined;
  const auto is_declined = [&](BlockId k) {
    const auto i = static_cast<std::size_t>(k.value());
    return i < declined.size() && declined[i] != 0;
  };
  for (;;) {
    std::vector<BlockId> coarse;
    for (BlockId k : mesh_.leaf_blocks())
      if (mesh_.level(k) < level && !is_declined(k)) coarse.push_back(k);
    if (coarse.empty()) break;
    bool progress = false;
    for (BlockId k : coarse) {
      if (!mesh_.alive(k) || !mesh_.can_split(k)) continue;
      progress = true;
      if (!split_stays_off_body(k, state.x)) {
        declined.resize(std::max(declined.size(), static_cast<std::size_t>(k.value()) + 1), 0);
        declined[static_cast<std::size_t>(k.value())] = 1;
        ++stats.splits_declined_on_body;
        continue;
      }
      count_split(mesh_.split(k), state, stats);
    }
    if (!progress) break;  // nothing left that can be split
  }
  return finish(state, stats, start);
}

void AdaptiveCloth::record(const StepOutcome& outcome, const AdaptStats& stats) {
  AdaptiveStepRecord step;
  step.time = simulation_->time();
  step.dt = outcome.dt;
  step.splits = stats.splits;
  step.forced_splits = stats.forced_splits;
  step.merges = stats.merges;
  step.vertices = mesh_.vertex_count();
  step.triangles = mesh_.triangle_count();
  step.max_level = mesh_.max_level();
  step.measured = settings_.measure_jumps && stats.changed();
  step.before = stats.before;
  step.after = stats.after;
  report_.steps.push_back(step);
  report_.vertices_min =
      report_.steps.size() == 1 ? step.vertices : std::min(report_.vertices_min, step.vertices);
  report_.vertices_max = std::max(report_.vertices_max, step.vertices);
  report_.max_level_reached = std::max(report_.max_level_reached, step.max_level);
  report_.body_sags_computed = body_sags_computed_;
  report_.body_sags_reused = body_sags_reused_;
}

StepOutcome AdaptiveCloth::step(double max_step) {
  const StepOutcome outcome = simulation_->step(max_step);
  if (!outcome.accepted) return outcome;
  newton_total_ += outcome.newton_iterations;
  cg_total_ += outcome.cg_iterations;
  record(outcome, adapt());
  return outcome;
}

AdaptiveReport AdaptiveCloth::run(const std::function<void(const AdaptiveCloth&)>& on_step) {
  const auto start = Clock::now();
  const SimulationSettings& settings = simulation_->settings();
  const SimulationReport before = simulation_->report();
  std::vector<EnergySample>& energy = report_.simulation.energy;
  const auto sample = [&] {
    if (!settings.record_energy) return;
    const EnergyBreakdown e = simulation_->energy();
    energy.push_back({simulation_->time(), e.stretch, e.shear, e.bend, e.kinetic, e.potential});
  };
  if (energy.empty()) sample();
  bool failed = false, at_rest = false;
  std::string failure;
  int failure_vertex = -1;
  const double epsilon = 1e-9 * std::max(1.0, settings.duration);
  while (simulation_->time() < settings.duration - epsilon) {
    const StepOutcome outcome = step(settings.duration - simulation_->time());
    if (!outcome.accepted) {
      failed = true;
      failure = outcome.failure_reason;
      failure_vertex = outcome.failure_vertex;
      break;
    }
    sample();
    if (on_step) on_step(*this);
    if (settings.stop_at_rest && simulation_->at_rest()) {
      at_rest = true;
      break;
    }
  }
  // As Simulation::run: what is still inside the body, or through the cloth, at the end (after
  // the last adaptation).
  int penetrating = 0;
  int piercing = 0;
  double highest_piercing = 0.0;
  double query_s = 0.0;
  if (const ContactResponse* contact = simulation_->contact();
      contact != nullptr && settings.contact.enabled) {
    const auto query_start = Clock::now();
    penetrating = contact->count_penetrating(simulation_->positions());
    piercing = contact->count_piercing(simulation_->positions(), &highest_piercing);
    query_s = seconds_since(query_start);
  }
  const double wall = seconds_since(start);
  // The simulation's own counters (steps, solves, timings) plus what its run() would add.
  std::vector<EnergySample> series = std::move(energy);
  const double wall_before = report_.simulation.wall_time_s;
  const double other_before = report_.simulation.other_s;
  report_.simulation = simulation_->report();
  report_.simulation.energy = std::move(series);
  report_.simulation.wall_time_s = wall_before + wall;
  report_.simulation.collision_s += query_s;
  report_.simulation.penetrating_vertices_final = penetrating;
  report_.simulation.piercing_body_vertices_final = piercing;
  report_.simulation.max_piercing_final_m = highest_piercing;
  report_.simulation.other_s = other_before + wall -
                               (report_.simulation.forces_s - before.forces_s) -
                               (report_.simulation.solve_s - before.solve_s) -
                               (report_.simulation.collision_s - before.collision_s);
  report_.simulation.at_rest = at_rest;
  report_.simulation.failed = failed;
  report_.simulation.failure_reason = failure;
  report_.simulation.failure_vertex = failure_vertex;
  const SimulationReport& s = report_.simulation;
  report_.simulation.cg_iterations_mean =
      s.linear_solves > 0 ? static_cast<double>(cg_total_) / s.linear_solves : 0.0;
  report_.simulation.newton_iterations_mean =
      s.steps > 0 ? static_cast<double>(newton_total_) / s.steps : 0.0;
  report_.simulation.max_strain =
      max_stretch_strain(simulation_->model(), simulation_->positions());
  report_.simulation.nan_free =
      simulation_->positions().allFinite() && simulation_->velocities().allFinite();
  return report_;
}

}  // namespace sd::sim
