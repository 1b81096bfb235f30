#pragma once
// Runs a batch: plans every job, skips the ones already done, and runs the rest as child
// processes of the sketchdrape binary (`sketchdrape <stage> <job>/sketch.json -o <job>`), at most
// `parallel` at a time. A crash, divergence or runaway memory in one job ends only that child.

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "src/app/batch/batch_summary.hpp"

namespace sd::app {

struct BatchOptions {
  std::vector<std::string> inputs;           // sketch files and manifests
  std::filesystem::path out;                 // the batch folder
  std::string stage = "run";                 // the subcommand each job runs
  int parallel = 1;                          // children at once (-j)
  bool force = false;                        // redo done jobs too
  std::optional<std::pair<int, int>> shard;  // (I, N): run slice I of N only
  double timeout_s = 0;                      // per job; 0: no limit
  bool quiet = false;                        // no progress line, no info logs
  bool verbose = false;                      // children log at debug level
  std::filesystem::path executable;          // the binary children run; empty: /proc/self/exe
};

struct BatchResult {
  std::vector<JobSummary> jobs;  // this run's jobs (the shard's when sharded)
  int ran = 0;                   // children started
  int reused = 0;                // done jobs skipped
  bool interrupted = false;      // SIGINT/SIGTERM stopped the batch early
  bool all_done() const;
};

// Runs the batch. Writes <out>/batch-plan.json, the job folders, and either batch.json and
// index.html (whole batch) or shards/shard-I-of-N.json (a shard). Throws ManifestError (and
// other std::invalid_argument) for bad manifests or options before anything runs.
BatchResult run_batch(const BatchOptions& options);

// The environment variable that tells a child the batch process it belongs to.
inline constexpr const char* kBatchParentVariable = "SKETCHDRAPE_BATCH_PARENT";

// In a child of a batch (kBatchParentVariable set): asks the kernel to send this process SIGTERM
// when the batch process dies (PR_SET_PDEATHSIG, kept across exec), and returns false when the
// batch is already gone (the child must not start). True otherwise.
bool follow_batch_parent();

// The planned jobs of a batch (all of them, or one shard's) without running anything.
std::vector<PlannedJob> plan_batch(const BatchOptions& options, BatchPlan* plan = nullptr);

}  // namespace sd::app
