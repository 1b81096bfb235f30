#include "src/app/bench/bench_textile.hpp"

#include <fmt/format.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <random>

#include "sim/cantilever.hpp"
#include "sim/drape_coefficient.hpp"
#include "sim/fabric.hpp"
#include "sim/sheet.hpp"
#include "sim/simulation.hpp"
#include "sim/static_equilibrium.hpp"

namespace sd::app {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace

sim::FabricParameters textile_fabric(const std::string& fabric) {
  // A name with a path separator or a .json ending is a fabric file (docs/fabrics.md).
  const bool is_file = fabric.find('/') != std::string::npos ||
                       (fabric.size() > 5 && fabric.compare(fabric.size() - 5, 5, ".json") == 0);
  return is_file ? sim::load_fabric_file(fabric) : sim::fabric_preset(fabric);
}

namespace {

// A fabric's label in the tables: a preset's name, or a file's fabric by its own "name" with the
// file after it (trial 37: the table said "crepe-de-chine.json", not the fabric it holds).
std::string fabric_label(const std::string& asked, const sim::FabricParameters& fabric) {
  if (fabric.name.empty() || fabric.name == asked || fabric.name == "custom") return asked;
  return fmt::format("{} ({})", fabric.name, asked);
}

}  // namespace

sim::ClothModelOptions textile_model_options(const TextileOptions& options) {
  sim::ClothModelOptions model;
  if (options.diamond_membrane) model.diamond_membrane = *options.diamond_membrane;
  if (options.clamp_ghost_points) model.clamp_ghost_points = *options.clamp_ghost_points;
  return model;
}

CantileverPoint run_cantilever(const std::string& name, int cells, const TextileOptions& options) {
  const auto start = Clock::now();
  const sim::FabricParameters fabric = textile_fabric(name);
  CantileverPoint point;
  point.fabric = fabric_label(name, fabric);
  point.cells = cells;
  point.predicted_c = std::cbrt(fabric.bend / (fabric.area_density * 9.81));
  // A strip 4 cells wide, the overhang 2c in `cells` square cells beyond a clamp of three lines
  // of vertices (two cells), as data/scenes/cantilever-cotton.json.
  const double overhang = 2.0 * point.predicted_c;
  const double cell = overhang / cells;
  sim::SheetSpec spec;
  spec.orientation = sim::SheetOrientation::horizontal;
  spec.columns = 4;
  spec.rows = cells + 2;
  spec.size = {4 * cell, overhang + 2 * cell};
  spec.centre = {0.0, 1.0, 0.0};
  spec.pins = {"top:3"};
  const sim::SheetScene scene = sim::build_sheet(spec);
  const sim::ClothModel model =
      sim::build_cloth_model(scene.input, fabric, textile_model_options(options));
  Eigen::VectorXd x = sim::flatten_positions(scene.input.rest_positions);
  sim::StaticOptions static_options;
  static_options.load_steps = 8;
  point.converged = sim::solve_static(model, x, scene.pinned_vertices, static_options).converged;
  const Eigen::MatrixX3d draped =
      Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(x.data(),
                                                                                  x.size() / 3, 3);
  const sim::CantileverMeasure measure =
      sim::measure_cantilever(scene, scene.input.rest_positions, draped, 3);
  point.chord_deg = measure.chord_deg;
  point.simulated_c = measure.bending_length;
  point.seconds = seconds_since(start);
  return point;
}

CusickPoint run_cusick(const std::string& name, int cells, int specimens,
                       const TextileOptions& options, double grain_deg) {
  const auto start = Clock::now();
  const sim::FabricParameters fabric = textile_fabric(name);
  sim::SheetSpec spec;
  spec.shape = sim::SheetShape::disc;
  spec.size = {0.3, 0.3};
  spec.columns = spec.rows = cells;
  spec.orientation = sim::SheetOrientation::horizontal;
  spec.centre = {0.0, 1.0, 0.0};
  spec.pins = {"centre:0.09"};
  sim::SheetScene scene = sim::build_sheet(spec);
  // The warp turned about the vertical against the mesh (the disc's warp runs along −Z).
  const Eigen::AngleAxisd turn(grain_deg * std::numbers::pi / 180.0, Eigen::Vector3d::UnitY());
  for (Eigen::Index t = 0; t < scene.input.warp.rows(); ++t)
    scene.input.warp.row(t) = (turn * scene.input.warp.row(t).transpose()).transpose();
  sim::ClothModelOptions model_options = textile_model_options(options);
  model_options.compression = sim::Compression::buckling;
  const sim::ClothModel model = sim::build_cloth_model(scene.input, fabric, model_options);
  std::vector<sim::Pin> pins;
  std::vector<char> pinned(static_cast<size_t>(model.vertex_count), 0);
  for (int v : scene.pinned_vertices) {
    pins.push_back({v, {}});
    pinned[static_cast<size_t>(v)] = 1;
  }
  // The drape as `run` drapes data/scenes/cusick-drape-cotton.json, at the step of its
  // measurements (docs/fabrics.md): dropped flat, implicit Euler at 1/60 s, to rest (every vertex
  // slower than 5 mm/s for 0.25 s, the simulator's rule) or 8 s (both settable).
  sim::SimulationSettings settings;
  settings.integrator = sim::Integrator::implicit_euler;
  settings.solver = sim::LinearSolverKind::cholmod;
  settings.dt = 1.0 / 60.0;
  settings.duration = options.cusick_duration;
  settings.rest_speed = options.cusick_rest_speed;
  settings.record_energy = false;
  CusickPoint point;
  point.fabric = fabric_label(name, fabric);
  point.cells = cells;
  point.grain_deg = grain_deg;
  point.vertices = model.vertex_count;
  point.specimens = specimens;
  point.converged = true;
  point.dc_min = 1.0;
  point.dc_max = 0.0;
  double dc_sum = 0.0, nodes_sum = 0.0;
  for (int s = 0; s < specimens; ++s) {
    // Each specimen leaves the symmetric flat state by its own random lift of up to 0.1 mm, as
    // the standard's specimens differ: the fold pattern a drape picks varies between them.
    Eigen::VectorXd x = sim::flatten_positions(scene.input.rest_positions);
    std::mt19937 rng(static_cast<unsigned>(s + 1));
    std::uniform_real_distribution<double> lift(0.0, 1e-4);
    for (int v = 0; v < model.vertex_count; ++v)
      if (!pinned[static_cast<size_t>(v)]) x(3 * v + 1) += lift(rng);
    sim::Simulation simulation(model, x, pins, settings);
    const sim::SimulationReport report = simulation.run();
    point.converged = point.converged && report.at_rest && !report.failed;
    point.rest_time = std::max(point.rest_time, simulation.time());
    const Eigen::VectorXd& y = simulation.positions();
    Eigen::MatrixX3d positions(model.vertex_count, 3);
    for (int v = 0; v < model.vertex_count; ++v) positions.row(v) = y.segment<3>(3 * v).transpose();
    const sim::DrapeShadow shadow = sim::measure_drape_shadow(
        positions, scene.input.triangles, spec.centre, Eigen::Vector3d::UnitY());
    dc_sum += shadow.drape_coefficient;
    nodes_sum += shadow.nodes;
    point.dc_min = std::min(point.dc_min, shadow.drape_coefficient);
    point.dc_max = std::max(point.dc_max, shadow.drape_coefficient);
  }
  point.drape_coefficient = dc_sum / specimens;
  point.nodes = static_cast<int>(std::lround(nodes_sum / specimens));
  point.seconds = seconds_since(start);
  return point;
}

int cusick_cells_for(const sim::FabricParameters& fabric, double per_c) {
  const double c = std::cbrt(fabric.bend / (fabric.area_density * 9.81));  // m
  // The small slack keeps an exact multiple (0.30·per_c/c an integer) from rounding up.
  return std::max(4, static_cast<int>(std::ceil(0.30 * per_c / c - 1e-9)));
}

void run_textile(const TextileOptions& options, std::vector<CantileverPoint>& cantilevers,
                 std::vector<CusickPoint>& drapes,
                 const std::function<void(const std::string&)>& note) {
  const std::vector<std::string> fabrics =
      options.fabrics.empty() ? sim::fabric_preset_names() : options.fabrics;
  for (const std::string& fabric : fabrics) {
    for (const int cells : options.cantilever_cells) {
      cantilevers.push_back(run_cantilever(fabric, cells, options));
      const CantileverPoint& p = cantilevers.back();
      note(fmt::format(
          "cantilever {} {} cells: chord {:.2f} deg, c {:.2f} cm (predicted {:.2f}), "
          "{:.1f} s",
          fabric, cells, p.chord_deg, 100 * p.simulated_c, 100 * p.predicted_c, p.seconds));
    }
    std::vector<int> cusick_cells = options.cusick_cells;
    if (!options.cusick_cells_per_c.empty()) {
      const sim::FabricParameters parameters = textile_fabric(fabric);
      cusick_cells.clear();
      for (const double per_c : options.cusick_cells_per_c)
        cusick_cells.push_back(cusick_cells_for(parameters, per_c));
    }
    for (const double grain : options.cusick_grain_deg)
      for (const int cells : cusick_cells) {
        drapes.push_back(run_cusick(fabric, cells, options.cusick_specimens, options, grain));
        const CusickPoint& p = drapes.back();
        note(fmt::format(
            "Cusick {} {} cells, grain {:g} deg: DC {:.3f} ({:.3f}-{:.3f} over {} specimens), "
            "{} nodes{}, rested by {:.2f} s, {:.1f} s",
            fabric, cells, grain, p.drape_coefficient, p.dc_min, p.dc_max, p.specimens, p.nodes,
            p.converged ? "" : " (not at rest)", p.rest_time, p.seconds));
      }
  }
}

std::string textile_table(const std::vector<CantileverPoint>& cantilevers,
                          const std::vector<CusickPoint>& drapes) {
  std::string out =
      "| fabric | cells along 2c | predicted c (cm) | simulated c (cm) | chord (41.5°) | static "
      "solve |\n|---|---|---|---|---|---|\n";
  for (const CantileverPoint& p : cantilevers)
    out += fmt::format("| {} | {} | {:.3f} | {:.3f} | {:.2f}° | {} |\n", p.fabric, p.cells,
                       100 * p.predicted_c, 100 * p.simulated_c, p.chord_deg,
                       p.converged ? "converged" : "not converged");
  out +=
      "\n| fabric | cells across the disc | grain | vertices | DC (mean) | DC (min-max) | nodes "
      "| specimens | dynamic drape |\n"
      "|---|---|---|---|---|---|---|---|---|\n";
  for (const CusickPoint& p : drapes)
    out += fmt::format(
        "| {} | {} | {:g}° | {} | {:.3f} | {:.3f}-{:.3f} | {} | {} | {} |\n", p.fabric, p.cells,
        p.grain_deg, p.vertices, p.drape_coefficient, p.dc_min, p.dc_max, p.nodes, p.specimens,
        p.converged ? fmt::format("at rest by {:.2f} s", p.rest_time) : std::string("not at rest"));
  return out;
}

std::string cantilever_csv(const std::vector<CantileverPoint>& cantilevers) {
  std::string out = "fabric,cells,predicted_c_m,simulated_c_m,chord_deg,converged,seconds\n";
  for (const CantileverPoint& p : cantilevers)
    out += fmt::format("{},{},{:.6g},{:.6g},{:.4f},{},{:.2f}\n", p.fabric, p.cells, p.predicted_c,
                       p.simulated_c, p.chord_deg, p.converged ? 1 : 0, p.seconds);
  return out;
}

std::string cusick_csv(const std::vector<CusickPoint>& drapes) {
  std::string out =
      "fabric,cells,vertices,drape_coefficient,nodes,converged,seconds,dc_min,dc_max,specimens,"
      "grain_deg,rest_time_s\n";
  for (const CusickPoint& p : drapes)
    out += fmt::format("{},{},{},{:.4f},{},{},{:.2f},{:.4f},{:.4f},{},{:g},{:.3f}\n", p.fabric,
                       p.cells, p.vertices, p.drape_coefficient, p.nodes, p.converged ? 1 : 0,
                       p.seconds, p.dc_min, p.dc_max, p.specimens, p.grain_deg, p.rest_time);
  return out;
}

std::string textile_gnuplot() {
  return R"(# gnuplot textile.gp: the textile bench's plots from its CSVs (converged solves and drapes at rest only).
set datafile separator ","
set terminal pngcairo size 900,600
set key outside right
set output "textile-cantilever.png"
set title "Peirce cantilever: simulated / predicted bending length"
set xlabel "cells along the overhang 2c"
set ylabel "simulated c / predicted c"
set logscale x 2
# A margin above and below the curves, so that the exact ratio 1 is not drawn on the frame.
set offsets 0, 0, graph 0.05, graph 0.05
plot for [f in "cotton denim jersey polyester silk wool"] "textile-cantilever.csv" \
  using ($2):(strcol(1) eq f && $6 == 1 ? $4/$3 : 1/0) with linespoints title f, \
  1 title "exact" dt 2
set output "textile-cusick.png"
set title "Cusick drape coefficient"
set xlabel "cells across the 30 cm disc"
set ylabel "DC: mean of the specimens, bars their range"
unset logscale x
set offsets graph 0.05, graph 0.05, graph 0.05, graph 0.05
plot for [f in "cotton denim jersey polyester silk wool"] "textile-cusick.csv" \
  using ($2):(strcol(1) eq f && $6 == 1 ? $4 : 1/0):8:9 with yerrorlines title f
)";
}

}  // namespace sd::app
