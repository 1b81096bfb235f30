#pragma once
// The scaling study of `sketchdrape bench --scaling` (docs/benchmarks.md, "Scaling"): the pinned
// 1 m cotton sheet at N×N quads (N = 32 … 256: 1,089 to 66,049 vertices), a fixed number of
// steps per solver, each size in its own child process (`sketchdrape run`), so the time per step
// comes from the run's report and the peak memory from the kernel. The CPU time per step is the
// difference between that run and a one-step run of the same scene (the set-up cancels), which
// other programs on the machine barely change; the wall time per step is the report's. The fit
// gives the exponent k of CPU time per step ∝ vertices^k and the memory each further vertex costs.

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace sd::app {

struct ScalingOptions {
  std::vector<int> sizes = {32, 64, 128, 256};  // quads a side
  // Sketch-file names; pcg-two-level is the PCG with the two-level preconditioner.
  std::vector<std::string> solvers = {"cholmod", "pcg", "pcg-two-level"};
  int steps = 10;          // steps of 1/60 s per run
  int threads = 0;         // --threads of the runs; 0: default
  double timeout_s = 900;  // per run
};

struct ScalingPoint {
  int quads_per_side = 0;
  std::string solver;
  int vertices = 0;
  std::string status;  // "ok", "failed", "timeout", "crashed"
  std::string message;
  int steps = 0;              // accepted steps (retries excluded)
  double simulation_s = 0.0;  // wall time of the stepping (the report's wall_time_s)
  double step_s = 0.0;        // simulation_s / steps (wall)
  double cpu_step_s = 0.0;    // (CPU of this run − CPU of a one-step run) / (steps − 1)
  double solve_s = 0.0, forces_s = 0.0, collision_s = 0.0;  // per run
  double cg_iterations_mean = 0.0;                          // PCG only
  double process_cpu_s = 0.0;                               // the whole child
  double peak_rss_mb = 0.0;
};

// Least-squares fit over the ok points of one solver (at least two sizes).
struct ScalingFit {
  std::string solver;
  int points = 0;
  double exponent = 0.0;        // k in step_s ∝ vertices^k (slope in log-log)
  double coefficient_s = 0.0;   // step_s at 1,000 vertices on the fitted line
  double kb_per_vertex = 0.0;   // slope of peak memory against vertices (marginal cost)
  double base_memory_mb = 0.0;  // its intercept (the process without cloth)
};

ScalingFit fit_scaling(const std::string& solver, const std::vector<ScalingPoint>& points);

// The scene file `sketchdrape run` reads for one point (a sheet scene, sketchdrape/1).
std::string scaling_scene(int quads_per_side, const std::string& solver, int steps);

// Runs every size × solver with `binary` under `work` (a folder it may fill). `note` is called
// with a line before each run and `tick` while it runs.
std::vector<ScalingPoint> run_scaling(const std::filesystem::path& binary,
                                      const ScalingOptions& options,
                                      const std::filesystem::path& work,
                                      const std::function<void(const std::string&)>& note = {},
                                      const std::function<void(double)>& tick = {});

// The CSV (one row per point) and the Markdown table with the fits under it.
std::string scaling_csv(const std::vector<ScalingPoint>& points);
std::string scaling_table(const std::vector<ScalingPoint>& points,
                          const std::vector<ScalingFit>& fits);

}  // namespace sd::app
