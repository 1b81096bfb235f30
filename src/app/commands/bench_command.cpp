// `sketchdrape bench`: the work-precision study (docs/benchmarks.md, "Work-precision study").
// Every configuration runs in its own child process (this binary with the hidden --worker
// option), so its CPU time and peak memory come from the kernel (wait4) and cannot leak into
// the next run; the child writes the material-point positions and energies at the sample times,
// the parent measures them against the scene's reference, which is computed once (also in a
// child) and cached on disk under a digest of the scene, the reference settings and the binary.
// Outputs (bench.csv, bench.json, plots) appear together or not at all.

#include <fmt/format.h>
#include <signal.h>
#include <spdlog/spdlog.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "sim/fabric.hpp"
#include "src/app/bench/bench_results.hpp"
#include "src/app/bench/bench_scaling.hpp"
#include "src/app/bench/bench_study.hpp"
#include "src/app/bench/bench_textile.hpp"
#include "src/app/commands/cli.hpp"
#include "src/app/pipeline/atomic_file.hpp"
#include "src/app/pipeline/child_process.hpp"
#include "src/app/pipeline/progress.hpp"
#include "src/app/pipeline/sha256.hpp"
#include "src/app/version.hpp"

namespace sd::app {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct BenchOptions {
  bool quick = false;
  std::string grid;  // tiny | quick | full (empty: full, or quick with --quick)
  std::vector<std::string> scenes;
  std::string out = "bench";
  bool json = false;
  std::string cache;
  double timeout = 0;  // s per run; 0: the grid's default
  // Worker side (hidden): run one configuration and write its trace.
  std::string worker_config;
  std::string worker_scene;
  std::string worker_out;
  // The scaling study (--scaling) instead of the work-precision grid.
  bool scaling = false;
  ScalingOptions scaling_options;
  // The textile study (--textile): cantilever and Cusick drape of every preset.
  bool textile = false;
  TextileOptions textile_options;
};

BenchGrid parse_grid(const BenchOptions& options) {
  const std::string grid = options.grid.empty() ? (options.quick ? "quick" : "full") : options.grid;
  if (options.quick && grid != "quick")
    throw std::invalid_argument("--quick and --grid " + grid +
                                " ask for different grids: give one");
  if (grid == "tiny") return BenchGrid::tiny;
  if (grid == "quick") return BenchGrid::quick;
  if (grid == "full") return BenchGrid::full;
  throw std::invalid_argument("--grid must be tiny, quick or full, not '" + grid + "'");
}

std::string grid_name(BenchGrid grid) {
  return grid == BenchGrid::tiny ? "tiny" : grid == BenchGrid::quick ? "quick" : "full";
}

fs::path default_cache_dir() {
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg != nullptr && *xdg != '\0')
    return fs::path(xdg) / "sketchdrape/bench";
  if (const char* home = std::getenv("HOME"); home != nullptr && *home != '\0')
    return fs::path(home) / ".cache/sketchdrape/bench";
  return fs::temp_directory_path() / "sketchdrape-bench-cache";
}

// --- child processes ---------------------------------------------------------------------------

// Runs `exe --quiet bench --worker ...` and waits for it (at most `timeout` seconds).
ChildResult run_worker(const fs::path& exe, const std::string& scene, BenchGrid grid,
                       const BenchConfig& config, const fs::path& work, const std::string& tag,
                       double timeout, Progress& progress, long done, const std::string& note) {
  const fs::path trace_path = work / (tag + ".trace");
  const fs::path log_path = work / (tag + ".log");
  const std::vector<std::string> args = {"--quiet",          "bench",    "--grid",
                                         grid_name(grid),    "--worker", config_to_json(config),
                                         "--worker-scene",   scene,      "--worker-out",
                                         trace_path.string()};
  const ChildRun child = run_child(exe, args, log_path, timeout, [&](double elapsed) {
    progress.update(done, fmt::format("{} ({:.0f} s)", note, elapsed));
  });
  ChildResult result;
  result.elapsed_s = child.elapsed_s;
  result.process_cpu_s = child.cpu_s;
  result.peak_rss_mb = child.peak_rss_mb;
  if (child.timed_out) {
    result.status = "timeout";
    result.message = fmt::format("stopped after {:.0f} s (--timeout)", timeout);
  } else if (!child.exited) {
    result.status = "crashed";
    result.message = fmt::format("killed by signal {}", child.signal);
  } else if (child.exit_code != 0 || !fs::exists(trace_path)) {
    result.status = "failed";
    result.message = last_line(log_path);
  } else {
    result.trace = deserialize_trace(read_file(trace_path));
    result.status = result.trace.failed ? "failed" : "ok";
    result.message = result.trace.failure;
  }
  return result;
}

