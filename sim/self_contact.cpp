#include "sim/self_contact.hpp"

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <unordered_map>
#include <utility>

#include "sim/forces.hpp"

namespace sd::sim {
namespace {

// rad/s: the repulsion springs' natural frequency, as for the body's piercing springs
// (sim/contact_response.cpp): stiff enough to stop a layer within a step at 1/60 s.
constexpr double kSpringFrequency = 400.0;
// An impulse lands a colliding pair this fraction of the thickness apart: clear of the
// continuous test's tolerance, and the next step's springs take it to the full thickness.
constexpr double kSeparation = 0.1;
// The share of the way to the thickness a repulsion spring pushes a pair in one step.
constexpr double kPushPerStep = 0.1;
// A pair already separating faster than this share of that push's speed gets no spring.
// Measured on the crumpled stress strip and the fold resting on a pinned layer: 0 (springs
// only on approaching pairs) leaves a resting layer to the fail-safe at 0.2 mm and costs the
// piling sheet 3.4 times the collisions; 1 (Bridson et al.'s bound) lets the crumpled strip
// under BDF2 gain twice its energy scale; 0.2 keeps both (0.53× and 0.59 mm).
constexpr double kSeparatingShare = 0.2;
// Friction between layers (step 2 of sim/self_contact.hpp): below this relative tangential
// speed (m/s) a pair is held by the largest drag Coulomb allows, μF/ε; a fifth of the rest speed
// (5 mm/s), so that a sticking layer's creep stays well inside "at rest".
constexpr double kStickSpeed = 1.0e-3;
// The drag of one pair is at most this many effective masses per β: a stiff but finite hold (a
// sticking pair's relative speed is cut by this factor per step), bounded so that the matrix
// stays well conditioned for the PCG.
constexpr double kMaxStick = 1000.0;
// A pair that started a step closer than the landing separation lands where it started, but at
// least this share of the landing separation apart (50 µm at 2 mm). Measured on the BDF2 fast
// fold of the stress family: landing as close as twice the tolerance (20 µm) ended it with 1.90
// times its energy bound, a quarter 0.82, a half 0.53 (lifting to the full separation: 0.96);
// the t-shirt rests at 1.35 s with a quarter as with none.
constexpr double kLandingFloor = 0.25;
// Gauss-Seidel sweeps of impulses over every pair found so far in the step between two
// continuous queries (a query costs far more than a sweep).
constexpr int kImpulseSweeps = 4;

Eigen::Vector3d row(const Eigen::VectorXd& x, int i) {
  return x.segment<3>(3 * i);
}

// A vertex the body's contact holds (kHeldByBody) weighs this many times its mass in the
// fail-safe's impulses: the free side of a pair gives way, not the side against the body.
constexpr double kHeldMassFactor = 1000.0;

double inverse_mass(int vertex, const Eigen::VectorXd& mass,
                    const std::vector<unsigned char>& pinned) {
  if (!pinned.empty() && pinned[vertex] == kHeldByBody)
    return 1.0 / (kHeldMassFactor * mass[vertex]);
  if (!pinned.empty() && pinned[vertex] != 0) return 0.0;
  return 1.0 / mass[vertex];
}

// Moves the members of a zone rigidly from x0: the mass-weighted mean translation and the
// rotation that carries their angular momentum about the centre of mass (a rotation vector ω
// with I ω = L, applied exactly by Rodrigues' formula so that the zone keeps its shape).
void move_rigidly(const std::vector<int>& members, const Eigen::VectorXd& x0, Eigen::VectorXd& x1,
                  const Eigen::VectorXd& mass, const std::vector<unsigned char>& pinned) {
  Eigen::Vector3d pin_shift = Eigen::Vector3d::Zero();
  int pins = 0;
  for (int i : members)
    if (!pinned.empty() && pinned[i] != 0 && pinned[i] != kHeldByBody) {
      pin_shift += row(x1, i) - row(x0, i);
      ++pins;
    }
  if (pins > 0) {
    pin_shift /= pins;
    for (int i : members)
      if (pinned.empty() || pinned[i] == 0 || pinned[i] == kHeldByBody)
        x1.segment<3>(3 * i) = row(x0, i) + pin_shift;
    return;
  }
  double total = 0.0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero(), shift = Eigen::Vector3d::Zero();
  for (int i : members) {
    total += mass[i];
    centre += mass[i] * row(x0, i);
    shift += mass[i] * (row(x1, i) - row(x0, i));
  }
  centre /= total;
  shift /= total;
  Eigen::Vector3d momentum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  for (int i : members) {
    const Eigen::Vector3d r = row(x0, i) - centre;
    momentum += mass[i] * r.cross(row(x1, i) - row(x0, i) - shift);
    inertia += mass[i] * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
  }
  const Eigen::Vector3d omega = inertia.completeOrthogonalDecomposition().solve(momentum);
  const double angle = omega.norm();
  const Eigen::Matrix3d rotation = angle > 1e-12
                                       ? Eigen::AngleAxisd(angle, omega / angle).toRotationMatrix()
                                       : Eigen::Matrix3d::Identity();
  for (int i : members) x1.segment<3>(3 * i) = centre + shift + rotation * (row(x0, i) - centre);
}

// The same pair whichever way a query met it: an edge-edge pair's two edges in a fixed order.
SelfContactResponse::PairKey key_of(const SelfPair& pair) {
  const std::array<int, 4>& v = pair.vertices;
  if (pair.kind == SelfPairKind::edge_edge &&
      std::make_pair(std::min(v[2], v[3]), std::max(v[2], v[3])) <
          std::make_pair(std::min(v[0], v[1]), std::max(v[0], v[1])))
    return {static_cast<int>(pair.kind), std::min(v[2], v[3]), std::max(v[2], v[3]),
            std::min(v[0], v[1]), std::max(v[0], v[1])};
  if (pair.kind == SelfPairKind::edge_edge)
    return {static_cast<int>(pair.kind), std::min(v[0], v[1]), std::max(v[0], v[1]),
            std::min(v[2], v[3]), std::max(v[2], v[3])};
  return {static_cast<int>(pair.kind), v[0], v[1], v[2], v[3]};
}

}  // namespace

std::size_t SelfContactResponse::PairKeyHash::operator()(const PairKey& key) const {
  std::size_t h = 1469598103934665603ull;
  for (int value : key)
    h = (h ^ static_cast<std::size_t>(static_cast<unsigned>(value))) * 1099511628211ull;
  return h;
}

double SelfContactResponse::lagged_force(const PairKey& key) const {
  const auto found = lagged_.find(key);
  return found == lagged_.end() ? 0.0 : 0.5 * (found->second[0] + found->second[1]);
}

void SelfContactResponse::accept_step() {
  // Every pair with a force now or in the last step keeps its history; the rest are dropped.
  std::unordered_map<PairKey, std::array<double, 2>, PairKeyHash> next;
  next.reserve(step_force_.size() + lagged_.size());
  for (const auto& [key, force] : step_force_) next[key] = {force, 0.0};
  for (const auto& [key, forces] : lagged_)
    if (forces[0] > 0.0) next[key][1] = forces[0];
  lagged_ = std::move(next);
  step_force_.clear();
}

void SelfContactSettings::validate() const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!positive(thickness))
    throw std::invalid_argument("the self-collision thickness must be a positive length");
  if (!positive(collision_tolerance) || collision_tolerance >= thickness)
    throw std::invalid_argument(
        "the self-collision tolerance must be positive and below the thickness");
  if (impulse_passes < 0 || max_zone_passes < 1)
    throw std::invalid_argument("self-collision passes: impulses ≥ 0, zones ≥ 1");
  if (!std::isfinite(friction))
    throw std::invalid_argument("the friction between layers must be a number");
}

