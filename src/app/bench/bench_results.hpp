#pragma once
// The work-precision study's results (`sketchdrape bench`, docs/benchmarks.md): each run's row
// (its child process and its error against the reference), the Pareto front, and the outputs
// made from them: bench.csv rows, bench.json rows, the gnuplot plots and the summary table.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "src/app/bench/bench_study.hpp"
#include "src/app/pipeline/atomic_file.hpp"

namespace sd::app {

// One child run of the study (the worker process): how it ended, what the kernel measured of
// it, and the trace it wrote.
struct ChildResult {
  std::string status;  // "ok", "failed" (the simulation or the worker), "timeout", "crashed"
  std::string message;
  double process_cpu_s = 0.0;  // user + system of the whole child
  double peak_rss_mb = 0.0;    // the child's peak resident memory
  double elapsed_s = 0.0;
  BenchTrace trace;
};

struct RunRow {
  BenchConfig config;
  std::vector<std::string> families;
  ChildResult child;
  BenchError error;
  bool pareto = false;
};

struct SceneResult {
  BenchScene scene;
  BenchPlan plan;
  std::string key;
  bool reference_cached = false;
  ChildResult reference;  // trace from the cache or this run
  std::vector<RunRow> rows;
  std::string defaults_note;
  std::string reference_failure;  // why the reference did not finish (the scene's runs are skipped)
};

// bench.csv's first line.
inline constexpr const char* kCsvHeader =
    "scene,run,mesh,level,threshold_mm,integrator,solver,dt_s,families,status,wall_s,cpu_s,"
    "process_cpu_s,peak_rss_mb,rss_before_run_mb,vertices_max,triangles_max,steps,retries,"
    "linear_solves,cg_iterations_mean,rms_error_m,max_error_m,final_rms_error_m,energy_error_j,"
    "energy_error_relative,pareto,note\n";

// The whole file as bytes ("" when it cannot be read).
std::string read_file(const std::filesystem::path& path);
// Last non-empty line of a worker's log, for messages.
std::string last_line(const std::filesystem::path& log);

// A run that finished and was measured against the reference.
bool usable(const RunRow& row);
// Marks the runs not beaten in both CPU time and RMS error by another run of the scene.
void mark_pareto(std::vector<RunRow>& rows);
// The accuracy bar's error band for the defaults: this many times the RMS error of the same mesh
// at 1/60 s, implicit Euler, CHOLMOD (see defaults_note).
inline constexpr double kDefaultErrorBand = 1.5;
// Where the sketch defaults sit on the scene's front, as a sentence.
std::string defaults_note(const SceneResult& s);
// One bench.csv row (`error` null when the run was not measured).
std::string csv_row(const SceneResult& s, const BenchConfig& c,
                    const std::vector<std::string>& families, const ChildResult& child,
                    const BenchError* error, bool pareto, const std::string& note);
nlohmann::json row_json(const RunRow& row);
// Draws every scene's front with gnuplot under `work` and stages the plots for `dir`; false
// (with a warning) when gnuplot is missing or fails.
bool stage_plots(const std::vector<SceneResult>& scenes, const std::filesystem::path& work,
                 const std::filesystem::path& dir, StagedOutputs& outputs);
// The summary printed on stdout.
std::string summary_table(const std::vector<SceneResult>& scenes, bool plots,
                          const std::filesystem::path& dir);

}  // namespace sd::app
