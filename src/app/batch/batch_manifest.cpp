#include "src/app/batch/batch_manifest.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "src/app/pipeline/cloth_scene.hpp"
#include "src/app/pipeline/sha256.hpp"

namespace sd::app {
namespace {

using nlohmann::json;

constexpr size_t kMaxIdLength = 80;
constexpr size_t kMaxJobs = 100000;  // a matrix larger than this is surely a mistake

std::string read_text(const std::filesystem::path& path, const std::string& shown) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ManifestError(shown, "", "cannot read the file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

// What a job's "sketch" is when it is a manifest, not a sketch (the manifest itself, or another
// one: its job failed with "sketch.json: /jobs: unknown key 'jobs' (did you mean 'join'?)");
// empty for anything else. Reads at most the 16 MB a sketch may have.
std::string manifest_kind(const std::filesystem::path& path) {
  if (path.extension() == ".csv") return "a CSV manifest";
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) return {};
  std::ifstream in(path, std::ios::binary);
  std::string text(static_cast<size_t>(std::min<std::uintmax_t>(size, 16u << 20)), '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<size_t>(in.gcount()));
  const json root = json::parse(text, nullptr, /*allow_exceptions=*/false,
                                /*ignore_comments=*/true);
  if (root.is_object() && root.contains("format") && root["format"] == kManifestFormat)
    return "a batch manifest";
  return {};
}

std::string manifest_as_sketch_sentence(const std::string& given, const std::string& kind) {
  return fmt::format(
      "'{}' is {}, not a sketch file; a manifest's jobs name sketch files (give another "
      "manifest to batch as an input of its own)",
      given, kind);
}

// Calls f on the sketch document's fabric names: the file's "fabric" and each panel's.
template <typename Json, typename F>
void for_each_fabric(Json& document, F&& f) {
  if (document.contains("fabric")) f(document["fabric"]);
  if (!document.contains("panels") || !document["panels"].is_array()) return;
  for (auto& panel : document["panels"])
    if (panel.is_object() && panel.contains("fabric")) f(panel["fabric"]);
}

std::filesystem::path absolute_path(const std::filesystem::path& base_dir,
                                    const std::string& relative) {
  const std::filesystem::path p(relative);
  return std::filesystem::absolute(p.is_absolute() ? p : base_dir / p).lexically_normal();
}

// JSON pointer tokens are escaped: "~1" is '/', "~0" is '~' (RFC 6901).
std::string escape_token(const std::string& token) {
  std::string out;
  for (char c : token) {
    if (c == '~')
      out += "~0";
    else if (c == '/')
      out += "~1";
    else
      out += c;
  }
  return out;
}

std::vector<std::string> pointer_tokens(const std::string& pointer) {
  std::vector<std::string> tokens;
  size_t start = 1;
  while (start <= pointer.size()) {
    const size_t slash = pointer.find('/', start);
    const std::string raw =
        pointer.substr(start, slash == std::string::npos ? std::string::npos : slash - start);
    std::string token;
    for (size_t i = 0; i < raw.size(); ++i) {
      if (raw[i] == '~' && i + 1 < raw.size() && (raw[i + 1] == '0' || raw[i + 1] == '1')) {
        token += raw[i + 1] == '0' ? '~' : '/';
        ++i;
      } else {
        token += raw[i];
      }
    }
    tokens.push_back(token);
    if (slash == std::string::npos) break;
    start = slash + 1;
  }
  return tokens;
}

bool is_index_token(const std::string& token) {
  return token == "-" ||
         (!token.empty() && std::all_of(token.begin(), token.end(),
                                        [](unsigned char c) { return std::isdigit(c) != 0; }));
}

void collect_leaves(const json& value, const std::string& prefix,
                    std::vector<std::pair<std::string, json>>& out) {
  if (value.is_object() && !value.empty()) {
    for (const auto& [key, child] : value.items())
      collect_leaves(child, prefix + "/" + escape_token(key), out);
  } else {
    out.emplace_back(prefix, value);
  }
}

std::string sanitise_id(const std::string& text) {
  std::string out;
  for (unsigned char c : text) {
    const bool keep =
        std::isalnum(c) != 0 || c == '.' || c == '_' || c == '=' || c == '+' || c == '-';
    const char ch = keep ? static_cast<char>(c) : '-';
    if (ch == '-' && !out.empty() && out.back() == '-') continue;
    out += ch;
  }
  if (out.empty()) out = "job";
  if (out.front() == '.' || out.front() == '-') out.front() = '_';
  return out;
}

bool valid_explicit_id(const std::string& id) {
  if (id.empty() || id.size() > 100 || id.front() == '.' || id.front() == '-') return false;
  return std::all_of(id.begin(), id.end(), [](unsigned char c) {
    return std::isalnum(c) != 0 || c == '.' || c == '_' || c == '=' || c == '+' || c == '-';
  });
}

std::string short_value(const json& value) {
  if (value.is_string()) {
    const std::string text = value.get<std::string>();
    // File references read better as the file's stem ("tall" for /data/bodies/tall.obj).
    if (text.find('/') != std::string::npos) return std::filesystem::path(text).stem().string();
    return text;
  }
  if (value.is_array() || value.is_object()) return sha256_hex(value.dump()).substr(0, 6);
  return value.dump();
}

std::string type_name(const json& value) {
  if (value.is_string()) return fmt::format("the text \"{}\"", value.get<std::string>());
  if (value.is_number()) return fmt::format("the number {}", value.dump());
  if (value.is_boolean()) return value.get<bool>() ? "true" : "false";
  if (value.is_null()) return "null";
  return value.is_array() ? "a list" : "an object";
}

// Reads one manifest's JSON rows; `file` names the manifest in every message.
class JsonManifestReader {
 public:
  JsonManifestReader(std::string file, std::filesystem::path base_dir)
      : file_(std::move(file)), base_dir_(std::move(base_dir)) {}

  [[noreturn]] void fail(const std::string& path, const std::string& sentence) const {
    throw ManifestError(file_, path, sentence);
  }

  void check_keys(const json& object, const std::string& path,
                  std::initializer_list<std::string_view> known) const {
    for (const auto& [key, value] : object.items())
      if (std::find(known.begin(), known.end(), key) == known.end())
        fail(path + "/" + escape_token(key),
             fmt::format("unknown key '{}' (known keys here: {})", key, fmt::join(known, ", ")));
  }

  // A merge patch object: {"fabric": "denim", "body": {"height": 1.7}}.
  json overrides(const json& value, const std::string& path) const {
    if (!value.is_object())
      fail(path, fmt::format("\"overrides\" is a merge patch: an object like {{\"fabric\": "
                             "\"denim\"}}, not {}",
                             type_name(value)));
    json patch = value;
    absolutise_file_references(patch, base_dir_);
    return patch;
  }

  // {"/pointer": value, ...} as one merge patch.
  json sets(const json& value, const std::string& path) const {
    if (!value.is_object())
      fail(path, fmt::format("\"set\" maps JSON pointers to values, like {{\"/body/height\": "
                             "1.7}}, not {}",
                             type_name(value)));
    json patch = json::object();
    for (const auto& [pointer, v] : value.items())
      patch = combine_patches(patch, checked_pointer_patch(pointer, v, path));
    return patch;
  }

  json checked_pointer_patch(const std::string& pointer, const json& value,
                             const std::string& path) const {
    json patch;
    try {
      patch = pointer_patch(pointer, value);
    } catch (const std::invalid_argument& e) {
      fail(path + "/" + escape_token(pointer), e.what());
    }
    absolutise_file_references(patch, base_dir_);
    return patch;
  }

  std::filesystem::path sketch_path(const json& value, const std::string& path) const {
    if (!value.is_string() || value.get<std::string>().empty())
      fail(path,
           fmt::format("expected the path of a sketch file in quotes, got {}", type_name(value)));
    const std::filesystem::path p = absolute_path(base_dir_, value.get<std::string>());
    if (!std::filesystem::is_regular_file(p))
      fail(path, fmt::format("there is no sketch file '{}' (looked for {})",
                             value.get<std::string>(), p.string()));
    if (const std::string kind = manifest_kind(p); !kind.empty())
      fail(path, manifest_as_sketch_sentence(value.get<std::string>(), kind));
    return p;
  }

  void row(const json& r, const std::string& path, const json& common,
           std::vector<BatchJob>& jobs) const {
    if (r.is_string()) {  // shorthand: just a sketch path
      jobs.push_back({"", sketch_path(r, path), common, file_ + ": " + path, json::object()});
      return;
    }
    if (!r.is_object())
      fail(path, fmt::format("a job is an object {{\"sketch\": ..., ...}} or a sketch path, not {}",
                             type_name(r)));
    check_keys(r, path, {"sketch", "id", "overrides", "set", "matrix"});
    if (!r.contains("sketch")) fail(path, "a job needs a \"sketch\" (a path or a list of paths)");
    std::vector<std::filesystem::path> sketches;
    if (r["sketch"].is_array()) {
      if (r["sketch"].empty()) fail(path + "/sketch", "the list of sketches is empty");
      for (size_t i = 0; i < r["sketch"].size(); ++i)
        sketches.push_back(sketch_path(r["sketch"][i], fmt::format("{}/sketch/{}", path, i)));
    } else {
      sketches.push_back(sketch_path(r["sketch"], path + "/sketch"));
    }
    json own = json::object();  // the row's overrides, without the batch-wide ones
    if (r.contains("overrides"))
      own = combine_patches(own, overrides(r["overrides"], path + "/overrides"));
    if (r.contains("set")) own = combine_patches(own, sets(r["set"], path + "/set"));

    // The matrix: every combination of the listed values (axes in key order).
    std::vector<std::pair<std::string, std::vector<json>>> axes;
    if (r.contains("matrix")) {
      const json& m = r["matrix"];
      if (!m.is_object() || m.empty())
        fail(path + "/matrix",
             "a matrix maps JSON pointers to lists of values, like "
             "{\"/fabric\": [\"denim\", \"silk\"]}");
      for (const auto& [pointer, values] : m.items()) {
        const std::string vp = path + "/matrix/" + escape_token(pointer);
        if (!values.is_array() || values.empty())
          fail(vp, fmt::format("expected a non-empty list of values, got {}", type_name(values)));
        std::vector<json> patches;
        for (const json& v : values)
          patches.push_back(checked_pointer_patch(pointer, v, path + "/matrix"));
        axes.emplace_back(vp, std::move(patches));
      }
    }
    size_t combinations = sketches.size();
    for (const auto& axis : axes) {
      combinations *= axis.second.size();
      if (combinations > kMaxJobs)
        fail(path + "/matrix", fmt::format("the matrix makes more than {} jobs", kMaxJobs));
    }
    std::string id;
    if (r.contains("id")) {
      if (!r["id"].is_string()) fail(path + "/id", "expected the job's id in quotes");
      id = r["id"].get<std::string>();
      if (combinations != 1)
        fail(path + "/id", fmt::format("this row makes {} jobs, so it cannot have one \"id\"; "
                                       "remove it to get generated ids",
                                       combinations));
      if (!valid_explicit_id(id))
        fail(path + "/id", fmt::format("'{}' cannot be a folder name: use letters, digits and "
                                       ". _ = + - (at most 100, not starting with . or -)",
                                       id));
    }
    std::vector<size_t> pick(axes.size(), 0);
    for (size_t n = 0; n < combinations; ++n) {
      const size_t s = n % sketches.size();
      size_t rest = n / sketches.size();
      json job_own = own;
      for (size_t a = axes.size(); a-- > 0;) {  // last axis varies fastest
        const size_t k = rest % axes[a].second.size();
        rest /= axes[a].second.size();
        job_own = combine_patches(job_own, axes[a].second[k]);
      }
      std::string origin = file_ + ": " + path;
      if (combinations > 1) origin += fmt::format(" (combination {} of {})", n + 1, combinations);
      jobs.push_back({id, sketches[s], combine_patches(common, job_own), origin, job_own});
    }
  }

 private:
  std::string file_;
  std::filesystem::path base_dir_;
};

// RFC 4180 records: fields separated by commas, optionally in double quotes ("" is a quote
// inside quotes), records ended by LF or CRLF. Lines starting with '#' are comments.
struct CsvRecord {
  int line = 0;
  std::vector<std::string> fields;
  std::vector<bool> quoted;
};

std::vector<CsvRecord> split_csv(std::string_view text, const std::string& file) {
  std::vector<CsvRecord> records;
  CsvRecord record;
  std::string field;
  bool in_quotes = false, field_quoted = false, at_line_start = true;
  int line = 1;
  record.line = 1;
  auto end_field = [&] {
    if (!field_quoted) {  // unquoted fields are trimmed of spaces
      const size_t a = field.find_first_not_of(" \t");
      const size_t b = field.find_last_not_of(" \t");
      field = a == std::string::npos ? std::string() : field.substr(a, b - a + 1);
    }
    record.fields.push_back(field);
    record.quoted.push_back(field_quoted);
    field.clear();
    field_quoted = false;
  };
  auto end_record = [&] {
    end_field();
    const bool blank = record.fields.size() == 1 && record.fields[0].empty() && !record.quoted[0];
    if (!blank) records.push_back(record);
    record = CsvRecord{};
    record.line = line;
    at_line_start = true;
  };
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_quotes) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
        field += '"';
        ++i;
      } else if (c == '"') {
        in_quotes = false;
      } else {
        if (c == '\n') ++line;
        field += c;
      }
      continue;
    }
    if (at_line_start && c == '#') {  // a comment line
      while (i < text.size() && text[i] != '\n') ++i;
      ++line;
      record.line = line;
      continue;
    }
    at_line_start = false;
    if (c == '"') {
      if (field.find_first_not_of(" \t") != std::string::npos || field_quoted)
        throw ManifestError(file, fmt::format("line {}", line),
                            "a quote inside an unquoted field; quote the whole field and "
                            "double the quotes inside (\"\")");
      in_quotes = true;
      field_quoted = true;
      field.clear();
    } else if (c == ',') {
      end_field();
    } else if (c == '\n') {
      ++line;
      end_record();
    } else if (c != '\r') {
      if (field_quoted && c != ' ' && c != '\t')
        throw ManifestError(file, fmt::format("line {}", line),
                            "text after the closing quote of a field; quote the whole field");
      if (!field_quoted) field += c;
    }
  }
  if (in_quotes)
    throw ManifestError(file, fmt::format("line {}", line), "a quoted field is not closed");
  if (!record.fields.empty() || !field.empty() || field_quoted) end_record();
  return records;
}

