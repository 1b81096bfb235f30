#include "src/app/batch/batch_job.hpp"

#include <fmt/format.h>

#include <ctime>
#include <fstream>
#include <sstream>
#include <system_error>
#include <vector>

#include "scene/sketch_file.hpp"
#include "src/app/pipeline/atomic_file.hpp"
#include "src/app/pipeline/sha256.hpp"

namespace sd::app {

using nlohmann::json;

json record_to_json(const JobRecord& r) {
  return {{"format", "sketchdrape-batch-job/1"},
          {"status", r.status},
          {"exit_code", r.exit_code},
          {"reason", r.reason},
          {"wall_time_s", r.wall_time_s},
          {"inputs_hash", r.inputs_hash},
          {"stage", r.stage},
          {"version", r.version},
          {"finished_at", r.finished_at},
          {"outputs", r.outputs}};
}

JobRecord record_from_json(const json& j) {
  JobRecord r;
  r.status = j.at("status").get<std::string>();
  r.exit_code = j.at("exit_code").get<int>();
  r.reason = j.at("reason").get<std::string>();
  r.wall_time_s = j.at("wall_time_s").get<double>();
  r.inputs_hash = j.at("inputs_hash").get<std::string>();
  r.stage = j.at("stage").get<std::string>();
  r.version = j.at("version").get<std::string>();
  r.finished_at = j.at("finished_at").get<std::string>();
  if (j.contains("outputs")) r.outputs = j.at("outputs").get<std::map<std::string, std::string>>();
  return r;
}

const std::string& FileDigests::digest(const std::filesystem::path& path) {
  auto it = cache_.find(path);
  if (it != cache_.end()) return it->second;
  std::string value;
  try {
    value = "sha256:" + sha256_file(path);
  } catch (const std::exception& e) {
    value = std::string("unreadable: ") + e.what();
  }
  return cache_.emplace(path, std::move(value)).first->second;
}

std::string job_inputs_hash(std::string_view document_text,
                            const std::vector<std::string>& file_digests, std::string_view stage,
                            std::string_view version) {
  // Length-prefixed fields, so no two different inputs give the same byte stream.
  Sha256 hash;
  auto field = [&](std::string_view name, std::string_view value) {
    hash.update(fmt::format("{}:{}:", name, value.size()));
    hash.update(value);
    hash.update("\n");
  };
  field("format", "sketchdrape-batch-inputs/1");
  field("stage", stage);
  field("version", version);
  field("document", document_text);
  for (const std::string& d : file_digests) field("file", d);
  return hash.hex_digest();
}

PlannedJob plan_job(const BatchJob& job, std::string_view stage, std::string_view version,
                    FileDigests& files) {
  PlannedJob planned;
  planned.job = job;
  std::string text;
  {
    std::ifstream in(job.sketch, std::ios::binary);
    if (in) {
      std::stringstream buffer;
      buffer << in.rdbuf();
      text = buffer.str();
    } else {
      planned.input_error = fmt::format("{}: cannot read the sketch file", job.sketch.string());
    }
  }
  if (planned.input_error.empty()) {
    json document = json::parse(text, nullptr, /*allow_exceptions=*/false,
                                /*ignore_comments=*/true);
    if (document.is_discarded()) {
      // The sketch parser's message names the line and column of the syntax error.
      planned.input_error = fmt::format("{}: the file is not valid JSON", job.sketch.string());
      try {
        scene::parse_sketch(text, job.sketch.string(), job.sketch.parent_path());
      } catch (const std::exception& e) {
        planned.input_error = e.what();
      }
    } else if (!document.is_object()) {
      planned.input_error =
          fmt::format("{}: a sketch file must be an object {{...}}", job.sketch.string());
    } else {
      absolutise_file_references(document, job.sketch.parent_path());
      document.merge_patch(job.overrides);
      planned.document = std::move(document);
    }
  }
  std::vector<std::string> digests;
  if (planned.document) {
    for (const std::filesystem::path& file : referenced_files(*planned.document))
      digests.push_back(file.string() + " " + files.digest(file));
    planned.inputs_hash = job_inputs_hash(planned.document->dump(), digests, stage, version);
  } else {
    planned.inputs_hash =
        job_inputs_hash(text + "\n" + job.overrides.dump(), digests, stage, version);
  }
  return planned;
}

std::optional<JobRecord> read_job_record(const std::filesystem::path& dir) {
  for (const char* name : {kDoneMarker, kFailedMarker}) {
    std::ifstream in(dir / name, std::ios::binary);
    if (!in) continue;
    std::stringstream buffer;
    buffer << in.rdbuf();
    const json j = json::parse(buffer.str(), nullptr, /*allow_exceptions=*/false);
    if (j.is_discarded()) continue;
    try {
      JobRecord record = record_from_json(j);
      // A done marker must say done and a failed marker must not: anything else is damaged.
      if ((record.status == "done") == (std::string(name) == kDoneMarker)) return record;
    } catch (const json::exception&) {
    }
  }
  return std::nullopt;
}

bool job_is_done(const std::filesystem::path& dir, const std::string& inputs_hash) {
  const std::optional<JobRecord> record = read_job_record(dir);
  if (!record || record->status != "done" || record->inputs_hash != inputs_hash) return false;
  for (const auto& [name, digest] : record->outputs) {
    try {
      if (sha256_file(dir / name) != digest) return false;
    } catch (const std::exception&) {
      return false;  // gone or unreadable
    }
  }
  return true;
}

std::map<std::string, std::string> digest_job_outputs(const std::filesystem::path& dir) {
  std::map<std::string, std::string> digests;
  std::error_code ec;
  for (auto it = std::filesystem::recursive_directory_iterator(dir, ec);
       !ec && it != std::filesystem::recursive_directory_iterator(); it.increment(ec)) {
    if (!it->is_regular_file()) continue;
    const std::string name = std::filesystem::relative(it->path(), dir).generic_string();
    const std::string file = it->path().filename().string();
    if (file.empty() || file[0] == '.' || name == kDoneMarker || name == kFailedMarker ||
        name == kJobLog)
      continue;
    digests[name] = sha256_file(it->path());
  }
  return digests;
}

void clean_job_folder(const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec)
    throw std::runtime_error(fmt::format("cannot create '{}': {}", dir.string(), ec.message()));
  // The markers first: once they are gone, an interruption leaves an unfinished job.
  for (const char* name : {kDoneMarker, kFailedMarker}) {
    std::filesystem::remove(dir / name, ec);
    if (ec)
      throw std::runtime_error(
          fmt::format("cannot remove '{}': {}", (dir / name).string(), ec.message()));
  }
  std::vector<std::filesystem::path> entries;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec))
    entries.push_back(entry.path());
  if (ec) throw std::runtime_error(fmt::format("cannot list '{}': {}", dir.string(), ec.message()));
  for (const std::filesystem::path& p : entries) {
    std::filesystem::remove_all(p, ec);
    if (ec)
      throw std::runtime_error(fmt::format("cannot remove '{}': {}", p.string(), ec.message()));
  }
}

void write_job_record(const std::filesystem::path& dir, const JobRecord& record) {
  const bool done = record.status == "done";
  write_file_atomically(dir / (done ? kDoneMarker : kFailedMarker),
                        record_to_json(record).dump(2) + "\n");
  std::error_code ignored;
  std::filesystem::remove(dir / (done ? kFailedMarker : kDoneMarker), ignored);
}

std::string failure_reason_from_log(const std::filesystem::path& log) {
  std::ifstream in(log);
  std::string line, last_error, last_line;
  while (std::getline(in, line)) {
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    if (line.empty()) continue;
    last_line = line;
    if (line.rfind("error: ", 0) == 0) last_error = line.substr(7);
    if (line.rfind("critical: ", 0) == 0) last_error = line.substr(10);
  }
  return last_error.empty() ? last_line : last_error;
}

std::string utc_timestamp() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return text;
}

}  // namespace sd::app
