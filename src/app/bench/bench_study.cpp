#include "src/app/bench/bench_study.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>

#include "scene/sketch_file.hpp"
#include "sim/automatic_settings.hpp"
#include "sim/cloth_driver.hpp"
#include "sim/sheet.hpp"
#include "sim/surface_sampling.hpp"
#include "src/app/pipeline/cloth_scene.hpp"
#include "src/app/pipeline/sha256.hpp"

namespace sd::app {
namespace {

// AdaptiveCloth drapes on a body (AdaptiveCloth::set_body), so scenes with a body have an
// adaptive family too.
constexpr bool kAdaptiveWithBody = true;

// --- scenes ------------------------------------------------------------------------------------

// A sheet of 4 by 4 level-0 quads: the fixed runs refine it uniformly (level 8 = 64 by 64 quads).
void set_sheet(BenchScene& scene, sim::SheetSpec spec) {
  spec.columns = spec.rows = 4;
  scene.sheet = true;
  const sim::SheetScene sheet = sim::build_sheet(spec);
  scene.mesh = sim::sheet_mesh48(sheet);
  // Warp runs from the bottom edge to the top edge: +Y for a vertical sheet, −Z when horizontal.
  scene.material.source_warp = sim::sheet_quad_warp(sheet);
  scene.material.up = sheet.input.up;
  scene.start = sheet.input.rest_positions;
  scene.pinned = sheet.pinned_vertices;
  // 33 by 33 material points over the sheet, inset by a hair so each lies inside a triangle.
  const int n = 33;
  scene.material_points.resize(n * n, 3);
  const Eigen::Vector2d half = 0.5 * spec.size * (1.0 - 1e-9);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double a = -half.x() + 2 * half.x() * i / (n - 1);
      const double b = -half.y() + 2 * half.y() * j / (n - 1);
      const Eigen::RowVector3d offset = spec.orientation == sim::SheetOrientation::vertical
                                            ? Eigen::RowVector3d(a, b, 0)
                                            : Eigen::RowVector3d(a, 0, b);
      scene.material_points.row(i * n + j) = spec.centre.transpose() + offset;
    }
}

double grid_duration(BenchGrid grid, bool garment) {
  switch (grid) {
    case BenchGrid::tiny:
      return 0.5;
    case BenchGrid::quick:
      return 1.0;
    case BenchGrid::full:
      return garment ? 1.0 : 2.0;
  }
  return 1.0;
}

// Birra & Santos' fig. 5 scene (as the adaptive study): a horizontal 1 m cotton sheet, bending
// rigidity x10, hung by three corners, air drag 0.5 kg/(m² s).
BenchScene hanging_sheet(BenchGrid grid) {
  BenchScene scene;
  scene.name = "hanging-sheet";
  scene.source = "built-in";
  sim::SheetSpec spec;
  spec.orientation = sim::SheetOrientation::horizontal;
  spec.centre = {0.0, 1.0, 0.0};
  spec.pins = {"top-left", "top-right", "bottom-left"};
  set_sheet(scene, spec);
  scene.material.fabric = sim::fabric_preset("cotton");
  scene.material.fabric.bend *= 10.0;
  scene.settings.forces.air_drag = 0.5;
  scene.duration = grid_duration(grid, false);
  return scene;
}

// A 0.8 m cotton sheet dropped from 5 cm onto a sphere of radius 0.25 m (5,120 triangles).
BenchScene sphere_drop(BenchGrid grid) {
  BenchScene scene;
  scene.name = "sphere-drop";
  scene.source = "built-in";
  const double radius = 0.25;
  sim::SheetSpec spec;
  spec.size = {0.8, 0.8};
  spec.orientation = sim::SheetOrientation::horizontal;
  // Off the sphere's top vertex: centred on it, the sheet's middle vertex lands exactly on it and
  // which neighbours touch first is decided by rounding (docs/simulator.md, Known gaps).
  spec.centre = {0.031, radius + 0.05, -0.017};
  set_sheet(scene, spec);
  scene.material.fabric = sim::fabric_preset("cotton");
  scene.settings.forces.air_drag = 0.5;
  scene.body = meshing::icosphere(radius, 4, Eigen::Vector3d::Zero());
  scene.duration = grid_duration(grid, false);
  return scene;
}

// Where the t-shirt example lives: ./data/examples, or next to the source tree of the binary
// (the build directory sits in it).
std::filesystem::path find_example(const std::string& file) {
  const std::filesystem::path here = std::filesystem::path("data/examples") / file;
  if (std::filesystem::exists(here)) return here;
  std::error_code error;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", error);
  if (!error)
    for (std::filesystem::path dir = exe.parent_path(); !dir.empty() && dir != dir.root_path();
         dir = dir.parent_path()) {
      const std::filesystem::path candidate = dir / "data/examples" / file;
      if (std::filesystem::exists(candidate)) return candidate;
    }
  throw BenchSceneError(fmt::format(
      "cannot find the example data/examples/{} (run from the sketchdrape folder, or pass the "
      "sketch file itself with --scene)",
      file));
}

BenchScene sketch_scene(const std::filesystem::path& file, BenchGrid grid) {
  const scene::Sketch sketch = scene::load_sketch(file);
  if (sketch.garment_mesh)
    throw BenchSceneError(fmt::format(
        "{}: bench runs sheets and sketched garments; an imported garment mesh is not supported",
        file.string()));
  BenchScene scene;
  scene.name = file.stem().string();
  scene.source = file.string();
  const sim::SimulationSettings settings = simulation_settings(sketch);
  scene.settings.forces = settings.forces;
  if (sketch.sheet) {
    // The bench chooses the resolution: the sheet's size, place, pins, fabric and body are kept.
    const scene::SheetSpec& given = *sketch.sheet;
    sim::SheetSpec spec;
    spec.size = given.size;
    spec.orientation =
        given.horizontal ? sim::SheetOrientation::horizontal : sim::SheetOrientation::vertical;
    spec.centre = given.centre;
    spec.pins = given.pins;
    try {
      set_sheet(scene, spec);
      scene.material.fabric = sim::fabric_preset(sketch.fabric);
    } catch (const std::invalid_argument& e) {
      sketch.fail("/sheet", e.what());
    }
    if (sketch.body.mesh != "none") scene.body = build_cloth_scene(sketch).body->mesh;
  } else {
    ClothScene cloth = build_cloth_scene(sketch);
    scene.mesh = std::move(*cloth.mesh48);
    scene.material.fabric = cloth.fabric;
    scene.material.source_warp = cloth.face_warp;
    scene.material.source_ease = cloth.face_ease;  // panel ease, as `run` applies it
    scene.start = cloth.start;
    scene.pinned = cloth.pinned;
    if (cloth.body) scene.body = cloth.body->mesh;
    // Material points: the centroids of (at most ~600 of) the garment's level-0 triangles.
    const meshing::Mesh48Arrays arrays = scene.mesh->arrays();
    const Eigen::Index faces = arrays.faces.rows();
    const Eigen::Index stride = std::max<Eigen::Index>(1, faces / 600);
    scene.material_points.resize((faces + stride - 1) / stride, 3);
    for (Eigen::Index f = 0, p = 0; f < faces; f += stride, ++p)
      scene.material_points.row(p) = (arrays.rest_positions.row(arrays.faces(f, 0)) +
                                      arrays.rest_positions.row(arrays.faces(f, 1)) +
                                      arrays.rest_positions.row(arrays.faces(f, 2))) /
                                     3.0;
  }
  scene.duration = std::min(sketch.simulate.duration, grid_duration(grid, !sketch.sheet));
  return scene;
}

// --- material points -----------------------------------------------------------------------------

double process_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double peak_rss_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

sim::SimulationSettings run_settings(const BenchScene& scene, const BenchConfig& config) {
  sim::SimulationSettings settings = scene.settings;
  settings.integrator = config.integrator;
  settings.solver = config.solver;
  if (config.linearized) settings.newton_iterations = 1;
  if (config.pcg_tolerance > 0.0) settings.pcg_tolerance = config.pcg_tolerance;
  settings.step_error = config.step_error;
  settings.dt = config.dt();
  settings.min_dt = std::min(settings.min_dt, settings.dt / 64);
  settings.duration = scene.duration;
  settings.stop_at_rest = false;  // every run covers the same simulated time
  settings.record_energy = false;
  return settings;
}

}  // namespace