SelfContactResponse::SelfContactResponse(SelfContactSettings settings)
    : settings_(std::move(settings)) {
  settings_.validate();
}

void SelfContactResponse::set_cloth(const ClothModel& model, const Eigen::VectorXd& x) {
  std::vector<std::array<int, 3>> triangles;
  triangles.reserve(model.triangles.size());
  for (const TriangleElement& t : model.triangles) triangles.push_back(t.vertices);
  collider_ = SelfCollider(std::move(triangles), x);
  collider_.set_culling(settings_.culling);
  lagged_.clear();  // the mesh was renumbered: no pair is the one it was
  step_force_.clear();
}

int SelfContactResponse::untangle(const ClothModel& model, Eigen::VectorXd& x,
                                  const std::vector<unsigned char>& pinned, int* found,
                                  int* remaining, double max_strain, Eigen::Vector3d* where) {
  const int n = model.vertex_count;
  std::vector<std::vector<int>> neighbours(static_cast<std::size_t>(n));
  for (const TriangleElement& t : model.triangles)
    for (int k = 0; k < 3; ++k) {
      neighbours[t.vertices[k]].push_back(t.vertices[(k + 1) % 3]);
      neighbours[t.vertices[k]].push_back(t.vertices[(k + 2) % 3]);
    }
  std::vector<unsigned char> moved(static_cast<std::size_t>(n), 0);
  std::vector<std::array<int, 2>> pairs = collider_.find_intersections(x);
  if (found != nullptr) *found = static_cast<int>(pairs.size());
  constexpr int kRounds = 120;
  // A start already stretched (a sheet's designed pre-strain) keeps its own strain as the bound.
  if (!pairs.empty() && std::isfinite(max_strain))
    max_strain = std::max(max_strain, max_stretch_strain(model, x));
  for (int round = 0; round < kRounds && !pairs.empty(); ++round) {
    // The region: the intersecting triangles' vertices, grown by a ring every 12 rounds. One
    // sweep per round and a check after it: the start moves as little as it can (5 sweeps a
    // round moved 70 of the t-shirt's vertices and stretched its underarm past the strain limit:
    // the adaptive drape's first step was retried down to 65 µs).
    std::vector<unsigned char> in(static_cast<std::size_t>(n), 0);
    std::vector<int> region;
    for (const auto& pair : pairs)
      for (int t : pair)
        for (int v : model.triangles[t].vertices)
          if (in[v] == 0) {
            in[v] = 1;
            region.push_back(v);
          }
    for (int ring = 0; ring < round / 12; ++ring) {
      const std::size_t size = region.size();
      for (std::size_t i = 0; i < size; ++i)
        for (int w : neighbours[region[i]])
          if (in[w] == 0) {
            in[w] = 1;
            region.push_back(w);
          }
    }
    const Eigen::VectorXd before = x;
    std::vector<int> round_moved;
    for (int v : region) {
      if ((!pinned.empty() && pinned[v] != 0) || neighbours[v].empty()) continue;
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (int w : neighbours[v]) mean += row(x, w);
      mean /= static_cast<double>(neighbours[v].size());
      x.segment<3>(3 * v) = 0.5 * (row(x, v) + mean);
      round_moved.push_back(v);
    }
    // The start's strain bound: a designed start is its rest shape (strain 0), and the first
    // step is rejected above the simulator's limit whatever its length, so a round that passes
    // the bound is undone and the pairs left stay as designed.
    if (std::isfinite(max_strain) && max_stretch_strain(model, x) > max_strain) {
      x = before;
      break;
    }
    for (int v : round_moved) moved[v] = 1;
    pairs = collider_.find_intersections(x);
  }
  if (remaining != nullptr) *remaining = static_cast<int>(pairs.size());
  if (where != nullptr) {  // the first pair's centre (a mean over both sleeves of a mirrored
                           // garment would lie between them)
    *where = Eigen::Vector3d::Zero();
    if (!pairs.empty())
      for (int t : pairs.front())
        for (int v : model.triangles[t].vertices) *where += row(x, v) / 6.0;
  }
  return static_cast<int>(std::count(moved.begin(), moved.end(), 1));
}

