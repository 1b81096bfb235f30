#include "src/app/bench/bench_scaling.hpp"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "src/app/pipeline/child_process.hpp"

namespace sd::app {
namespace {

namespace fs = std::filesystem;

// Ordinary least squares y = a + b·x; {a, b}. Needs two distinct x.
std::pair<double, double> line_fit(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sx += x[i];
    sy += y[i];
    sxx += x[i] * x[i];
    sxy += x[i] * y[i];
  }
  const double denominator = n * sxx - sx * sx;
  if (!(std::abs(denominator) > 0.0)) return {std::nan(""), std::nan("")};
  const double b = (n * sxy - sx * sy) / denominator;
  return {(sy - b * sx) / n, b};
}

std::string last_line(const fs::path& log) {
  std::ifstream in(log);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  return last;
}

}  // namespace

ScalingFit fit_scaling(const std::string& solver, const std::vector<ScalingPoint>& points) {
  ScalingFit fit;
  fit.solver = solver;
  std::vector<double> log_v, log_t, v, mb;
  for (const ScalingPoint& p : points)
    if (p.solver == solver && p.status == "ok" && p.cpu_step_s > 0.0 && p.vertices > 0) {
      log_v.push_back(std::log(static_cast<double>(p.vertices)));
      log_t.push_back(std::log(p.cpu_step_s));
      v.push_back(static_cast<double>(p.vertices));
      mb.push_back(p.peak_rss_mb);
    }
  fit.points = static_cast<int>(v.size());
  if (fit.points < 2) return fit;
  const auto [log_c, k] = line_fit(log_v, log_t);
  fit.exponent = k;
  fit.coefficient_s = std::exp(log_c + k * std::log(1000.0));
  const auto [base, slope] = line_fit(v, mb);
  fit.kb_per_vertex = slope * 1024.0;
  fit.base_memory_mb = base;
  return fit;
}

std::string scaling_scene(int quads_per_side, const std::string& solver, int steps) {
  constexpr double kStep = 1.0 / 60.0;
  const nlohmann::json scene = {{"format", "sketchdrape/1"},
                                {"sheet",
                                 {{"size", {1.0, 1.0}},
                                  {"resolution", {quads_per_side, quads_per_side}},
                                  {"orientation", "horizontal"},
                                  {"centre", {0.0, 1.2, 0.0}},
                                  {"pins", {"top-left", "top-right"}}}},
                                {"fabric", "cotton"},
                                {"simulate",
                                 {{"duration", steps * kStep},
                                  {"time_step", kStep},
                                  {"stop_at_rest", false},
                                  {"integrator", "implicit-euler"},
                                  {"solver", solver}}},
                                {"output", {{"images", nlohmann::json::array()}}}};
  return scene.dump(2) + "\n";
}

std::vector<ScalingPoint> run_scaling(const fs::path& binary, const ScalingOptions& options,
                                      const fs::path& work,
                                      const std::function<void(const std::string&)>& note,
                                      const std::function<void(double)>& tick) {
  std::vector<ScalingPoint> points;
  for (const std::string& solver : options.solvers)
    for (int n : options.sizes) {
      ScalingPoint p;
      p.quads_per_side = n;
      p.solver = solver;
      p.vertices = (n + 1) * (n + 1);
      if (note) note(fmt::format("{}×{} sheet, {}", n, n, solver));
      // One child run of `steps` steps; the report's figures into p when `full`.
      const auto run_once = [&](int steps, bool full) {
        const std::string tag = fmt::format("sheet-{}-{}-{}", n, solver, steps);
        const fs::path scene = work / (tag + ".json");
        const fs::path out = work / tag;
        {
          std::ofstream file(scene);
          file << scaling_scene(n, solver, steps);
        }
        std::vector<std::string> args = {"--quiet"};
        if (options.threads > 0) {
          args.push_back("--threads");
          args.push_back(std::to_string(options.threads));
        }
        args.insert(args.end(), {"run", scene.string(), "-o", out.string()});
        const ChildRun run =
            run_child(binary, args, work / (tag + ".log"), options.timeout_s, tick);
        const fs::path report_path = out / "report.json";
        ScalingPoint r;
        r.process_cpu_s = run.cpu_s;
        r.peak_rss_mb = run.peak_rss_mb;
        if (run.timed_out) {
          r.status = "timeout";
          r.message = fmt::format("stopped after {:.0f} s", options.timeout_s);
        } else if (!run.exited) {
          r.status = "crashed";
          r.message = fmt::format("killed by signal {}", run.signal);
        } else if (run.exit_code != 0 || !fs::exists(report_path)) {
          r.status = "failed";
          r.message = last_line(work / (tag + ".log"));
        } else {
          std::ifstream in(report_path);
          const nlohmann::json report = nlohmann::json::parse(in);
          r.steps = report.at("steps").get<int>();
          r.simulation_s = report.at("wall_time_s").get<double>();
          r.step_s = r.steps > 0 ? r.simulation_s / r.steps : 0.0;
          const nlohmann::json& timing = report.at("timing_s");
          r.solve_s = timing.value("solve", 0.0);
          r.forces_s = timing.value("forces", 0.0);
          r.collision_s = timing.value("collision", 0.0);
          r.cg_iterations_mean = report.value("cg_iterations_mean", 0.0);
          const bool failed = report.value("failed", false);
          r.status = failed ? "failed" : "ok";
          if (failed) r.message = report.value("failure_reason", std::string());
        }
        if (full) {
          r.quads_per_side = p.quads_per_side;
          r.solver = p.solver;
          r.vertices = p.vertices;
          p = r;
        }
        return r;
      };
      const ScalingPoint baseline = run_once(1, false);
      run_once(options.steps, true);
      if (p.status == "ok" && baseline.status != "ok") {
        p.status = baseline.status;
        p.message = "the one-step run: " + baseline.message;
      }
      if (p.status == "ok" && p.steps > baseline.steps)
        p.cpu_step_s = (p.process_cpu_s - baseline.process_cpu_s) / (p.steps - baseline.steps);
      points.push_back(p);
    }
  return points;
}