// --- configurations
// --------------------------------------------------------------------------------

std::string BenchConfig::id() const {
  const std::string integ =
      std::string(sim::integrator_short_name(integrator)) + (linearized ? "lin" : "");
  const std::string solv(sim::solver_name(solver));
  if (mesh == BenchMeshKind::adaptive)
    return fmt::format("adaptive-{:g}mm-L{}-{}-{}-{}", threshold * 1e3, level, integ, solv,
                       steps_per_second);
  const std::string tolerance =
      pcg_tolerance > 0.0 ? fmt::format("-tol{:g}", pcg_tolerance) : std::string();
  const std::string error =
      step_error > 0.0 ? fmt::format("-err{:g}mm", step_error * 1e3) : std::string();
  return fmt::format("fixed-L{}-{}-{}{}-{}{}", level, integ, solv, tolerance, steps_per_second,
                     error);
}

std::string BenchConfig::label() const {
  const std::string integ =
      integrator == sim::Integrator::bdf2 ? (linearized ? "BDF2 (linearised)" : "BDF2") : "IE";
  const std::string solv = solver == sim::LinearSolverKind::pcg ? "PCG" : "CHOLMOD";
  if (mesh == BenchMeshKind::adaptive)
    return fmt::format("adaptive {:g} mm (<= L{}), {}, {}, 1/{} s", threshold * 1e3, level, integ,
                       solv, steps_per_second);
  const std::string tolerance =
      pcg_tolerance > 0.0 ? fmt::format(" to {:g}", pcg_tolerance) : std::string();
  if (step_error > 0.0)
    return fmt::format("fixed L{}, {}, {}{}, up to 1/{} s by {:g} mm", level, integ, solv,
                       tolerance, steps_per_second, step_error * 1e3);
  return fmt::format("fixed L{}, {}, {}{}, 1/{} s", level, integ, solv, tolerance,
                     steps_per_second);
}

