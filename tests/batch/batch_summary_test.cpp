#include "src/app/batch/batch_summary.hpp"

#include <gtest/gtest.h>

#include "tests/batch/batch_test_util.hpp"

namespace sd::app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

JobRecord record(const std::string& status, const std::string& hash,
                 const std::string& reason = "") {
  JobRecord r;
  r.status = status;
  r.exit_code = status == "done" ? 0 : 1;
  r.reason = reason;
  r.wall_time_s = 0.25;
  r.inputs_hash = hash;
  r.stage = "mesh";
  r.version = "1.0";
  r.finished_at = "2025-01-01T00:00:00Z";
  return r;
}

// Writes a job's marker as a finished job would have.
void mark(const fs::path& out, const std::string& id, const JobRecord& r) {
  fs::create_directories(out / kJobsFolder / id);
  write_job_record(out / kJobsFolder / id, r);
}

BatchPlan plan_of(const std::vector<std::string>& ids) {
  BatchPlan plan{"mesh", "1.0", {}};
  for (const std::string& id : ids)
    plan.jobs.push_back(
        {id, "/data/" + id + ".json", json{{"fabric", "denim"}}, "m.json", "hash-" + id, ""});
  return plan;
}

TEST(ReportFigures, TopLevelThenNamedGroupsScalarsOnly) {
  const json report = json::parse(R"({"format": "x", "at_rest": true, "max_penetration_m": 0.001,
      "vertices": 900, "totals": {"vertices": 812, "distortion": 3, "area_m2": 1.25},
      "meshing": {"quads": 400, "panels": [{"distortion": 99}]}, "timing_ms": {"total": 12}})");
  EXPECT_EQ(report_figures(report), json::parse(R"({"at_rest": true, "max_penetration_m": 0.001,
      "vertices": 900, "distortion": 3, "area_m2": 1.25, "quads": 400})"));
}

TEST(SummariseJobs, RecordsCountOnlyWithThePlansDigestAndCurrentWins) {
  const fs::path out = test::fresh_batch_dir("summarise");
  const BatchPlan plan = plan_of({"a", "b", "c", "d", "e"});
  mark(out, "a", record("done", "hash-a"));
  mark(out, "b", record("done", "old-hash"));  // stale
  mark(out, "c", record("failed", "hash-c", "from marker"));
  test::write_text(out / kJobsFolder / "a" / "garment-front.png", "not really a png");
  test::write_text(out / kJobsFolder / "a" / ".garment-back.png.tmp-1-0", "partial");
  test::write_text(out / kJobsFolder / "a" / "report.json", R"({"totals": {"vertices": 10}})");
  test::write_text(out / kJobsFolder / "a" / kJobLog, "info: ok\n");
  std::map<std::string, KnownRecord> current = {{"c", {record("done", "hash-c"), false}}};
  std::map<std::string, KnownRecord> fallback = {
      {"d", {record("failed", "hash-d", "disk full"), std::nullopt}},
      {"e", {record("failed", "wrong"), std::nullopt}}};
  const auto jobs = summarise_jobs(plan, out, current, fallback);
  ASSERT_EQ(jobs.size(), 5u);
  EXPECT_EQ(jobs[0].status, "done");
  EXPECT_EQ(jobs[0].images, std::vector<std::string>{"jobs/a/garment-front.png"});
  EXPECT_EQ(jobs[0].figures["vertices"], 10);
  EXPECT_EQ(jobs[0].log, "jobs/a/log.txt");
  EXPECT_EQ(jobs[1].status, "missing");  // its marker is for other inputs
  EXPECT_EQ(jobs[2].status, "done");     // this run's record beats the folder's
  EXPECT_EQ(jobs[3].status, "failed");   // only known from a shard file
  EXPECT_EQ(jobs[3].record->reason, "disk full");
  EXPECT_EQ(jobs[4].status, "missing");
  const json summary = summary_json(plan, jobs);
  EXPECT_EQ(summary["counts"]["done"], 2);
  EXPECT_EQ(summary["counts"]["failed"], 1);
  EXPECT_EQ(summary["counts"]["missing"], 2);
  EXPECT_EQ(summary["jobs"][3]["reason"], "disk full");
  EXPECT_EQ(summary["jobs"][2]["reused"], false);
}

