#pragma once
// The batch's plan and summary files under -o DIR (docs/batch.md):
//   batch-plan.json            every job of the batch with its input digest (written by every run
//                              and every shard; identical content, so concurrent writes agree)
//   shards/shard-I-of-N.json   the records of one shard's jobs (also those whose marker could not
//                              be written, e.g. on a full disk)
//   batch.json, index.html     the summary and the contact sheet, from the plan and the job folders

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "src/app/batch/batch_job.hpp"

namespace sd::app {

inline constexpr const char* kPlanFile = "batch-plan.json";
inline constexpr const char* kSummaryFile = "batch.json";
inline constexpr const char* kContactSheetFile = "index.html";
inline constexpr const char* kJobsFolder = "jobs";
inline constexpr const char* kShardsFolder = "shards";

struct PlanEntry {
  std::string id;
  std::string sketch;  // absolute path of the source sketch file
  nlohmann::json overrides = nlohmann::json::object();
  std::string origin;  // where the job was declared
  std::string inputs_hash;
  std::string input_error;  // non-empty when the sketch could not be read as JSON
};

struct BatchPlan {
  std::string stage;
  std::string version;
  std::vector<PlanEntry> jobs;  // sorted by id
};

nlohmann::json plan_to_json(const BatchPlan& plan);
// Throws std::invalid_argument naming `file` when the plan is not one this program wrote.
BatchPlan plan_from_json(const nlohmann::json& j, const std::string& file);
PlanEntry plan_entry(const PlannedJob& planned);

// What is known about one job at the end of a run or a collect.
struct JobSummary {
  PlanEntry entry;
  std::string status;               // "done", "failed", "bad-input" or "missing"
  std::optional<bool> reused;       // true: skipped because done; unknown after a collect
  std::optional<JobRecord> record;  // absent when missing
  std::vector<std::string> images;  // PNGs of the job, relative to the batch folder
  nlohmann::json figures = nlohmann::json::object();  // scalars from the job's report.json
  std::string log;                                    // "jobs/<id>/log.txt" when it exists
};

// A record together with whether this run reused it (skipped a done job).
struct KnownRecord {
  JobRecord record;
  std::optional<bool> reused;
};

// The state of every planned job. A record counts only when its inputs_hash is the plan's:
// first `current` (this run's own results), then the job folder's marker, then `fallback`
// (records from shard files). Anything else is "missing".
std::vector<JobSummary> summarise_jobs(const BatchPlan& plan, const std::filesystem::path& out,
                                       const std::map<std::string, KnownRecord>& current,
                                       const std::map<std::string, KnownRecord>& fallback);

// Figures copied from a report.json: its top-level numbers and booleans, then those of its
// "totals", "meshing", "collision" and "contact" objects (`mesh` keeps vertices, quads,
// distortion in "totals"; `run` keeps distortion in "meshing"). A top-level name wins.
nlohmann::json report_figures(const nlohmann::json& report);

nlohmann::json summary_json(const BatchPlan& plan, const std::vector<JobSummary>& jobs);

// The contact sheet: one self-contained HTML page (inline CSS and JS, images by relative path)
// with a table of one row per job, sortable by clicking a column header.
std::string contact_sheet_html(const BatchPlan& plan, const std::vector<JobSummary>& jobs);

// Writes <out>/batch-plan.json unless it already holds exactly this plan. Shards on several
// hosts write it at once into a shared folder, so the temporary file's name carries the host
// name, the process id and a random number (a pid alone may repeat across hosts).
void write_plan(const std::filesystem::path& out, const BatchPlan& plan);

// Writes batch.json and index.html atomically into `out`.
void write_summary(const std::filesystem::path& out, const BatchPlan& plan,
                   const std::vector<JobSummary>& jobs);

// The shard file name "shard-I-of-N.json".
std::string shard_file_name(int index, int count);
nlohmann::json shard_json(int index, int count, const std::map<std::string, KnownRecord>& records);

// Rebuilds batch.json and index.html of `out` from its plan, the job folders and the shard
// files; returns the summaries. Throws std::invalid_argument when `out` has no plan.
std::vector<JobSummary> collect_batch(const std::filesystem::path& out);

// Counts by status, for messages: {"done": 5, "failed": 1, ...}.
std::map<std::string, int> count_statuses(const std::vector<JobSummary>& jobs);

}  // namespace sd::app