void SelfContactResponse::add_springs(const Eigen::VectorXd& start, const Eigen::VectorXd& mass,
                                      const std::vector<unsigned char>& pinned, StepForces& extra,
                                      const Eigen::VectorXd* velocity, double beta) {
  const auto begin = std::chrono::steady_clock::now();
  stats_ = SelfContactStepStats{};
  step_force_.clear();
  spring_keys_.clear();
  first_spring_ = extra.pair_springs.size();
  SelfQueryStats query;
  const std::vector<SelfPair> pairs =
      collider_.find_proximities(start, settings_.thickness, &query);
  stats_.triangles = query.triangles;
  stats_.culled_triangles = query.culled_triangles;
  const double mu = friction();
  const bool in_solve_friction = mu > 0.0 && beta > 0.0;
  struct Sizing {
    double effective = 0.0;  // kg
    double slide = 0.0;      // m/s: relative tangential speed at the start
    double lagged = 0.0;     // N
    double distance = 0.0;   // m: separation at the start
  };
  std::vector<Sizing> sizing;
  for (const SelfPair& pair : pairs) {
    double inverse = 0.0;
    for (int k = 0; k < 4; ++k)
      inverse += pair.weights[k] * pair.weights[k] * inverse_mass(pair.vertices[k], mass, pinned);
    if (!(inverse > 0.0)) continue;
    const double effective = 1.0 / inverse;
    PairSpring spring;
    spring.vertices = pair.vertices;
    spring.weights = pair.weights;
    spring.normal = pair.normal;
    const PairKey key = key_of(pair);
    const double lagged = in_solve_friction ? lagged_force(key) : 0.0;
    double slide = 0.0;
    if (velocity != nullptr) {
      const Eigen::Vector3d relative = pair_relative(spring, *velocity);
      slide = (relative - pair.normal.dot(relative) * pair.normal).norm();
    }
    // A spring pushes its pair a tenth of the way to the thickness per step, and only a pair
    // not already moving apart gets one (Bridson et al. 2002 §7.2 bound the repulsion the same
    // way). A spring born with the full thickness as its target holds ½ k (thickness − s)² it
    // did not take from anywhere; in a pile those pushes stretched the cloth step after step
    // (the crumpled stress strip ended at rest with 14 times its energy scale in stretch).
    const bool separating =
        velocity != nullptr &&
        along_pair_normal(spring, *velocity) >
            kSeparatingShare * kPushPerStep * (settings_.thickness - pair.distance) / beta;
    if (separating) {
      // No push, but a pair that pressed on the other layer in the last steps still rubs on it
      // (a layer resting under gravity alternates between steps with a spring and steps caught
      // by the fail-safe: friction in only one of them let it slide).
      if (!(lagged > 0.0)) continue;
    } else {
      spring.target = pair.distance + kPushPerStep * (settings_.thickness - pair.distance);
      spring.stiffness = effective * kSpringFrequency * kSpringFrequency;
      spring.damping = 2.0 * effective * kSpringFrequency;
    }
    extra.pair_springs.push_back(spring);
    spring_keys_.push_back(key);
    sizing.push_back({effective, slide, lagged, pair.distance});
  }
  // A vertex inside a pile is near many elements at once; the sum of their springs on it would
  // be many times one spring's stiffness, and their coupling across the pairs is explicit
  // (measured: a crumpled strip gained 40 times its energy scale). Each spring is divided by the
  // square root of the largest number of springs sharing one of its vertices (dividing by the
  // number itself left too little to hold layers apart: the fail-safe then did the work, 88 %
  // of the piling sheet's time).
  std::vector<int> count(static_cast<std::size_t>(mass.size()), 0);
  for (std::size_t p = first_spring_; p < extra.pair_springs.size(); ++p) {
    const PairSpring& spring = extra.pair_springs[p];
    if (spring.stiffness > 0.0)
      for (int k = 0; k < 4; ++k)
        if (std::abs(spring.weights[k]) > 0.0) ++count[spring.vertices[k]];
  }
  int springs = 0;
  for (std::size_t p = first_spring_; p < extra.pair_springs.size(); ++p) {
    PairSpring& spring = extra.pair_springs[p];
    const Sizing& size = sizing[p - first_spring_];
    if (spring.stiffness > 0.0) {
      int most = 1;
      for (int k = 0; k < 4; ++k)
        if (std::abs(spring.weights[k]) > 0.0) most = std::max(most, count[spring.vertices[k]]);
      spring.stiffness /= std::sqrt(static_cast<double>(most));
      spring.damping /= std::sqrt(static_cast<double>(most));
      ++springs;
    }
    if (!in_solve_friction) continue;
    // The normal force: what the pair carried in the last steps, or for a pair new to contact
    // the spring's push at the start.
    const double normal =
        size.lagged > 0.0 ? size.lagged : spring.stiffness * (spring.target - size.distance);
    spring.friction = std::min(kMaxStick * size.effective / beta,
                               mu * std::max(normal, 0.0) / std::max(size.slide, kStickSpeed));
  }
  stats_.springs = springs;
  stats_.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
}

