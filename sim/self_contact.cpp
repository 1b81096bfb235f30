#include "sim/self_contact.hpp"

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <unordered_map>

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

}  // namespace

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
}

int SelfContactResponse::untangle(const ClothModel& model, Eigen::VectorXd& x,
                                  const std::vector<unsigned char>& pinned, int* found,
                                  int* remaining) {
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
    for (int v : region) {
      if ((!pinned.empty() && pinned[v] != 0) || neighbours[v].empty()) continue;
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (int w : neighbours[v]) mean += row(x, w);
      mean /= static_cast<double>(neighbours[v].size());
      x.segment<3>(3 * v) = 0.5 * (row(x, v) + mean);
      moved[v] = 1;
    }
    pairs = collider_.find_intersections(x);
  }
  if (remaining != nullptr) *remaining = static_cast<int>(pairs.size());
  return static_cast<int>(std::count(moved.begin(), moved.end(), 1));
}

void SelfContactResponse::add_springs(const Eigen::VectorXd& start, const Eigen::VectorXd& mass,
                                      const std::vector<unsigned char>& pinned, StepForces& extra,
                                      const Eigen::VectorXd* velocity, double beta) {
  const auto begin = std::chrono::steady_clock::now();
  stats_ = SelfContactStepStats{};
  SelfQueryStats query;
  const std::vector<SelfPair> pairs =
      collider_.find_proximities(start, settings_.thickness, &query);
  stats_.triangles = query.triangles;
  stats_.culled_triangles = query.culled_triangles;
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
    // A spring pushes its pair a tenth of the way to the thickness per step, and only a pair
    // not already moving apart gets one (Bridson et al. 2002 §7.2 bound the repulsion the same
    // way). A spring born with the full thickness as its target holds ½ k (thickness − s)² it
    // did not take from anywhere; in a pile those pushes stretched the cloth step after step
    // (the crumpled stress strip ended at rest with 14 times its energy scale in stretch).
    if (velocity != nullptr &&
        along_pair_normal(spring, *velocity) >
            kSeparatingShare * kPushPerStep * (settings_.thickness - pair.distance) / beta)
      continue;
    spring.target = pair.distance + kPushPerStep * (settings_.thickness - pair.distance);
    spring.stiffness = effective * kSpringFrequency * kSpringFrequency;
    spring.damping = 2.0 * effective * kSpringFrequency;
    extra.pair_springs.push_back(spring);
  }
  // A vertex inside a pile is near many elements at once; the sum of their springs on it would
  // be many times one spring's stiffness, and their coupling across the pairs is explicit
  // (measured: a crumpled strip gained 40 times its energy scale). Each spring is divided by the
  // square root of the largest number of springs sharing one of its vertices (dividing by the
  // number itself left too little to hold layers apart: the fail-safe then did the work, 88 %
  // of the piling sheet's time).
  std::vector<int> count(static_cast<std::size_t>(mass.size()), 0);
  for (const PairSpring& spring : extra.pair_springs)
    for (int k = 0; k < 4; ++k)
      if (std::abs(spring.weights[k]) > 0.0) ++count[spring.vertices[k]];
  for (PairSpring& spring : extra.pair_springs) {
    int most = 1;
    for (int k = 0; k < 4; ++k)
      if (std::abs(spring.weights[k]) > 0.0) most = std::max(most, count[spring.vertices[k]]);
    spring.stiffness /= std::sqrt(static_cast<double>(most));
    spring.damping /= std::sqrt(static_cast<double>(most));
  }
  stats_.springs = static_cast<int>(extra.pair_springs.size());
  stats_.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
}

void SelfContactResponse::apply_friction(Eigen::VectorXd& x1, Eigen::VectorXd& v1, double beta,
                                         const Eigen::VectorXd& mass,
                                         const std::vector<unsigned char>& pinned,
                                         const StepForces& extra) const {
  const double mu = friction();
  if (!(mu > 0.0)) return;
  for (const PairSpring& s : extra.pair_springs) {
    const double force =
        s.stiffness * (s.target - along_pair_normal(s, x1)) - s.damping * along_pair_normal(s, v1);
    if (!(force > 0.0)) continue;
    double inverse = 0.0;
    Eigen::Vector3d relative = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) {
      inverse += s.weights[k] * s.weights[k] * inverse_mass(s.vertices[k], mass, pinned);
      relative += s.weights[k] * row(v1, s.vertices[k]);
    }
    if (!(inverse > 0.0)) continue;
    const Eigen::Vector3d tangential = relative - s.normal.dot(relative) * s.normal;
    const double speed = tangential.norm();
    if (!(speed > 0.0)) continue;
    // Coulomb: the tangential impulse is at most μ times the normal one, J = β F.
    const double change = std::min(speed, mu * beta * force * inverse);
    const Eigen::Vector3d direction = tangential / speed;
    for (int k = 0; k < 4; ++k) {
      const int i = s.vertices[k];
      const double share = s.weights[k] * inverse_mass(i, mass, pinned) / inverse;
      const Eigen::Vector3d dv = -(share * change) * direction;
      v1.segment<3>(3 * i) += dv;
      x1.segment<3>(3 * i) += beta * dv;
    }
  }
}

void SelfContactResponse::apply_impulses(const std::vector<SelfPair>& hits, Eigen::VectorXd& x1,
                                         const Eigen::VectorXd& mass,
                                         const std::vector<unsigned char>& pinned) const {
  const double target = kSeparation * settings_.thickness;
  for (const SelfPair& hit : hits) {
    double separation = 0.0, inverse = 0.0;
    for (int k = 0; k < 4; ++k) {
      separation += hit.weights[k] * hit.normal.dot(row(x1, hit.vertices[k]));
      inverse += hit.weights[k] * hit.weights[k] * inverse_mass(hit.vertices[k], mass, pinned);
    }
    if (separation >= target || !(inverse > 0.0)) continue;
    const double impulse = (target - separation) / inverse;
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
  apply_friction(x1, v1, beta, mass, pinned, extra);
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
    for (int sweep = 0; sweep < kImpulseSweeps; ++sweep) apply_impulses(seen, x1, mass, pinned);
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
