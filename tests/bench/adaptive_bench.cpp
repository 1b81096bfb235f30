// Adaptive level of detail (docs/adaptive.md, docs/benchmarks.md "Adaptive detail").
//
// Two modes:
//   adaptive_bench [google benchmark flags]   kernels: the error estimate, one adapt() with
//                                             splits and merges, a model rebuild
//   adaptive_bench --study=DIR [--quick] [--scene=SCENE] [--only=RUN] [--finest=N]
//                  [--perturbed=K] [--adaptive-start=L] [--even-levels] [--fine-ladder]
//                  [--target-levels=0|1] [--lookahead=S] [--change-interval=S] [--max-level=L]
//                  [--motion-horizon=S] [--sample-errors]
//                                             the work-precision study: the 3-corner and 2-corner
//                                             sheets, a tablecloth and a sheet dropped on a sphere
//                                             run fixed at levels N-4, N-2, N
//                                             and adaptively (max level N) against a fixed
//                                             level-(N+2) reference; writes DIR/<scene>_<run>.csv
//                                             time series and DIR/summary.csv, prints the
//                                             summary. --scene: one scene (three_corner,
//                                             two_corner, tablecloth, sphere); --only: one
//                                             run (e.g. adaptive_2mm) without the reference
//                                             (measured against the one a full run kept in
//                                             DIR, if any), to profile; --finest: N, 4 to 11
//                                             (default 6);
//                                             --perturbed: K more runs of fixed level N with
//                                             the body moved by 1 µm (scenes with a body);
//                                             --adaptive-start: the adaptive runs' first level
//                                             (default 0); --even-levels: adaptive runs keep
//                                             even levels; --fine-ladder: thresholds in steps
//                                             of √2 instead of 2; --target-levels,
//                                             --lookahead, --change-interval,
//                                             --motion-horizon: the adaptive runs'
//                                             AdaptiveSettings of those names;
//                                             --max-level: their max level instead of N;
//                                             --sample-errors: print each run's error at
//                                             every sample time; --threads=N: the
//                                             simulator's own parallel loops on N threads
//                                             (default: every core; 1 keeps the CPU time free
//                                             of idle worker threads' spinning).
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "sim/adaptive_detail.hpp"
#include "sim/parallel.hpp"
#include "sim/solver_library_threads.hpp"
#include "tests/sim/adaptive_scenes.hpp"
#include "tests/sim/test_bodies.hpp"