std::vector<std::string> builtin_bench_scenes() {
  return {"hanging-sheet", "sphere-drop", "tshirt"};
}

BenchScene build_bench_scene(const std::string& name_or_file, BenchGrid grid) {
  if (name_or_file == "hanging-sheet") return hanging_sheet(grid);
  if (name_or_file == "sphere-drop") return sphere_drop(grid);
  if (name_or_file == "tshirt") {
    BenchScene scene = sketch_scene(find_example("tshirt.json"), grid);
    scene.name = "tshirt";
    return scene;
  }
  if (!std::filesystem::exists(name_or_file))
    throw BenchSceneError(fmt::format(
        "unknown scene '{}': give one of hanging-sheet, sphere-drop, tshirt, or a sketch file",
        name_or_file));
  return sketch_scene(name_or_file, grid);
}

BenchPlan bench_plan(const BenchScene& scene, BenchGrid grid) {
  using sim::Integrator;
  using sim::LinearSolverKind;
  const bool sheet = scene.sheet;
  const bool adaptive = !scene.body || kAdaptiveWithBody;
  // Levels: sheets start from 4 by 4 quads (level 2k = 4·2^k quads a side); garments from their
  // meshed quads (level 0), each level doubling the triangles.
  std::vector<int> levels;
  int reference_level = 0, reference_rate = 480;
  std::vector<int> rates;
  std::vector<double> thresholds;
  bool bdf2_steps = false;
  switch (grid) {
    case BenchGrid::tiny:
      levels = sheet ? std::vector<int>{1, 3} : std::vector<int>{0};
      reference_level = sheet ? 5 : 1;
      rates = {30, 60, 120};
      thresholds = {2e-3};
      break;
    case BenchGrid::quick:
      levels = sheet ? std::vector<int>{2, 4} : std::vector<int>{0};
      reference_level = sheet ? 6 : 1;
      reference_rate = 240;
      rates = {30, 60, 120};
      thresholds = {4e-3, 1e-3};
      break;
    case BenchGrid::full:
      levels = sheet ? std::vector<int>{2, 4, 6} : std::vector<int>{0, 1};
      reference_level = sheet ? 8 : 2;
      rates = {30, 60, 120, 240};
      thresholds = {4e-3, 2e-3, 1e-3, 5e-4};
      bdf2_steps = true;
      break;
  }
  const int finest = levels.back();
  const int step_level = finest;  // the step families run on the finest fixed mesh
  const auto config = [](BenchMeshKind mesh, int level, Integrator integ, LinearSolverKind solv,
                         int rate, double threshold = 0.0) {
    BenchConfig c;
    c.mesh = mesh;
    c.level = level;
    c.integrator = integ;
    c.solver = solv;
    c.steps_per_second = rate;
    c.threshold = threshold;
    return c;
  };
  BenchPlan plan;
  plan.reference = config(BenchMeshKind::fixed, reference_level, Integrator::implicit_euler,
                          LinearSolverKind::cholmod, reference_rate);
  const auto resolution_family = [&](const std::string& name, Integrator integ,
                                     LinearSolverKind solv, const std::vector<int>& family_levels) {
    BenchFamily family{name, {}};
    for (int level : family_levels)
      family.members.push_back(config(BenchMeshKind::fixed, level, integ, solv, 60));
    plan.families.push_back(family);
  };
  const auto step_family = [&](const std::string& name, Integrator integ) {
    BenchFamily family{name, {}};
    for (int rate : rates)
      family.members.push_back(
          config(BenchMeshKind::fixed, step_level, integ, LinearSolverKind::cholmod, rate));
    plan.families.push_back(family);
  };
  resolution_family("fixed, IE, CHOLMOD, 1/60 s: levels", Integrator::implicit_euler,
                    LinearSolverKind::cholmod, levels);
  resolution_family("fixed, IE, PCG, 1/60 s: levels", Integrator::implicit_euler,
                    LinearSolverKind::pcg,
                    grid == BenchGrid::full ? levels : std::vector<int>{finest});
  resolution_family("fixed, BDF2, CHOLMOD, 1/60 s: levels", Integrator::bdf2,
                    LinearSolverKind::cholmod,
                    grid == BenchGrid::full ? levels : std::vector<int>{finest});
  step_family(fmt::format("fixed L{}, IE, CHOLMOD: steps", step_level), Integrator::implicit_euler);
  if (bdf2_steps)
    step_family(fmt::format("fixed L{}, BDF2, CHOLMOD: steps", step_level), Integrator::bdf2);
  const auto adaptive_family = [&](int rate) {
    BenchFamily family{
        fmt::format("adaptive <= L{}, IE, CHOLMOD, 1/{} s: thresholds", finest, rate), {}};
    for (double t : thresholds)
      family.members.push_back(config(BenchMeshKind::adaptive, finest, Integrator::implicit_euler,
                                      LinearSolverKind::cholmod, rate, t));
    plan.families.push_back(family);
  };
  if (adaptive) adaptive_family(60);
  // What "solver": "auto" and "time_step": "auto" (the sketch defaults) choose at each level
  // (sim/automatic_settings.hpp), so that the summary shows where the default sits on the front.
  // A level roughly doubles the vertices (each doubles the triangles).
  // Twice: for a drape (the end state) and with `run --frames` (the motion asked for).
  for (const bool motion : {false, true}) {
    BenchFamily family{motion ? kAutomaticMotionFamily : kAutomaticFamily, {}};
    for (int level : levels) {
      sim::SceneTraits traits;
      traits.vertices = scene.mesh->vertex_count() << level;
      traits.self_contact = scene.settings.self_contact.enabled;
      traits.garment = !scene.sheet;
      traits.body = scene.body.has_value() && scene.settings.contact.enabled;
      traits.motion = motion;
      traits.pins_hold_shape = sim::pins_hold_shape(scene.start, scene.pinned);
      const sim::AutomaticChoice choice = sim::choose_settings(traits);
      BenchConfig c = config(BenchMeshKind::fixed, level, choice.integrator, choice.solver,
                             static_cast<int>(std::lround(1.0 / choice.dt)));
      if (choice.solver == sim::LinearSolverKind::pcg &&
          choice.pcg_tolerance != sim::kDefaultPcgTolerance)
        c.pcg_tolerance = choice.pcg_tolerance;
      c.step_error = choice.step_error;
      family.members.push_back(c);
    }
    plan.families.push_back(family);
  }
  // The automatic rule's candidates for a sheet (docs/simulator.md, "Automatic settings"): the
  // PCG at the long steps, implicit Euler against the linearly implicit BDF2 step, on the finest
  // fixed mesh, so the summary shows what the rule chose from. Every step divides the 0.1 s
  // between samples.
  if (sheet && grid != BenchGrid::tiny)
    for (const bool bdf2 : {false, true}) {
      BenchFamily family{
          fmt::format("fixed L{}, {}, PCG: long steps", finest, bdf2 ? "BDF2 (linearised)" : "IE"),
          {}};
      for (int rate : {10, 20, 30, 40, 50}) {
        BenchConfig c = config(BenchMeshKind::fixed, finest,
                               bdf2 ? Integrator::bdf2 : Integrator::implicit_euler,
                               LinearSolverKind::pcg, rate);
        c.linearized = bdf2;
        family.members.push_back(c);
      }
      plan.families.push_back(family);
    }
  // At 1/60 s the step's error hides the mesh's (every level within a few per cent on the
  // sheets): the full grid repeats the levels and the adaptive family at its smallest step,
  // where refinement shows and adaptive detail can pay.
  if (grid == BenchGrid::full && sheet) {
    const int small_step = rates.back();
    BenchFamily family{fmt::format("fixed, IE, CHOLMOD, 1/{} s: levels", small_step), {}};
    for (int level : levels)
      family.members.push_back(config(BenchMeshKind::fixed, level, Integrator::implicit_euler,
                                      LinearSolverKind::cholmod, small_step));
    plan.families.push_back(family);
    if (adaptive) adaptive_family(small_step);
  }
  for (const BenchFamily& family : plan.families)
    for (const BenchConfig& c : family.members)
      if (std::none_of(plan.runs.begin(), plan.runs.end(),
                       [&](const BenchConfig& r) { return r.id() == c.id(); }))
        plan.runs.push_back(c);
  return plan;
}