// --- the command
// ----------------------------------------------------------------------------------

void run_worker_side(const BenchOptions& options) {
  // A worker must not outlive the study (killed parent, Ctrl-C in another terminal).
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (getppid() == 1) return;  // the parent is already gone
  const BenchGrid grid = parse_grid(options);
  const BenchScene scene = build_bench_scene(options.worker_scene, grid);
  const BenchConfig config = config_from_json(options.worker_config);
  const BenchTrace trace = run_bench_config(scene, config);
  write_file_atomically(options.worker_out, serialize_trace(trace));
}

// Removes the work folder of the child processes at the end, whatever happens.
struct WorkDir {
  fs::path path;
  ~WorkDir() {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
};

// `bench --scaling`: time per step and memory against the sheet's size, in child runs.
void run_scaling_study(const BenchOptions& options, const GlobalOptions& global) {
  ScalingOptions o = options.scaling_options;
  o.threads = global.threads;  // `sketchdrape --threads N bench --scaling` runs the sizes on N
  for (int n : o.sizes)
    if (n < 2 || n > 1024)
      throw std::invalid_argument(fmt::format("--sizes: {} is not in 2 .. 1024 quads a side", n));
  for (const std::string& solver : o.solvers)
    if (!sim::parse_solver(solver))
      throw std::invalid_argument(
          fmt::format("--solver: '{}' is not a solver (cholmod, pcg or pcg-two-level)", solver));
  const fs::path exe = fs::read_symlink("/proc/self/exe");
  const fs::path dir = options.out;
  WorkDir work{fs::temp_directory_path() / fmt::format("sketchdrape-scaling-{}", getpid())};
  fs::create_directories(work.path);
  Progress progress("bench --scaling", static_cast<long>(o.sizes.size() * o.solvers.size()),
                    global.quiet);
  long done = 0;
  std::string current;
  const std::vector<ScalingPoint> points = run_scaling(
      exe, o, work.path, [&](const std::string& line) { progress.update(done++, current = line); },
      [&](double elapsed) {
        progress.update(done - 1, fmt::format("{} ({:.0f} s)", current, elapsed));
      });
  progress.finish();
  std::vector<ScalingFit> fits;
  nlohmann::json json = {{"format", "sketchdrape/1 bench scaling"},
                         {"version", kVersion},
                         {"steps", o.steps},
                         {"threads", o.threads},
                         {"points", nlohmann::json::array()},
                         {"fits", nlohmann::json::array()}};
  for (const ScalingPoint& p : points)
    json["points"].push_back({{"quads_per_side", p.quads_per_side},
                              {"solver", p.solver},
                              {"vertices", p.vertices},
                              {"status", p.status},
                              {"message", p.message},
                              {"steps", p.steps},
                              {"step_s", p.step_s},
                              {"cpu_step_s", p.cpu_step_s},
                              {"solve_s", p.solve_s},
                              {"forces_s", p.forces_s},
                              {"collision_s", p.collision_s},
                              {"cg_iterations_mean", p.cg_iterations_mean},
                              {"process_cpu_s", p.process_cpu_s},
                              {"peak_rss_mb", p.peak_rss_mb}});
  for (const std::string& solver : o.solvers) {
    fits.push_back(fit_scaling(solver, points));
    const ScalingFit& f = fits.back();
    json["fits"].push_back({{"solver", f.solver},
                            {"points", f.points},
                            {"exponent", f.exponent},
                            {"step_s_at_1000_vertices", f.coefficient_s},
                            {"kb_per_vertex", f.kb_per_vertex},
                            {"base_memory_mb", f.base_memory_mb}});
  }
  const std::string table = scaling_table(points, fits);
  StagedOutputs outputs;
  outputs.stage(dir / "scaling.csv", scaling_csv(points));
  outputs.stage(dir / "scaling.md", table);
  outputs.stage(dir / "scaling.json", json.dump(2) + "\n");
  outputs.commit();
  if (options.json)
    fmt::print("{}\n", json.dump(2));
  else
    fmt::print("{}", table);
  for (const ScalingPoint& p : points)
    if (p.status != "ok")
      throw std::runtime_error(
          fmt::format("the {0}×{0} sheet with {1} did not finish: {2} (the "
                      "other sizes were written)",
                      p.quads_per_side, p.solver, p.message));
}

// `bench --textile`: Peirce's cantilever and the Cusick drape of every preset at three
// resolutions (docs/fabrics.md, "The textile bench"), in this process (cantilever static, Cusick
// dynamic).
void run_textile_study(const BenchOptions& options, const GlobalOptions& global) {
  const TextileOptions& o = options.textile_options;
  const std::vector<std::string> known = sim::fabric_preset_names();
  for (const std::string& fabric : o.fabrics) {
    try {
      textile_fabric(fabric);  // a preset or a readable, valid fabric file, before any drape
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(fmt::format(
          "--fabric: '{}' is neither a preset nor a fabric file ({})", fabric, e.what()));
    }
  }
  const long count = static_cast<long>(
      (o.fabrics.empty() ? known.size() : o.fabrics.size()) *
      (o.cantilever_cells.size() +
       o.cusick_grain_deg.size() *
           (o.cusick_cells_per_c.empty() ? o.cusick_cells.size() : o.cusick_cells_per_c.size())));
  Progress progress("bench --textile", count, global.quiet);
  long done = 0;
  std::vector<CantileverPoint> cantilevers;
  std::vector<CusickPoint> drapes;
  run_textile(o, cantilevers, drapes,
              [&](const std::string& line) { progress.update(++done, line); });
  progress.finish();
  nlohmann::json json = {{"format", "sketchdrape/1 bench textile"},
                         {"version", kVersion},
                         {"cantilever", nlohmann::json::array()},
                         {"cusick", nlohmann::json::array()}};
  for (const CantileverPoint& p : cantilevers)
    json["cantilever"].push_back({{"fabric", p.fabric},
                                  {"cells", p.cells},
                                  {"predicted_c_m", p.predicted_c},
                                  {"simulated_c_m", p.simulated_c},
                                  {"chord_deg", p.chord_deg},
                                  {"converged", p.converged},
                                  {"seconds", p.seconds}});
  for (const CusickPoint& p : drapes)
    json["cusick"].push_back({{"fabric", p.fabric},
                              {"cells", p.cells},
                              {"grain_deg", p.grain_deg},
                              {"vertices", p.vertices},
                              {"drape_coefficient", p.drape_coefficient},
                              {"drape_coefficient_min", p.dc_min},
                              {"drape_coefficient_max", p.dc_max},
                              {"specimens", p.specimens},
                              {"nodes", p.nodes},
                              {"converged", p.converged},
                              {"rest_time_s", p.rest_time},
                              {"seconds", p.seconds}});
  nlohmann::json model = nlohmann::json::object();
  const sim::ClothModelOptions model_options = textile_model_options(o);
  model["diamond_membrane"] = model_options.diamond_membrane;
  model["clamp_ghost_points"] = model_options.clamp_ghost_points;
  json["model"] = model;
  const fs::path dir = options.out;
  const std::string table = textile_table(cantilevers, drapes);
  StagedOutputs outputs;
  outputs.stage(dir / "textile-cantilever.csv", cantilever_csv(cantilevers));
  outputs.stage(dir / "textile-cusick.csv", cusick_csv(drapes));
  outputs.stage(dir / "textile.gp", textile_gnuplot());
  outputs.stage(dir / "textile.md", table);
  outputs.stage(dir / "textile.json", json.dump(2) + "\n");
  outputs.commit();
  if (options.json)
    fmt::print("{}\n", json.dump(2));
  else
    fmt::print("{}", table);
}

void run_bench(const BenchOptions& options, const GlobalOptions& global) {
  if (!options.worker_config.empty()) return run_worker_side(options);
  check_output_folder(options.out);  // every study writes its tables there
  if (options.scaling) return run_scaling_study(options, global);
  if (options.textile) return run_textile_study(options, global);
  const BenchGrid grid = parse_grid(options);
  if (options.timeout < 0)
    throw std::invalid_argument("--timeout must be positive (seconds per run)");
  const double timeout = options.timeout > 0       ? options.timeout
                         : grid == BenchGrid::full ? 900.0
                                                   : 120.0;
  std::vector<std::string> names = options.scenes;
  if (names.empty())
    names = grid == BenchGrid::full ? builtin_bench_scenes()
                                    : std::vector<std::string>{"hanging-sheet"};

  // Scenes first: a bad --scene fails before any run.
  std::vector<SceneResult> scenes;
  for (const std::string& name : names) {
    SceneResult s;
    s.scene = build_bench_scene(name, grid);
    s.plan = bench_plan(s.scene, grid);
    for (const SceneResult& other : scenes)
      if (other.scene.name == s.scene.name)
        throw std::invalid_argument(fmt::format("scene '{}' is given twice", name));
    scenes.push_back(std::move(s));
  }

  const fs::path exe = fs::read_symlink("/proc/self/exe");
  const std::string binary_digest = sha256_file(exe);
  const fs::path cache = options.cache.empty() ? default_cache_dir() : fs::path(options.cache);
  fs::create_directories(cache);
  WorkDir work{fs::temp_directory_path() / fmt::format("sketchdrape-bench-{}", getpid())};
  fs::create_directories(work.path);

  long total = 0;
  for (const SceneResult& s : scenes) total += static_cast<long>(s.plan.runs.size()) + 1;
  Progress progress("bench", total, global.quiet);
  long done = 0;
  for (size_t i = 0; i < scenes.size(); ++i) {
    SceneResult& s = scenes[i];
    const std::string scene_arg = names[i];
    // The reference: from the cache, or computed now and cached.
    s.key = reference_key(s.scene, s.plan.reference, binary_digest);
    const fs::path cached = cache / (s.key + ".bin");
    if (fs::exists(cached)) {
      try {
        s.reference.trace = deserialize_trace(read_file(cached));
        s.reference.status = "ok";
        s.reference_cached = true;
      } catch (const std::exception& e) {
        spdlog::warn("ignoring the unreadable cached reference {}: {}", cached.string(), e.what());
      }
    }
    if (!s.reference_cached) {
      spdlog::info("{}: computing the reference ({}), cached as {}", s.scene.name,
                   s.plan.reference.label(), cached.string());
      s.reference =
          run_worker(exe, scene_arg, grid, s.plan.reference, work.path, s.scene.name + "-reference",
                     4 * timeout, progress, done, s.scene.name + " reference");
      if (s.reference.status != "ok") {
        // Nothing to measure against: the scene's runs are skipped, the other scenes go on.
        s.reference_failure =
            fmt::format("the reference run ({}) did not finish ({}): {}", s.plan.reference.label(),
                        s.reference.status, s.reference.message);
        spdlog::error("{}: {}", s.scene.name, s.reference_failure);
        s.defaults_note = "not measured (no reference)";
        done += static_cast<long>(s.plan.runs.size()) + 1;
        progress.update(done);
        continue;
      }
      write_file_atomically(cached, serialize_trace(s.reference.trace));
    }
    progress.update(++done);
    for (const BenchConfig& config : s.plan.runs) {
      RunRow row;
      row.config = config;
      for (const BenchFamily& family : s.plan.families)
        for (const BenchConfig& member : family.members)
          if (member.id() == config.id()) row.families.push_back(family.name);
      row.child =
          run_worker(exe, scene_arg, grid, config, work.path, s.scene.name + "-" + config.id(),
                     timeout, progress, done, s.scene.name + " " + config.id());
      if (row.child.status == "ok") row.error = bench_error(row.child.trace, s.reference.trace);
      if (row.child.status != "ok")
        spdlog::warn("{} {}: {} ({})", s.scene.name, config.label(), row.child.status,
                     row.child.message);
      s.rows.push_back(std::move(row));
      progress.update(++done);
    }
    mark_pareto(s.rows);
    s.defaults_note = defaults_note(s);
  }
  progress.finish();

  // Outputs.
  const fs::path dir(options.out);
  StagedOutputs outputs;
  std::string csv = kCsvHeader;
  nlohmann::json json = {{"format", "sketchdrape/1 bench"},
                         {"version", kVersion},
                         {"grid", grid_name(grid)},
                         {"cache", cache.string()},
                         {"scenes", nlohmann::json::array()}};
  for (const SceneResult& s : scenes) {
    csv += csv_row(s, s.plan.reference, {"reference"}, s.reference, nullptr, false,
                   !s.reference_failure.empty() ? "reference: " + s.reference_failure
                   : s.reference_cached         ? "reference (cached)"
                                                : "reference");
    for (const RunRow& row : s.rows)
      csv += csv_row(s, row.config, row.families, row.child, usable(row) ? &row.error : nullptr,
                     row.pareto, row.child.message);
    nlohmann::json runs = nlohmann::json::array();
    for (const RunRow& row : s.rows) runs.push_back(row_json(row));
    json["scenes"].push_back({{"name", s.scene.name},
                              {"source", s.scene.source},
                              {"duration_s", s.scene.duration},
                              {"sample_every_s", s.scene.sample_every},
                              {"material_points", s.scene.material_points.rows()},
                              {"reference",
                               {{"run", s.plan.reference.id()},
                                {"label", s.plan.reference.label()},
                                {"key", s.key},
                                {"cached", s.reference_cached},
                                {"failure", s.reference_failure},
                                {"cpu_s", s.reference.trace.cpu_s},
                                {"wall_s", s.reference.trace.wall_s}}},
                              {"runs", runs},
                              {"defaults", s.defaults_note}});
  }
  outputs.stage(dir / "bench.csv", csv);
  const bool plots = stage_plots(scenes, work.path, dir, outputs);
  json["plots"] = plots;
  outputs.stage(dir / "bench.json", json.dump(2) + "\n");
  outputs.commit();
  if (options.json)
    fmt::print("{}\n", json.dump(2));
  else
    fmt::print("{}", summary_table(scenes, plots, dir));
  for (const SceneResult& s : scenes)
    if (!s.reference_failure.empty())
      throw std::runtime_error(
          fmt::format("{}: {} (the other scenes were written)", s.scene.name, s.reference_failure));
}

}  // namespace