TEST(ContactSheet, OneRowPerJobEscapedTextRelativeImagesAndSortableHeaders) {
  const fs::path out = test::fresh_batch_dir("sheet");
  BatchPlan plan = plan_of({"a", "b"});
  plan.jobs[1].overrides = json{{"fabric", "<b>bold</b> & co"}};
  mark(out, "a", record("done", "hash-a"));
  test::write_text(out / kJobsFolder / "a" / "garment front.png", "x");
  test::write_text(out / kJobsFolder / "a" / "report.json",
                   R"({"at_rest": true, "totals": {"vertices": 10}})");
  mark(out, "b", record("failed", "hash-b", "s.json: /fabric: unknown <fabric>"));
  const auto jobs = summarise_jobs(plan, out, {}, {});
  const std::string html = contact_sheet_html(plan, jobs);
  auto count = [&](const std::string& needle) {
    size_t n = 0;
    for (size_t at = html.find(needle); at != std::string::npos; at = html.find(needle, at + 1))
      ++n;
    return n;
  };
  EXPECT_EQ(count("<tr class=\"job "), 2u);
  EXPECT_EQ(count("<img class=\"thumb\""), 1u);
  EXPECT_NE(html.find("src=\"jobs/a/garment%20front.png\""), std::string::npos);
  EXPECT_NE(html.find("unknown &lt;fabric&gt;"), std::string::npos);
  EXPECT_NE(html.find("&lt;b&gt;bold&lt;/b&gt; &amp; co"), std::string::npos);
  EXPECT_EQ(html.find("<b>bold</b>"), std::string::npos);
  EXPECT_NE(html.find("data-type=\"num\">at_rest</th>"), std::string::npos);
  EXPECT_NE(html.find("data-type=\"num\">vertices</th>"), std::string::npos);
  EXPECT_NE(html.find("<tr class=\"job failed\""), std::string::npos);
  EXPECT_EQ(html.find("http"), std::string::npos) << "nothing is loaded from a server";
  EXPECT_EQ(html.find("<link"), std::string::npos);
  EXPECT_EQ(html.find("<script src"), std::string::npos);
}

TEST(WritePlan, WritesOnceLeavesNoTemporariesAndReplacesAChangedPlan) {
  const fs::path out = test::fresh_batch_dir("write_plan");
  BatchPlan plan = plan_of({"a", "b"});
  write_plan(out, plan);
  EXPECT_EQ(plan_from_json(json::parse(test::read_text(out / kPlanFile)), "p").jobs.size(), 2u);
  const auto first = fs::last_write_time(out / kPlanFile);
  fs::last_write_time(out / kPlanFile, first - std::chrono::hours(1));
  write_plan(out, plan);  // the same plan: the file is left alone
  EXPECT_EQ(fs::last_write_time(out / kPlanFile), first - std::chrono::hours(1));
  plan.jobs.pop_back();
  write_plan(out, plan);
  EXPECT_EQ(plan_from_json(json::parse(test::read_text(out / kPlanFile)), "p").jobs.size(), 1u);
  EXPECT_EQ(std::distance(fs::directory_iterator(out), fs::directory_iterator()), 1);
}

TEST(Collect, RebuildsFromPlanMarkersAndShardFiles) {
  const fs::path out = test::fresh_batch_dir("collect");
  EXPECT_THROW(collect_batch(out), std::invalid_argument);
  const BatchPlan plan = plan_of({"a", "b", "c"});
  test::write_text(out / kPlanFile, plan_to_json(plan).dump());
  mark(out, "a", record("done", "hash-a"));
  // b could not write its marker (a full disk): only its shard knows.
  std::map<std::string, KnownRecord> shard = {
      {"b", {record("failed", "hash-b", "No space left on device"), false}},
      {"a", {record("done", "hash-a"), true}}};
  test::write_text(out / kShardsFolder / shard_file_name(2, 3), shard_json(2, 3, shard).dump());
  const auto jobs = collect_batch(out);
  ASSERT_EQ(jobs.size(), 3u);
  EXPECT_EQ(jobs[0].status, "done");
  EXPECT_EQ(jobs[0].reused, std::optional<bool>(true));
  EXPECT_EQ(jobs[1].status, "failed");
  EXPECT_EQ(jobs[1].record->reason, "No space left on device");
  EXPECT_EQ(jobs[2].status, "missing");
  const json written = json::parse(test::read_text(out / kSummaryFile));
  EXPECT_EQ(written["jobs"].size(), 3u);
  EXPECT_EQ(written["counts"]["missing"], 1);
  EXPECT_TRUE(fs::exists(out / kContactSheetFile));
  // The plan round-trips.
  const BatchPlan back = plan_from_json(plan_to_json(plan), "p");
  EXPECT_EQ(back.jobs.size(), 3u);
  EXPECT_EQ(back.jobs[2].inputs_hash, "hash-c");
  EXPECT_THROW(plan_from_json(json::parse(R"({"format": "other"})"), "p"), std::invalid_argument);
}

}  // namespace
}  // namespace sd::app