// --- keys
// ------------------------------------------------------------------------------------------

namespace {

template <class Matrix>
void hash_matrix(Sha256& hash, const Matrix& m) {
  const std::string shape = fmt::format("[{}x{}]", m.rows(), m.cols());
  hash.update(shape);
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j) {
      const auto value = m(i, j);
      hash.update(std::string_view(reinterpret_cast<const char*>(&value), sizeof value));
    }
}

}  // namespace

std::string reference_key(const BenchScene& scene, const BenchConfig& reference,
                          const std::string& binary_digest) {
  Sha256 hash;
  hash.update("sketchdrape bench reference v1\n");
  hash.update(binary_digest);
  hash.update(config_to_json(reference));
  const meshing::Mesh48Arrays arrays = scene.mesh->arrays();
  hash_matrix(hash, arrays.rest_positions);
  hash_matrix(hash, arrays.faces);
  hash_matrix(hash, scene.material.source_warp);
  hash_matrix(hash, scene.material.source_ease);
  hash_matrix(hash, scene.start);
  hash_matrix(hash, scene.material_points);
  for (int v : scene.pinned) hash.update(fmt::format("pin {}\n", v));
  const sim::FabricParameters& f = scene.material.fabric;
  hash.update(fmt::format("fabric {} {} {} {} {} {} {} {} {} {}\n", f.name, f.area_density,
                          f.stretch_warp, f.stretch_weft, f.shear, f.bend, f.damping,
                          f.bend_damping, f.friction, f.thickness));
  const sim::ForceSettings& forces = scene.settings.forces;
  hash.update(fmt::format("forces {} {} {} {} {} {} {}\n", forces.gravity.x(), forces.gravity.y(),
                          forces.gravity.z(), forces.wind.x(), forces.wind.y(), forces.wind.z(),
                          forces.air_drag));
  hash.update(fmt::format("time {} {}\n", scene.duration, scene.sample_every));
  if (scene.body) {
    hash_matrix(hash, scene.body->vertices);
    hash_matrix(hash, scene.body->faces);
  }
  return hash.hex_digest();
}

