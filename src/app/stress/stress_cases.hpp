#pragma once
// The matrix of hostile conditions `sketchdrape stress` runs (docs/stress.md): each case is a
// recipe (scene builder + simulator settings) that builds its cloth fresh when it runs.
// Families: stiffness x10^0..10^6 crossed with the step and integrator/solver, zero damping,
// near-degenerate triangles, adaptivity churn, a fast body, pins moved abruptly, huge gravity,
// non-finite start states (which must be rejected) and large start stretch.

#include <Eigen/Core>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "meshing/mesh48.hpp"
#include "sim/adaptive_detail.hpp"
#include "sim/body_motion.hpp"
#include "sim/cloth_model.hpp"
#include "sim/simulation.hpp"

namespace sd::app {

// An adaptive (4-8 level of detail) cloth instead of a fixed mesh.
struct StressAdaptive {
  meshing::Mesh48 mesh;
  sim::AdaptiveMaterial material;
  std::vector<sim::Pin> pins;
  sim::AdaptiveSettings settings;
  int start_level = 0;  // uniform refinement before the run
  // Split or merge one random block (fixed seed) before every step, on top of what the
  // thresholds do: every step then changes the topology.
  bool forced_churn = false;
  int churn_max_level = 5;
};

// What one case simulates. Built by the case's recipe right before it runs; a recipe may throw
// std::invalid_argument (that is what a non-finite start must do).
struct StressScene {
  sim::ClothModel model;  // fixed-mesh runs (ignored when `adaptive` is set)
  Eigen::VectorXd x0;     // 3n start positions
  Eigen::VectorXd v0;     // 3n start velocities; empty: at rest
  std::vector<sim::Pin> pins;
  std::optional<sim::PoseSequence> body;  // a body the cloth collides with (possibly moving)
  std::optional<StressAdaptive> adaptive;
  // s: pins and body no longer move from this time on. From the first state at or after it,
  // the total energy may not grow (see docs/stress.md, "Bounds").
  double drive_end = 0.0;
  double length = 0.5;  // m, the cloth's size: the energy scale is M·|g|·length
};

struct StressCase {
  std::string id;         // unique, e.g. "stiffness-1e4-h1/10-bdf2-cholmod"
  std::string family;     // "stiffness", "undamped", "sliver", ...
  std::string condition;  // what is hostile, in words
  nlohmann::json parameters = nlohmann::json::object();
  sim::SimulationSettings settings;
  bool quick = false;             // part of the reduced matrix (--quick)
  bool expect_rejection = false;  // the input is invalid: the case passes when it is refused
  std::function<StressScene()> build;
};

// Every case of the full matrix, or only the --quick ones, in a fixed order.
std::vector<StressCase> stress_matrix(bool quick);

// "1/10" for 0.1 s, "1/24" for 1/24 s: how step sizes appear in ids and tables.
std::string step_label(double dt);

}  // namespace sd::app