void SelfContactResponse::apply_impulses(const std::vector<SelfPair>& hits,
                                         const Eigen::VectorXd& x0, Eigen::VectorXd& x1,
                                         double beta, const Eigen::VectorXd& mass,
                                         const std::vector<unsigned char>& pinned) {
  const double landing = kSeparation * settings_.thickness;
  for (const SelfPair& hit : hits) {
    double separation = 0.0, inverse = 0.0, started = 0.0;
    for (int k = 0; k < 4; ++k) {
      separation += hit.weights[k] * hit.normal.dot(row(x1, hit.vertices[k]));
      started += hit.weights[k] * hit.normal.dot(row(x0, hit.vertices[k]));
      inverse += hit.weights[k] * hit.weights[k] * inverse_mass(hit.vertices[k], mass, pinned);
    }
    // A pair that started the step closer than the landing separation lands where it started
    // (inelastic, no lift), but not closer than kLandingFloor of it: lifted to the landing
    // separation, a layer resting at 0.2–1 mm on another fell back within a step, was lifted
    // again, and the t-shirt's underarm never came to rest (a 5-step cycle; docs/collision.md,
    // "Resting layers").
    const double target = std::clamp(
        started, std::max(2.0 * settings_.collision_tolerance, kLandingFloor * landing), landing);
    if (separation >= target || !(inverse > 0.0)) continue;
    const double impulse = (target - separation) / inverse;
    // impulse is in kg·m (a position change times mass): the force over the step is impulse/β².
    step_force_[key_of(hit)] += impulse / (beta * beta);
    for (int k = 0; k < 4; ++k) {
      const int i = hit.vertices[k];
      x1.segment<3>(3 * i) +=
          (hit.weights[k] * impulse * inverse_mass(i, mass, pinned)) * hit.normal;
    }
  }
}