// --- one run
// -----------------------------------------------------------------------------------------

BenchTrace run_bench_config(const BenchScene& scene, const BenchConfig& config) {
  BenchTrace trace;
  const sim::SimulationSettings settings = run_settings(scene, config);
  std::vector<sim::Pin> pins;
  for (int v : scene.pinned) pins.push_back({v, {}});

  // Fixed: the scene's 4-8 mesh refined uniformly to the level, then draped with adaptivity off
  // (warp, panel ease and masses as in an adaptive run). Adaptive: refined to the scene's start
  // level, then refining and coarsening as it goes.
  sim::AdaptiveSettings adaptive;
  if (config.mesh == BenchMeshKind::adaptive) {
    adaptive.refine_threshold = config.threshold;
    adaptive.coarsen_threshold = 0.25 * config.threshold;
    adaptive.max_level = config.level;
  } else {
    adaptive.enabled = false;
  }
  sim::ClothDriver driver(*scene.mesh, scene.material, scene.start, pins, settings, adaptive);
  sim::AdaptiveCloth& cloth = *driver.adaptive();
  const int start_level = config.mesh == BenchMeshKind::adaptive ? scene.start_level : config.level;
  if (config.mesh == BenchMeshKind::adaptive) {
    if (start_level > 0) cloth.refine_uniformly(start_level);
    if (scene.body) driver.set_body(*scene.body);
  } else {
    // With the body, split vertices that a chord puts inside the contact thickness are moved out
    // to it, as in an adaptive run. Without, a garment refined on the body starts with chord
    // midpoints inside it (the t-shirt at L2: the start repair then blew up within 5 steps).
    if (scene.body) driver.set_body(*scene.body);
    if (start_level > 0) cloth.refine_uniformly(start_level);
  }

  // Material points located once per mesh (the fixed mesh never changes).
  std::optional<std::vector<sim::MaterialLocation>> fixed_located;
  const auto sample = [&] {
    if (config.mesh == BenchMeshKind::fixed && !fixed_located)
      fixed_located =
          sim::locate_material_points(cloth.rest_positions(), cloth.faces(), scene.material_points);
    const std::vector<sim::MaterialLocation> located =
        fixed_located ? *fixed_located
                      : sim::locate_material_points(cloth.rest_positions(), cloth.faces(),
                                                    scene.material_points);
    trace.times.push_back(cloth.time());
    trace.positions.push_back(sim::positions_at(located, cloth.faces(), cloth.positions()));
    trace.energy.push_back(cloth.simulation().energy().total());
  };
  const auto count_mesh = [&] {
    trace.vertices_max = std::max(trace.vertices_max, cloth.mesh().vertex_count());
    trace.triangles_max = std::max(trace.triangles_max, cloth.mesh().triangle_count());
  };
  count_mesh();
  trace.rss_before_mb = peak_rss_mb();

  // Steps land on every sample time; the sample taken there is outside the timed part.
  const double epsilon = 1e-9;
  double next = scene.sample_every;
  auto wall_start = std::chrono::steady_clock::now();
  double cpu_start = 0.0;
  sim::ClothObserver observer;
  observer.max_step = [&](const sim::ClothDriver& d) {
    return std::min(scene.duration, next) - d.time();
  };
  observer.before_step = [&](sim::ClothDriver&) {
    wall_start = std::chrono::steady_clock::now();
    cpu_start = process_cpu_seconds();
  };
  observer.after_step = [&](const sim::ClothDriver& d, const sim::StepOutcome& outcome) {
    trace.cpu_s += process_cpu_seconds() - cpu_start;
    trace.wall_s +=
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    if (!outcome.accepted) {
      trace.failed = true;
      trace.failure =
          fmt::format("step at t = {:.4f} s failed: {}", d.time(), outcome.failure_reason);
      return false;
    }
    count_mesh();
    if (d.time() >= next - epsilon) {
      sample();
      next += scene.sample_every;
    }
    return true;
  };
  sample();
  driver.run(observer);

  const sim::SimulationReport& r = cloth.simulation().report();
  trace.steps = r.steps;
  trace.retries = r.retries;
  trace.linear_solves = r.linear_solves;
  trace.cg_iterations_mean = r.cg_iterations_mean;
  trace.splits = cloth.report().splits + cloth.report().forced_splits;
  trace.merges = cloth.report().merges;
  trace.vertices_final = cloth.mesh().vertex_count();
  if (config.mesh == BenchMeshKind::fixed) trace.splits = trace.merges = 0;
  return trace;
}