// A CSV cell as a JSON value: JSON when it parses (1.7, true, [600, 900], "text"), else text.
json csv_value(const std::string& cell) {
  json value = json::parse(cell, nullptr, /*allow_exceptions=*/false);
  if (value.is_discarded()) return json(cell);
  return value;
}

}  // namespace

json pointer_patch(const std::string& pointer, const json& value) {
  if (pointer.empty() || pointer.front() != '/')
    throw std::invalid_argument(fmt::format(
        "'{}' is not a JSON pointer: overrides name a field with a pointer like /fabric or "
        "/body/height",
        pointer));
  const std::vector<std::string> tokens = pointer_tokens(pointer);
  for (const std::string& token : tokens) {
    if (token.empty())
      throw std::invalid_argument(fmt::format(
          "the pointer '{}' has an empty part (two slashes or a trailing slash)", pointer));
    if (is_index_token(token))
      throw std::invalid_argument(fmt::format(
          "the pointer '{}' indexes into a list; an override replaces a whole list, so give the "
          "list's pointer and the complete new list",
          pointer));
  }
  json patch = value;
  for (auto it = tokens.rbegin(); it != tokens.rend(); ++it) patch = json{{*it, std::move(patch)}};
  return patch;
}

json combine_patches(const json& earlier, const json& later) {
  if (!earlier.is_object() || !later.is_object()) return later;
  json out = earlier;
  for (const auto& [key, value] : later.items())
    out[key] = out.contains(key) ? combine_patches(out[key], value) : value;
  return out;
}