std::string scaling_csv(const std::vector<ScalingPoint>& points) {
  std::ostringstream out;
  out << "quads_per_side,solver,vertices,status,steps,simulation_s,step_s,cpu_step_s,solve_s,"
         "forces_s,collision_s,cg_iterations_mean,process_cpu_s,peak_rss_mb\n";
  for (const ScalingPoint& p : points)
    out << fmt::format(
        "{},{},{},{},{},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.4g},{:.6g},{:.6g}\n",
        p.quads_per_side, p.solver, p.vertices, p.status, p.steps, p.simulation_s, p.step_s,
        p.cpu_step_s, p.solve_s, p.forces_s, p.collision_s, p.cg_iterations_mean, p.process_cpu_s,
        p.peak_rss_mb);
  return out.str();
}

std::string scaling_table(const std::vector<ScalingPoint>& points,
                          const std::vector<ScalingFit>& fits) {
  std::ostringstream out;
  out << "| sheet | solver | vertices | CPU ms per step | wall ms per step | solve / forces / "
         "collision wall ms per step | PCG iterations | peak MB | KB per vertex |\n"
         "|---|---|---|---|---|---|---|---|---|\n";
  for (const ScalingPoint& p : points) {
    if (p.status != "ok") {
      out << fmt::format("| {0}×{0} | {1} | {2} | {3}: {4} | | | | {5:.0f} | |\n", p.quads_per_side,
                         p.solver, p.vertices, p.status, p.message, p.peak_rss_mb);
      continue;
    }
    const double per = p.steps > 0 ? 1000.0 / p.steps : 0.0;
    out << fmt::format(
        "| {0}×{0} | {1} | {2} | {10:.1f} | {3:.1f} | {4:.1f} / {5:.1f} / {6:.1f} | {7} | {8:.0f} "
        "| "
        "{9:.2f} |\n",
        p.quads_per_side, p.solver, p.vertices, 1000.0 * p.step_s, per * p.solve_s,
        per * p.forces_s, per * p.collision_s,
        p.solver != "cholmod" ? fmt::format("{:.0f}", p.cg_iterations_mean) : std::string("–"),
        p.peak_rss_mb, 1024.0 * p.peak_rss_mb / p.vertices, 1000.0 * p.cpu_step_s);
  }
  out << "\n";
  for (const ScalingFit& f : fits) {
    if (f.points < 2) {
      out << fmt::format("{}: fewer than two sizes ran; no fit\n", f.solver);
      continue;
    }
    out << fmt::format(
        "{}: CPU time per step ∝ vertices^{:.2f} ({:.1f} ms at 1,000 vertices on the fitted line, "
        "{} "
        "sizes); memory {:.2f} KB per further vertex over {:.0f} MB\n",
        f.solver, f.exponent, 1000.0 * f.coefficient_s, f.points, f.kb_per_vertex,
        f.base_memory_mb);
  }
  return out.str();
}

}  // namespace sd::app
