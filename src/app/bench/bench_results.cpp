#include "src/app/bench/bench_results.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace sd::app {

namespace fs = std::filesystem;

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string last_line(const fs::path& log) {
  std::istringstream in(read_file(log));
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  return last;
}

bool usable(const RunRow& row) {
  return row.child.status == "ok" && row.error.samples > 0;
}

// Runs not beaten in both CPU time and RMS error by another run of the scene.
void mark_pareto(std::vector<RunRow>& rows) {
  for (RunRow& a : rows) {
    if (!usable(a)) continue;
    a.pareto = std::none_of(rows.begin(), rows.end(), [&](const RunRow& b) {
      return &a != &b && usable(b) && b.child.trace.cpu_s <= a.child.trace.cpu_s &&
             b.error.rms_m <= a.error.rms_m &&
             (b.child.trace.cpu_s < a.child.trace.cpu_s || b.error.rms_m < a.error.rms_m);
    });
  }
}

// What the sketch defaults run ("solver" and "time_step" "auto": the automatic families, their
// finest level) against the study. The accuracy bar's error band: an RMS error at most
// kDefaultErrorBand times that of the same mesh at 1/60 s with implicit Euler and CHOLMOD (the
// configuration every earlier default ran; 1.5x as the adaptive study's bar). The rule chooses the
// solver and the step, not the mesh (the sketch's resolution), so the default is compared with the
// runs on its own mesh: the fastest of them within the band, and whether any run of the study
// (any mesh) is both faster and more accurate (the Pareto front).
std::string defaults_note(const SceneResult& s) {
  std::string note;
  for (const std::string& family : {kAutomaticFamily, kAutomaticMotionFamily}) {
    const RunRow* def = nullptr;
    for (const RunRow& row : s.rows)
      if (std::find(row.families.begin(), row.families.end(), family) != row.families.end() &&
          (def == nullptr || row.config.level > def->config.level))
        def = &row;
    const std::string what =
        family == kAutomaticFamily ? "the sketch default" : "the default with --frames";
    if (!note.empty()) note += "; ";
    if (def == nullptr || !usable(*def)) {
      note += what + " did not run";
      continue;
    }
    const auto same_mesh = [&](const RunRow& row) {
      return usable(row) && row.config.mesh == BenchMeshKind::fixed &&
             row.config.level == def->config.level;
    };
    const RunRow* standard = nullptr;  // the same mesh at 1/60 s, IE, CHOLMOD
    for (const RunRow& row : s.rows)
      if (same_mesh(row) && row.config.integrator == sim::Integrator::implicit_euler &&
          row.config.solver == sim::LinearSolverKind::cholmod && !row.config.linearized &&
          row.config.steps_per_second == 60)
        standard = &row;
    note +=
        fmt::format("{} (automatic: {}; {:.2f} mm RMS in {:.2f} s CPU) is {}on the Pareto front",
                    what, def->config.label(), 1e3 * def->error.rms_m, def->child.trace.cpu_s,
                    def->pareto ? "" : "not ");
    if (standard == nullptr || !(standard->error.rms_m > 0.0)) continue;
    const double band = kDefaultErrorBand * standard->error.rms_m;
    const RunRow* fastest = nullptr;  // the cheapest run on the same mesh within the band
    for (const RunRow& row : s.rows)
      if (same_mesh(row) && row.error.rms_m <= band &&
          (fastest == nullptr || row.child.trace.cpu_s < fastest->child.trace.cpu_s))
        fastest = &row;
    const double ratio = def->error.rms_m / standard->error.rms_m;
    if (def->error.rms_m <= band)
      note += fmt::format(
          ", within the error band ({:.2f}x the 1/60 s run's error on its mesh, band {:.1f}x) at "
          "{:.2f}x the CPU time of the fastest run there within it ({})",
          ratio, kDefaultErrorBand,
          fastest->child.trace.cpu_s > 0.0 ? def->child.trace.cpu_s / fastest->child.trace.cpu_s
                                           : 1.0,
          fastest->config.label());
    else
      note += fmt::format(
          ", outside the error band ({:.2f}x the 1/60 s run's error on its mesh, band {:.1f}x; the "
          "fastest run there within it: {}, {:.2f} s CPU)",
          ratio, kDefaultErrorBand, fastest->config.label(), fastest->child.trace.cpu_s);
  }
  return note;
}

namespace {

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string quoted = "\"";
  for (char c : s) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

std::string join(const std::vector<std::string>& parts, const std::string& separator) {
  std::string out;
  for (size_t i = 0; i < parts.size(); ++i) out += (i ? separator : "") + parts[i];
  return out;
}

std::string number(double value) {
  return fmt::format("{:.6g}", value);
}

}  // namespace