std::vector<std::pair<std::string, json>> patch_leaves(const json& patch) {
  std::vector<std::pair<std::string, json>> out;
  if (patch.is_object() && patch.empty()) return out;
  collect_leaves(patch, "", out);
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return out;
}

void absolutise_file_references(json& document, const std::filesystem::path& base_dir) {
  if (!document.is_object()) return;
  auto fix = [&](json& value) {
    if (!value.is_string()) return;
    const std::string text = value.get<std::string>();
    if (text.empty() || text == "builtin") return;
    value = absolute_path(base_dir, text).string();
  };
  if (document.contains("body")) {
    json& body = document["body"];
    if (body.is_string()) fix(body);
    if (body.is_object() && body.contains("mesh")) fix(body["mesh"]);
  }
  if (document.contains("garment_mesh")) fix(document["garment_mesh"]);
  // A fabric file, the file's or a panel's, as `run` reads it (scene_fabric): against the
  // sketch's folder; presets, unknown names and inline fabrics stay as they are.
  for_each_fabric(document, [&](json& fabric) {
    if (fabric.is_string() && fabric_name_is_path(fabric.get<std::string>())) fix(fabric);
  });
}

std::vector<std::filesystem::path> referenced_files(const json& document) {
  std::vector<std::filesystem::path> files;
  if (!document.is_object()) return files;
  auto add = [&](const json& value) {
    if (value.is_string() && value.get<std::string>() != "builtin" &&
        !value.get<std::string>().empty())
      files.emplace_back(value.get<std::string>());
  };
  if (document.contains("body")) {
    const json& body = document["body"];
    if (body.is_string()) add(body);
    if (body.is_object() && body.contains("mesh")) add(body["mesh"]);
  }
  if (document.contains("garment_mesh")) add(document["garment_mesh"]);
  for_each_fabric(document, [&](const json& fabric) {
    if (fabric.is_string() && fabric_name_is_path(fabric.get<std::string>())) add(fabric);
  });
  return files;
}