// --- serialisation
// ---------------------------------------------------------------------------------

namespace {

constexpr char kTraceMagic[8] = {'S', 'D', 'B', 'T', 'R', 'C', '0', '1'};

void put(std::string& out, const void* data, size_t bytes) {
  out.append(static_cast<const char*>(data), bytes);
}

template <class T>
T take(const std::string& in, size_t& at) {
  if (at + sizeof(T) > in.size()) throw std::runtime_error("truncated bench trace");
  T value;
  std::memcpy(&value, in.data() + at, sizeof(T));
  at += sizeof(T);
  return value;
}

}  // namespace

std::string serialize_trace(const BenchTrace& t) {
  const nlohmann::json header = {{"failed", t.failed},
                                 {"failure", t.failure},
                                 {"wall_s", t.wall_s},
                                 {"cpu_s", t.cpu_s},
                                 {"rss_before_mb", t.rss_before_mb},
                                 {"steps", t.steps},
                                 {"retries", t.retries},
                                 {"linear_solves", t.linear_solves},
                                 {"cg_iterations_mean", t.cg_iterations_mean},
                                 {"vertices_max", t.vertices_max},
                                 {"triangles_max", t.triangles_max},
                                 {"vertices_final", t.vertices_final},
                                 {"splits", t.splits},
                                 {"merges", t.merges}};
  const std::string text = header.dump();
  std::string out(kTraceMagic, sizeof kTraceMagic);
  const uint64_t text_size = text.size();
  put(out, &text_size, sizeof text_size);
  out += text;
  const uint64_t samples = t.times.size();
  const uint64_t points = t.positions.empty() ? 0 : static_cast<uint64_t>(t.positions[0].rows());
  put(out, &samples, sizeof samples);
  put(out, &points, sizeof points);
  for (size_t s = 0; s < samples; ++s) {
    put(out, &t.times[s], sizeof(double));
    put(out, &t.energy[s], sizeof(double));
    for (Eigen::Index p = 0; p < t.positions[s].rows(); ++p)
      for (int k = 0; k < 3; ++k) {
        const double value = t.positions[s](p, k);
        put(out, &value, sizeof value);
      }
  }
  return out;
}