void add_bench_command(CLI::App& app, const GlobalOptions& global) {
  auto options = std::make_shared<BenchOptions>();
  CLI::App* cmd = app.add_subcommand(
      "bench",
      "Work-precision study: run time, memory and error against a fine reference for a "
      "grid of simulator configurations; CSV, plots and a summary table");
  cmd->add_flag("--quick", options->quick,
                "The quick grid (under two minutes): the hanging sheet only");
  cmd->add_option("--grid", options->grid, "tiny (seconds, for tests), quick or full (default)");
  cmd->add_option("--scene", options->scenes,
                  "hanging-sheet, sphere-drop, tshirt or a sketch file (sheet or garment); "
                  "repeat for several (default: all three, or the hanging sheet when quick)");
  cmd->add_option("-o,--out", options->out, "Output directory (created if needed; default ./bench)")
      ->check(non_empty_path());
  cmd->add_flag("--json", options->json,
                "Print the results as one JSON object instead of the table");
  cmd->add_option("--cache", options->cache,
                  "Where references are cached (default ~/.cache/sketchdrape/bench)");
  cmd->add_option("--timeout", options->timeout,
                  "Seconds a run may take before it is stopped (default 900, quick 120)");
  cmd->add_flag("--scaling", options->scaling,
                "The scaling study instead: time per step and memory of the pinned sheet from "
                "32×32 to 256×256 quads (1k to 66k vertices), with the fitted exponent");
  cmd->add_option("--sizes", options->scaling_options.sizes,
                  "With --scaling: quads a side (default 32 64 128 256)");
  cmd->add_option("--solver", options->scaling_options.solvers,
                  "With --scaling: cholmod, pcg, pcg-two-level (default all three)");
  cmd->add_option("--steps", options->scaling_options.steps,
                  "With --scaling: steps of 1/60 s per run (default 10)")
      ->check(CLI::Range(2, 10000));
  cmd->add_flag("--textile", options->textile,
                "The textile study instead: Peirce's cantilever and the Cusick drape of every "
                "preset at three resolutions each (table, CSVs and a gnuplot script)");
  cmd->add_option(
      "--fabric", options->textile_options.fabrics,
      "With --textile: the presets to measure, or fabric files (a path with a '/' or ending "
      "in .json; default all six presets)");
  cmd->add_option("--cantilever-cells", options->textile_options.cantilever_cells,
                  "With --textile: cells along the overhang (default 4 8 16)")
      ->check(CLI::Range(2, 256));
  CLI::Option* cusick_cells =
      cmd->add_option("--cusick-cells", options->textile_options.cusick_cells,
                      "With --textile: cells across the disc (default 16 20 30)")
          ->check(CLI::Range(4, 200));
  cmd->add_option("--cusick-cells-per-c", options->textile_options.cusick_cells_per_c,
                  "With --textile: the Cusick resolutions per fabric as cells per bending length "
                  "c = (B/rho g)^(1/3) instead of --cusick-cells (2.5 3: where the DC converges)")
      ->check(CLI::Range(0.5, 10.0))
      ->excludes(cusick_cells);
  cmd->add_option("--cusick-specimens", options->textile_options.cusick_specimens,
                  "With --textile: Cusick drapes per point, each from its own random lift; the "
                  "table gives their mean and range (default 3)")
      ->check(CLI::Range(1, 20));
  cmd->add_option("--cusick-grain", options->textile_options.cusick_grain_deg,
                  "With --textile: the specimen's warp turned by these angles (degrees) against "
                  "the disc's mesh, each its own point (default 0)")
      ->check(CLI::Range(-360.0, 360.0));
  cmd->add_option("--cusick-rest-speed", options->textile_options.cusick_rest_speed,
                  "With --textile: a drape is at rest when every vertex stays slower than this "
                  "(m/s) for 0.25 s (default 0.005)")
      ->check(CLI::Range(1e-5, 1.0));
  cmd->add_option("--cusick-duration", options->textile_options.cusick_duration,
                  "With --textile: the longest a Cusick drape runs (s, default 8)")
      ->check(CLI::Range(0.5, 60.0));
  const auto on_off = [](std::optional<bool>& target) {
    return [&target](const std::string& value) { target = value == "on"; };
  };
  cmd->add_option_function<std::string>(
         "--diamond-membrane", on_off(options->textile_options.diamond_membrane),
         "With --textile: on or off, the diamond membrane (default: the simulator's)")
      ->check(CLI::IsMember({"on", "off"}));
  cmd->add_option_function<std::string>(
         "--ghost-points", on_off(options->textile_options.clamp_ghost_points),
         "With --textile: on or off, the clamp's ghost points (default: the simulator's)")
      ->check(CLI::IsMember({"on", "off"}));
  cmd->add_option("--worker", options->worker_config)->group("");  // internal: one run
  cmd->add_option("--worker-scene", options->worker_scene)->group("");
  cmd->add_option("--worker-out", options->worker_out)->group("");
  cmd->callback([options, &global] { run_bench(*options, global); });
}

}  // namespace sd::app