std::vector<BatchJob> parse_json_manifest(std::string_view text, const std::string& file,
                                          const std::filesystem::path& base_dir) {
  const JsonManifestReader r(file, base_dir);
  json root;
  try {
    root = json::parse(text, nullptr, /*allow_exceptions=*/true, /*ignore_comments=*/true);
  } catch (const json::parse_error& e) {
    r.fail("", fmt::format("the file is not valid JSON ({})", e.what()));
  }
  if (!root.is_object()) r.fail("", "a manifest is an object {\"format\": ..., \"jobs\": [...]}");
  r.check_keys(root, "", {"format", "overrides", "set", "jobs"});
  if (!root.contains("format") || root["format"] != kManifestFormat)
    r.fail("/format", fmt::format("a batch manifest says \"format\": \"{}\"", kManifestFormat));
  json common = json::object();
  if (root.contains("overrides")) common = r.overrides(root["overrides"], "/overrides");
  if (root.contains("set")) common = combine_patches(common, r.sets(root["set"], "/set"));
  if (!root.contains("jobs") || !root["jobs"].is_array() || root["jobs"].empty())
    r.fail("/jobs", "a manifest needs a non-empty list of \"jobs\"");
  std::vector<BatchJob> jobs;
  for (size_t i = 0; i < root["jobs"].size(); ++i) {
    r.row(root["jobs"][i], fmt::format("/jobs/{}", i), common, jobs);
    if (jobs.size() > kMaxJobs)
      r.fail("/jobs", fmt::format("the manifest makes more than {} jobs", kMaxJobs));
  }
  return jobs;
}