BenchTrace deserialize_trace(const std::string& bytes) {
  if (bytes.size() < sizeof kTraceMagic ||
      std::memcmp(bytes.data(), kTraceMagic, sizeof kTraceMagic) != 0)
    throw std::runtime_error("not a sketchdrape bench trace");
  size_t at = sizeof kTraceMagic;
  const auto text_size = take<uint64_t>(bytes, at);
  if (at + text_size > bytes.size()) throw std::runtime_error("truncated bench trace");
  const nlohmann::json h = nlohmann::json::parse(bytes.substr(at, text_size));
  at += text_size;
  BenchTrace t;
  t.failed = h.at("failed");
  t.failure = h.at("failure");
  t.wall_s = h.at("wall_s");
  t.cpu_s = h.at("cpu_s");
  t.rss_before_mb = h.at("rss_before_mb");
  t.steps = h.at("steps");
  t.retries = h.at("retries");
  t.linear_solves = h.at("linear_solves");
  t.cg_iterations_mean = h.at("cg_iterations_mean");
  t.vertices_max = h.at("vertices_max");
  t.triangles_max = h.at("triangles_max");
  t.vertices_final = h.at("vertices_final");
  t.splits = h.at("splits");
  t.merges = h.at("merges");
  const auto samples = take<uint64_t>(bytes, at);
  const auto points = take<uint64_t>(bytes, at);
  if (bytes.size() - at != samples * (2 + 3 * points) * sizeof(double))
    throw std::runtime_error("bench trace has the wrong size");
  for (uint64_t s = 0; s < samples; ++s) {
    t.times.push_back(take<double>(bytes, at));
    t.energy.push_back(take<double>(bytes, at));
    Eigen::MatrixX3d x(static_cast<Eigen::Index>(points), 3);
    for (Eigen::Index p = 0; p < x.rows(); ++p)
      for (int k = 0; k < 3; ++k) x(p, k) = take<double>(bytes, at);
    t.positions.push_back(std::move(x));
  }
  return t;
}

