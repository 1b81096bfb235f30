#include "src/app/batch/batch_summary.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>

#include "src/app/pipeline/atomic_file.hpp"
#include "src/app/pipeline/markup_escape.hpp"

namespace sd::app {
namespace {

using nlohmann::json;

// Figures shown first in the contact sheet, in this order; others follow alphabetically.
const std::vector<std::string> kPreferredFigures = {
    "at_rest", "max_penetration_m", "distortion",         "vertices", "quads", "triangles",
    "panels",  "triangles_48",      "irregular_vertices", "area_m2"};

std::optional<json> read_json_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::stringstream buffer;
  buffer << in.rdbuf();
  json j = json::parse(buffer.str(), nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) return std::nullopt;
  return j;
}

// A relative path as a URL: unreserved characters and '/' stay, everything else is %XX.
std::string url_path(std::string_view path) {
  std::string out;
  for (unsigned char c : path) {
    if (std::isalnum(c) != 0 || c == '-' || c == '.' || c == '_' || c == '~' || c == '/')
      out += static_cast<char>(c);
    else
      out += fmt::format("%{:02X}", c);
  }
  return out;
}

std::string overrides_text(const json& overrides) {
  std::vector<std::string> parts;
  for (const auto& [pointer, value] : patch_leaves(overrides))
    parts.push_back(pointer + " = " +
                    (value.is_string() ? value.get<std::string>() : value.dump()));
  return fmt::format("{}", fmt::join(parts, ", "));
}

std::string figure_text(const json& value) {
  if (value.is_boolean()) return value.get<bool>() ? "yes" : "no";
  if (value.is_number_integer() || value.is_number_unsigned()) return value.dump();
  if (value.is_number()) return fmt::format("{:.4g}", value.get<double>());
  return value.dump();
}

std::string figure_sort_key(const json& value) {
  if (value.is_boolean()) return value.get<bool>() ? "1" : "0";
  if (value.is_number()) return fmt::format("{:.17g}", value.get<double>());
  return value.dump();
}

std::vector<std::string> figure_columns(const std::vector<JobSummary>& jobs) {
  std::set<std::string> names;
  for (const JobSummary& j : jobs)
    for (const auto& [name, value] : j.figures.items()) names.insert(name);
  std::vector<std::string> columns;
  for (const std::string& name : kPreferredFigures)
    if (names.erase(name) > 0) columns.push_back(name);
  columns.insert(columns.end(), names.begin(), names.end());
  return columns;
}

constexpr const char* kStyle = R"(
body { font: 14px/1.4 system-ui, sans-serif; margin: 1.5em; color: #222; }
h1 { font-size: 1.4em; margin: 0 0 .3em; }
.meta { color: #555; margin: 0 0 1em; }
table { border-collapse: collapse; }
th, td { border-bottom: 1px solid #ddd; padding: 4px 8px; text-align: left; vertical-align: top; }
th { background: #f2f2f2; position: sticky; top: 0; user-select: none; white-space: nowrap; }
th.sortable { cursor: pointer; }
th.asc::after { content: " \25B2"; }
th.desc::after { content: " \25BC"; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
tr.failed, tr.bad-input { background: #fdecea; }
tr.missing { background: #fff8e1; }
.status { font-weight: 600; }
.overrides, .sketch { color: #555; font-size: .9em; }
.reason { color: #b00020; max-width: 36em; }
td.images { white-space: nowrap; }
img.thumb { height: 120px; margin: 0 4px 4px 0; border: 1px solid #ccc; background: #fafafa; }
img.broken { outline: 2px solid #b00020; }
)";

// Sorting by clicking a header (numbers as numbers, empty cells last) and a check that marks
// on <body> how many thumbnails loaded, so a headless browser test can read it from the DOM.
constexpr const char* kScript = R"(
(function () {
  var table = document.getElementById('jobs');
  var headers = table.tHead.rows[0].cells;
  Array.prototype.forEach.call(headers, function (th, column) {
    if (!th.classList.contains('sortable')) return;
    th.addEventListener('click', function () {
      var descending = th.classList.contains('asc');
      Array.prototype.forEach.call(headers, function (h) { h.classList.remove('asc', 'desc'); });
      th.classList.add(descending ? 'desc' : 'asc');
      var numeric = th.dataset.type === 'num';
      var rows = Array.prototype.slice.call(table.tBodies[0].rows);
      rows.sort(function (a, b) {
        var x = a.cells[column].dataset.sort, y = b.cells[column].dataset.sort;
        if (x === '' || x === undefined) return (y === '' || y === undefined) ? 0 : 1;
        if (y === '' || y === undefined) return -1;
        var order = numeric ? parseFloat(x) - parseFloat(y) : x.localeCompare(y);
        return descending ? -order : order;
      });
      rows.forEach(function (r) { table.tBodies[0].appendChild(r); });
    });
  });
  var images = document.querySelectorAll('img.thumb');
  var loaded = 0, broken = 0;
  var state = document.getElementById('thumbnails');
  function report() {
    document.body.dataset.imagesTotal = images.length;
    document.body.dataset.imagesLoaded = loaded;
    document.body.dataset.imagesBroken = broken;
    if (loaded + broken < images.length) return;
    document.body.dataset.imagesSettled = 'yes';
    state.textContent = broken === 0 ? images.length + ' thumbnails loaded'
                                     : broken + ' of ' + images.length + ' thumbnails did not load';
  }
  Array.prototype.forEach.call(images, function (img) {
    function done() { if (img.naturalWidth > 0) { loaded++; } else { broken++; img.classList.add('broken'); } report(); }
    if (img.complete) { done(); } else { img.addEventListener('load', done); img.addEventListener('error', done); }
  });
  report();
})();
)";

}  // namespace

json plan_to_json(const BatchPlan& plan) {
  json jobs = json::array();
  for (const PlanEntry& e : plan.jobs)
    jobs.push_back({{"id", e.id},
                    {"sketch", e.sketch},
                    {"overrides", e.overrides},
                    {"origin", e.origin},
                    {"inputs_hash", e.inputs_hash},
                    {"input_error", e.input_error}});
  return {{"format", "sketchdrape-batch-plan/1"},
          {"stage", plan.stage},
          {"version", plan.version},
          {"shard_rule", "jobs sorted by id; shard I of N takes positions I-1, I-1+N, I-1+2N, ..."},
          {"jobs", jobs}};
}

BatchPlan plan_from_json(const json& j, const std::string& file) {
  try {
    if (j.at("format") != "sketchdrape-batch-plan/1") throw std::invalid_argument("format");
    BatchPlan plan;
    plan.stage = j.at("stage").get<std::string>();
    plan.version = j.at("version").get<std::string>();
    for (const json& e : j.at("jobs"))
      plan.jobs.push_back({e.at("id").get<std::string>(), e.at("sketch").get<std::string>(),
                           e.at("overrides"), e.at("origin").get<std::string>(),
                           e.at("inputs_hash").get<std::string>(),
                           e.at("input_error").get<std::string>()});
    return plan;
  } catch (const std::exception&) {
    throw std::invalid_argument(file + ": this is not a batch plan written by sketchdrape batch");
  }
}

PlanEntry plan_entry(const PlannedJob& p) {
  return {p.job.id,     p.job.sketch.string(), p.job.overrides,
          p.job.origin, p.inputs_hash,         p.input_error};
}

json report_figures(const json& report) {
  json figures = json::object();
  if (!report.is_object()) return figures;
  auto take = [&](const json& object) {
    for (const auto& [key, value] : object.items())
      if (value.is_number() || value.is_boolean()) figures[key] = value;
  };
  take(report);
  // Objects whose scalars are figures too (a top-level name wins over a nested one).
  for (const char* group : {"totals", "meshing", "collision", "contact"})
    if (report.contains(group) && report[group].is_object())
      for (const auto& [key, value] : report[group].items())
        if ((value.is_number() || value.is_boolean()) && !figures.contains(key))
          figures[key] = value;
  return figures;
}

std::vector<JobSummary> summarise_jobs(const BatchPlan& plan, const std::filesystem::path& out,
                                       const std::map<std::string, KnownRecord>& current,
                                       const std::map<std::string, KnownRecord>& fallback) {
  std::vector<JobSummary> summaries;
  for (const PlanEntry& entry : plan.jobs) {
    JobSummary s;
    s.entry = entry;
    const std::filesystem::path dir = out / kJobsFolder / entry.id;
    auto matching = [&](const std::map<std::string, KnownRecord>& known) -> const KnownRecord* {
      auto it = known.find(entry.id);
      return it != known.end() && it->second.record.inputs_hash == entry.inputs_hash ? &it->second
                                                                                     : nullptr;
    };
    if (const KnownRecord* k = matching(current)) {
      s.record = k->record;
      s.reused = k->reused;
    } else if (std::optional<JobRecord> r = read_job_record(dir);
               r && r->inputs_hash == entry.inputs_hash) {
      s.record = *r;
      if (const KnownRecord* f = matching(fallback)) s.reused = f->reused;
    } else if (const KnownRecord* f = matching(fallback)) {
      s.record = f->record;
      s.reused = f->reused;
    }
    s.status = s.record ? s.record->status : "missing";
    std::error_code ec;
    if (std::filesystem::is_regular_file(dir / kJobLog, ec))
      s.log = (std::filesystem::path(kJobsFolder) / entry.id / kJobLog).generic_string();
    if (s.status == "done") {
      for (const auto& file : std::filesystem::directory_iterator(dir, ec)) {
        const std::string name = file.path().filename().string();
        if (file.path().extension() == ".png" && !name.starts_with("."))
          s.images.push_back(
              (std::filesystem::path(kJobsFolder) / entry.id / name).generic_string());
      }
      std::sort(s.images.begin(), s.images.end());
      if (std::optional<json> report = read_json_file(dir / "report.json"))
        s.figures = report_figures(*report);
    }
    summaries.push_back(std::move(s));
  }
  return summaries;
}

std::map<std::string, int> count_statuses(const std::vector<JobSummary>& jobs) {
  std::map<std::string, int> counts;
  for (const JobSummary& j : jobs) ++counts[j.status];
  return counts;
}

json summary_json(const BatchPlan& plan, const std::vector<JobSummary>& jobs) {
  const std::map<std::string, int> counts = count_statuses(jobs);
  auto count = [&](const std::string& s) {
    auto it = counts.find(s);
    return it == counts.end() ? 0 : it->second;
  };
  int reused = 0;
  json rows = json::array();
  for (const JobSummary& j : jobs) {
    json row = {{"id", j.entry.id},
                {"sketch", j.entry.sketch},
                {"overrides", j.entry.overrides},
                {"origin", j.entry.origin},
                {"folder", (std::filesystem::path(kJobsFolder) / j.entry.id).generic_string()},
                {"status", j.status},
                {"inputs_hash", j.entry.inputs_hash}};
    if (j.reused) {
      row["reused"] = *j.reused;
      reused += *j.reused ? 1 : 0;
    }
    if (j.record) {
      row["exit_code"] = j.record->exit_code;
      row["reason"] = j.record->reason;
      row["wall_time_s"] = j.record->wall_time_s;
      row["finished_at"] = j.record->finished_at;
    } else {
      row["reason"] = "not run yet, or interrupted before it finished";
    }
    if (!j.log.empty()) row["log"] = j.log;
    row["images"] = j.images;
    row["figures"] = j.figures;
    rows.push_back(std::move(row));
  }
  return {{"format", "sketchdrape-batch-summary/1"},
          {"stage", plan.stage},
          {"version", plan.version},
          {"generated_at", utc_timestamp()},
          {"counts",
           {{"jobs", jobs.size()},
            {"done", count("done")},
            {"failed", count("failed")},
            {"bad_input", count("bad-input")},
            {"missing", count("missing")},
            {"reused", reused}}},
          {"jobs", rows}};
}

std::string contact_sheet_html(const BatchPlan& plan, const std::vector<JobSummary>& jobs) {
  const std::vector<std::string> figures = figure_columns(jobs);
  const std::map<std::string, int> counts = count_statuses(jobs);
  std::vector<std::string> count_parts;
  for (const auto& [status, n] : counts) count_parts.push_back(fmt::format("{} {}", n, status));

  std::string h;
  h += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  h += fmt::format("<title>sketchdrape batch: {} jobs</title>\n", jobs.size());
  h += "<style>" + std::string(kStyle) + "</style>\n</head>\n";
  h += fmt::format("<body data-jobs=\"{}\">\n<h1>sketchdrape batch</h1>\n", jobs.size());
  h += fmt::format("<p class=\"meta\">stage <b>{}</b> · sketchdrape {} · {} · {} jobs: {}</p>\n",
                   markup_escape(plan.stage), markup_escape(plan.version), utc_timestamp(),
                   jobs.size(), markup_escape(fmt::format("{}", fmt::join(count_parts, ", "))));
  h += "<p class=\"meta\" id=\"thumbnails\">loading thumbnails…</p>\n";
  h += "<table id=\"jobs\">\n<thead><tr>";
  h += "<th class=\"sortable\" data-type=\"text\">job</th>";
  h += "<th class=\"sortable\" data-type=\"text\">status</th>";
  h += "<th>images</th>";
  h += "<th class=\"sortable\" data-type=\"num\">wall time (s)</th>";
  for (const std::string& f : figures)
    h += fmt::format("<th class=\"sortable\" data-type=\"num\">{}</th>", markup_escape(f));
  h += "<th class=\"sortable\" data-type=\"text\">reason</th>";
  h += "</tr></thead>\n<tbody>\n";
  for (const JobSummary& j : jobs) {
    h += fmt::format("<tr class=\"job {}\" data-id=\"{}\">", markup_escape(j.status),
                     markup_escape(j.entry.id));
    h += fmt::format("<td data-sort=\"{0}\"><b>{0}</b>", markup_escape(j.entry.id));
    h += fmt::format("<div class=\"sketch\">{}</div>",
                     markup_escape(std::filesystem::path(j.entry.sketch).filename().string()));
    const std::string over = overrides_text(j.entry.overrides);
    if (!over.empty()) h += fmt::format("<div class=\"overrides\">{}</div>", markup_escape(over));
    h += "</td>";
    std::string status = j.status;
    if (j.reused && *j.reused) status += " (reused)";
    h += fmt::format("<td class=\"status\" data-sort=\"{}\">{}</td>", markup_escape(j.status),
                     markup_escape(status));
    h += "<td class=\"images\">";
    for (const std::string& image : j.images)
      h += fmt::format("<a href=\"{0}\"><img class=\"thumb\" src=\"{0}\" alt=\"{1}\"></a>",
                       markup_escape(url_path(image)),
                       markup_escape(std::filesystem::path(image).filename().string()));
    h += "</td>";
    if (j.record)
      h += fmt::format("<td class=\"num\" data-sort=\"{:.6f}\">{:.2f}</td>", j.record->wall_time_s,
                       j.record->wall_time_s);
    else
      h += "<td class=\"num\" data-sort=\"\"></td>";
    for (const std::string& f : figures) {
      if (j.figures.contains(f))
        h += fmt::format("<td class=\"num\" data-sort=\"{}\">{}</td>",
                         markup_escape(figure_sort_key(j.figures[f])),
                         markup_escape(figure_text(j.figures[f])));
      else
        h += "<td class=\"num\" data-sort=\"\"></td>";
    }
    const std::string reason =
        j.record ? j.record->reason : "not run yet, or interrupted before it finished";
    h += fmt::format("<td class=\"reason\" data-sort=\"{0}\">{0}", markup_escape(reason));
    if (!j.log.empty())
      h += fmt::format("{}<a href=\"{}\">log</a>", reason.empty() ? "" : " ",
                       markup_escape(url_path(j.log)));
    h += "</td></tr>\n";
  }
  h += "</tbody>\n</table>\n<script>" + std::string(kScript) + "</script>\n</body>\n</html>\n";
  return h;
}

void write_plan(const std::filesystem::path& out, const BatchPlan& plan) {
  const std::string text = plan_to_json(plan).dump(2) + "\n";
  const std::filesystem::path path = out / kPlanFile;
  {
    std::ifstream in(path, std::ios::binary);
    std::stringstream existing;
    existing << in.rdbuf();
    if (in && existing.str() == text) return;
  }
  char host[256] = "host";
  ::gethostname(host, sizeof host - 1);
  std::random_device random;
  const std::filesystem::path temp =
      out / fmt::format(".{}.tmp-{}-{}-{:08x}", kPlanFile, host, ::getpid(), random());
  {
    std::ofstream file(temp, std::ios::binary);
    file << text;
    file.close();
    if (!file) {
      std::error_code ignored;
      std::filesystem::remove(temp, ignored);
      throw std::runtime_error(fmt::format("cannot write '{}'", path.string()));
    }
  }
  std::error_code ec;
  std::filesystem::rename(temp, path, ec);
  if (ec) {
    std::filesystem::remove(temp, ec);
    throw std::runtime_error(fmt::format("cannot write '{}': {}", path.string(), ec.message()));
  }
}

void write_summary(const std::filesystem::path& out, const BatchPlan& plan,
                   const std::vector<JobSummary>& jobs) {
  write_file_atomically(out / kSummaryFile, summary_json(plan, jobs).dump(2) + "\n");
  write_file_atomically(out / kContactSheetFile, contact_sheet_html(plan, jobs));
}

std::string shard_file_name(int index, int count) {
  return fmt::format("shard-{}-of-{}.json", index, count);
}

json shard_json(int index, int count, const std::map<std::string, KnownRecord>& records) {
  json jobs = json::object();
  for (const auto& [id, known] : records) {
    json row = record_to_json(known.record);
    if (known.reused) row["reused"] = *known.reused;
    jobs[id] = row;
  }
  return {{"format", "sketchdrape-batch-shard/1"},
          {"shard", index},
          {"shards", count},
          {"written_at", utc_timestamp()},
          {"jobs", jobs}};
}

std::vector<JobSummary> collect_batch(const std::filesystem::path& out) {
  const std::optional<json> plan_json = read_json_file(out / kPlanFile);
  if (!plan_json)
    throw std::invalid_argument(fmt::format(
        "{}: no readable {} here; is this the -o folder of a batch?", out.string(), kPlanFile));
  const BatchPlan plan = plan_from_json(*plan_json, (out / kPlanFile).string());
  // Records from the shard files, for jobs whose own marker could not be written. Files are
  // read in name order; a later file's record of the same job wins.
  std::map<std::string, KnownRecord> fallback;
  std::error_code ec;
  std::vector<std::filesystem::path> shard_files;
  for (const auto& f : std::filesystem::directory_iterator(out / kShardsFolder, ec))
    if (f.path().extension() == ".json") shard_files.push_back(f.path());
  std::sort(shard_files.begin(), shard_files.end());
  for (const std::filesystem::path& file : shard_files) {
    const std::optional<json> shard = read_json_file(file);
    if (!shard || !shard->contains("jobs") || !(*shard)["jobs"].is_object()) continue;
    for (const auto& [id, row] : (*shard)["jobs"].items()) {
      try {
        KnownRecord known{record_from_json(row), std::nullopt};
        if (row.contains("reused") && row["reused"].is_boolean())
          known.reused = row["reused"].get<bool>();
        fallback[id] = known;
      } catch (const json::exception&) {
      }
    }
  }
  std::vector<JobSummary> jobs = summarise_jobs(plan, out, {}, fallback);
  write_summary(out, plan, jobs);
  return jobs;
}

}  // namespace sd::app
