#include "sim/simulation.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

namespace sd::sim {

namespace {

// The CPU time of the whole process, every thread (s): what the run costs, comparable with
// another program's CPU time for the same simulation (scripts/compare_blender.py).
double process_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

}  // namespace

std::string_view integrator_name(Integrator integrator) {
  return integrator == Integrator::bdf2 ? "bdf2" : "implicit-euler";
}

std::string_view integrator_short_name(Integrator integrator) {
  return integrator == Integrator::bdf2 ? "bdf2" : "ie";
}

std::string_view rest_break_name(RestBreak reason) {
  switch (reason) {
    case RestBreak::none:
      return "none";
    case RestBreak::body_moving:
      return "body moving";
    case RestBreak::too_early:
      return "too early";
    case RestBreak::new_anchor:
      return "new anchor";
    case RestBreak::kinetic_energy:
      return "kinetic energy";
    case RestBreak::drift:
      return "drift";
  }
  return "none";
}

std::optional<Integrator> parse_integrator(std::string_view name) {
  if (name == "implicit-euler" || name == "ie") return Integrator::implicit_euler;
  if (name == "bdf2") return Integrator::bdf2;
  return std::nullopt;
}
namespace {

// The start's untangling may stretch the cloth by at most this multiple of max_strain (the limit
// a step is rejected above): a first step of 1/60 s pulls a moderately stretched start back
// (the cropped jacket's untangled start at strain 1.16 ended its first step accepted, and the
// drape rests with no layer through another), but not the Collada long-sleeve top's 7.61 (1.64
// after the step, rejected at every length down to the minimum step).
constexpr double kUntangleStrainShare = 2.0;

void require(bool ok, const std::string& message) {
  if (!ok) throw InvalidSimulationSettingsError(message);
}

double max_speed(const Eigen::VectorXd& v) {
  double speed = 0.0;
  for (Eigen::Index i = 0; i < v.size() / 3; ++i)
    speed = std::max(speed, v.segment<3>(3 * i).norm());
  return speed;
}

// A corner of the most stretched triangle (its largest stretch along u or v), −1 without
// triangles: where a drape stuck on the strain limit is held.
int most_stretched_vertex(const ClothModel& model, const Eigen::VectorXd& x) {
  double strain = -std::numeric_limits<double>::infinity();
  int vertex = -1;
  for (const TriangleElement& t : model.triangles) {
    Eigen::Vector3d wu = Eigen::Vector3d::Zero(), wv = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      wu += t.du[k] * x.segment<3>(3 * t.vertices[k]);
      wv += t.dv[k] * x.segment<3>(3 * t.vertices[k]);
    }
    if (const double s = std::max(wu.norm(), wv.norm()) - 1.0; s > strain)
      strain = s, vertex = t.vertices[0];
  }
  return vertex;
}

// Forced steps printed one by one before they are only counted (summed up at the run's end).
constexpr int kForcedStepsLogged = 5;

}  // namespace

void SimulationSettings::validate() const {
  const auto positive = [](double value) { return std::isfinite(value) && value > 0.0; };
  require(positive(dt), "the time step dt must be a positive number of seconds");
  require(positive(min_dt) && min_dt <= dt,
          "the minimum time step must be positive and not larger than dt");
  require(std::isfinite(duration) && duration >= 0.0, "the duration must be zero or more seconds");
  require(!newton_iterations || *newton_iterations >= 1, "Newton iterations must be at least 1");
  require(positive(newton_tolerance), "the Newton tolerance must be positive");
  require(positive(pcg_tolerance) && pcg_tolerance < 1.0,
          "the PCG tolerance must be between 0 and 1");
  require(pcg_max_iterations >= 1, "the PCG iteration limit must be at least 1");
  require(positive(max_strain), "the strain limit must be positive");
  require(positive(max_speed), "the speed limit must be positive");
  require(std::isfinite(step_error) && step_error >= 0.0,
          "the step's error target must be zero (off) or a positive length in metres");
  require(easy_steps_to_grow >= 1, "easy_steps_to_grow must be at least 1");
  require(std::isfinite(grow_factor) && grow_factor >= 1.0, "the growth factor must be at least 1");
  require(positive(rest_speed) && positive(rest_kinetic_energy) && std::isfinite(rest_window) &&
              rest_window >= 0.0,
          "the at-rest thresholds must be positive and the window zero or more");
  require(stuck_steps >= 0 && std::isfinite(stuck_share) && stuck_share > 0.0 && stuck_share <= 1.0,
          "the stuck test needs a window of zero (off) or more steps and a share in (0, 1]");
  require(unsettled_retries >= 0 && std::isfinite(settled_energy) && settled_energy > 0.0 &&
              std::isfinite(unsettled_window) && unsettled_window > 0.0,
          "the thrown-about test needs a settled energy and a window above zero and zero (off) or "
          "more retries");
  require(std::isfinite(rest_not_before) && rest_not_before >= 0.0,
          "the earliest at-rest time must be zero or more seconds");
  require(forces.gravity.allFinite() && forces.wind.allFinite() && std::isfinite(forces.air_drag) &&
              forces.air_drag >= 0.0,
          "gravity, wind and air drag must be finite (air drag zero or more)");
  try {
    contact.validate();
  } catch (const InvalidContactSettingsError& error) {
    throw InvalidSimulationSettingsError(error.what());
  }
  try {
    self_contact.validate();
  } catch (const std::invalid_argument& error) {
    throw InvalidSimulationSettingsError(error.what());
  }
}