std::vector<BatchJob> parse_csv_manifest(std::string_view text, const std::string& file,
                                         const std::filesystem::path& base_dir) {
  const std::vector<CsvRecord> records = split_csv(text, file);
  if (records.empty()) throw ManifestError(file, "", "the file has no header line");
  const CsvRecord& header = records.front();
  int sketch_column = -1, id_column = -1;
  for (size_t c = 0; c < header.fields.size(); ++c) {
    const std::string& name = header.fields[c];
    const std::string where = fmt::format("line {}, column {}", header.line, c + 1);
    if (name == "sketch" || name == "id") {
      int& column = name == "sketch" ? sketch_column : id_column;
      if (column >= 0) throw ManifestError(file, where, fmt::format("two '{}' columns", name));
      column = static_cast<int>(c);
    } else if (name.empty() || name.front() != '/') {
      throw ManifestError(file, where,
                          fmt::format("'{}' is not a column name: use sketch, id or a JSON "
                                      "pointer such as /fabric or /body/height",
                                      name));
    } else {
      try {
        pointer_patch(name, nullptr);
      } catch (const std::invalid_argument& e) {
        throw ManifestError(file, where, e.what());
      }
    }
  }
  if (sketch_column < 0)
    throw ManifestError(file, fmt::format("line {}", header.line),
                        "the header needs a 'sketch' column (the sketch file of each row)");
  if (records.size() == 1) throw ManifestError(file, "", "the file has a header but no jobs");
  std::vector<BatchJob> jobs;
  for (size_t r = 1; r < records.size(); ++r) {
    const CsvRecord& rec = records[r];
    if (rec.fields.size() != header.fields.size())
      throw ManifestError(file, fmt::format("line {}", rec.line),
                          fmt::format("{} fields, but the header has {} columns", rec.fields.size(),
                                      header.fields.size()));
    BatchJob job;
    job.origin = fmt::format("{}:{}", file, rec.line);
    const std::string& sketch = rec.fields[static_cast<size_t>(sketch_column)];
    const std::string where_sketch = fmt::format("line {}, column sketch", rec.line);
    if (sketch.empty()) throw ManifestError(file, where_sketch, "the sketch file is missing");
    job.sketch = absolute_path(base_dir, sketch);
    if (!std::filesystem::is_regular_file(job.sketch))
      throw ManifestError(
          file, where_sketch,
          fmt::format("there is no sketch file '{}' (looked for {})", sketch, job.sketch.string()));
    if (const std::string kind = manifest_kind(job.sketch); !kind.empty())
      throw ManifestError(file, where_sketch, manifest_as_sketch_sentence(sketch, kind));
    if (id_column >= 0) {
      job.id = rec.fields[static_cast<size_t>(id_column)];
      if (!job.id.empty() && !valid_explicit_id(job.id))
        throw ManifestError(file, fmt::format("line {}, column id", rec.line),
                            fmt::format("'{}' cannot be a folder name: use letters, digits and "
                                        ". _ = + - (at most 100, not starting with . or -)",
                                        job.id));
    }
    for (size_t c = 0; c < header.fields.size(); ++c) {
      if (static_cast<int>(c) == sketch_column || static_cast<int>(c) == id_column) continue;
      const std::string& cell = rec.fields[c];
      if (cell.empty() && !rec.quoted[c]) continue;  // no override in this row
      json patch = pointer_patch(header.fields[c], csv_value(cell));
      absolutise_file_references(patch, base_dir);
      job.overrides = combine_patches(job.overrides, patch);
    }
    job.id_overrides = job.overrides;
    jobs.push_back(std::move(job));
    if (jobs.size() > kMaxJobs)
      throw ManifestError(file, "", fmt::format("the manifest makes more than {} jobs", kMaxJobs));
  }
  return jobs;
}