std::string csv_row(const SceneResult& s, const BenchConfig& c,
                    const std::vector<std::string>& families, const ChildResult& child,
                    const BenchError* error, bool pareto, const std::string& note) {
  const BenchTrace& t = child.trace;
  const bool measured = child.status == "ok" || child.status == "failed";
  const bool process = child.peak_rss_mb > 0;
  std::vector<std::string> f = {csv_field(s.scene.name),
                                c.id(),
                                c.mesh == BenchMeshKind::adaptive ? "adaptive" : "fixed",
                                std::to_string(c.level),
                                c.mesh == BenchMeshKind::adaptive ? number(c.threshold * 1e3) : "",
                                std::string(sim::integrator_name(c.integrator)),
                                std::string(sim::solver_name(c.solver)),
                                number(c.dt()),
                                csv_field(join(families, "; ")),
                                child.status,
                                measured ? number(t.wall_s) : "",
                                measured ? number(t.cpu_s) : "",
                                process ? number(child.process_cpu_s) : "",
                                process ? number(child.peak_rss_mb) : "",
                                measured ? number(t.rss_before_mb) : "",
                                measured ? std::to_string(t.vertices_max) : "",
                                measured ? std::to_string(t.triangles_max) : "",
                                measured ? std::to_string(t.steps) : "",
                                measured ? std::to_string(t.retries) : "",
                                measured ? std::to_string(t.linear_solves) : "",
                                measured ? number(t.cg_iterations_mean) : "",
                                error ? number(error->rms_m) : "",
                                error ? number(error->max_m) : "",
                                error ? number(error->final_rms_m) : "",
                                error ? number(error->energy_j) : "",
                                error ? number(error->energy_relative) : "",
                                pareto ? "1" : "0",
                                csv_field(note)};
  return join(f, ",") + "\n";
}

nlohmann::json row_json(const RunRow& row) {
  const BenchTrace& t = row.child.trace;
  nlohmann::json j = {{"run", row.config.id()},
                      {"label", row.config.label()},
                      {"families", row.families},
                      {"status", row.child.status},
                      {"message", row.child.message},
                      {"wall_s", t.wall_s},
                      {"cpu_s", t.cpu_s},
                      {"process_cpu_s", row.child.process_cpu_s},
                      {"peak_rss_mb", row.child.peak_rss_mb},
                      {"rss_before_run_mb", t.rss_before_mb},
                      {"vertices_max", t.vertices_max},
                      {"steps", t.steps},
                      {"retries", t.retries},
                      {"pareto", row.pareto}};
  if (usable(row))
    j["error"] = {{"rms_m", row.error.rms_m},
                  {"max_m", row.error.max_m},
                  {"final_rms_m", row.error.final_rms_m},
                  {"energy_j", row.error.energy_j},
                  {"energy_relative", row.error.energy_relative}};
  return j;
}

// --- plots ---------------------------------------------------------------------------------------

namespace {

std::string plot_data(const SceneResult& s) {
  std::string out;
  for (const BenchFamily& family : s.plan.families) {
    out += fmt::format("# {}\n", family.name);
    for (const BenchConfig& c : family.members)
      for (const RunRow& row : s.rows)
        if (row.config.id() == c.id() && usable(row) && row.error.rms_m > 0)
          out += fmt::format("{:.6g} {:.6g} {:.6g} \"{}\"\n", row.child.trace.cpu_s,
                             row.error.rms_m, row.child.trace.wall_s, c.id());
    out += "\n\n";
  }
  std::vector<const RunRow*> front;
  for (const RunRow& row : s.rows)
    if (row.pareto && row.error.rms_m > 0) front.push_back(&row);
  std::sort(front.begin(), front.end(), [](const RunRow* a, const RunRow* b) {
    return a->child.trace.cpu_s < b->child.trace.cpu_s;
  });
  out += "# Pareto front\n";
  for (const RunRow* row : front)
    out += fmt::format("{:.6g} {:.6g} {:.6g} \"{}\"\n", row->child.trace.cpu_s, row->error.rms_m,
                       row->child.trace.wall_s, row->config.id());
  out += "\n\n";
  return out;
}

std::string plot_script(const SceneResult& s, const std::string& stem) {
  std::string plots;
  const size_t n = s.plan.families.size();
  for (size_t i = 0; i < n; ++i)
    plots +=
        fmt::format("'{}.dat' index {} using 1:2 with linespoints lw 2 pt 7 ps 1.2 title \"{}\", ",
                    stem, i, s.plan.families[i].name);
  plots += fmt::format(
      "'{}.dat' index {} using 1:2 with lines dt 2 lc rgb 'black' notitle, "
      "'{}.dat' index {} using 1:2 with points pt 6 ps 2.6 lw 1.5 lc rgb 'black' title \"Pareto "
      "front\"",
      stem, n, stem, n);
  const std::string title = fmt::format("{}: error against the reference ({}) over {:g} s",
                                        s.scene.name, s.plan.reference.label(), s.scene.duration);
  std::string script;
  for (const auto& [terminal, extension] :
       {std::pair<std::string, std::string>{"pngcairo size 1100,700 font 'DejaVu Sans,10'", "png"},
        {"svg size 1100,700 font 'DejaVu Sans,10' background rgb 'white'", "svg"}}) {
    script += fmt::format(
        "set terminal {}\nset output '{}.{}'\nset logscale xy\nset grid xtics ytics mxtics mytics\n"
        "set xlabel 'CPU time of the run (s)'\nset ylabel 'RMS distance at material points (m)'\n"
        "set title \"{}\" noenhanced\nset key below left Left reverse maxrows 4 noenhanced\nset "
        "format y '%.0e'\n"
        "plot {}\nunset output\n",
        terminal, stem, extension, title, plots);
  }
  return script;
}

}  // namespace