// --- error
// -----------------------------------------------------------------------------------------

BenchError bench_error(const BenchTrace& run, const BenchTrace& reference) {
  BenchError error;
  const size_t n = std::min(run.times.size(), reference.times.size());
  double sum = 0.0;
  long count = 0;
  double e_min = std::numeric_limits<double>::infinity(), e_max = -e_min;
  for (double e : reference.energy) {
    e_min = std::min(e_min, e);
    e_max = std::max(e_max, e);
  }
  for (size_t s = 1; s < n; ++s) {  // t = 0 is the same start for every run
    if (std::abs(run.times[s] - reference.times[s]) > 1e-6)
      throw std::runtime_error(fmt::format("sample times differ: {} s against the reference's {} s",
                                           run.times[s], reference.times[s]));
    const Eigen::VectorXd d = (run.positions[s] - reference.positions[s]).rowwise().norm();
    sum += d.squaredNorm();
    count += d.size();
    error.max_m = std::max(error.max_m, d.maxCoeff());
    error.final_rms_m = std::sqrt(d.squaredNorm() / static_cast<double>(d.size()));
    error.energy_j = std::max(error.energy_j, std::abs(run.energy[s] - reference.energy[s]));
    ++error.samples;
  }
  error.rms_m = count > 0 ? std::sqrt(sum / static_cast<double>(count)) : 0.0;
  error.energy_relative = e_max > e_min ? error.energy_j / (e_max - e_min) : 0.0;
  return error;
}

std::string config_to_json(const BenchConfig& c) {
  return nlohmann::json{{"mesh", c.mesh == BenchMeshKind::adaptive ? "adaptive" : "fixed"},
                        {"level", c.level},
                        {"threshold", c.threshold},
                        {"integrator", sim::integrator_short_name(c.integrator)},
                        {"solver", sim::solver_name(c.solver)},
                        {"steps_per_second", c.steps_per_second},
                        {"linearized", c.linearized},
                        {"pcg_tolerance", c.pcg_tolerance},
                        {"step_error", c.step_error}}
      .dump();
}

BenchConfig config_from_json(const std::string& text) {
  const nlohmann::json j = nlohmann::json::parse(text);
  BenchConfig c;
  c.mesh = j.at("mesh") == "adaptive" ? BenchMeshKind::adaptive : BenchMeshKind::fixed;
  c.level = j.at("level");
  c.threshold = j.at("threshold");
  c.integrator = sim::parse_integrator(j.at("integrator").get<std::string>())
                     .value_or(sim::Integrator::implicit_euler);
  c.solver =
      sim::parse_solver(j.at("solver").get<std::string>()).value_or(sim::LinearSolverKind::cholmod);
  c.steps_per_second = j.at("steps_per_second");
  c.linearized = j.value("linearized", false);
  c.pcg_tolerance = j.value("pcg_tolerance", 0.0);
  c.step_error = j.value("step_error", 0.0);
  return c;
}

}  // namespace sd::app