void SelfContactResponse::resolve(const Eigen::VectorXd& x0, Eigen::VectorXd& x1,
                                  Eigen::VectorXd& v1, double beta, const Eigen::VectorXd& mass,
                                  const std::vector<unsigned char>& pinned,
                                  const StepForces& extra) {
  const auto begin = std::chrono::steady_clock::now();
  // The normal force each spring applied over the step (at the solve's end), for the friction
  // of the next steps.
  for (std::size_t p = first_spring_; p < extra.pair_springs.size(); ++p) {
    const PairSpring& s = extra.pair_springs[p];
    if (!(s.stiffness > 0.0) || p - first_spring_ >= spring_keys_.size()) continue;
    const double force =
        s.stiffness * (s.target - along_pair_normal(s, x1)) - s.damping * along_pair_normal(s, v1);
    if (force > 0.0) step_force_[spring_keys_[p - first_spring_]] += force;
  }
  const Eigen::VectorXd solved = x1;
  const double tolerance = settings_.collision_tolerance;
  std::vector<SelfPair> hits = collider_.find_collisions(x0, x1, tolerance);
  stats_.collisions = static_cast<int>(hits.size());
  // Each later round changes only some vertices: the pairs without one are as the last query
  // found them, so only pairs with a moved vertex are queried again (the piling sheet spent 82 %
  // of its step in full queries here). `before` holds x1 as the last query saw it.
  const int vertex_count = static_cast<int>(x0.size() / 3);
  std::vector<unsigned char> moved(static_cast<std::size_t>(vertex_count), 0);
  Eigen::VectorXd before = x1;
  const auto requery = [&] {
    for (int i = 0; i < vertex_count; ++i)
      moved[i] = (x1.segment<3>(3 * i) != before.segment<3>(3 * i)) ? 1 : 0;
    std::vector<SelfPair> kept;
    for (const SelfPair& hit : hits)
      if (!moved[hit.vertices[0]] && !moved[hit.vertices[1]] && !moved[hit.vertices[2]] &&
          !moved[hit.vertices[3]])
        kept.push_back(hit);
    std::vector<SelfPair> found = collider_.find_collisions(x0, x1, tolerance, nullptr, &moved);
    kept.insert(kept.end(), found.begin(), found.end());
    before = x1;
    return kept;
  };
  std::vector<SelfPair> seen;  // every pair found this step, for the sweeps
  for (int round = 0; round < settings_.impulse_passes && !hits.empty(); ++round) {
    seen.insert(seen.end(), hits.begin(), hits.end());
    for (int sweep = 0; sweep < kImpulseSweeps; ++sweep)
      apply_impulses(seen, x0, x1, beta, mass, pinned);
    hits = requery();
    ++stats_.impulse_rounds;
  }
  if (!hits.empty()) {
    // Impact zones: union-find over the vertices of colliding pairs, grown until clean.
    const int n = vertex_count;
    std::vector<int> parent(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) parent[i] = i;
    const auto find = [&](int i) {
      while (parent[i] != i) i = parent[i] = parent[parent[i]];
      return i;
    };
    std::vector<unsigned char> zoned(static_cast<std::size_t>(n), 0);
    const auto move_zones = [&] {
      std::unordered_map<int, std::vector<int>> zones;
      for (int i = 0; i < n; ++i)
        if (zoned[i] != 0) zones[find(i)].push_back(i);
      for (const auto& [root, members] : zones) move_rigidly(members, x0, x1, mass, pinned);
    };
    for (int round = 0; round < settings_.max_zone_passes && !hits.empty(); ++round) {
      for (const SelfPair& hit : hits)
        for (int k = 0; k < 4; ++k) {
          zoned[hit.vertices[k]] = 1;
          const int a = find(hit.vertices[0]), b = find(hit.vertices[k]);
          if (a != b) parent[a] = b;
        }
      move_zones();
      hits = requery();
      ++stats_.zone_rounds;
    }
    if (!hits.empty()) {
      // Last resort: the whole cloth as one zone.
      for (int i = 0; i < n; ++i) {
        zoned[i] = 1;
        parent[i] = 0;
      }
      move_zones();
      hits = requery();
    }
    stats_.zone_vertices = static_cast<int>(std::count(zoned.begin(), zoned.end(), 1));
    stats_.unresolved = !hits.empty();
  }
  v1 += (x1 - solved) / beta;
  stats_.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
}

}  // namespace sd::sim