namespace {

using namespace sd::sim;
using namespace sd::sim::testing;
using Clock = std::chrono::steady_clock;

AdaptiveSettings fixed_settings() {
  AdaptiveSettings settings;
  settings.enabled = false;
  return settings;
}

AdaptiveSettings adaptive_settings(double refine_threshold, int max_level,
                                   bool even_levels = false) {
  AdaptiveSettings settings;
  settings.refine_threshold = refine_threshold;
  settings.coarsen_threshold = 0.25 * refine_threshold;
  settings.max_level = max_level;
  settings.even_levels = even_levels;
  return settings;
}

// The study's adaptive runs with the method options of the command line applied.
struct MethodOptions {
  int target_levels = -1;      // -1: the default
  double lookahead = -1;       // s; negative: the default
  double interval = -1;        // s; negative: the default
  int max_level = -1;          // the adaptive runs' max level; -1: the study's finest
  double motion_horizon = -1;  // s; negative: the default
};
MethodOptions g_method;

AdaptiveSettings study_settings(double refine_threshold, int max_level, bool even_levels) {
  AdaptiveSettings settings = adaptive_settings(refine_threshold, max_level, even_levels);
  if (g_method.target_levels >= 0) settings.target_levels = g_method.target_levels != 0;
  if (g_method.lookahead >= 0) settings.lookahead = g_method.lookahead;
  if (g_method.interval >= 0) settings.change_interval = g_method.interval;
  if (g_method.max_level >= 0) settings.max_level = g_method.max_level;
  if (g_method.motion_horizon >= 0) settings.motion_horizon = g_method.motion_horizon;
  return settings;
}

// The study's refine thresholds with `finest` as the max level: 4 mm halving down to
// 0.5 mm · 2^(6 − finest) (4, 2, 1, 0.5 mm at level 6). The sag estimate on a smooth curve halves
// with each level (θ and w both halve every two), so the threshold that lets the smooth parts
// reach level N is half the one for level N − 1; the coarser thresholds stay for comparison.
// fine_ladder: steps of √2 instead of 2 (4, 2.83, 2, 1.41, 1, 0.707 mm, ...).
std::vector<double> refine_thresholds(int finest, bool fine_ladder) {
  const double smallest = 0.5e-3 * std::ldexp(1.0, 6 - finest);
  std::vector<double> thresholds;
  const double ratio = fine_ladder ? std::sqrt(2.0) : 2.0;
  for (double t = 4e-3; t > 0.99 * smallest; t /= ratio) thresholds.push_back(t);
  return thresholds;
}

// --- kernels -------------------------------------------------------------------------------

// A 3-corner sheet that has fallen for 1 s adaptively (a fold at the free corner).
AdaptiveCloth fallen_sheet() {
  AdaptiveSheetSpec spec;
  spec.duration = 1.0;
  AdaptiveCloth cloth = make_adaptive_sheet(spec, 0, adaptive_settings(2e-3, 6));
  cloth.run();
  return cloth;
}

void BM_EdgeErrors(benchmark::State& state) {
  AdaptiveCloth cloth = fallen_sheet();  // edge_errors() updates the body-sag cache
  for (auto _ : state) benchmark::DoNotOptimize(cloth.edge_errors());
  state.counters["edges"] = static_cast<double>(cloth.edge_errors().size());
  state.counters["vertices"] = cloth.mesh().vertex_count();
}
BENCHMARK(BM_EdgeErrors)->Unit(benchmark::kMicrosecond);

// Splitting every leaf block once, then merging them back, with transfer and two rebuilds.
void BM_SplitMergeRebuild(benchmark::State& state) {
  AdaptiveCloth cloth = fallen_sheet();
  double operations = 0, rebuild = 0;
  int changes = 0;
  for (auto _ : state) {
    std::vector<sd::meshing::BlockId> leaves;
    for (auto k : cloth.mesh().leaf_blocks())
      if (cloth.mesh().level(k) < 7) leaves.push_back(k);
    const AdaptStats split = cloth.split_blocks(leaves);
    std::vector<sd::meshing::BlockId> mergeable = cloth.mesh().mergeable_blocks();
    const AdaptStats merge = cloth.merge_blocks(mergeable);
    operations += split.operations_s + merge.operations_s;
    rebuild += split.rebuild_s + merge.rebuild_s;
    changes += split.splits + split.forced_splits + merge.merges;
  }
  state.counters["changes"] = benchmark::Counter(changes, benchmark::Counter::kAvgIterations);
  state.counters["operations_ms"] =
      benchmark::Counter(1e3 * operations, benchmark::Counter::kAvgIterations);
  state.counters["rebuild_ms"] =
      benchmark::Counter(1e3 * rebuild, benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_SplitMergeRebuild)->Unit(benchmark::kMillisecond);

// The model rebuild after a topology change, on the uniform level-L sheet: arg 0 builds the model
// (build_cloth_model), arg 1 the whole AdaptStats::rebuild path (one split and one merge: compact,
// export, build, replace_model).
void BM_Rebuild(benchmark::State& state) {
  AdaptiveSheetSpec spec;
  AdaptiveCloth cloth =
      make_adaptive_sheet(spec, static_cast<int>(state.range(0)), fixed_settings());
  const sd::meshing::Mesh48Arrays arrays = cloth.mesh().arrays();
  ClothInput input;
  input.rest_positions = arrays.rest_positions;
  input.triangles = arrays.faces;
  const FabricParameters fabric = adaptive_sheet_fabric();
  double rebuild = 0;
  for (auto _ : state) {
    if (state.range(1) == 0) {
      benchmark::DoNotOptimize(build_cloth_model(input, fabric));
    } else {
      // Split one block and merge it back: its split vertex is the newest (last) vertex.
      const sd::meshing::BlockId leaf = cloth.mesh().leaf_blocks().front();
      rebuild += cloth.split_blocks({leaf}).rebuild_s;
      const sd::meshing::VertexId newest(cloth.mesh().vertex_count() - 1);
      for (sd::meshing::BlockId k : cloth.mesh().mergeable_blocks())
        if (cloth.mesh().split_vertex(k) == newest) rebuild += cloth.merge_blocks({k}).rebuild_s;
    }
  }
  state.counters["vertices"] = cloth.mesh().vertex_count();
  if (state.range(1) == 1)
    state.counters["rebuild_ms"] =
        benchmark::Counter(1e3 * rebuild / 2, benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_Rebuild)->ArgsProduct({{4, 6, 8}, {0, 1}})->Unit(benchmark::kMillisecond);

// One adaptive step of the falling sheet (solve + estimate + operations + rebuild).
void BM_AdaptiveStep(benchmark::State& state) {
  AdaptiveCloth cloth = fallen_sheet();
  for (auto _ : state) cloth.step();
  state.counters["vertices"] = cloth.mesh().vertex_count();
}
BENCHMARK(BM_AdaptiveStep)->Unit(benchmark::kMillisecond)->Iterations(30);

// --- study ---------------------------------------------------------------------------------

struct RunResult {
  std::string name;
  double wall_s = 0;  // stepping only (sampling for the error excluded)
  double cpu_s = 0;   // process CPU time of the stepping (single-threaded BLAS/OpenMP)
  double solve_s = 0;
  double forces_s = 0;
  double adaptivity_s = 0;  // estimates + operations + rebuild
  double estimate_s = 0, operations_s = 0, rebuild_s = 0;
  int vertices_final = 0, vertices_max = 0;
  int splits = 0, merges = 0, forced = 0, changes = 0, steps = 0, retries = 0;
  std::vector<Eigen::MatrixX3d> samples;  // material-point positions at the sample times
  double error_final = 0, error_trajectory = 0;
  std::vector<double> errors;  // at each sample time
  ShapeFigures shape;
};

// The mesh as gnuplot polygons: per triangle its 3 corners (x y z rgb-of-level), blank line after.
void write_mesh(const std::string& path, const AdaptiveCloth& cloth) {
  static const int kColours[] = {0x440154, 0x3b528b, 0x21918c, 0x5ec962, 0xb5de2b,
                                 0xfde725, 0xf89540, 0xcc4778, 0x7e03a8};
  std::ofstream out(path);
  const Eigen::MatrixX3d x = cloth.positions();
  for (Eigen::Index f = 0; f < cloth.faces().rows(); ++f) {
    const int colour = kColours[std::min(8, cloth.face_levels()(f))];
    for (int k = 0; k < 3; ++k) {
      const auto p = x.row(cloth.faces()(f, k));
      out << p(0) << ' ' << p(1) << ' ' << p(2) << ' ' << colour << '\n';
    }
    out << "\n";
  }
}

RunResult run_case(const std::string& dir, const std::string& scene, const std::string& name,
                   const AdaptiveSheetSpec& spec, int start_level, const AdaptiveSettings& adaptive,
                   const Eigen::MatrixX3d& points, double sample_every) {
  AdaptiveCloth cloth = make_adaptive_sheet(spec, start_level, adaptive);
  RunResult result;
  result.name = name;
  std::ofstream csv(dir + "/" + scene + "_" + name + ".csv");
  csv << "time,wall_s,cpu_s,vertices,triangles,splits,merges,stretch,shear,bend,kinetic,"
         "potential\n";
  double wall = 0.0;
  double next_sample = 0.0;
  const auto write_row = [&](const AdaptiveCloth& c, int splits, int merges) {
    const EnergyBreakdown e = c.simulation().energy();
    csv << c.time() << ',' << wall << ',' << result.cpu_s << ',' << c.mesh().vertex_count() << ','
        << c.mesh().triangle_count() << ',' << splits << ',' << merges << ',' << e.stretch << ','
        << e.shear << ',' << e.bend << ',' << e.kinetic << ',' << e.potential << '\n';
  };
  write_row(cloth, 0, 0);
  result.samples.push_back(material_positions(cloth, points));
  next_sample += sample_every;
  const double epsilon = 1e-9;
  while (cloth.time() < spec.duration - epsilon) {
    const double until = std::min(spec.duration, next_sample) - cloth.time();
    const auto start = Clock::now();
    const std::clock_t cpu_start = std::clock();
    const StepOutcome outcome = cloth.step(until);
    wall += std::chrono::duration<double>(Clock::now() - start).count();
    result.cpu_s += static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
    if (!outcome.accepted) {
      std::fprintf(stderr, "%s %s: step failed: %s\n", scene.c_str(), name.c_str(),
                   outcome.failure_reason.c_str());
      break;
    }
    const AdaptiveStepRecord& record = cloth.report().steps.back();
    write_row(cloth, record.splits + record.forced_splits, record.merges);
    if (std::abs(cloth.time() - 1.0) < epsilon)
      write_mesh(dir + "/" + scene + "_" + name + "_t1.dat", cloth);
    if (cloth.time() >= next_sample - epsilon) {
      result.samples.push_back(material_positions(cloth, points));
      next_sample += sample_every;
    }
  }
  write_mesh(dir + "/" + scene + "_" + name + "_end.dat", cloth);
  const AdaptiveReport& report = cloth.report();
  const SimulationReport& sim = cloth.simulation().report();
  result.wall_s = wall;
  result.solve_s = sim.solve_s;
  result.forces_s = sim.forces_s;
  result.estimate_s = report.estimate_s;
  result.operations_s = report.operations_s;
  result.rebuild_s = report.rebuild_s;
  result.adaptivity_s = report.adaptivity_s();
  result.vertices_final = cloth.mesh().vertex_count();
  result.vertices_max = report.vertices_max;
  result.splits = report.splits;
  result.forced = report.forced_splits;
  result.merges = report.merges;
  result.changes = report.topology_changes;
  result.steps = sim.steps;
  result.retries = sim.retries;
  result.shape = shape_figures(cloth.positions());
  return result;
}

// Sample matrices as raw doubles: count, then per sample its rows and values (column-major).
void write_samples(const std::string& path, const std::vector<Eigen::MatrixX3d>& samples) {
  std::ofstream out(path, std::ios::binary);
  const auto put = [&](const void* data, std::size_t bytes) {
    out.write(static_cast<const char*>(data), static_cast<std::streamsize>(bytes));
  };
  const std::int64_t count = static_cast<std::int64_t>(samples.size());
  put(&count, sizeof count);
  for (const Eigen::MatrixX3d& m : samples) {
    const std::int64_t rows = m.rows();
    put(&rows, sizeof rows);
    put(m.data(), sizeof(double) * static_cast<std::size_t>(m.size()));
  }
}

std::vector<Eigen::MatrixX3d> read_samples(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<Eigen::MatrixX3d> samples;
  std::int64_t count = 0;
  if (!in.read(reinterpret_cast<char*>(&count), sizeof count)) return {};
  for (std::int64_t k = 0; k < count; ++k) {
    std::int64_t rows = 0;
    if (!in.read(reinterpret_cast<char*>(&rows), sizeof rows)) return {};
    Eigen::MatrixX3d m(rows, 3);
    if (!in.read(reinterpret_cast<char*>(m.data()),
                 static_cast<std::streamsize>(sizeof(double) * static_cast<std::size_t>(m.size()))))
      return {};
    samples.push_back(std::move(m));
  }
  return samples;
}

void errors_against(RunResult& run, const RunResult& reference) {
  const std::size_t n = std::min(run.samples.size(), reference.samples.size());
  double sum = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double e = rms_distance(run.samples[k], reference.samples[k]);
    run.errors.push_back(e);
    sum += e * e;
  }
  run.error_trajectory = std::sqrt(sum / static_cast<double>(n));
  run.error_final = rms_distance(run.samples[n - 1], reference.samples[n - 1]);
}

// What the study runs (the command line's options, see the top of the file).
struct StudyOptions {
  std::string dir;
  bool quick = false;      // 1 s instead of 4, reference one level finer
  std::string only_scene;  // that scene alone; empty: all
  std::string only;        // just the runs of this name (e.g. adaptive_2mm), no reference
  int finest = 6;          // finest fixed level and adaptive max level (reference: two finer)
  int perturbed = 0;       // runs of the finest fixed level with the body moved by 1 µm
  int adaptive_start = 0;  // level the adaptive runs start from
  bool even_levels = false;
  bool fine_ladder = false;    // refine thresholds in steps of √2
  bool sample_errors = false;  // print each run's error at every sample time
};

int run_study(const StudyOptions& options) {
  const std::string& dir = options.dir;
  const std::string& only_scene = options.only_scene;
  const std::string& only = options.only;
  const bool quick = options.quick;
  const int finest = options.finest;
  std::filesystem::create_directories(dir);
  std::ofstream summary(dir + "/summary.csv");
  summary
      << "scene,run,cpu_s,wall_s,forces_s,solve_s,estimate_s,operations_s,rebuild_s,steps,retries,"
         "vertices_final,vertices_max,splits,forced_splits,merges,topology_changes,"
         "error_final_m,error_trajectory_m,lowest_m,extent_x,extent_y,extent_z,finest_level\n";
  std::vector<std::pair<std::string, AdaptiveSheetSpec>> scenes(4);
  scenes[0].first = "three_corner";
  scenes[0].second.pins = {"top-left", "top-right", "bottom-left"};
  scenes[1].first = "two_corner";
  scenes[1].second.pins = {"top-left", "top-right"};
  // A tablecloth: the 1 m sheet dropped from 2 cm onto a 0.6 m square table, a little off
  // centre (a symmetric start leaves which side folds first to rounding). Its detail is local:
  // the top lies flat, the four drops hang flat but for the folds at the corners, and the
  // crease runs along the table's edges.
  scenes[2].first = "tablecloth";
  scenes[2].second.pins = {};
  scenes[2].second.body = make_box({-0.29, 0.2, -0.31}, {0.31, 0.98, 0.29});
  // The sheet dropped from 5 cm onto a sphere of radius 0.25 m, off its top vertex (as the
  // sphere-drop scene of `sketchdrape bench`).
  scenes[3].first = "sphere";
  scenes[3].second.pins = {};
  scenes[3].second.body = make_sphere(0.25, 4, Eigen::Vector3d(0.031, 0.70, -0.017));
  for (auto& [scene, spec] : scenes) {
    if (!only_scene.empty() && scene != only_scene) continue;
    spec.duration = quick ? 1.0 : 4.0;
    const Eigen::MatrixX3d points = sheet_material_points(spec, 33);
    const double every = 0.25;
    std::vector<RunResult> runs;
    const auto wanted = [&](const std::string& name) { return only.empty() || only == name; };
    for (int level : {finest - 4, finest - 2, finest})
      if (const std::string name = "fixed_l" + std::to_string(level); wanted(name))
        runs.push_back(run_case(dir, scene, name, spec, level, fixed_settings(), points, every));
    // Where the drape is sensitive to its start (a sheet landing on a body), the finest fixed run
    // with the body moved by 1 µm: how far a perturbation no mesh can resolve moves the result,
    // the width of the fixed-finest run's own error band.
    for (int k = 0; k < options.perturbed && spec.body.face_count() > 0; ++k) {
      const std::string name = "fixed_l" + std::to_string(finest) + "_moved_" + std::to_string(k);
      if (!wanted(name)) continue;
      AdaptiveSheetSpec moved = spec;
      const double angle = 2.0 * std::numbers::pi * (k + 0.5) / options.perturbed;
      const Eigen::RowVector3d shift(1e-6 * std::cos(angle), 0.0, 1e-6 * std::sin(angle));
      moved.body.vertices.rowwise() += shift;
      runs.push_back(run_case(dir, scene, name, moved, finest, fixed_settings(), points, every));
    }
    for (double threshold : refine_thresholds(finest, options.fine_ladder)) {
      char name[64];
      std::snprintf(name, sizeof name, "adaptive_%gmm", threshold * 1e3);
      if (wanted(name))
        runs.push_back(run_case(dir, scene, name, spec, options.adaptive_start,
                                study_settings(threshold, finest, options.even_levels), points,
                                every));
    }
    if (runs.empty()) continue;
    // The reference last, so that a profiled run is not preceded by it. Its samples are kept in
    // DIR, so that a later --only run is measured against them; with --only and no kept
    // reference each run is measured against itself (errors 0).
    const int reference_level = quick ? finest + 1 : finest + 2;
    const std::string reference_name = "fixed_l" + std::to_string(reference_level);
    const std::string kept =
        dir + "/" + scene + "_" + reference_name + (quick ? "_quick" : "") + "_samples.bin";
    RunResult reference;
    if (only.empty()) {
      runs.push_back(run_case(dir, scene, reference_name, spec, reference_level, fixed_settings(),
                              points, every));
      reference = runs.back();
      write_samples(kept, reference.samples);
    } else if (std::vector<Eigen::MatrixX3d> samples = read_samples(kept); !samples.empty()) {
      reference.samples = std::move(samples);
    } else {
      reference = runs.back();
    }
    for (RunResult& run : runs) {
      errors_against(run, reference);
      summary << scene << ',' << run.name << ',' << run.cpu_s << ',' << run.wall_s << ','
              << run.forces_s << ',' << run.solve_s << ',' << run.estimate_s << ','
              << run.operations_s << ',' << run.rebuild_s << ',' << run.steps << ',' << run.retries
              << ',' << run.vertices_final << ',' << run.vertices_max << ',' << run.splits << ','
              << run.forced << ',' << run.merges << ',' << run.changes << ',' << run.error_final
              << ',' << run.error_trajectory << ',' << run.shape.lowest << ','
              << run.shape.extent.x() << ',' << run.shape.extent.y() << ',' << run.shape.extent.z()
              << ',' << finest << '\n';
      std::printf(
          "%-13s %-16s cpu %7.2f s wall %7.2f s (forces %6.2f solve %6.2f adapt %5.3f = est %5.3f "
          "+ ops %5.3f "
          "+ rebuild %5.3f) steps %4d retries %3d verts %5d (max %5d) splits %5d+%4d merges %5d "
          "error final %.2f mm trajectory %.2f mm lowest %.4f\n",
          scene.c_str(), run.name.c_str(), run.cpu_s, run.wall_s, run.forces_s, run.solve_s,
          run.adaptivity_s, run.estimate_s, run.operations_s, run.rebuild_s, run.steps, run.retries,
          run.vertices_final, run.vertices_max, run.splits, run.forced, run.merges,
          1e3 * run.error_final, 1e3 * run.error_trajectory, run.shape.lowest);
      if (options.sample_errors) {
        std::printf("%-13s %-16s errors mm:", scene.c_str(), run.name.c_str());
        for (double e : run.errors) std::printf(" %.2f", 1e3 * e);
        std::printf("\n");
      }
      std::fflush(stdout);
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  sd::sim::limit_solver_library_threads();  // the solvers as sketchdrape runs them
  StudyOptions options;
  std::vector<char*> rest;
  for (int i = 0; i < argc; ++i) {
    if (std::strncmp(argv[i], "--study=", 8) == 0)
      options.dir = argv[i] + 8;
    else if (std::strncmp(argv[i], "--scene=", 8) == 0)
      options.only_scene = argv[i] + 8;
    else if (std::strncmp(argv[i], "--only=", 7) == 0)
      options.only = argv[i] + 7;
    else if (std::strncmp(argv[i], "--finest=", 9) == 0)
      options.finest = std::atoi(argv[i] + 9);
    else if (std::strncmp(argv[i], "--perturbed=", 12) == 0)
      options.perturbed = std::atoi(argv[i] + 12);
    else if (std::strncmp(argv[i], "--adaptive-start=", 17) == 0)
      options.adaptive_start = std::atoi(argv[i] + 17);
    else if (std::strcmp(argv[i], "--even-levels") == 0)
      options.even_levels = true;
    else if (std::strcmp(argv[i], "--fine-ladder") == 0)
      options.fine_ladder = true;
    else if (std::strncmp(argv[i], "--target-levels=", 16) == 0)
      g_method.target_levels = std::atoi(argv[i] + 16);
    else if (std::strncmp(argv[i], "--change-interval=", 18) == 0)
      g_method.interval = std::atof(argv[i] + 18);
    else if (std::strncmp(argv[i], "--max-level=", 12) == 0)
      g_method.max_level = std::atoi(argv[i] + 12);
    else if (std::strncmp(argv[i], "--motion-horizon=", 17) == 0)
      g_method.motion_horizon = std::atof(argv[i] + 17);
    else if (std::strncmp(argv[i], "--lookahead=", 12) == 0)
      g_method.lookahead = std::atof(argv[i] + 12);
    else if (std::strcmp(argv[i], "--sample-errors") == 0)
      options.sample_errors = true;
    else if (std::strcmp(argv[i], "--quick") == 0)
      options.quick = true;
    else if (std::strncmp(argv[i], "--threads=", 10) == 0)
      sd::sim::set_thread_count(std::atoi(argv[i] + 10));
    else
      rest.push_back(argv[i]);
  }
  if (options.finest < 4 || options.finest > 11) {
    std::fprintf(stderr, "--finest must be 4 to 11 (fixed runs at N-4, N-2, N, reference N+2)\n");
    return 1;
  }
  if (!options.dir.empty()) return run_study(options);
  int count = static_cast<int>(rest.size());
  benchmark::Initialize(&count, rest.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
