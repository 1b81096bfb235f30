// Body contact inside the simulator (docs/benchmarks.md, "Contacts"): a 32x32 sheet settling
// on a sphere and over the built-in mannequin's head and shoulders, time per step split into
// collision, forces, solve and the rest.
#include <benchmark/benchmark.h>

#include <algorithm>

#include "garment/body.hpp"
#include "meshing/tri_mesh.hpp"
#include "sim/sheet.hpp"
#include "sim/simulation.hpp"
#include "tests/sim/test_bodies.hpp"

namespace {

using namespace sd::sim;

struct Sheet {
  SheetScene scene;
  ClothModel model;
};

Sheet horizontal_sheet(int n, double size, const Eigen::Vector3d& centre) {
  SheetSpec spec;
  spec.size = {size, size};
  spec.columns = n;
  spec.rows = n;
  spec.orientation = SheetOrientation::horizontal;
  spec.centre = centre;
  Sheet s{build_sheet(spec), {}};
  s.model = build_cloth_model(s.scene.input, fabric_preset("cotton"));
  return s;
}

SimulationSettings settle_settings(LinearSolverKind solver, double dt) {
  SimulationSettings settings;
  settings.solver = solver;
  settings.dt = dt;
  settings.duration = 8.0;
  settings.record_energy = false;
  settings.forces.air_drag = 0.3;
  settings.contact.thickness = 0.003;
  return settings;
}

void report_counters(benchmark::State& state, const SimulationReport& report) {
  const double steps = std::max(1, report.steps);
  state.counters["steps"] = report.steps;
  state.counters["retries"] = report.retries;
  state.counters["sim_s"] = report.sim_time;
  state.counters["at_rest"] = report.at_rest;
  state.counters["wall_s"] = report.wall_time_s;
  state.counters["ms_step"] = 1e3 * report.wall_time_s / steps;
  state.counters["collision_ms"] = 1e3 * report.collision_s / steps;
  state.counters["forces_ms"] = 1e3 * report.forces_s / steps;
  state.counters["solve_ms"] = 1e3 * report.solve_s / steps;
  state.counters["other_ms"] = 1e3 * report.other_s / steps;
  state.counters["contacts_max"] = report.contacts_max;
  state.counters["resolves"] = report.contact_resolves;
  state.counters["projected"] = report.projected_vertices;
  state.counters["max_pen_mm"] = 1e3 * report.max_penetration_m;
  state.counters["cg_mean"] = report.cg_iterations_mean;
  state.counters["vertices"] = report.vertices;
}

// A 0.8 m sheet (32x32 quads, 1089 vertices) dropped from 5 cm onto a 0.25 m sphere (5120
// triangles) until at rest (or 8 s). Args: solver (0 PCG, 1 CHOLMOD), steps per second.
void BM_SheetSettlesOnSphere32(benchmark::State& state) {
  const double radius = 0.25;
  const sd::meshing::TriMesh sphere = sd::sim::testing::make_sphere(radius, 4);
  const Sheet s = horizontal_sheet(32, 0.8, {0.0, radius + 0.05, 0.0});
  const auto solver = state.range(0) == 0 ? LinearSolverKind::pcg : LinearSolverKind::cholmod;
  SimulationReport report;
  for (auto _ : state) {
    Simulation sim(s.model, flatten_positions(s.scene.input.rest_positions), {},
                   settle_settings(solver, 1.0 / static_cast<double>(state.range(1))));
    sim.set_body(sphere);
    report = sim.run();
    benchmark::DoNotOptimize(sim.positions().data());
  }
  report_counters(state, report);
}
BENCHMARK(BM_SheetSettlesOnSphere32)
    ->Args({0, 60})
    ->Args({1, 60})
    ->Args({1, 30})
    ->Args({1, 24})
    ->Unit(benchmark::kSecond)
    ->Iterations(1);

// The same sheet (0.9 m) dropped over the built-in mannequin's head and shoulders (8,560
// triangles): a sheet-ghost drape, 2 s at 60 steps/s, CHOLMOD.
void BM_SheetOnMannequin32(benchmark::State& state) {
  const sd::garment::Body body = sd::garment::load_body("builtin");
  const sd::meshing::BoundingBox box = sd::meshing::bounding_box(body.mesh);
  const Sheet s = horizontal_sheet(32, 0.9, {0.0, box.max.y() + 0.02, 0.0});
  SimulationReport report;
  for (auto _ : state) {
    SimulationSettings settings = settle_settings(LinearSolverKind::cholmod, 1.0 / 60.0);
    settings.duration = 2.0;
    settings.stop_at_rest = false;
    Simulation sim(s.model, flatten_positions(s.scene.input.rest_positions), {}, settings);
    sim.set_body(body.mesh);
    report = sim.run();
    benchmark::DoNotOptimize(sim.positions().data());
  }
  report_counters(state, report);
  state.counters["pen_final"] = report.penetrating_vertices_final;
}
BENCHMARK(BM_SheetOnMannequin32)->Unit(benchmark::kSecond)->Iterations(1);

}  // namespace
