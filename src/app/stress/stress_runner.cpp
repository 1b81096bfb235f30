#include "src/app/stress/stress_runner.hpp"

#include <fmt/format.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <memory>
#include <optional>
#include <random>
#include <stdexcept>

#include "sim/cloth_driver.hpp"
#include "sim/forces.hpp"
#include "src/app/pipeline/self_intersections.hpp"

namespace sd::app {
namespace {

using Clock = std::chrono::steady_clock;

double max_vertex_speed(const Eigen::VectorXd& v) {
  double speed = 0.0;
  for (Eigen::Index i = 0; i < v.size() / 3; ++i)
    speed = std::max(speed, v.segment<3>(3 * i).norm());
  return speed;
}

// The cloth being stressed: a fixed model or an adaptive 4-8 mesh, in one driver.
sim::ClothDriver make_driver(StressScene& scene, const sim::SimulationSettings& settings) {
  if (!scene.adaptive) {
    sim::ClothDriver driver(std::move(scene.model), scene.x0, scene.pins, settings);
    if (scene.body) driver.set_body_motion(std::move(*scene.body));
    if (scene.v0.size() > 0) driver.set_velocities(scene.v0);
    return driver;
  }
  StressAdaptive& a = *scene.adaptive;
  if (scene.v0.size() > 0)
    throw std::invalid_argument("start velocities are not supported for adaptive cases");
  Eigen::MatrixX3d start;
  if (scene.x0.size() > 0) start = sim::unflatten_positions(scene.x0);
  sim::ClothDriver driver(std::move(a.mesh), a.material, start, a.pins, settings, a.settings);
  if (a.start_level > 0) driver.adaptive()->refine_uniformly(a.start_level);
  return driver;
}

// Forced churn: one random block (fixed seed) split or merged before every step. Returns whether
// the mesh changed.
class Churner {
 public:
  explicit Churner(int max_level) : max_level_(max_level) {}
  bool churn(sim::AdaptiveCloth& cloth) {
    const meshing::Mesh48& mesh = cloth.mesh();
    const std::vector<meshing::BlockId> mergeable = mesh.mergeable_blocks();
    std::vector<meshing::BlockId> splittable;
    for (meshing::BlockId k : mesh.leaf_blocks())
      if (mesh.level(k) < max_level_) splittable.push_back(k);
    const bool merge = !mergeable.empty() && (splittable.empty() || rng_() % 2 == 0);
    const sim::AdaptStats stats =
        merge ? cloth.merge_blocks({mergeable[rng_() % mergeable.size()]})
              : (splittable.empty() ? sim::AdaptStats{}
                                    : cloth.split_blocks({splittable[rng_() % splittable.size()]}));
    return stats.changed();
  }

