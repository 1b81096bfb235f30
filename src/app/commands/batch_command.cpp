// `sketchdrape batch INPUTS... -o DIR`: many sketches (files, JSON or CSV manifests with
// overrides and matrices) run as child processes, resumable, optionally one shard of N;
// `sketchdrape batch --collect DIR` rebuilds the summary from what the shards wrote.
// See docs/batch.md.

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <iostream>
#include <memory>
#include <set>

#include "src/app/batch/batch_runner.hpp"
#include "src/app/commands/cli.hpp"
#include "src/app/pipeline/atomic_file.hpp"

namespace sd::app {
namespace {

// The subcommands a job can run: each reads `SKETCH -o DIR`.
const std::set<std::string> kStages = {"mesh", "run"};

struct BatchCommandOptions {
  BatchOptions batch;
  std::string shard;
  std::string collect;
  bool list = false;
};

void fail_if_not_all_done(const std::vector<JobSummary>& jobs, bool interrupted,
                          const std::filesystem::path& where) {
  int bad = 0;
  for (const JobSummary& j : jobs) bad += j.status == "done" ? 0 : 1;
  if (interrupted)
    throw std::runtime_error(
        fmt::format("the batch was stopped; {} of {} jobs are not done (run "
                    "the same command again to finish it)",
                    bad, jobs.size()));
  if (bad > 0)
    throw std::runtime_error(
        fmt::format("{} of {} jobs did not finish; see {}", bad, jobs.size(), where.string()));
}

void run_batch_command(BatchCommandOptions& o, const CLI::App& root, const GlobalOptions& global) {
  if (!o.collect.empty()) {
    if (!o.batch.inputs.empty())
      throw std::invalid_argument("--collect DIR takes no sketch files or manifests");
    const std::filesystem::path out(o.collect);
    const std::vector<JobSummary> jobs = collect_batch(out);
    const std::map<std::string, int> counts = count_statuses(jobs);
    std::vector<std::string> parts;
    for (const auto& [status, n] : counts) parts.push_back(fmt::format("{} {}", n, status));
    spdlog::info("collected {} jobs: {} → {}", jobs.size(), fmt::join(parts, ", "),
                 (out / kContactSheetFile).string());
    fail_if_not_all_done(jobs, false, out / kSummaryFile);
    return;
  }
  if (o.batch.inputs.empty())
    throw std::invalid_argument("give sketch files or manifests to run (or --collect DIR)");
  if (!kStages.contains(o.batch.stage))
    throw std::invalid_argument(
        fmt::format("--stage '{}' is not one of: {}", o.batch.stage, fmt::join(kStages, ", ")));
  if (!o.shard.empty()) o.batch.shard = parse_shard(o.shard);
  o.batch.quiet = global.quiet;
  o.batch.verbose = global.verbose;
  if (o.list) {
    for (const PlannedJob& p : plan_batch(o.batch)) {
      std::string overrides;
      for (const auto& [pointer, value] : patch_leaves(p.job.overrides))
        overrides += fmt::format(" {}={}", pointer,
                                 value.is_string() ? value.get<std::string>() : value.dump());
      std::cout << p.job.id << '\t' << p.job.sketch.string() << overrides << '\n';
    }
    return;
  }
  if (o.batch.out.empty()) throw std::invalid_argument("give the batch folder with -o DIR");
  check_output_folder(o.batch.out);
  try {
    root.get_subcommand(o.batch.stage);
  } catch (const CLI::OptionNotFound&) {
    throw std::invalid_argument(fmt::format(
        "this build of sketchdrape has no '{}' command yet; choose another --stage (mesh)",
        o.batch.stage));
  }
  const BatchResult result = run_batch(o.batch);
  fail_if_not_all_done(
      result.jobs, result.interrupted,
      o.batch.shard ? o.batch.out / kShardsFolder : o.batch.out / kContactSheetFile);
}

}  // namespace

void add_batch_command(CLI::App& app, const GlobalOptions& global) {
  auto o = std::make_shared<BatchCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "batch",
      "Run many sketches (files or JSON/CSV manifests with overrides) as separate jobs: "
      "resumable, in parallel, one shard of N; summary in batch.json and index.html");
  cmd->add_option("INPUTS", o->batch.inputs,
                  "Sketch files and manifests (JSON with \"format\": \"sketchdrape-batch/1\", or "
                  "*.csv)");
  cmd->add_option("-o,--out", o->batch.out, "Batch folder (job folders, batch.json, index.html)")
      ->check(non_empty_path());
  cmd->add_option("--stage", o->batch.stage, "Command each job runs: run (default) or mesh")
      ->capture_default_str();
  cmd->add_option("-j,--jobs", o->batch.parallel, "Jobs at once (child processes)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1024));
  cmd->add_flag("--force", o->batch.force, "Redo jobs that are already done");
  cmd->add_option("--shard", o->shard,
                  "Run only slice I of N (I/N, 1-based; round robin over jobs sorted by id)");
  cmd->add_option("--timeout", o->batch.timeout_s, "Seconds after which a job is killed (0: none)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--collect", o->collect,
                  "Rebuild batch.json and index.html of DIR from its job folders and shard files");
  cmd->add_flag("--list", o->list, "Print the jobs (id, sketch, overrides) and exit");
  const CLI::App* root = &app;
  cmd->callback([o, root, &global] { run_batch_command(*o, *root, global); });
}

}  // namespace sd::app