std::string job_digest8(const BatchJob& job) {
  return sha256_hex(job.sketch.string() + "\n" + job.overrides.dump()).substr(0, 8);
}

std::string generated_job_id(const BatchJob& job) {
  std::string id = job.sketch.stem().string();
  for (const auto& [pointer, value] : patch_leaves(job.id_overrides)) {
    const std::vector<std::string> tokens = pointer_tokens(pointer);
    id += "_" + tokens.back() + "=" + short_value(value);
  }
  id = sanitise_id(id);
  if (id.size() > kMaxIdLength) {
    id = id.substr(0, kMaxIdLength - 9);
    while (!id.empty() && (id.back() == '-' || id.back() == '_' || id.back() == '.')) id.pop_back();
    id += "-" + job_digest8(job);
  }
  return id;
}

void assign_job_ids(std::vector<BatchJob>& jobs) {
  std::vector<bool> generated(jobs.size(), false);
  for (size_t i = 0; i < jobs.size(); ++i) {
    if (!jobs[i].id.empty()) continue;
    jobs[i].id = generated_job_id(jobs[i]);
    generated[i] = true;
  }
  // Generated ids that collide (same stem and summary) get the digest of the job appended.
  std::map<std::string, std::vector<size_t>> by_id;
  for (size_t i = 0; i < jobs.size(); ++i) by_id[jobs[i].id].push_back(i);
  for (const auto& [id, members] : by_id) {
    if (members.size() < 2) continue;
    for (size_t i : members)
      if (generated[i]) jobs[i].id += "-" + job_digest8(jobs[i]);
  }
  std::map<std::string, size_t> seen;
  for (size_t i = 0; i < jobs.size(); ++i) {
    auto [it, inserted] = seen.emplace(jobs[i].id, i);
    if (inserted) continue;
    const BatchJob& first = jobs[it->second];
    if (generated[i] && generated[it->second])
      throw ManifestError(jobs[i].origin, "",
                          fmt::format("this job is the same as the one at {} (same sketch and "
                                      "overrides); remove one of them",
                                      first.origin));
    throw ManifestError(jobs[i].origin, "",
                        fmt::format("the job id '{}' is also used at {}; ids must be unique",
                                    jobs[i].id, first.origin));
  }
  std::sort(jobs.begin(), jobs.end(),
            [](const BatchJob& a, const BatchJob& b) { return a.id < b.id; });
}