 private:
  int max_level_;
  std::mt19937 rng_{20261122};
};

void fail(StressResult& r, std::string status, std::string reason) {
  r.status = std::move(status);
  r.reason = std::move(reason);
  r.ok = false;
}

}  // namespace

StressResult run_stress_case(const StressCase& c, const StressOptions& options) {
  StressResult r;
  r.id = c.id;
  r.family = c.family;
  r.condition = c.condition;
  r.parameters = c.parameters;
  sim::SimulationSettings settings = c.settings;
  if (options.min_dt) settings.min_dt = std::min(*options.min_dt, settings.dt);
  r.duration = settings.duration;
  r.dt = settings.dt;
  r.min_dt = settings.min_dt;
  r.speed_bound = settings.max_speed;
  const auto start = Clock::now();
  const auto finish = [&] {
    r.wall_time_s = std::chrono::duration<double>(Clock::now() - start).count();
    return r;
  };

  std::optional<sim::ClothDriver> driver;
  StressScene scene;
  // The driver's own energy series is not needed: the bounds read the energy themselves.
  settings.record_energy = false;
  try {
    scene = c.build();
    driver.emplace(make_driver(scene, settings));
  } catch (const std::invalid_argument& e) {
    r.finite = true;
    if (c.expect_rejection) {
      r.status = "rejected";
      r.ok = true;
      r.reason = e.what();
    } else {
      fail(r, "error", fmt::format("the case could not be set up: {}", e.what()));
    }
    return finish();
  } catch (const std::exception& e) {
    fail(r, "error", fmt::format("the case could not be set up: {}", e.what()));
    return finish();
  }
  if (c.expect_rejection) {
    fail(r, "error", "the invalid start was accepted instead of being refused");
    return finish();
  }

  const auto model_of = [&]() -> const sim::ClothModel& { return driver->simulation().model(); };
  const auto strain_now = [&] {
    return sim::max_stretch_strain(model_of(), driver->simulation().positions());
  };
  r.vertices = model_of().vertex_count;
  r.strain_bound = std::max(settings.max_strain, strain_now());
  const double gravity = settings.forces.gravity.norm();

  // The energy reference: the first state at or after drive_end (the start for passive cases).
  bool have_reference = false;
  double reference = 0.0;
  const auto observe_energy = [&] {
    const sim::Simulation& s = driver->simulation();
    const sim::EnergyBreakdown e = s.energy();
    if (!have_reference) {
      if (s.time() < scene.drive_end - 1e-12) return;
      have_reference = true;
      reference = e.total();
      r.energy_scale =
          model_of().total_mass() * gravity * scene.length + std::abs(e.elastic()) + e.kinetic;
      r.energy_bound = kStressEnergyTolerance * r.energy_scale;
      r.energy_growth = 0.0;
      return;
    }
    r.energy_growth = std::max(r.energy_growth, e.total() - reference);
    r.energy_final_growth = e.total() - reference;
  };

  std::optional<Churner> churner;
  if (scene.adaptive && scene.adaptive->forced_churn)
    churner.emplace(scene.adaptive->churn_max_level);
  bool changed = false;  // the mesh changed before or after the current step
  std::size_t records = 0;
  sim::ClothObserver observer;
  observer.before_step = [&](sim::ClothDriver& d) {
    changed = churner && churner->churn(*d.adaptive());
    if (d.adaptive()) records = d.adaptive_report()->steps.size();
  };
  observer.after_step = [&](const sim::ClothDriver& d, const sim::StepOutcome& outcome) {
    r.attempts += 1 + outcome.retries;
    if (!outcome.accepted) {
      fail(r, "failed",
           fmt::format("t = {:.4f} s (step {}): the simulator gave up at a step of {:.3g} s: {}",
                       d.time(), r.steps + 1, outcome.dt, outcome.failure_reason));
      return false;
    }
    ++r.steps;
    if (const sim::AdaptiveReport* a = d.adaptive_report(); a && a->steps.size() > records) {
      const sim::AdaptiveStepRecord& last = a->steps.back();
      changed = changed || last.splits + last.forced_splits + last.merges > 0;
    }
    if (changed) ++r.topology_changes;
    const sim::Simulation& now = d.simulation();
    const Eigen::VectorXd& x = now.positions();
    const Eigen::VectorXd& v = now.velocities();
    if (!x.allFinite() || !v.allFinite()) {
      r.finite = false;
      fail(r, "exploded",
           fmt::format("t = {:.4f} s (step {}): non-finite state", now.time(), r.steps));
      return false;
    }
    const double strain = strain_now();
    const double speed = max_vertex_speed(v);
    r.max_strain = std::max(r.max_strain, strain);
    r.max_speed = std::max(r.max_speed, speed);
    observe_energy();
    if (strain > r.strain_bound) {
      fail(r, "exploded",
           fmt::format("t = {:.4f} s (step {}): stretch strain {:.3g} above the bound {:.3g}",
                       now.time(), r.steps, strain, r.strain_bound));
      return false;
    }
    if (speed > r.speed_bound) {
      fail(r, "exploded",
           fmt::format("t = {:.4f} s (step {}): a vertex at {:.3g} m/s, above {:.3g}", now.time(),
                       r.steps, speed, r.speed_bound));
      return false;
    }
    if (r.attempts > kStressMaxAttempts) {
      fail(r, "stalled",
           fmt::format("t = {:.4f} s: {} step attempts spent (budget {}), last step {:.3g} s",
                       now.time(), r.attempts, kStressMaxAttempts, outcome.dt));
      return false;
    }
    return true;
  };
  try {
    observe_energy();
    const sim::SimulationReport report = driver->run(observer);
    r.at_rest = report.at_rest;
  } catch (const std::exception& e) {
    fail(r, "error", fmt::format("t = {:.4f} s: {}", driver->simulation().time(), e.what()));
  }

  if (r.status.empty() && have_reference && r.energy_final_growth > r.energy_bound)
    fail(r, "exploded",
         fmt::format("t = {:.4f} s: the cloth ends with {:.3g} J more than when it was left to "
                     "itself (bound {:.3g} J; peak excess {:.3g} J)",
                     driver->simulation().time(), r.energy_final_growth, r.energy_bound,
                     r.energy_growth));
  const sim::Simulation& s = driver->simulation();
  const sim::SimulationReport& report = s.report();
  r.sim_time = s.time();
  r.retries = report.retries;
  r.forced_steps = report.forced_steps;
  r.dt_min_used = report.dt_min_used;
  r.contacts_max = report.contacts_max;
  r.max_penetration_m = report.max_penetration_m;
  r.vertices = s.model().vertex_count;
  // Self-contact holds when the cloth ends without passing through itself (an independent
  // count on the final mesh) and no step's fail-safe left a collision.
  if (settings.self_contact.enabled) {
    const sim::ClothModel& model = s.model();
    Eigen::MatrixX3i faces(static_cast<Eigen::Index>(model.triangles.size()), 3);
    for (std::size_t t = 0; t < model.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k)
        faces(static_cast<Eigen::Index>(t), k) = model.triangles[t].vertices[k];
    r.self_intersections_final =
        count_self_intersections(sim::unflatten_positions(s.positions()), faces);
    r.self_contacts_max = report.self_contacts_max;
    if (r.status.empty() && r.self_intersections_final > 0)
      fail(r, "exploded",
           fmt::format("t = {:.4f} s: {} pairs of triangles pass through each other at the end",
                       s.time(), r.self_intersections_final));
    if (r.status.empty() && report.self_unresolved_steps > 0)
      fail(r, "exploded",
           fmt::format("{} steps ended with cloth passing through itself (the fail-safe did not "
                       "resolve them)",
                       report.self_unresolved_steps));
  }
  r.ran_to_end =
      r.status.empty() &&
      (r.at_rest || r.sim_time >= settings.duration - 1e-9 * std::max(1.0, settings.duration));
  if (r.status.empty()) {
    if (r.ran_to_end) {
      r.status = "stable";
      r.ok = true;
    } else {
      fail(r, "error", "the run stopped early without a reason");
    }
  }
  return finish();
}

nlohmann::json stress_result_json(const StressResult& r) {
  return {{"id", r.id},
          {"family", r.family},
          {"condition", r.condition},
          {"parameters", r.parameters},
          {"status", r.status},
          {"ok", r.ok},
          {"reason", r.reason},
          {"finite", r.finite},
          {"ran_to_end", r.ran_to_end},
          {"at_rest", r.at_rest},
          {"duration", r.duration},
          {"sim_time", r.sim_time},
          {"steps", r.steps},
          {"attempts", r.attempts},
          {"retries", r.retries},
          {"forced_steps", r.forced_steps},
          {"dt", r.dt},
          {"min_dt", r.min_dt},
          {"dt_min_used", r.dt_min_used},
          {"max_strain", r.max_strain},
          {"strain_bound", r.strain_bound},
          {"max_speed", r.max_speed},
          {"speed_bound", r.speed_bound},
          {"energy_scale_j", r.energy_scale},
          {"energy_peak_growth_j", r.energy_growth},
          {"energy_final_growth_j", r.energy_final_growth},
          {"energy_bound_j", r.energy_bound},
          {"vertices", r.vertices},
          {"topology_changes", r.topology_changes},
          {"contacts_max", r.contacts_max},
          {"max_penetration_m", r.max_penetration_m},
          {"self_intersections_final", r.self_intersections_final},
          {"self_contacts_max", r.self_contacts_max},
          {"wall_time_s", r.wall_time_s}};
}

StressResult stress_result_from_json(const nlohmann::json& j) {
  StressResult r;
  r.id = j.at("id");
  r.family = j.at("family");
  r.condition = j.at("condition");
  r.parameters = j.at("parameters");
  r.status = j.at("status");
  r.ok = j.at("ok");
  r.reason = j.at("reason");
  r.finite = j.at("finite");
  r.ran_to_end = j.at("ran_to_end");
  r.at_rest = j.at("at_rest");
  r.duration = j.at("duration");
  r.sim_time = j.at("sim_time");
  r.steps = j.at("steps");
  r.attempts = j.at("attempts");
  r.retries = j.at("retries");
  r.forced_steps = j.at("forced_steps");
  r.dt = j.at("dt");
  r.min_dt = j.at("min_dt");
  r.dt_min_used = j.at("dt_min_used");
  r.max_strain = j.at("max_strain");
  r.strain_bound = j.at("strain_bound");
  r.max_speed = j.at("max_speed");
  r.speed_bound = j.at("speed_bound");
  r.energy_scale = j.at("energy_scale_j");
  r.energy_growth = j.at("energy_peak_growth_j");
  r.energy_final_growth = j.at("energy_final_growth_j");
  r.energy_bound = j.at("energy_bound_j");
  r.vertices = j.at("vertices");
  r.topology_changes = j.at("topology_changes");
  r.contacts_max = j.at("contacts_max");
  r.max_penetration_m = j.at("max_penetration_m");
  r.self_intersections_final = j.value("self_intersections_final", -1);
  r.self_contacts_max = j.value("self_contacts_max", 0);
  r.wall_time_s = j.at("wall_time_s");
  return r;
}

StressResult run_stress_case_isolated(const StressCase& c, const StressOptions& options) {
  const auto start = Clock::now();
  int fds[2];
  if (::pipe(fds) != 0)
    throw std::runtime_error(std::string("cannot create a pipe: ") + std::strerror(errno));
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    throw std::runtime_error(std::string("cannot start a process: ") + std::strerror(errno));
  }
  if (pid == 0) {
    ::close(fds[0]);
    int code = 0;
    try {
      const std::string bytes = stress_result_json(run_stress_case(c, options)).dump();
      for (size_t at = 0; at < bytes.size();) {
        const ssize_t n = ::write(fds[1], bytes.data() + at, bytes.size() - at);
        if (n <= 0) break;
        at += static_cast<size_t>(n);
      }
    } catch (...) {
      code = 3;
    }
    std::fflush(nullptr);
    ::_exit(code);
  }
  ::close(fds[1]);
  std::string bytes;
  char buffer[4096];
  for (;;) {
    const ssize_t n = ::read(fds[0], buffer, sizeof buffer);
    if (n > 0) {
      bytes.append(buffer, static_cast<size_t>(n));
    } else if (n == 0 || errno != EINTR) {
      break;
    }
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) {
    try {
      return stress_result_from_json(nlohmann::json::parse(bytes));
    } catch (const std::exception&) {
      // Falls through: reported as a crash below.
    }
  }
  StressResult r;
  r.id = c.id;
  r.family = c.family;
  r.condition = c.condition;
  r.parameters = c.parameters;
  r.duration = c.settings.duration;
  r.dt = c.settings.dt;
  r.min_dt = options.min_dt ? std::min(*options.min_dt, c.settings.dt) : c.settings.min_dt;
  r.speed_bound = c.settings.max_speed;
  r.finite = false;  // unknown: the process died before it could say
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    const char* name = ::strsignal(sig);
    fail(r, "crashed",
         fmt::format("the simulation process was killed by signal {} ({})", sig,
                     name != nullptr ? name : "unknown"));
  } else {
    fail(r, "crashed",
         fmt::format("the simulation process exited with code {} without a result",
                     WIFEXITED(status) ? WEXITSTATUS(status) : -1));
  }
  r.wall_time_s = std::chrono::duration<double>(Clock::now() - start).count();
  return r;
}

}  // namespace sd::app