// Writes the plots of every scene with gnuplot into `work` and stages them; false (and a
// warning) when gnuplot is not installed or fails.
bool stage_plots(const std::vector<SceneResult>& scenes, const fs::path& work, const fs::path& dir,
                 StagedOutputs& outputs) {
  const fs::path plot_dir = work / "plots";
  fs::create_directories(plot_dir);
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) {
    spdlog::warn(
        "gnuplot is not installed: bench.csv is written, the plots are not "
        "(apt-get install gnuplot-nox, or run ./scripts/setup.sh)");
    return false;
  }
  for (const SceneResult& s : scenes) {
    if (std::none_of(s.rows.begin(), s.rows.end(), usable)) continue;  // nothing to draw
    const std::string stem = "bench_" + s.scene.name;
    const std::string data = plot_data(s);
    const std::string script = plot_script(s, stem);
    write_file_atomically(plot_dir / (stem + ".dat"), data);
    write_file_atomically(plot_dir / (stem + ".gp"), script);
    const std::string command =
        fmt::format("cd '{}' && gnuplot '{}.gp' > '{}.log' 2>&1", plot_dir.string(), stem, stem);
    if (std::system(command.c_str()) != 0) {
      spdlog::warn("gnuplot failed on {}.gp: {}", stem, last_line(plot_dir / (stem + ".log")));
      return false;
    }
    outputs.stage(dir / (stem + ".dat"), data);
    outputs.stage(dir / (stem + ".gp"), script);
    outputs.stage(dir / (stem + ".png"), read_file(plot_dir / (stem + ".png")));
    outputs.stage(dir / (stem + ".svg"), read_file(plot_dir / (stem + ".svg")));
  }
  return true;
}

// --- the summary on stdout
// ------------------------------------------------------------------------

std::string summary_table(const std::vector<SceneResult>& scenes, bool plots, const fs::path& dir) {
  std::string out;
  for (const SceneResult& s : scenes) {
    out += fmt::format("\n{} ({:g} s simulated; reference: {}, {}{:.1f} s CPU)\n", s.scene.name,
                       s.scene.duration, s.plan.reference.label(),
                       s.reference_cached ? "cached, " : "", s.reference.trace.cpu_s);
    if (!s.reference_failure.empty()) {
      out += fmt::format("  not measured: {}\n", s.reference_failure);
      continue;
    }
    out += fmt::format("  {:<44} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>9}\n", "configuration",
                       "CPU s", "wall s", "peak MB", "vertices", "RMS mm", "max mm", "energy %");
    std::vector<const RunRow*> order;
    for (const RunRow& row : s.rows) order.push_back(&row);
    std::stable_sort(order.begin(), order.end(), [](const RunRow* a, const RunRow* b) {
      return a->child.trace.cpu_s < b->child.trace.cpu_s;
    });
    for (const RunRow* row : order) {
      const BenchTrace& t = row->child.trace;
      if (!usable(*row)) {
        out += fmt::format("  {:<44} {}: {}\n", row->config.label(), row->child.status,
                           row->child.message);
        continue;
      }
      out += fmt::format("{} {:<44} {:>8.2f} {:>8.2f} {:>8.0f} {:>8} {:>8.2f} {:>8.2f} {:>9.1f}\n",
                         row->pareto ? "*" : " ", row->config.label(), t.cpu_s, t.wall_s,
                         row->child.peak_rss_mb, t.vertices_max, 1e3 * row->error.rms_m,
                         1e3 * row->error.max_m, 100 * row->error.energy_relative);
    }
    out += fmt::format("  * on the Pareto front (no run is both faster and more accurate)\n");
    out += fmt::format("  defaults: {}\n", s.defaults_note);
  }
  out +=
      fmt::format("\nwrote {}{}\n", (dir / "bench.csv").string(),
                  plots ? fmt::format(" and the plots {}", (dir / "bench_<scene>.png|svg").string())
                        : std::string(" (no plots: gnuplot missing)"));
  return out;
}

}  // namespace sd::app
