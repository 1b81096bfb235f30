// `sketchdrape stress [--quick] [-o DIR | --json] [--case TEXT]... [--min-dt S] [--list]`: runs
// the matrix of hostile conditions (src/app/stress/stress_cases.hpp) through the simulator, prints
// a table, writes stress.json, and exits 1 when any case diverged (docs/stress.md).

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>

#include "src/app/commands/cli.hpp"
#include "src/app/pipeline/atomic_file.hpp"
#include "src/app/pipeline/progress.hpp"
#include "src/app/stress/stress_runner.hpp"
#include "src/app/version.hpp"

namespace sd::app {
namespace {

struct StressCommandOptions {
  bool quick = false;
  std::string out;
  bool json = false;
  std::vector<std::string> cases;  // substrings of case ids; empty: all
  double min_dt = 0.0;             // 0: each case's own
  bool list = false;
};

std::vector<StressCase> selected_cases(const StressCommandOptions& options) {
  std::vector<StressCase> all = stress_matrix(options.quick);
  if (options.cases.empty()) return all;
  std::vector<StressCase> chosen;
  for (StressCase& c : all)
    if (std::any_of(options.cases.begin(), options.cases.end(),
                    [&](const std::string& text) { return c.id.find(text) != std::string::npos; }))
      chosen.push_back(std::move(c));
  if (chosen.empty())
    throw std::invalid_argument(
        fmt::format("no stress case id contains {}; `sketchdrape stress --list{}` prints them",
                    fmt::join(options.cases, " or "), options.quick ? " --quick" : ""));
  return chosen;
}

std::string short_status(const StressResult& r) {
  if (r.status == "rejected") return "rejected (ok)";
  return r.ok ? r.status : r.status + " !";
}

void print_table(const std::vector<StressResult>& results, std::FILE* out) {
  size_t width = 4;
  for (const StressResult& r : results) width = std::max(width, r.id.size());
  std::fprintf(out, "%-*s  %-14s %6s %6s %7s %6s %9s %7s %9s %9s %7s %6s %4s %7s\n",
               static_cast<int>(width), "case", "status", "t_end", "steps", "retries", "forced",
               "dt_min", "strain", "Epeak/sc", "Eend/sc", "speed", "verts", "rest", "wall_s");
  for (const StressResult& r : results) {
    if (r.status == "rejected" || (r.steps == 0 && !r.ok)) {
      std::fprintf(out, "%-*s  %-14s %s\n", static_cast<int>(width), r.id.c_str(),
                   short_status(r).c_str(), r.reason.c_str());
      continue;
    }
    const double scale = r.energy_scale > 0 ? r.energy_scale : 1.0;
    std::fprintf(out, "%-*s  %-14s %6.3f %6d %7d %6d %9.3g %7.3f %9.2e %9.2e %7.2f %6d %4s %7.2f\n",
                 static_cast<int>(width), r.id.c_str(), short_status(r).c_str(), r.sim_time,
                 r.steps, r.retries, r.forced_steps, r.dt_min_used, r.max_strain,
                 r.energy_growth / scale, r.energy_final_growth / scale, r.max_speed, r.vertices,
                 r.at_rest ? "yes" : "no", r.wall_time_s);
    if (!r.ok) std::fprintf(out, "%*s  -> %s\n", static_cast<int>(width), "", r.reason.c_str());
  }
}

nlohmann::json bounds_json() {
  return {{"strain", "max(simulator strain limit, start strain)"},
          {"speed", "the simulator's speed limit (m/s)"},
          {"energy",
           fmt::format("total energy at the end minus that of the reference state (the first "
                       "state nothing drives any more) <= {:g} x (M |g| L + elastic + kinetic of "
                       "the reference state)",
                       kStressEnergyTolerance)},
          {"energy_tolerance", kStressEnergyTolerance},
          {"max_attempts", kStressMaxAttempts}};
}

void run_stress(const StressCommandOptions& options, const GlobalOptions& global) {
  if (options.min_dt < 0.0 || !std::isfinite(options.min_dt))
    throw std::invalid_argument("--min-dt must be a positive number of seconds");
  if (options.json && !options.out.empty())
    throw std::invalid_argument(
        "give either -o DIR (writes DIR/stress.json) or --json (stdout), not both");
  const std::vector<StressCase> cases = selected_cases(options);
  if (!options.list && !options.out.empty()) check_output_folder(options.out);
  if (options.list) {
    for (const StressCase& c : cases)
      std::printf("%s%s  %s\n", c.id.c_str(), c.quick && !options.quick ? " (quick)" : "",
                  c.condition.c_str());
    return;
  }

  StressOptions run_options;
  if (options.min_dt > 0.0) run_options.min_dt = options.min_dt;
  // The simulator warns on every forced step; under stress that is expected and counted in the
  // table, so its logs are kept to errors unless --verbose.
  const spdlog::level::level_enum level = spdlog::get_level();
  if (!global.verbose) spdlog::set_level(spdlog::level::err);
  std::vector<StressResult> results;
  {
    // Libraries that print (CHOLMOD warns "matrix not positive definite" on stdout) must not mix
    // into the table or the JSON: stdout goes to stderr while the cases run.
    std::fflush(stdout);
    const int saved_stdout = ::dup(1);
    ::dup2(2, 1);
    struct RestoreStdout {
      int fd;
      ~RestoreStdout() {
        std::fflush(stdout);
        if (fd >= 0) {
          ::dup2(fd, 1);
          ::close(fd);
        }
      }
    } restore{saved_stdout};
    Progress progress(options.quick ? "stress --quick" : "stress", static_cast<long>(cases.size()),
                      global.quiet);
    for (const StressCase& c : cases) {
      progress.update(static_cast<long>(results.size()), c.id);
      results.push_back(run_stress_case_isolated(c, run_options));
    }
    progress.finish();
  }
  spdlog::set_level(level);

  std::map<std::string, int> counts;
  double wall = 0.0;
  std::vector<std::string> bad;
  for (const StressResult& r : results) {
    ++counts[r.status];
    wall += r.wall_time_s;
    if (!r.ok) bad.push_back(r.id);
  }
  nlohmann::json out = {
      {"format", "sketchdrape/1 stress report"},
      {"version", kVersion},
      {"matrix", options.quick ? "quick" : "full"},
      {"selection", options.cases},
      {"min_dt_override", options.min_dt > 0.0 ? nlohmann::json(options.min_dt) : nullptr},
      {"bounds", bounds_json()},
      {"counts", counts},
      {"diverged", bad},
      {"wall_time_s", wall},
      {"cases", nlohmann::json::array()}};
  for (const StressResult& r : results) out["cases"].push_back(stress_result_json(r));

  if (options.json) {
    std::cout << out.dump(2) << "\n";
  } else if (!global.quiet) {
    print_table(results, stdout);
  }
  if (!options.out.empty()) {
    const std::filesystem::path path = std::filesystem::path(options.out) / "stress.json";
    std::filesystem::create_directories(options.out);
    write_file_atomically(path, out.dump(2) + "\n");
    spdlog::info("wrote {}", path.string());
  }
  const std::string summary = fmt::format("{} of {} stress cases held ({:.1f} s)",
                                          results.size() - bad.size(), results.size(), wall);
  if (!bad.empty())
    throw std::runtime_error(
        fmt::format("{}; diverged or failed: {}", summary, fmt::join(bad, ", ")));
  spdlog::info("{}", summary);
}

}  // namespace

void add_stress_command(CLI::App& app, const GlobalOptions& global) {
  auto options = std::make_shared<StressCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "stress",
      "Run the simulator through a matrix of hostile conditions; exit 1 if any case "
      "diverges (docs/stress.md)");
  cmd->add_flag("--quick", options->quick, "The reduced matrix CI runs (under a minute)");
  cmd->add_option("-o,--out", options->out, "Write DIR/stress.json")->check(non_empty_path());
  cmd->add_flag("--json", options->json, "Print the JSON report on stdout instead of the table");
  cmd->add_option("--case", options->cases,
                  "Only cases whose id contains this text (repeatable; see --list)");
  cmd->add_option("--min-dt", options->min_dt,
                  "Override every case's minimum step, seconds (capped at its step): how much "
                  "the cases rely on step control halving")
      ->check(finite_range(1e-9, 1.0));
  cmd->add_flag("--list", options->list, "Print the case ids and conditions, run nothing");
  cmd->callback([options, &global] { run_stress(*options, global); });
}

}  // namespace sd::app
