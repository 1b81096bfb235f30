#pragma once
// What a batch runs: the list of jobs read from sketch files and manifests (docs/batch.md).
// A job is a sketch file plus overrides; the overrides are one JSON merge patch (RFC 7386)
// applied to the sketch document before it is parsed, so an override is checked exactly like
// the file itself and its errors carry the same JSON paths.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace sd::app {

inline constexpr const char* kManifestFormat = "sketchdrape-batch/1";

// A manifest (or a sketch path named in it) that cannot be used. The message is
// "<file>: <where>: <sentence>", where <where> is a JSON path ("/jobs/2/matrix/~1fabric") or a
// CSV position ("line 4, column /body/height").
class ManifestError : public std::invalid_argument {
 public:
  ManifestError(const std::string& file, const std::string& where, const std::string& sentence)
      : std::invalid_argument(file + ": " + (where.empty() ? "" : where + ": ") + sentence) {}
};

// One job after expansion of the manifest rows.
struct BatchJob {
  std::string id;                // folder name under <out>/jobs/; unique in the batch
  std::filesystem::path sketch;  // absolute, normalised path of the source sketch file
  nlohmann::json overrides = nlohmann::json::object();  // one merge patch; paths made absolute
  std::string origin;  // where the job was declared, for messages ("m.csv:4")
  // The part of `overrides` a generated id names: the row's own overrides. A manifest's
  // batch-wide "overrides"/"set" apply to every job, so they would only lengthen every id.
  nlohmann::json id_overrides = nlohmann::json::object();
};

// Reads the jobs of every input, in order: a sketch file (a job without overrides), a JSON
// manifest (an object with "format": "sketchdrape-batch/1") or a CSV manifest (*.csv). Gives
// each job its id (explicit or generated), checks ids are unique and returns the jobs sorted
// by id. Throws ManifestError.
std::vector<BatchJob> load_batch_jobs(const std::vector<std::string>& inputs);

// The same for text already read: a JSON manifest document / CSV text named `file`, whose
// relative paths resolve against `base_dir`. Ids are not assigned yet (empty unless explicit).
std::vector<BatchJob> parse_json_manifest(std::string_view text, const std::string& file,
                                          const std::filesystem::path& base_dir);
std::vector<BatchJob> parse_csv_manifest(std::string_view text, const std::string& file,
                                         const std::filesystem::path& base_dir);

// Gives every job without an explicit id a generated one, checks explicit ids, makes ids
// unique and sorts the jobs by id. Throws ManifestError when two jobs are the same job.
void assign_job_ids(std::vector<BatchJob>& jobs);

// The generated id of a job: "<sketch stem>" followed by "_<key>=<value>" for each leaf of its
// id_overrides (sorted by JSON pointer; key is the pointer's last part), sanitised to
// [A-Za-z0-9._=+-], and shortened with a hash suffix when longer than 80 characters.
std::string generated_job_id(const BatchJob& job);

// An 8-hex-digit digest of a job's sketch path and overrides: appended to ids that collide.
std::string job_digest8(const BatchJob& job);

// Turns "/body/height" and a value into the merge patch {"body": {"height": value}}.
// Throws std::invalid_argument (with a sentence, no file) for an empty pointer or one that
// indexes into a list.
nlohmann::json pointer_patch(const std::string& pointer, const nlohmann::json& value);

// Combines two merge patches into one: keys of `later` win; objects combine key by key; a
// null in `later` stays (it deletes the key from the sketch).
nlohmann::json combine_patches(const nlohmann::json& earlier, const nlohmann::json& later);

// The leaves of a merge patch as (JSON pointer, value) pairs, sorted by pointer. Lists and
// scalars are leaves.
std::vector<std::pair<std::string, nlohmann::json>> patch_leaves(const nlohmann::json& patch);

// Rewrites the file references of a sketch document or patch (body.mesh or a "body" string,
// garment_mesh, a fabric file named by the file's or a panel's "fabric") that are relative paths
// into absolute ones against `base_dir`. "builtin", presets and absolute paths are left alone.
void absolutise_file_references(nlohmann::json& document, const std::filesystem::path& base_dir);

// The files a merged sketch document reads (body mesh, garment mesh, fabric files), absolute.
std::vector<std::filesystem::path> referenced_files(const nlohmann::json& document);

// The slice `index` (1-based) of `count` of a job list sorted by id: jobs at positions
// index-1, index-1+count, index-1+2·count, ... (round robin, so sizes and fabrics spread evenly).
std::vector<BatchJob> shard_slice(const std::vector<BatchJob>& jobs, int index, int count);

// Parses "I/N" (1 <= I <= N). Throws std::invalid_argument with a sentence.
std::pair<int, int> parse_shard(const std::string& text);

}  // namespace sd::app