std::vector<BatchJob> load_batch_jobs(const std::vector<std::string>& inputs) {
  std::vector<BatchJob> jobs;
  for (const std::string& input : inputs) {
    const std::filesystem::path path = absolute_path(std::filesystem::current_path(), input);
    if (!std::filesystem::is_regular_file(path))
      throw ManifestError(
          input, "", std::filesystem::exists(path) ? "is not a file" : "there is no such file");
    const std::filesystem::path base_dir = path.parent_path();
    std::vector<BatchJob> found;
    if (path.extension() == ".csv") {
      found = parse_csv_manifest(read_text(path, input), input, base_dir);
    } else {
      const std::string text = read_text(path, input);
      const json root = json::parse(text, nullptr, /*allow_exceptions=*/false,
                                    /*ignore_comments=*/true);
      const bool manifest =
          root.is_object() && root.contains("format") && root["format"] == kManifestFormat;
      // A manifest whose "format" line was left out was run as a sketch and failed with
      // "sketch.json: /jobs: unknown key 'jobs' (did you mean 'join'?)" (trial 42, P8): a sketch
      // has no "jobs", so the file is a manifest that does not say so.
      if (!manifest && root.is_object() && root.contains("jobs"))
        throw ManifestError(
            input, "",
            root.contains("format")
                ? fmt::format("it has \"jobs\" like a batch manifest but its \"format\" is {}, "
                              "not \"{}\"",
                              root["format"].dump(), kManifestFormat)
                : fmt::format("it has \"jobs\" like a batch manifest but no \"format\": \"{}\"",
                              kManifestFormat));
      if (manifest)
        found = parse_json_manifest(text, input, base_dir);
      else  // a sketch file; if it is broken, its job fails with the parser's message
        found.push_back({"", path, json::object(), input, json::object()});
    }
    jobs.insert(jobs.end(), std::make_move_iterator(found.begin()),
                std::make_move_iterator(found.end()));
    if (jobs.size() > kMaxJobs)
      throw ManifestError(input, "", fmt::format("the batch has more than {} jobs", kMaxJobs));
  }
  if (jobs.empty()) throw ManifestError("batch", "", "no sketch files or manifests were given");
  assign_job_ids(jobs);
  return jobs;
}

std::vector<BatchJob> shard_slice(const std::vector<BatchJob>& jobs, int index, int count) {
  if (count < 1 || index < 1 || index > count)
    throw std::invalid_argument(fmt::format("shard {}/{} does not exist", index, count));
  std::vector<BatchJob> slice;
  for (size_t i = static_cast<size_t>(index - 1); i < jobs.size(); i += static_cast<size_t>(count))
    slice.push_back(jobs[i]);
  return slice;
}

std::pair<int, int> parse_shard(const std::string& text) {
  const size_t slash = text.find('/');
  int index = 0, count = 0;
  auto parse_int = [](std::string_view s, int& out) {
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
    return ec == std::errc() && end == s.data() + s.size() && !s.empty();
  };
  if (slash == std::string::npos || !parse_int(std::string_view(text).substr(0, slash), index) ||
      !parse_int(std::string_view(text).substr(slash + 1), count) || count < 1 || index < 1 ||
      index > count)
    throw std::invalid_argument(fmt::format(
        "--shard '{}' is not I/N with 1 <= I <= N (for example 2/3: the second of three slices)",
        text));
  return {index, count};
}

}  // namespace sd::app
