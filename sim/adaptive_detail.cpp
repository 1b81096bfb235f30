#include "sim/adaptive_detail.hpp"

#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
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

#include "meshing/mesh48_transfer.hpp"
#include "sim/element_forces.hpp"

namespace sd::sim {
namespace {

using meshing::BlockChange;
using meshing::BlockId;
using meshing::TriangleId;
using meshing::VertexId;
using Clock = std::chrono::steady_clock;

// The error estimates (bend sags |θ − θ0|·w/8 for splits and merges) measure the cloth against
// the surface it was drawn as, whatever its bending rests in: the level-0 mesh resolves that
// surface at the file's edge length, so detail is added where the cloth leaves it, for a
// shaped and a flat-rest drape alike. Against a flat rest (θ0 = 0) every hinge curved round the
// body asked for detail and held it: trial 44's flat-rest blouse refined its armholes to level
// 5 and never came to rest (docs/adaptive.md, "Round 44").
constexpr BendRestShape kEstimateRest = BendRestShape::designed;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

void require(bool ok, const std::string& message) {
  if (!ok) throw InvalidAdaptiveSettingsError(message);
}

Eigen::Vector3d row3(const Eigen::VectorXd& flat, int i) {
  return flat.segment<3>(3 * i);
}

// The vertex areas and lumped masses ρ·A/3 of `input`'s pattern triangles (rest_uv, #F×6),
// each area scaled by its face's ease a·b (`ease`: #F×1 or #F×2, or empty), into `model`.
void lump_pattern_areas(const ClothInput& input, const Eigen::MatrixXd& ease, ClothModel& model) {
  model.vertex_area.setZero(input.rest_positions.rows());
  model.mass.setZero(input.rest_positions.rows());
  for (Eigen::Index f = 0; f < input.triangles.rows(); ++f) {
    const auto uv = input.rest_uv.row(f);
    double area =
        0.5 * std::abs((uv(2) - uv(0)) * (uv(5) - uv(1)) - (uv(4) - uv(0)) * (uv(3) - uv(1)));
    if (ease.size() > 0) area *= ease(f, 0) * (ease.cols() > 1 ? ease(f, 1) : ease(f, 0));
    for (int k = 0; k < 3; ++k) {
      model.vertex_area(input.triangles(f, k)) += area / 3.0;
      model.mass(input.triangles(f, k)) += model.fabric.area_density * area / 3.0;
    }
  }
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
  require(std::isfinite(change_interval) && change_interval >= 0.0,
          "the interval between topology changes must be zero (every step) or positive seconds");
  require(std::isfinite(lookahead) && lookahead >= 0.0,
          "the refinement lookahead must be zero (none) or a positive time in seconds");
  require(std::isfinite(motion_horizon) && motion_horizon >= 0.0,
          "the motion criterion's horizon must be zero (off) or a positive time in seconds");
}

AdaptiveCloth::AdaptiveCloth(meshing::Mesh48 mesh, AdaptiveMaterial material,
                             Eigen::MatrixX3d positions, std::vector<Pin> pins,
                             SimulationSettings simulation, AdaptiveSettings adaptive)
    : mesh_(std::move(mesh)), material_(std::move(material)), settings_(adaptive) {
  settings_.validate();
  simulation.validate();
  if (!mesh_.is_compact())
    throw std::invalid_argument("the adaptive cloth needs a compact 4-8 mesh (call compact())");
  arrays_ = mesh_.arrays();
  if (material_.rest_uv.rows() > 0) {
    const Eigen::Index faces = arrays_.faces.rows();
    if (material_.rest_uv.rows() != faces || material_.rest_uv.cols() != 6 ||
        !material_.rest_uv.allFinite())
      throw InvalidClothError("the rest coordinates must be finite, one row of 6 per triangle (" +
                              std::to_string(faces) + ")");
    if (faces > 0 && arrays_.face_level.maxCoeff() > 0)
      throw std::invalid_argument(
          "pattern rest shapes (rest_uv) are given on a 4-8 mesh's level-0 triangles");
    root_uv_.setZero(faces, 6);
    root_rest_.setZero(faces, 9);
    root_area_scale_.setZero(faces);
    for (Eigen::Index f = 0; f < faces; ++f) {
      const int r = mesh_.root(arrays_.triangle_ids[static_cast<std::size_t>(f)]);
      if (r < 0 || r >= faces)
        throw std::invalid_argument("a level-0 triangle's root is not a triangle of the mesh");
      root_uv_.row(r) = material_.rest_uv.row(f);
      for (int k = 0; k < 3; ++k)
        root_rest_.block<1, 3>(r, 3 * k) = arrays_.rest_positions.row(arrays_.faces(f, k));
      const Eigen::Vector3d p0 = arrays_.rest_positions.row(arrays_.faces(f, 0));
      const Eigen::Vector3d p1 = arrays_.rest_positions.row(arrays_.faces(f, 1));
      const Eigen::Vector3d p2 = arrays_.rest_positions.row(arrays_.faces(f, 2));
      const auto uv = material_.rest_uv.row(f);
      const double area_uv =
          0.5 * ((uv(2) - uv(0)) * (uv(5) - uv(1)) - (uv(4) - uv(0)) * (uv(3) - uv(1)));
      const double area_3d = 0.5 * (p1 - p0).cross(p2 - p0).norm();
      // build_cloth_model refuses degenerate and inverted rest triangles with their names.
      root_area_scale_(r) = area_3d > 0.0 ? area_uv / area_3d : 1.0;
    }
    if (material_.rest_ramp > 0.0) {
      if (material_.start_rest_uv.rows() != faces || material_.start_rest_uv.cols() != 6 ||
          !material_.start_rest_uv.allFinite())
        throw InvalidClothError(
            "the rest ramp's start coordinates must be finite, one row of 6 per triangle (" +
            std::to_string(faces) + ")");
      root_start_uv_.setZero(faces, 6);
      for (Eigen::Index f = 0; f < faces; ++f)
        root_start_uv_.row(mesh_.root(arrays_.triangle_ids[static_cast<std::size_t>(f)])) =
            material_.start_rest_uv.row(f);
    }
  }
  if (!std::isfinite(material_.rest_ramp) || material_.rest_ramp < 0.0)
    throw std::invalid_argument("the rest ramp must be zero (none) or a positive time in seconds");
  if (root_start_uv_.rows() > 0) {
    ramp_finished_ = false;
    // Still while its rest shape still moves is not at rest.
    simulation.rest_not_before = std::max(simulation.rest_not_before, material_.rest_ramp);
  }
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

  AdaptiveTransfer state;
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

Eigen::VectorXi AdaptiveCloth::source_faces() const {
  Eigen::VectorXi source(arrays_.faces.rows());
  for (Eigen::Index f = 0; f < source.size(); ++f)
    source(f) = mesh_.source_face(arrays_.triangle_ids[static_cast<std::size_t>(f)]);
  return source;
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

Eigen::VectorXd AdaptiveCloth::edge_errors() {
  Eigen::VectorXd errors = bend_sags(arrays_, edge_rest_, simulation_->positions());
  if (has_body()) errors = errors.cwiseMax(body_sags());
  return errors;
}

Eigen::VectorXd AdaptiveCloth::body_sags() {
  const ContactResponse* contact = active_contact();
  if (contact == nullptr) return Eigen::VectorXd::Zero(arrays_.interior_edges.rows());
  return body_sag_cache_.sags(arrays_, *contact, body_reach(simulation_->settings().contact),
                              simulation_->positions(), settings_.refine_threshold,
                              settings_.coarsen_threshold, settings_.max_level);
}

const ContactResponse* AdaptiveCloth::active_contact() const {
  const ContactResponse* contact = simulation_->contact();
  return contact != nullptr && simulation_->settings().contact.enabled ? contact : nullptr;
}

AdaptiveTransfer AdaptiveCloth::begin_transfer() const {
  return sim::begin_transfer(mesh_, positions(), velocities(), masses_, birth_, pins_,
                             simulation_->time());
}

void AdaptiveCloth::apply(const BlockChange& change, AdaptiveTransfer& state) {
  if (!state.changed && settings_.measure_jumps) {
    state.before = conserved_quantities();  // the simulation still holds the old state
    state.measured = true;
  }
  transfer_change(change, mesh_, material_.fabric.area_density, material_.source_ease, state,
                  root_area_scale_);
  if (change.kind == BlockChange::Kind::kSplit)
    if (const ContactResponse* contact = active_contact())
      if (keep_off_body(change.e.value(), state.x, *contact)) ++state.moved_off_body;
}

bool AdaptiveCloth::split_stays_off_body(BlockId k, const Eigen::MatrixX3d& x) const {
  const ContactResponse* contact = active_contact();
  return contact == nullptr || sim::split_stays_off_body(mesh_, k, x, *contact);
}

void AdaptiveCloth::set_body(const meshing::TriMesh& body) {
  simulation_->set_body(body);
  body_sag_cache_.clear();
  if (settings_.lookahead > 0.0 || settings_.motion_horizon > 0.0) still_body_ = body;
}

void AdaptiveCloth::set_body_motion(PoseSequence motion) {
  simulation_->set_body_motion(std::move(motion));
  body_sag_cache_.clear();
  still_body_ = {};
}

void AdaptiveCloth::clear_body() {
  simulation_->clear_body();
  body_sag_cache_.clear();
  still_body_ = {};
}

Eigen::MatrixXd AdaptiveCloth::pattern_rest_uv(const Eigen::MatrixXd& roots) const {
  const Eigen::Index faces = arrays_.faces.rows();
  Eigen::MatrixXd uv(faces, 6);
  for (Eigen::Index f = 0; f < faces; ++f) {
    const TriangleId t = arrays_.triangle_ids[static_cast<std::size_t>(f)];
    const int r = mesh_.root(t);
    if (arrays_.face_level(f) == 0) {  // the root itself, as given (bit for bit)
      uv.row(f) = roots.row(r);
      continue;
    }
    // Barycentric coordinates in the root's plane (the normal equations of the 3×2 edge matrix:
    // exact for points in the plane, the closest in-plane point otherwise).
    const Eigen::Vector3d p0 = root_rest_.block<1, 3>(r, 0).transpose();
    Eigen::Matrix<double, 3, 2> edges;
    edges.col(0) = root_rest_.block<1, 3>(r, 3).transpose() - p0;
    edges.col(1) = root_rest_.block<1, 3>(r, 6).transpose() - p0;
    const Eigen::Matrix2d gram = edges.transpose() * edges;
    const Eigen::Vector2d u0 = roots.block<1, 2>(r, 0).transpose();
    Eigen::Matrix2d uv_edges;
    uv_edges.col(0) = roots.block<1, 2>(r, 2).transpose() - u0;
    uv_edges.col(1) = roots.block<1, 2>(r, 4).transpose() - u0;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d p = arrays_.rest_positions.row(arrays_.faces(f, k)).transpose();
      const Eigen::Vector2d lambda = gram.ldlt().solve(edges.transpose() * (p - p0));
      uv.block<1, 2>(f, 2 * k) = (u0 + uv_edges * lambda).transpose();
    }
  }
  return uv;
}

Eigen::MatrixXd AdaptiveCloth::ease_scale() const {
  Eigen::MatrixXd scale;  // per face, empty without ease
  if (material_.source_ease.size() > 0) {
    scale.resize(arrays_.faces.rows(), 2);
    for (Eigen::Index f = 0; f < scale.rows(); ++f)
      scale.row(f) = face_ease(material_.source_ease,
                               mesh_.source_face(arrays_.triangle_ids[static_cast<std::size_t>(f)]))
                         .transpose();
  }
  return scale;
}

Eigen::MatrixX2d AdaptiveCloth::root_widths(const Eigen::MatrixXd& roots) const {
  const int count = mesh_.root_count();
  ClothInput input;
  input.rest_positions.resize(3 * static_cast<Eigen::Index>(count), 3);
  input.triangles.resize(count, 3);
  input.up = material_.up;
  if (material_.source_warp.rows() > 0) input.warp.resize(count, 3);
  for (int r = 0; r < count; ++r) {
    for (int k = 0; k < 3; ++k) {
      input.rest_positions.row(3 * r + k) = mesh_.root_corners(r)[static_cast<std::size_t>(k)];
      input.triangles(r, k) = 3 * r + k;
    }
    if (input.warp.rows() > 0) input.warp.row(r) = material_.source_warp.row(mesh_.root_source(r));
  }
  input.rest_uv = roots;
  return rest_widths(input);
}

Eigen::MatrixX2d AdaptiveCloth::buckling_widths(const Eigen::MatrixX2d& roots) const {
  Eigen::MatrixX2d widths(arrays_.faces.rows(), 2);
  for (Eigen::Index f = 0; f < widths.rows(); ++f)
    widths.row(f) = roots.row(mesh_.root(arrays_.triangle_ids[static_cast<std::size_t>(f)]));
  return widths;
}

std::vector<TriangleElement> AdaptiveCloth::ramped_triangles() const {
  const double t = simulation_ ? simulation_->time() : 0.0;
  const double a = std::min(t / material_.rest_ramp, 1.0);
  ClothInput input;
  input.rest_positions = arrays_.rest_positions;
  input.triangles = arrays_.faces;
  input.up = material_.up;
  const Eigen::MatrixXd roots = a >= 1.0 ? root_uv_
                                         : ((1.0 - a * a * (3.0 - 2.0 * a)) * root_start_uv_ +
                                            (a * a * (3.0 - 2.0 * a)) * root_uv_)
                                               .eval();
  input.rest_uv = pattern_rest_uv(roots);
  input.buckling_width = buckling_widths(a >= 1.0 ? root_width_ : root_widths(roots));
  ClothModel model = build_cloth_model(input, material_.fabric, material_.model_options);
  const Eigen::MatrixXd scale = ease_scale();
  if (scale.size() > 0) scale_rest_shapes(model, scale);
  return std::move(model.triangles);
}

double AdaptiveCloth::rebuild(AdaptiveTransfer& state, const SimulationSettings* first_settings) {
  const auto start = Clock::now();
  const bool first = simulation_ == nullptr;
  ClothModelReuse reuse;
  if (!first) {
    reuse = compact_transfer(mesh_.compact(), state);
    const Eigen::MatrixX4i old_edges = arrays_.interior_edges;
    arrays_ = mesh_.arrays();
    body_sag_cache_.carry(old_edges, arrays_.interior_edges, state.origin);
  }

  ClothInput input;
  input.rest_positions = arrays_.rest_positions;
  input.triangles = arrays_.faces;
  input.up = material_.up;
  if (root_uv_.rows() > 0) input.rest_uv = pattern_rest_uv();
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
  if (first) root_width_ = root_widths(root_uv_);
  input.buckling_width = buckling_widths(root_width_);
  const Eigen::MatrixXd ease_scale = this->ease_scale();  // per face, empty without ease
  ClothModel model;
  if (first) {
    model = build_cloth_model(input, material_.fabric, material_.model_options);
    if (ease_scale.size() > 0) scale_rest_shapes(model, ease_scale);
  } else {
    model =
        update_cloth_model(simulation_->model(), reuse, input, ease_scale, material_.model_options);
    // On the rest ramp the kept triangles hold the blend of rest shapes of the last step (below),
    // the new ones the pattern's, and the vertex areas and lumped masses summed from them mixed
    // the two: the carried masses, the pattern's, then read as up to 3e-5 kg (a fifth of a
    // vertex) "different" on every topology change of a flat drape with "rest_ramp". Both are
    // the pattern's throughout, as on the first build.
    if (!ramp_finished_) lump_pattern_areas(input, ease_scale, model);
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

  edge_rest_ = edge_rest_geometry(arrays_, kEstimateRest);

  std::vector<Pin> pins;
  for (const PinRecord& pin : state.pins) pins.push_back({pin.vertex, pin.path});
  masses_ = state.m;
  birth_ = std::move(state.birth);
  pins_ = std::move(state.pins);
  // On the rest ramp the membrane rests in the blend of the current time (masses, bending and
  // the rest of the model are rest_uv's); the reused triangles held an earlier blend.
  if (!ramp_finished_) {
    std::vector<TriangleElement> ramped = ramped_triangles();
    for (std::size_t t = 0; t < ramped.size(); ++t) {
      model.triangles[t].du = ramped[t].du;
      model.triangles[t].dv = ramped[t].dv;
      model.triangles[t].rest_area = ramped[t].rest_area;
      model.triangles[t].width_u = ramped[t].width_u;
      model.triangles[t].width_v = ramped[t].width_v;
    }
  }
  if (first) {
    simulation_ = std::make_unique<Simulation>(std::move(model), flatten_positions(state.x),
                                               std::move(pins), *first_settings);
  } else {
    simulation_->replace_model(std::move(model), flatten_positions(state.x),
                               flatten_positions(state.v), std::move(pins), state.origin);
    last_origin_ = state.origin;
  }
  return seconds_since(start);
}

AdaptStats AdaptiveCloth::finish(AdaptiveTransfer& state, AdaptStats stats,
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

void AdaptiveCloth::count_split(const std::vector<BlockChange>& changes, AdaptiveTransfer& state,
                                AdaptStats& stats) {
  for (const BlockChange& change : changes) {
    apply(change, state);
    ++(change.forced ? stats.forced_splits : stats.splits);
  }
}

MergeInputs AdaptiveCloth::merge_inputs() const {
  MergeInputs in{mesh_,
                 settings_,
                 kEstimateRest,
                 birth_,
                 simulation_->positions(),
                 simulation_->velocities(),
                 simulation_->time(),
                 {}};
  if (const ContactResponse* contact = active_contact()) {
    const double reach = body_reach(simulation_->settings().contact);
    in.body_sag = [contact, reach](const Eigen::Vector3d& xi, const Eigen::Vector3d& xj) {
      return body_sag(contact->collider(), reach, xi, xj);
    };
  }
  return in;
}

void AdaptiveCloth::split_edges(const std::vector<std::pair<double, int>>& refinements,
                                AdaptiveTransfer& state, AdaptStats& stats) {
  for (const auto& [error, r] : refinements) {
    if (settings_.max_vertices > 0 && mesh_.vertex_count() >= settings_.max_vertices) break;
    const VertexId i(arrays_.interior_edges(r, 0)), j(arrays_.interior_edges(r, 1));
    // The blocks on the two sides of the edge, if the edge still exists (an edge already split
    // or merged away in this batch waits for the next step: one level per block per step).
    std::array<BlockId, 2> blocks;
    for (int side = 0; side < 2; ++side) {
      const TriangleId t =
          arrays_.triangle_ids[static_cast<std::size_t>(arrays_.edge_faces(r, side))];
      if (!mesh_.alive(t)) continue;
      const auto& corners = mesh_.vertices(t);
      const bool has_edge = std::find(corners.begin(), corners.end(), i) != corners.end() &&
                            std::find(corners.begin(), corners.end(), j) != corners.end();
      if (has_edge) blocks[static_cast<std::size_t>(side)] = mesh_.block(t);
    }
    if (blocks[1] == blocks[0]) blocks[1] = BlockId();
    for (BlockId k : blocks) {
      if (!k.valid() || !mesh_.can_split(k) || state.touched(k)) continue;
      if (mesh_.level(k) + 1 > settings_.max_level) continue;
      if (!split_stays_off_body(k, state.x)) {
        ++stats.splits_declined_on_body;
        continue;
      }
      split_towards(k, mesh_.level(k) + levels_asked(error), state, stats);
    }
  }
}

int AdaptiveCloth::levels_asked(double error) const {
  if (!settings_.target_levels || !(error > settings_.refine_threshold)) return 1;
  // The sag halves per level on a smooth curve (θ and w each fall by √2).
  return std::max(1, static_cast<int>(std::ceil(std::log2(error / settings_.refine_threshold))));
}

void AdaptiveCloth::split_towards(BlockId k, int level, AdaptiveTransfer& state,
                                  AdaptStats& stats) {
  const int target = std::min(level, settings_.max_level);
  std::vector<BlockId> pending{k};
  while (!pending.empty()) {
    const BlockId b = pending.back();
    pending.pop_back();
    // The budget is checked per edge by the caller, and here for the levels beyond the first.
    if (b != k && settings_.max_vertices > 0 && mesh_.vertex_count() >= settings_.max_vertices)
      return;
    if (!mesh_.alive(b) || !mesh_.can_split(b) || mesh_.level(b) + 1 > target) continue;
    // k itself was checked by the caller; the blocks its split made are checked here.
    if (b != k && !split_stays_off_body(b, state.x)) {
      ++stats.splits_declined_on_body;
      continue;
    }
    count_split(mesh_.split(b), state, stats);
    for (BlockId child : mesh_.children(b))
      if (child.valid()) pending.push_back(child);
  }
}

AdaptStats AdaptiveCloth::adapt() {
  AdaptStats stats;
  if (!settings_.enabled || !(settings_.refine || settings_.coarsen)) {
    stats.vertices = mesh_.vertex_count();
    stats.triangles = mesh_.triangle_count();
    return stats;
  }
  const auto estimate_start = Clock::now();
  // Merge candidates, flattest first; split candidates, largest estimate first; with even
  // levels, the odd blocks that are split whatever their estimate (adaptive_policy.hpp).
  // Between regular changes (change_interval) only an edge a whole level behind (sag above
  // twice the threshold) changes the mesh; the lookahead covers the time to the next change.
  const bool due = time() >= next_change_ - 1e-9 * settings_.change_interval;
  // The motion criterion, at most every horizon: merges wait for it (they need its word that
  // the coarser mesh moves alike), and its errors join the estimate.
  const double horizon = settings_.motion_horizon;
  const bool motion_check = horizon > 0.0 && time() >= next_motion_check_ - 1e-9 * horizon;
  MotionErrors motion;
  if (motion_check) {
    motion = motion_errors();
    next_motion_check_ = time() + horizon;
  }
  std::vector<std::pair<double, BlockId>> merges;
  if (settings_.coarsen && due && (horizon == 0.0 || motion_check)) {
    merges = merge_candidates(merge_inputs());
    if (motion_check)
      std::erase_if(merges, [&](const std::pair<double, BlockId>& merge) {
        return motion.vertex(mesh_.split_vertex(merge.second).value()) >
               settings_.coarsen_threshold;
      });
  }
  std::vector<std::pair<double, int>> refinements;
  if (settings_.refine) {
    Eigen::VectorXd errors = edge_errors();
    if (!due) {
      errors = (errors.array() > 2.0 * settings_.refine_threshold).select(errors, 0.0);
    } else if (settings_.lookahead > 0.0) {
      errors = errors.cwiseMax(
          bend_sags(arrays_, edge_rest_,
                    simulation_->positions() + settings_.lookahead * simulation_->velocities()));
    }
    if (motion_check) errors = errors.cwiseMax(motion.edge);
    refinements = refine_candidates(errors, arrays_, settings_);
  }
  std::vector<BlockId> odd_blocks;
  if (settings_.refine && settings_.even_levels) odd_blocks = odd_level_blocks(mesh_, settings_);
  stats.estimate_s = seconds_since(estimate_start);
  // Merges on their own wait until enough of them pay for a rebuild (merge_batch); blocks that
  // stay flat and steady are still candidates on the next step.
  if (refinements.empty() && odd_blocks.empty() &&
      static_cast<double>(merge_count(mesh_, settings_, merges)) <
          settings_.merge_batch * mesh_.vertex_count())
    merges.clear();
  if (due && !(refinements.empty() && odd_blocks.empty() && merges.empty()))
    next_change_ = time() + settings_.change_interval;

  const auto operations_start = Clock::now();
  AdaptiveTransfer state = begin_transfer();
  const auto touched = [&](BlockId k) { return state.touched(k); };
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
  split_edges(refinements, state, stats);
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

Eigen::VectorXd AdaptiveCloth::preview_sags() const {
  SimulationSettings trial = simulation_->settings();
  trial.duration = settings_.lookahead;
  trial.stop_at_rest = false;
  std::vector<Pin> pins;
  for (const PinRecord& pin : pins_) pins.push_back({pin.vertex, pin.path});
  Simulation preview(simulation_->model(), simulation_->positions(), std::move(pins), trial);
  if (still_body_.face_count() > 0) preview.set_body(still_body_);
  Eigen::VectorXd sags = Eigen::VectorXd::Zero(arrays_.interior_edges.rows());
  // The run's own steps: contacts are found within a step's reach, so one long step would
  // pass through a body the cloth is about to land on.
  while (preview.time() < settings_.lookahead * (1.0 - 1e-9)) {
    if (!preview.step(settings_.lookahead - preview.time()).accepted) break;
    sags = sags.cwiseMax(bend_sags(arrays_, edge_rest_, preview.positions()));
  }
  if (const ContactResponse* contact = preview.contact()) {
    const double reach = body_reach(trial.contact);
    const Eigen::VectorXd& x = preview.positions();
    for (Eigen::Index r = 0; r < sags.size(); ++r) {
      if (!edge_refinable(arrays_, r, settings_.max_level)) continue;
      const int i = arrays_.interior_edges(r, 0), j = arrays_.interior_edges(r, 1);
      sags(r) = std::max(sags(r), body_sag(contact->collider(), reach, row3(x, i), row3(x, j)));
    }
  }

  return sags;
}

MotionErrors AdaptiveCloth::motion_errors() const {
  MotionErrors out;
  out.vertex = Eigen::VectorXd::Zero(mesh_.vertex_count());
  out.edge = Eigen::VectorXd::Zero(arrays_.interior_edges.rows());
  const double horizon = settings_.motion_horizon;
  // The copies are built from the current mesh as input, which pattern rest shapes refuse.
  if (!(horizon > 0.0) || root_uv_.rows() > 0 || !ramp_finished_) return out;
  // One implicit step over the whole horizon: the two meshes' responses to the same state,
  // pins and body (one step of the run's dt grown by (horizon/dt)² sees nothing away from pins
  // and contacts at a still start, where every mesh falls alike for one step).
  SimulationSettings trial = simulation_->settings();
  trial.dt = horizon;
  trial.duration = horizon;
  trial.stop_at_rest = false;
  const double start = time();
  std::vector<Pin> pins;
  for (const PinRecord& pin : pins_) {
    Pin copy{pin.vertex, {}};
    if (pin.path) copy.path = [path = pin.path, start](double t) { return path(start + t); };
    pins.push_back(std::move(copy));
  }
  AdaptiveSettings fixed;
  fixed.enabled = false;
  const Eigen::MatrixX3d x = positions();
  const auto trial_copy = [&] {
    AdaptiveCloth copy(mesh_, material_, x, pins, trial, fixed);
    copy.simulation_->set_velocities(simulation_->velocities());
    if (still_body_.face_count() > 0) copy.set_body(still_body_);
    return copy;
  };
  AdaptiveCloth coarse = trial_copy();
  AdaptiveCloth fine = trial_copy();
  std::vector<BlockId> leaves;
  for (BlockId k : fine.mesh_.leaf_blocks())
    if (fine.mesh_.level(k) < settings_.max_level) leaves.push_back(k);
  if (leaves.empty() || !fine.split_blocks(leaves).changed()) return out;
  const Eigen::VectorXd coarse_start = coarse.simulation_->positions();
  const Eigen::VectorXd fine_start = fine.simulation_->positions();
  if (!coarse.simulation_->step(horizon).accepted || !fine.simulation_->step(horizon).accepted)
    return out;
  const Eigen::VectorXd coarse_move = coarse.simulation_->positions() - coarse_start;
  const Eigen::VectorXd fine_move = fine.simulation_->positions() - fine_start;
  // Displacements, not positions: a split vertex moved off the body starts away from the
  // midpoint, which is not a difference in motion.
  const auto key = [](int a, int b) {
    return (static_cast<std::int64_t>(std::min(a, b)) << 32) | std::max(a, b);
  };
  std::unordered_map<std::int64_t, double> midpoints;
  const auto& origin = fine.last_origin_;
  for (std::size_t i = 0; i < origin.size(); ++i) {
    const VertexOrigin& from = origin[i];
    if (from.a < 0 || from.b < 0) continue;  // made between vertices the batch made
    const Eigen::Vector3d expected = 0.5 * (row3(coarse_move, from.a) + row3(coarse_move, from.b));
    const double d = (row3(fine_move, static_cast<int>(i)) - expected).norm();
    if (from.a == from.b) {
      out.vertex(from.a) = std::max(out.vertex(from.a), d);
    } else {
      double& m = midpoints[key(from.a, from.b)];
      m = std::max(m, d);
    }
  }
  for (Eigen::Index r = 0; r < out.edge.size(); ++r) {
    const int i = arrays_.interior_edges(r, 0), j = arrays_.interior_edges(r, 1);
    double e = std::max(out.vertex(i), out.vertex(j));
    if (const auto m = midpoints.find(key(i, j)); m != midpoints.end()) e = std::max(e, m->second);
    out.edge(r) = e;
  }
  return out;
}

AdaptStats AdaptiveCloth::refine_ahead() {
  AdaptStats stats;
  const auto estimate_start = Clock::now();
  std::vector<std::pair<double, int>> refinements;
  if (settings_.enabled && settings_.refine && settings_.lookahead > 0.0)
    refinements = refine_candidates(edge_errors().cwiseMax(preview_sags()), arrays_, settings_);
  stats.estimate_s = seconds_since(estimate_start);
  const auto operations_start = Clock::now();
  AdaptiveTransfer state = begin_transfer();
  split_edges(refinements, state, stats);
  return finish(state, stats, operations_start);
}

AdaptStats AdaptiveCloth::split_blocks(const std::vector<BlockId>& blocks) {
  AdaptStats stats;
  const auto start = Clock::now();
  AdaptiveTransfer state = begin_transfer();
  for (BlockId k : blocks)
    if (mesh_.can_split(k)) count_split(mesh_.split(k), state, stats);
  return finish(state, stats, start);
}

AdaptStats AdaptiveCloth::merge_blocks(const std::vector<BlockId>& blocks) {
  AdaptStats stats;
  const auto start = Clock::now();
  AdaptiveTransfer state = begin_transfer();
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
  AdaptiveTransfer state = begin_transfer();
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
  report_.body_sags_computed = body_sag_cache_.computed();
  report_.body_sags_reused = body_sag_cache_.reused();
}

StepOutcome AdaptiveCloth::step(double max_step) {
  if (!looked_ahead_ && settings_.lookahead > 0.0) {
    looked_ahead_ = true;
    for (int round = 0; round < settings_.max_level && refine_ahead().changed(); ++round) {
    }
  }
  if (!motion_started_ && settings_.enabled && settings_.refine && settings_.motion_horizon > 0.0) {
    // Before the first step: refine where the motion differs, round by round (one level per
    // block and round), until the once-refined copy moves alike everywhere.
    motion_started_ = true;
    for (int round = 0; round < settings_.max_level; ++round) {
      AdaptStats stats;
      const auto estimate_start = Clock::now();
      const auto refinements = refine_candidates(motion_errors().edge, arrays_, settings_);
      stats.estimate_s = seconds_since(estimate_start);
      const auto operations_start = Clock::now();
      AdaptiveTransfer state = begin_transfer();
      split_edges(refinements, state, stats);
      if (!finish(state, stats, operations_start).changed()) break;
    }
    next_motion_check_ = time() + settings_.motion_horizon;
  }
  if (!ramp_finished_) {
    // The step starts in the rest shapes of its start time; from the first step at or after the
    // ramp's end, in rest_uv's exactly.
    simulation_->set_triangle_rest_shapes(ramped_triangles());
    ramp_finished_ = time() >= material_.rest_ramp;
  }
  const StepOutcome outcome = simulation_->step(max_step);
  if (!outcome.accepted) return outcome;
  record(outcome, adapt());
  return outcome;
}

AdaptiveReport AdaptiveCloth::run(const std::function<void(const AdaptiveCloth&)>& on_step) {
  Simulation::RunHooks hooks;
  if (on_step)
    hooks.after_step = [&](const StepOutcome& outcome) {
      if (outcome.accepted) on_step(*this);
      return true;
    };
  return run(hooks);
}

AdaptiveReport AdaptiveCloth::run(const Simulation::RunHooks& hooks) {
  // The simulation's own loop and report; each of its steps is this driver's (step, then adapt).
  Simulation::RunHooks adaptive = hooks;
  if (!adaptive.step) adaptive.step = [this](double max_step) { return step(max_step); };
  report_.simulation = simulation_->run(adaptive);
  return report_;
}

}  // namespace sd::sim
