#pragma once
// One batch job on disk: its merged sketch document, the digest of its inputs, its folder and
// the markers that say how it ended. A job is done exactly when <job>/done exists, parses and
// records the digest of the current inputs; the marker is written last and atomically, so a
// job killed half-way is never taken for done (docs/batch.md, "Resume").

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>

#include "src/app/batch/batch_manifest.hpp"

namespace sd::app {

inline constexpr const char* kDoneMarker = "done";
inline constexpr const char* kFailedMarker = "failed";
inline constexpr const char* kJobSketch = "sketch.json";
inline constexpr const char* kJobLog = "log.txt";

// How a job attempt ended, as stored in its marker and in batch.json.
struct JobRecord {
  std::string status;        // "done", "failed" or "bad-input"
  int exit_code = -1;        // the child's exit code; -1 if it was killed or never started
  std::string reason;        // one sentence; empty when done
  double wall_time_s = 0.0;  // the child's wall time
  std::string inputs_hash;   // sha256 of the inputs (job_inputs_hash)
  std::string stage;         // "mesh", "run", ...
  std::string version;       // sketchdrape version that ran it
  std::string finished_at;   // UTC, ISO 8601
  // A done job's files (path relative to its folder → sha256), as they were when the job
  // finished: the marker binds these outputs to inputs_hash (job_is_done checks them).
  std::map<std::string, std::string> outputs;
};

nlohmann::json record_to_json(const JobRecord& record);
// Throws nlohmann::json::exception when a field is missing or of the wrong type.
JobRecord record_from_json(const nlohmann::json& j);

// A job ready to run: its merged document and input digest, or why it cannot run.
struct PlannedJob {
  BatchJob job;
  std::optional<nlohmann::json> document;  // sketch + overrides, file paths absolute
  std::string input_error;                 // set when the sketch is not a JSON object
  std::string inputs_hash;
};

// Digests of referenced files (body meshes, ...) by path, so a body shared by 500 jobs is
// read once per batch.
class FileDigests {
 public:
  // "sha256:<hex>" or "unreadable: <reason>" (the job then fails in the child with a clear
  // message, and the digest changes once the file is fixed).
  const std::string& digest(const std::filesystem::path& path);

 private:
  std::map<std::filesystem::path, std::string> cache_;
};

// Reads the job's sketch, makes its file references absolute (against the sketch's folder),
// applies the overrides (RFC 7386 merge patch) and computes the input digest over the merged
// document, the contents of every referenced file, `stage` and `version`.
PlannedJob plan_job(const BatchJob& job, std::string_view stage, std::string_view version,
                    FileDigests& files);

// The digest of a job's inputs (what plan_job stores in inputs_hash). `document_text` is the
// merged document's compact dump, or the raw sketch text plus overrides when it did not parse.
std::string job_inputs_hash(std::string_view document_text,
                            const std::vector<std::string>& file_digests, std::string_view stage,
                            std::string_view version);

// The record in <dir>/done, or else <dir>/failed; nullopt when neither exists or parses.
std::optional<JobRecord> read_job_record(const std::filesystem::path& dir);

// True when <dir>/done exists, parses, says "done", records `inputs_hash`, and every output it
// lists is still there with the digest it recorded (a file written later, by a process that
// outlived its batch, or edited by hand, makes the job not done).
bool job_is_done(const std::filesystem::path& dir, const std::string& inputs_hash);

// The digests of a job folder's files (recursively; path relative to `dir` → sha256), but its
// markers, its log and hidden temporaries.
std::map<std::string, std::string> digest_job_outputs(const std::filesystem::path& dir);

// Empties a job folder for a fresh attempt (creating it if needed): the markers go first, then
// everything else (outputs, temporaries of a killed attempt, the old log). The folder itself
// stays, so it may be a mount point. Throws std::runtime_error when something cannot be removed.
void clean_job_folder(const std::filesystem::path& dir);

// Writes <dir>/done (status "done") or <dir>/failed (otherwise) atomically and removes the
// other marker. Throws std::runtime_error when the file cannot be written.
void write_job_record(const std::filesystem::path& dir, const JobRecord& record);

// The reason of a failed child from its log: the last "error: ..." line without the prefix,
// else the last non-empty line; empty when the log is empty or unreadable.
std::string failure_reason_from_log(const std::filesystem::path& log);

// Now in UTC as "2025-01-31T12:34:56Z".
std::string utc_timestamp();

}  // namespace sd::app