Simulation::Simulation(ClothModel model, Eigen::VectorXd x0, std::vector<Pin> pins,
                       SimulationSettings settings)
    : settings_(std::move(settings)) {
  settings_.validate();
  dt_ = error_controlled() ? 0.5 * settings_.dt : settings_.dt;
  replace_model(std::move(model), std::move(x0), Eigen::VectorXd(), std::move(pins));
  report_.dt_min_used = 0.0;
}

void Simulation::set_triangle_rest_shapes(const std::vector<TriangleElement>& rest) {
  flush_energy_sample();
  if (rest.size() != model_.triangles.size())
    throw std::invalid_argument("new rest shapes need one triangle per triangle of the model");
  for (std::size_t t = 0; t < rest.size(); ++t) {
    TriangleElement& e = model_.triangles[t];
    if (rest[t].vertices != e.vertices)
      throw std::invalid_argument("new rest shapes must be given for the model's own triangles");
    e.du = rest[t].du;
    e.dv = rest[t].dv;
    e.rest_area = rest[t].rest_area;
    e.width_u = rest[t].width_u;
    e.width_v = rest[t].width_v;
  }
}

void Simulation::replace_model(ClothModel model, Eigen::VectorXd x, Eigen::VectorXd v,
                               std::vector<Pin> pins) {
  flush_energy_sample();
  const int n = model.vertex_count;
  if (x.size() != 3 * n)
    throw std::invalid_argument("the start positions must have 3 coordinates per cloth vertex");
  if (!x.allFinite()) throw std::invalid_argument("the start positions must be finite");
  if (v.size() == 0) v = Eigen::VectorXd::Zero(3 * n);
  if (v.size() != 3 * n || !v.allFinite())
    throw std::invalid_argument("the start velocities must be finite, 3 per cloth vertex");
  for (const Pin& pin : pins)
    if (pin.vertex < 0 || pin.vertex >= n)
      throw std::invalid_argument("pinned vertex " + std::to_string(pin.vertex) +
                                  " is not a cloth vertex (the cloth has " + std::to_string(n) +
                                  ")");
  model_ = std::move(model);
  {  // fixed pins that hold a region flat are clamps for the bending (issue 21)
    std::vector<int> fixed;
    for (const Pin& pin : pins)
      if (!pin.path) fixed.push_back(pin.vertex);
    clamp_bending(model_, fixed, &x);
  }
  x_ = std::move(x);
  v_ = std::move(v);
  rest_anchor_ = x_;  // the first still stretch is measured from the start
  pins_ = std::move(pins);
  pin_rest_.clear();
  for (const Pin& pin : pins_) pin_rest_.emplace_back(x_.segment<3>(3 * pin.vertex));
  filter_ = ConstraintFilter(n);
  has_history_ = false;
  report_.vertices = n;
  report_.triangles = static_cast<int>(model_.triangles.size());
  // A new mesh: the self-contact tree is rebuilt on it.
  if (settings_.self_contact.enabled) {
    const auto start = std::chrono::steady_clock::now();
    const bool first = !self_contact_;
    if (first) self_contact_ = std::make_unique<SelfContactResponse>(settings_.self_contact);
    self_contact_->set_fabric_friction(model_.fabric.friction);
    self_contact_->set_cloth(model_, x_);
    if (first) {
      // A designed start that passes through itself is smoothed apart once, before anything
      // moves: the continuous tests would keep the intersections for the whole run. Pinned
      // vertices stay where they are.
      std::vector<unsigned char> pinned(static_cast<std::size_t>(n), 0);
      for (const Pin& pin : pins_) pinned[pin.vertex] = 1;
      // Bounded by kUntangleStrainShare × the strain limit: a start stretched far past it has
      // every first step rejected whatever its length (docs/collision.md, "An untangled start").
      Eigen::Vector3d left_at = Eigen::Vector3d::Zero();
      report_.self_untangled_vertices = self_contact_->untangle(
          model_, x_, pinned, &report_.self_intersections_start, &report_.self_untangle_left,
          kUntangleStrainShare * settings_.max_strain, &left_at);
      spdlog::debug("sim: the start's untangling moved {} vertices; its stretch strain is {:.3g}",
                    report_.self_untangled_vertices, max_stretch_strain(model_, x_));
      if (report_.self_untangle_left > 0) {
        report_.self_untangle_warning = fmt::format(
            "{} pair(s) of cloth triangles pass through each other at the start around "
            "({:.3f}, {:.3f}, {:.3f}) m and stay so: separating them would stretch the cloth "
            "more than {:.0f} % (or took every round); the layers there may stay through each "
            "other (validate names the panel: sliver or folded quads there)",
            report_.self_untangle_left, left_at.x(), left_at.y(), left_at.z(),
            100.0 * kUntangleStrainShare * settings_.max_strain);
        spdlog::warn("sim: {}", report_.self_untangle_warning);
      }
    }
    report_.self_collision_s +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  // New vertex numbering: the contact cache and last step's contacts no longer apply.
  if (contact_) {
    contact_->set_fabric_friction(model_.fabric.friction);
    contact_->set_cloth_triangles(model_);
    contact_->reset_cloth(x_, model_.mass, settings_.forces.gravity.norm());
    report_.collision_s += contact_->step_stats().collision_seconds;
  }
}

void Simulation::replace_model(ClothModel model, Eigen::VectorXd x, Eigen::VectorXd v,
                               std::vector<Pin> pins, const std::vector<VertexOrigin>& origin) {
  flush_energy_sample();
  if (static_cast<int>(origin.size()) != model.vertex_count)
    throw std::invalid_argument("replace_model needs the origin of every new cloth vertex");
  // Normal force per unit mass (N/kg) of every old vertex, NaN without a pressed contact.
  std::vector<double> specific;
  if (contact_) {
    specific = contact_->last_normal_forces();
    for (std::size_t i = 0; i < specific.size(); ++i)
      specific[i] /= model_.mass[static_cast<Eigen::Index>(i)];
  }
  // The still stretch's displacement of every old vertex (m), carried to the new ones so that
  // the at-rest drift measures from where the stretch began, not from the mesh change (a drape
  // that adapted reported a drift of 0 while its hem still moved at 9 cm/s).
  Eigen::VectorXd displaced;
  if (rest_anchor_.size() == x_.size()) displaced = x_ - rest_anchor_;
  replace_model(std::move(model), std::move(x), std::move(v), std::move(pins));
  if (displaced.size() > 0) {
    const auto moved = [&](int i) -> Eigen::Vector3d {
      if (i < 0 || 3 * i + 2 >= displaced.size()) return Eigen::Vector3d::Zero();
      return displaced.segment<3>(3 * i);
    };
    for (std::size_t i = 0; i < origin.size(); ++i) {
      // A vertex made between two old ones moved as their mean; one without an origin as new.
      const VertexOrigin& o = origin[i];
      const Eigen::Vector3d d =
          o.b < 0 || o.b == o.a ? moved(o.a) : 0.5 * (moved(o.a) + moved(o.b));
      rest_anchor_.segment<3>(3 * static_cast<Eigen::Index>(i)) -= d;
    }
  }
  if (!contact_) return;
  const auto old_force = [&](int i) {
    if (i < 0 || i >= static_cast<int>(specific.size()))
      return std::numeric_limits<double>::quiet_NaN();
    return specific[static_cast<std::size_t>(i)];
  };
  std::vector<double> forces(origin.size());
  for (std::size_t i = 0; i < origin.size(); ++i) {
    // NaN (no contact) unless both origins had one: the mean force per unit mass, times the
    // new mass (a particle's share of a pressure scales with its mass, i.e. its area).
    const double f = 0.5 * (old_force(origin[i].a) + old_force(origin[i].b));
    forces[i] = f * model_.mass[static_cast<Eigen::Index>(i)];
  }
  contact_->restore_normal_forces(std::move(forces));
}

void Simulation::set_body(const meshing::TriMesh& body) {
  contact_ = std::make_unique<ContactResponse>(body, settings_.contact);
  start_body();
}

void Simulation::set_body_motion(PoseSequence motion) {
  contact_ = std::make_unique<ContactResponse>(std::move(motion), time_, settings_.contact);
  start_body();
}

void Simulation::clear_body() {
  contact_.reset();
}

void Simulation::start_body() {
  contact_->set_fabric_friction(model_.fabric.friction);
  contact_->set_cloth_triangles(model_);
  contact_->reset_cloth(x_, model_.mass, settings_.forces.gravity.norm());
  const StartRepair& repair = contact_->start_repair();
  report_.start_repair_vertices = static_cast<int>(repair.pushed.size());
  report_.start_repair_depth_m = repair.max_depth;
  report_.collision_s += contact_->step_stats().collision_seconds;
}

void Simulation::set_velocities(const Eigen::VectorXd& v) {
  flush_energy_sample();
  if (v.size() != x_.size() || !v.allFinite())
    throw std::invalid_argument("velocities must be finite, 3 per cloth vertex");
  v_ = v;
  has_history_ = false;
}

void Simulation::flush_energy_sample(const EnergyBreakdown* energy) {
  if (!energy_pending_) return;
  energy_pending_ = false;
  const EnergyBreakdown e = energy != nullptr ? *energy : this->energy();
  report_.energy.push_back({time_, e.stretch, e.shear, e.bend, e.kinetic, e.potential});
}

EnergyBreakdown Simulation::energy() const {
  Eigen::VectorXd force;
  EnergyBreakdown energy;
  evaluate_forces(model_, settings_.forces, x_, v_, force, &energy);
  return energy;
}

double Simulation::residual_force() const {
  Eigen::VectorXd force;
  evaluate_forces(model_, settings_.forces, x_, Eigen::VectorXd::Zero(x_.size()), force);
  ConstraintFilter filter(model_.vertex_count);
  for (const Pin& pin : pins_) filter.pin(pin.vertex, Eigen::Vector3d::Zero());
  filter.apply(force);
  return force.lpNorm<Eigen::Infinity>();
}

Simulation::Attempt Simulation::attempt(double h) {
  Attempt result;
  const bool bdf2 = settings_.integrator == Integrator::bdf2;
  const int newton =
      fallback_ || linearised_steps_ > 0 ? 1 : settings_.newton_iterations.value_or(bdf2 ? 8 : 1);
  NewtonSettings newton_settings;
  newton_settings.max_iterations = newton;
  newton_settings.tolerance = settings_.newton_tolerance;
  newton_settings.solver = settings_.solver;
  newton_settings.pcg_tolerance = settings_.pcg_tolerance;
  newton_settings.pcg_max_iterations = settings_.pcg_max_iterations;
  newton_settings.pcg_preconditioner = settings_.pcg_preconditioner;
  newton_settings.factor_reuse_iterations = settings_.factor_reuse_iterations;
  newton_settings.factor_reuse_tolerance = settings_.factor_reuse_tolerance;

  // Variable-step BDF2 (ω = h/h_prev): y1 − (1+ω)²/(1+2ω) y0 + ω²/(1+2ω) y−1 = h(1+ω)/(1+2ω) f1.
  Eigen::VectorXd x_hat, v_hat, x_lin, v_lin;
  double beta = h;
  if (bdf2 && has_history_) {
    const double omega = h / h_previous_;
    const double a0 = (1.0 + omega) * (1.0 + omega) / (1.0 + 2.0 * omega);
    const double a1 = omega * omega / (1.0 + 2.0 * omega);
    beta = h * (1.0 + omega) / (1.0 + 2.0 * omega);
    x_hat = a0 * x_ - a1 * x_previous_;
    v_hat = a0 * v_ - a1 * v_previous_;
    v_lin = v_ + omega * (v_ - v_previous_);  // linear extrapolation of the velocity
    x_lin = x_hat + beta * v_lin;
    // A single iteration is the linearly implicit BDF2 step: linearised at the start of the
    // step like Baraff & Witkin's implicit Euler (stable on stiff cloth, where the predictor
    // is not; see the fallback in step()).
    if (newton == 1) {
      x_lin = x_;
      v_lin = v_;
    }
  } else {
    x_hat = x_;
    v_hat = v_;
    x_lin = x_;
    v_lin = v_;
  }
  filter_.clear();
  for (std::size_t k = 0; k < pins_.size(); ++k) {
    const int i = pins_[k].vertex;
    const Eigen::Vector3d target = pins_[k].path ? pins_[k].path(time_ + h) : pin_rest_[k];
    filter_.pin(i, (target - x_hat.segment<3>(3 * i)) / beta);
  }
  // Body contact (see sim/contact_response.hpp): start contacts constrain the normal velocity
  // and correct the start by y; after each solve, friction, then vertices that still ended too
  // deep join the constraints and the step is solved again.
  ContactResponse* contact = settings_.contact.enabled ? contact_.get() : nullptr;
  Eigen::VectorXd& y = result.correction;
  if (contact != nullptr) {
    contact->move_body_to(time_, h);
    contact->constrain_start(x_hat, v_, beta, filter_, y, contact_forces_);
  }
  // Self-contact (sim/self_contact.hpp): repulsion springs of the layers closer than the
  // thickness at the start, joining the body's forces in the solve.
  SelfContactResponse* self = self_contact_.get();
  std::vector<unsigned char> pinned;
  if (self != nullptr) {
    if (contact == nullptr) contact_forces_.clear();
    pinned.assign(static_cast<std::size_t>(model_.vertex_count), 0);
    for (int i = 0; i < model_.vertex_count; ++i) pinned[i] = filter_.is_pinned(i);
    self->add_springs(y.size() == x_.size() ? Eigen::VectorXd(x_ + y) : x_, model_.mass, pinned,
                      contact_forces_, &v_, beta);
  }
  // The pending energy sample from this solve's first force evaluation when it is at the
  // current state: implicit Euler's (and BDF2's linearised step's) x_lin = x_, v_lin = v_, with
  // no contact correction (y = 0: x_lin + y is x_ to the bit). The contact and self-contact
  // forces join the solve apart from the cloth's (ImplicitSolver::add_extra_force) and are not
  // in the sample. A garment's own evaluation was 3.7 % of its drape (docs/benchmarks.md,
  // "Eighth round").
  EnergyBreakdown start_energy;
  const bool uncorrected = y.size() == 0 || (y.array() == 0.0).all();
  const bool sample_here =
      energy_pending_ && uncorrected && (!(bdf2 && has_history_) || newton == 1);
  if (sample_here)
    solver_.request_start_energy(&start_energy);
  else
    flush_energy_sample();  // evaluated here, before the step moves the state
  for (;;) {
    if (contact != nullptr) {
      result.solve = solver_.solve(model_, settings_.forces, filter_, x_hat + y, v_hat, beta,
                                   x_lin + y, v_lin, newton_settings, &contact_forces_);
    } else if (self != nullptr) {
      result.solve = solver_.solve(model_, settings_.forces, filter_, x_hat, v_hat, beta, x_lin,
                                   v_lin, newton_settings, &contact_forces_);
    } else {
      result.solve = solver_.solve(model_, settings_.forces, filter_, x_hat, v_hat, beta, x_lin,
                                   v_lin, newton_settings);
    }
    result.forces_seconds += result.solve.forces_seconds;
    result.solve_seconds += result.solve.solve_seconds;
    result.linear_solves += result.solve.linear_solves;
    result.cg_iterations += result.solve.cg_iterations;
    result.cg_iterations_max = std::max(result.cg_iterations_max, result.solve.cg_iterations_max);
    if (sample_here) flush_energy_sample(&start_energy);  // the first pass only: then not pending
    result.x = std::move(result.solve.x);
    result.v = std::move(result.solve.v);
    if (result.solve.cholmod_failures > 0)
      spdlog::debug(
          "sim: t = {:.6f} s: the CHOLMOD factorisation failed {} time(s); PCG solved "
          "instead{}",
          time_, result.solve.cholmod_failures,
          result.solve.linear_failure.empty() ? "" : " (and failed)");
    if (!result.solve.linear_failure.empty()) break;
    if (contact == nullptr || !result.solve.linear_converged || !result.x.allFinite() ||
        !result.v.allFinite())
      break;
    contact->apply_friction(result.solve.constraint_impulse, model_.mass, x_hat + y, beta, result.v,
                            result.x);
    if (contact->constrain_deep(x_, result.x, x_hat, beta, filter_, y, contact_forces_) == 0) {
      contact->finish_step(result.x, result.v, contact_forces_);
      break;
    }
  }

  // Friction between layers, then the fail-safe on the step's straight paths (impulses, impact
  // zones): the cloth leaves the step without passing through itself. The paths start at the
  // accepted state, before the body's position correction, so that a correction pushing a
  // vertex out of the body cannot carry it through a layer lying on it unseen.
  if (self != nullptr && result.solve.linear_converged && result.x.allFinite() &&
      result.v.allFinite()) {
    // In the fail-safe, vertices the body's contact constrains are heavy: cloth pinched between
    // cloth and body gives way on its free side rather than into the body.
    for (int i = 0; i < model_.vertex_count; ++i)
      if (pinned[i] == 0 && !filter_.is_free(i)) pinned[i] = kHeldByBody;
    self->resolve(x_, result.x, result.v, beta, model_.mass, pinned, contact_forces_);
  }

  std::ostringstream why;
  // Where a failing attempt broke: its first non-finite vertex, else its fastest one.
  for (Eigen::Index i = 0; i < result.v.size() / 3 && result.failure_vertex < 0; ++i)
    if (!result.x.segment<3>(3 * i).allFinite() || !result.v.segment<3>(3 * i).allFinite())
      result.failure_vertex = static_cast<int>(i);
  if (result.failure_vertex < 0 && result.v.size() >= 3) {
    double fastest = -1.0;
    for (Eigen::Index i = 0; i < result.v.size() / 3; ++i)
      if (const double speed = result.v.segment<3>(3 * i).norm(); speed > fastest)
        fastest = speed, result.failure_vertex = static_cast<int>(i);
  }
  if (!result.solve.linear_failure.empty()) {
    // No step came out of the solve: never accepted, not even at the minimum step.
    why << result.solve.linear_failure;
    result.hard_failure = true;
  } else if (!result.x.allFinite() || !result.v.allFinite()) {
    why << "non-finite positions or velocities";
    result.hard_failure = true;
  } else if (const double speed = max_speed(result.v); speed > settings_.max_speed) {
    why << "a vertex reached " << speed << " m/s (limit " << settings_.max_speed << ")";
    result.hard_failure = true;
  } else if (!result.solve.linear_converged) {
    why << (settings_.solver == LinearSolverKind::pcg ? "PCG did not converge"
                                                      : "CHOLMOD factorisation failed");
  } else if (!result.solve.newton_converged) {
    why << "Newton did not converge in " << result.solve.newton_iterations
        << " iterations (last update " << result.solve.last_update << " m)";
  } else if (const double strain = max_stretch_strain(model_, result.x);
             strain > settings_.max_strain) {
    why << "stretch strain " << strain << " above the limit " << settings_.max_strain;
  }
  result.failure = why.str();
  return result;
}

void Simulation::accept(Attempt& attempt, double h) {
  // The position correction moved the start: shift the history with it, so that BDF2 does not
  // read the correction as motion (x̂ = a0 x0 − a1 x−1 with a0 − a1 = 1 moves by y exactly).
  if (attempt.correction.size() == x_.size()) x_ += attempt.correction;
  x_previous_ = std::move(x_);
  v_previous_ = std::move(v_);
  x_ = std::move(attempt.x);
  v_ = std::move(attempt.v);
  h_previous_ = h;
  has_history_ = true;
  time_ += h;
  ++report_.steps;
  report_.sim_time = time_;
  report_.dt_min_used = report_.steps == 1 ? h : std::min(report_.dt_min_used, h);
  report_.dt_max_used = std::max(report_.dt_max_used, h);
  if (contact_ && settings_.contact.enabled) {
    const ContactStepStats& stats = contact_->step_stats();
    report_.contacts_max = std::max(report_.contacts_max, stats.contacts);
    report_.contacts_final = stats.contacts;
    report_.max_penetration_m = std::max(report_.max_penetration_m, stats.max_penetration);
    report_.contact_resolves += stats.resolves;
    report_.projected_vertices += stats.projected;
    contact_->accept_step(attempt.solve.constraint_impulse);
  }
  if (self_contact_) {
    self_contact_->accept_step();
    const SelfContactStepStats& stats = self_contact_->step_stats();
    report_.self_contacts_max = std::max(report_.self_contacts_max, stats.springs);
    report_.self_contacts_final = stats.springs;
    report_.self_collisions += stats.collisions;
    report_.self_zone_vertices += stats.zone_vertices;
    if (stats.unresolved) ++report_.self_unresolved_steps;
    report_.self_culled_triangles += stats.culled_triangles;
    report_.self_tested_triangles += stats.triangles;
    // Kept current here: the adaptive driver steps without run().
    report_.self_culled_share =
        report_.self_tested_triangles > 0
            ? static_cast<double>(report_.self_culled_triangles) / report_.self_tested_triangles
            : 0.0;
  }

  const double mass = model_.total_mass();
  const double speed = max_speed(v_);
  const double kinetic = kinetic_energy(model_, v_);
  // A body still moving (a pose sequence not yet over) is not a scene at rest.
  const bool body_moving = contact_ && contact_->motion() && time_ < contact_->motion()->end_time();
  moved_ = moved_ || kinetic / mass > settings_.settled_energy;
  if (report_.settled_time < 0.0 && moved_ && !body_moving && time_ >= settings_.rest_not_before &&
      kinetic / mass < settings_.settled_energy)
    report_.settled_time = time_;
  while (!unsettled_retry_times_.empty() &&
         unsettled_retry_times_.front() < time_ - settings_.unsettled_window)
    unsettled_retry_times_.pop_front();
  rest_history_.push_back({time_, speed, kinetic / mass, h});
  std::erase_if(rest_history_, [this](const std::array<double, 4>& r) {
    return r[0] < time_ - settings_.rest_window - 1e-12;
  });
  report_.rest_speed_final = speed;
  report_.rest_kinetic_per_kg_final = kinetic / mass;
  report_.rest_speed_window = report_.rest_kinetic_per_kg_window = 0.0;
  // The kinetic energy's time mean over the window: each step's sample stands for its step, the
  // steps that ended inside the window.
  double energy_time = 0.0, window_time = 0.0;
  for (const auto& [t, s, k, step] : rest_history_) {
    report_.rest_speed_window = std::max(report_.rest_speed_window, s);
    report_.rest_kinetic_per_kg_window = std::max(report_.rest_kinetic_per_kg_window, k);
    if (t <= time_ - settings_.rest_window + 1e-12) continue;
    energy_time += k * step;
    window_time += step;
  }
  report_.rest_kinetic_per_kg_window_mean = window_time > 0.0 ? energy_time / window_time : 0.0;
  // The still stretch is measured from an anchor: the positions when it began. A vertex
  // chattering in place (sub-millimetre steps between contacts, its speed flipping every step)
  // stays near the anchor; a hem still swinging or creeping faster than rest_speed leaves it.
  // A step is still when its kinetic energy, or the energy's mean over the window, is below the
  // bound, and at rest asks for the mean (at_rest()): the t-shirt at 2 cm edges kept a patch of
  // its underarm chattering between its self-contact springs and the fail-safe (0.2-1 mm of
  // drift in 0.25 s, 2-5 cm/s at single steps), whose energy rose above 1e-6 J/kg at one step in
  // five while its mean stayed below, and it never rested in its 10 s. Where the energy decays
  // without chatter its mean over the last window lags above it, so a step is still when its
  // own energy is below the bound, as before (docs/simulator.md, "Step control and at rest").
  const double drift_limit = settings_.rest_speed * settings_.rest_window;
  double drift = 0.0;
  int drift_vertex = -1;
  const bool anchored = rest_anchor_.size() == x_.size();
  if (anchored)
    for (Eigen::Index i = 0; i < x_.size() / 3; ++i) {
      const double d = (x_.segment<3>(3 * i) - rest_anchor_.segment<3>(3 * i)).norm();
      if (d > drift) drift = d, drift_vertex = static_cast<int>(i);
    }
  const bool calm = kinetic / mass < settings_.rest_kinetic_energy ||
                    report_.rest_kinetic_per_kg_window_mean < settings_.rest_kinetic_energy;
  report_.rest_break = body_moving                         ? RestBreak::body_moving
                       : time_ < settings_.rest_not_before ? RestBreak::too_early
                       : !anchored                         ? RestBreak::new_anchor
                       : !calm                             ? RestBreak::kinetic_energy
                       : drift > drift_limit               ? RestBreak::drift
                                                           : RestBreak::none;
  report_.rest_break_vertex = drift_vertex;
  report_.rest_break_drift = drift;
  const bool still = report_.rest_break == RestBreak::none;
  if (still) {
    rest_time_ += h;
    report_.rest_drift = drift;
    report_.rest_still_time = rest_time_;
  } else {
    rest_anchor_ = x_;
    rest_time_ = 0.0;
    report_.rest_still_time = 0.0;
    // Not in a still stretch: there is no drift to give (NaN, "null" in report.json), not 0,
    // which read as perfectly still next to a final speed of 9 cm/s.
    report_.rest_drift = std::numeric_limits<double>::quiet_NaN();
  }
}

StepOutcome Simulation::step(double max_step) {
  StepOutcome outcome;
  // Stuck at the minimum step (SimulationSettings::stuck_steps): no further step, a failure
  // that says so, with the state of the last accepted step left as it is.
  if (settings_.stuck_steps > 0 &&
      static_cast<int>(recent_forced_.size()) >= settings_.stuck_steps &&
      recent_forced_count_ >= settings_.stuck_share * settings_.stuck_steps) {
    const bool stretched = last_forced_reason_.starts_with("stretch strain");
    outcome.stuck = true;
    outcome.dt = settings_.min_dt;
    outcome.failure_vertex = stretched ? most_stretched_vertex(model_, x_) : last_forced_vertex_;
    std::ostringstream why;
    why << "stuck: " << recent_forced_count_ << " of the last " << recent_forced_.size()
        << " steps were taken at the minimum step " << last_forced_dt_ << " s despite a failed "
        << "check (the last: " << last_forced_reason_ << "), "
        << (stretched ? "the cloth held stretched beyond the limit" : "without progress")
        << " and the simulated time crawling; it would not finish";
    outcome.failure_reason = why.str();
    spdlog::debug("sim: t = {:.6f} s: {}", time_, outcome.failure_reason);
    return outcome;
  }
  // Settled once and thrown about again (SimulationSettings::unsettled_retries): no further
  // step, a failure that says where, before a vertex flies off.
  if (settings_.unsettled_retries > 0 &&
      static_cast<int>(unsettled_retry_times_.size()) >= settings_.unsettled_retries) {
    outcome.unsettled = true;
    outcome.dt = dt_;
    outcome.failure_vertex = last_retry_vertex_;
    outcome.failure_reason = fmt::format(
        "thrown about: the drape had settled (kinetic energy below {:.3g} J/kg at t = {:.2f} s), "
        "then {} steps within {:.3g} s failed their checks here and were retried shorter (the "
        "last: {}); cloth caught in a crease of the body (a cleft: the seat, between the legs) "
        "and pumped by its contacts would blow up, so the drape stops; move the seam junction "
        "there out of the crease or let the panel bridge it (validate names a junction in a "
        "cleft)",
        settings_.settled_energy, report_.settled_time, unsettled_retry_times_.size(),
        settings_.unsettled_window, last_retry_reason_);
    spdlog::debug("sim: t = {:.6f} s: {}", time_, outcome.failure_reason);
    return outcome;
  }
  double h = std::min(dt_, max_step);
  const double planned = dt_;  // before a cut to land on max_step
  // Land exactly on max_step instead of leaving a sliver for the next step.
  if (max_step - h < 1e-3 * h) h = max_step;
  Attempt candidate;
  for (;;) {
    candidate = attempt(h);
    report_.forces_s += candidate.forces_seconds;
    report_.solve_s += candidate.solve_seconds;
    if (contact_) report_.collision_s += contact_->step_stats().collision_seconds;
    if (self_contact_) report_.self_collision_s += self_contact_->step_stats().seconds;
    report_.linear_solves += candidate.linear_solves;
    cg_total_ += candidate.cg_iterations;
    report_.cg_iterations_max = std::max(report_.cg_iterations_max, candidate.cg_iterations_max);
    if (candidate.failure.empty()) break;
    last_retry_reason_ = candidate.failure;
    last_retry_vertex_ = candidate.failure_vertex;
    // A BDF2 step whose Newton iteration failed is first retried at the same step as the
    // linearly implicit step, one solve linearised at the start (implicit Euler for the first
    // step); only a failure of that one halves the step.
    if (settings_.integrator == Integrator::bdf2 && !fallback_ &&
        settings_.newton_iterations.value_or(8) > 1) {
      ++outcome.retries;
      ++report_.retries;
      ++report_.integrator_fallbacks;
      spdlog::debug("sim: t = {:.6f} s: BDF2 step {:.4g} s rejected ({}), retrying linearised",
                    time_, h, candidate.failure);
      fallback_ = true;
      // Newton is likely to fail on the next steps too: stay linearised for a few.
      linearised_steps_ = settings_.easy_steps_to_grow;
      continue;
    }
    if (h * 0.5 < settings_.min_dt) {
      if (!candidate.hard_failure) {
        // The first few one by one; the rest counted, and summed up at the end of the run.
        if (report_.forced_steps < kForcedStepsLogged)
          spdlog::warn(
              "sim: t = {:.6f} s: accepting a step of {:.3g} s at the minimum despite: {}{}", time_,
              h, candidate.failure,
              report_.forced_steps + 1 == kForcedStepsLogged
                  ? " (further such steps are counted, not printed; the sum comes at the end)"
                  : "");
        else
          spdlog::debug(
              "sim: t = {:.6f} s: accepting a step of {:.3g} s at the minimum despite: {}", time_,
              h, candidate.failure);
        ++report_.forced_steps;
        last_forced_reason_ = candidate.failure;
        last_forced_vertex_ = candidate.failure_vertex;
        last_forced_dt_ = h;
        outcome.forced = true;
        break;
      }
      // A debug line: the caller says it once, with where (run: "the simulation failed at t =
      // ... in panel ..."; trial 39, P13 found this one printed raw before it).
      spdlog::debug("sim: t = {:.6f} s: step failed at the minimum step {:.3g} s: {}", time_, h,
                    candidate.failure);
      outcome.failure_reason = candidate.failure;
      outcome.failure_vertex = candidate.failure_vertex;
      outcome.dt = h;
      return outcome;
    }
    ++outcome.retries;
    ++report_.retries;
    spdlog::debug("sim: t = {:.6f} s: step {:.4g} s rejected ({}), retrying with {:.4g} s", time_,
                  h, candidate.failure, 0.5 * h);
    h *= 0.5;
    dt_ = h;
    easy_steps_ = 0;
  }
  if (!fallback_ && linearised_steps_ > 0) --linearised_steps_;
  fallback_ = false;
  outcome.accepted = true;
  outcome.dt = h;
  if (report_.settled_time >= 0.0 && (outcome.retries > 0 || outcome.forced))
    unsettled_retry_times_.push_back(time_);
  outcome.newton_iterations = candidate.solve.newton_iterations;
  outcome.cg_iterations = candidate.cg_iterations;
  newton_total_ += candidate.solve.newton_iterations;
  accept(candidate, h);
  if (settings_.stuck_steps > 0) {
    recent_forced_.push_back(outcome.forced);
    recent_forced_count_ += outcome.forced ? 1 : 0;
    if (static_cast<int>(recent_forced_.size()) > settings_.stuck_steps) {
      recent_forced_count_ -= recent_forced_.front() ? 1 : 0;
      recent_forced_.pop_front();
    }
  }

  // Grow back after a run of easy steps: no retry and Newton converging in a few iterations.
  const int newton_budget =
      settings_.newton_iterations.value_or(settings_.integrator == Integrator::bdf2 ? 8 : 1);
  const bool easy = outcome.retries == 0 && !outcome.forced &&
                    outcome.newton_iterations <= std::max(1, (newton_budget + 1) / 2);
  easy_steps_ = easy ? easy_steps_ + 1 : 0;
  if (easy_steps_ >= settings_.easy_steps_to_grow && dt_ < settings_.dt) {
    const double factor = settings_.integrator == Integrator::bdf2
                              ? std::min(settings_.grow_factor, 2.0)
                              : settings_.grow_factor;
    dt_ = std::min(settings_.dt, dt_ * factor);
    easy_steps_ = 0;
    spdlog::debug("sim: t = {:.6f} s: step grows to {:.4g} s", time_, dt_);
  }
  if (error_controlled() && v_previous_.size() == v_.size()) {
    // Implicit Euler's local error (SimulationSettings::step_error): x1 = x0 + h v1 against
    // x0 + h v0 + (h²/2) a, i.e. (h/2)(v1 − v0), as an RMS over the vertices; it scales with h²,
    // hence the square root and a proposal that does not depend on h (a step cut short to land
    // on max_step proposes the same; its bounds are those of the step planned). After a
    // rejected attempt the step does not grow.
    const double estimate = 0.5 * h * (v_ - v_previous_).norm() / std::sqrt(v_.size() / 3.0);
    const double base = outcome.retries > 0 ? h : std::max(h, planned);
    double next =
        estimate > 0.0 ? 0.9 * h * std::sqrt(settings_.step_error / estimate) : 2.0 * base;
    next = std::clamp(next, 0.5 * base, 2.0 * base);
    if (outcome.retries > 0 || outcome.forced) next = std::min(next, h);
    dt_ = std::clamp(next, settings_.min_dt, settings_.dt);
    easy_steps_ = 0;
  }
  return outcome;
}

SimulationReport Simulation::run(const std::function<void(const Simulation&)>& on_step) {
  RunHooks hooks;
  if (on_step)
    hooks.after_step = [&](const StepOutcome& outcome) {
      if (outcome.accepted) on_step(*this);
      return true;
    };
  return run(hooks);
}

SimulationReport Simulation::run(const RunHooks& hooks) {
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = process_cpu_seconds();
  const double forces_before = report_.forces_s;
  const double solve_before = report_.solve_s;
  const double collision_before = report_.collision_s;
  const double self_before = report_.self_collision_s;
  const auto sample = [&] {
    if (!settings_.record_energy) return;
    energy_pending_ = true;
    if (!settings_.energy_from_next_step) flush_energy_sample();
  };
  if (report_.energy.empty()) sample();
  const double epsilon = 1e-9 * std::max(1.0, settings_.duration);
  while (time_ < settings_.duration - epsilon) {
    const double max_step = settings_.duration - time_;
    const StepOutcome outcome = hooks.step ? hooks.step(max_step) : step(max_step);
    if (!outcome.accepted) {
      report_.failed = true;
      report_.stuck = outcome.stuck;
      report_.unsettled = outcome.unsettled;
      report_.failure_reason = outcome.failure_reason;
      report_.failure_vertex = outcome.failure_vertex;
      if (hooks.after_step) hooks.after_step(outcome);
      break;
    }
    sample();
    if (hooks.after_step && !hooks.after_step(outcome)) break;
    if (settings_.stop_at_rest && at_rest()) {
      report_.at_rest = true;
      break;
    }
  }
  flush_energy_sample();
  if (report_.forced_steps > kForcedStepsLogged)
    spdlog::warn(
        "sim: {} of {} steps were taken at the minimum step {:.3g} s despite a failed "
        "check (the first {} printed above)",
        report_.forced_steps, report_.steps, last_forced_dt_, kForcedStepsLogged);
  if (contact_ && settings_.contact.enabled) {
    const auto query_start = std::chrono::steady_clock::now();
    report_.penetrating_vertices_final = contact_->count_penetrating(x_);
    report_.piercing_body_vertices_final =
        contact_->count_piercing(x_, &report_.max_piercing_final_m);
    report_.collision_s +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - query_start).count();
  }
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  report_.wall_time_s += wall;
  report_.cpu_time_s += process_cpu_seconds() - cpu_start;
  report_.other_s += wall - (report_.forces_s - forces_before) - (report_.solve_s - solve_before) -
                     (report_.collision_s - collision_before) -
                     (report_.self_collision_s - self_before);
  report_.cg_iterations_mean =
      report_.linear_solves > 0 ? static_cast<double>(cg_total_) / report_.linear_solves : 0.0;
  report_.newton_iterations_mean =
      report_.steps > 0 ? static_cast<double>(newton_total_) / report_.steps : 0.0;
  report_.max_strain = max_stretch_strain(model_, x_);
  const PrincipalStrain principal = max_principal_strain(model_, x_);
  report_.max_principal_stretch = principal.stretch;
  report_.max_principal_compression = principal.compression;
  report_.nan_free = x_.allFinite() && v_.allFinite();
  report_.cholmod_factorizations = solver_.cholmod().numeric_factorizations();
  report_.cholmod_analyses = solver_.cholmod().symbolic_analyses();
  if (settings_.solver == LinearSolverKind::cholmod)
    spdlog::debug("sim: CHOLMOD: {} symbolic analyses, {} numeric factorisations",
                  solver_.cholmod().symbolic_analyses(),
                  solver_.cholmod().numeric_factorizations());
  return report_;
}

}  // namespace sd::sim
