// `sketchdrape batch` end to end with the real binary: each job is a child `sketchdrape mesh`
// (the `run` stage is not needed). Resume, changed inputs, failures, shards and collect, a
// SIGKILL in the middle, a full disk, and the contact sheet in headless Chromium.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <thread>

#include "tests/batch/batch_test_util.hpp"
#include "tests/cli/run_command.hpp"

namespace sd::test {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const fs::path kExamples = fs::path(SD_SOURCE_DIR) / "data" / "examples";

std::string shell_quoted(const fs::path& p) {
  return "'" + p.string() + "'";
}

// Copies the example sketches into dir/sketches (so a test may edit one) and writes a manifest
// of the 3 sketches x the given fabrics, with one small front image each to keep jobs quick.
fs::path wardrobe(const fs::path& dir, const std::vector<std::string>& fabrics) {
  fs::create_directories(dir / "sketches");
  for (const char* name : {"a-line-skirt.json", "sleeveless-dress.json", "tshirt.json"})
    fs::copy_file(kExamples / name, dir / "sketches" / name, fs::copy_options::overwrite_existing);
  const json manifest = {
      {"format", "sketchdrape-batch/1"},
      {"set", {{"/output/images", json::array({{{"view", "front"}, {"size", {120, 180}}}})}}},
      {"jobs", json::array({{{"sketch",
                              {"sketches/a-line-skirt.json", "sketches/sleeveless-dress.json",
                               "sketches/tshirt.json"}},
                             {"matrix", {{"/fabric", fabrics}}}}})}};
  write_text(dir / "wardrobe.json", manifest.dump(2));
  return dir / "wardrobe.json";
}

json read_json(const fs::path& p) {
  return json::parse(read_text(p));
}

std::map<std::string, json> jobs_by_id(const json& summary) {
  std::map<std::string, json> out;
  for (const json& j : summary["jobs"]) out[j["id"].get<std::string>()] = j;
  return out;
}

// The done marker's bytes and modification time: unchanged means the job was not redone.
struct MarkerStamp {
  std::string bytes;
  fs::file_time_type mtime;
  bool operator==(const MarkerStamp&) const = default;
};
std::map<std::string, MarkerStamp> marker_stamps(const fs::path& out) {
  std::map<std::string, MarkerStamp> stamps;
  for (const auto& d : fs::directory_iterator(out / "jobs"))
    if (fs::exists(d.path() / "done"))
      stamps[d.path().filename().string()] = {read_text(d.path() / "done"),
                                              fs::last_write_time(d.path() / "done")};
  return stamps;
}

TEST(BatchCommand, RunsResumesAndRedoesOnlyChangedJobs) {
  const fs::path dir = fresh_batch_dir("resume");
  const fs::path manifest = wardrobe(dir, {"jersey", "denim"});
  const fs::path out = dir / "out";

  const CommandResult first = run_sketchdrape("batch " + shell_quoted(manifest) + " -o " +
                                              shell_quoted(out) + " --stage mesh -j 2");
  ASSERT_EQ(first.exit_code, 0) << first.output;
  json summary = read_json(out / "batch.json");
  ASSERT_EQ(summary["jobs"].size(), 6u);
  EXPECT_EQ(summary["counts"]["done"], 6);
  EXPECT_EQ(summary["counts"]["reused"], 0);
  for (const json& j : summary["jobs"]) {
    const fs::path job = out / j["folder"].get<std::string>();
    EXPECT_EQ(j["status"], "done") << j.dump();
    EXPECT_EQ(j["exit_code"], 0);
    EXPECT_GT(j["figures"]["vertices"].get<int>(), 50) << j.dump();
    EXPECT_TRUE(j["figures"].contains("distortion"));
    ASSERT_EQ(j["images"].size(), 1u);
    for (const char* f :
         {"done", "sketch.json", "log.txt", "report.json", "garment.obj", "garment-front.png"})
      EXPECT_TRUE(fs::exists(job / f)) << job / f;
    // The job's sketch is the merged document: the fabric override is in it.
    EXPECT_EQ(read_json(job / "sketch.json")["fabric"], j["overrides"]["fabric"]);
  }
  EXPECT_EQ(jobs_by_id(summary).count("tshirt_fabric=denim"), 1u);
  EXPECT_TRUE(fs::exists(out / "index.html"));
  const auto stamps = marker_stamps(out);
  ASSERT_EQ(stamps.size(), 6u);

  // The same batch again: nothing runs.
  const CommandResult again = run_sketchdrape("batch " + shell_quoted(manifest) + " -o " +
                                              shell_quoted(out) + " --stage mesh -j 2");
  ASSERT_EQ(again.exit_code, 0) << again.output;
  summary = read_json(out / "batch.json");
  EXPECT_EQ(summary["counts"]["reused"], 6);
  for (const json& j : summary["jobs"]) EXPECT_EQ(j["reused"], true) << j["id"];
  EXPECT_EQ(marker_stamps(out), stamps);

  // Edit one sketch file: its two jobs (two fabrics) are redone, the other four are not.
  std::string tshirt = read_text(dir / "sketches" / "tshirt.json");
  const size_t at = tshirt.find("\"edge_length\": 0.025");
  ASSERT_NE(at, std::string::npos);
  tshirt.replace(at, 20, "\"edge_length\": 0.030");
  write_text(dir / "sketches" / "tshirt.json", tshirt);
  const CommandResult edited = run_sketchdrape("batch " + shell_quoted(manifest) + " -o " +
                                               shell_quoted(out) + " --stage mesh -j 2");
  ASSERT_EQ(edited.exit_code, 0) << edited.output;
  summary = read_json(out / "batch.json");
  const auto now = marker_stamps(out);
  for (const json& j : summary["jobs"]) {
    const std::string id = j["id"];
    const bool is_tshirt = id.rfind("tshirt", 0) == 0;
    EXPECT_EQ(j["reused"], !is_tshirt) << id;
    EXPECT_EQ(now.at(id) == stamps.at(id), !is_tshirt) << id;
    if (is_tshirt) {
      EXPECT_EQ(read_json(out / "jobs" / id / "sketch.json")["edge_length"], 0.03);
    }
  }

  // Change one override value (denim -> silk): three new jobs run, the jersey ones are reused.
  const fs::path manifest2 = wardrobe(dir, {"jersey", "silk"});
  write_text(dir / "sketches" / "tshirt.json", tshirt);  // keep the edited t-shirt
  const CommandResult changed = run_sketchdrape("batch " + shell_quoted(manifest2) + " -o " +
                                                shell_quoted(out) + " --stage mesh -j 2");
  ASSERT_EQ(changed.exit_code, 0) << changed.output;
  summary = read_json(out / "batch.json");
  ASSERT_EQ(summary["jobs"].size(), 6u);
  for (const json& j : summary["jobs"]) {
    const bool silk = j["overrides"]["fabric"] == "silk";
    EXPECT_EQ(j["reused"], !silk) << j["id"];
    EXPECT_EQ(j["status"], "done");
  }

  // --force redoes everything.
  const CommandResult forced = run_sketchdrape("batch " + shell_quoted(manifest2) + " -o " +
                                               shell_quoted(out) + " --stage mesh -j 2 --force");
  ASSERT_EQ(forced.exit_code, 0) << forced.output;
  EXPECT_EQ(read_json(out / "batch.json")["counts"]["reused"], 0);
}

TEST(BatchCommand, BadJobsFailWithTheirReasonWhileOthersFinish) {
  const fs::path dir = fresh_batch_dir("bad_jobs");
  fs::copy_file(kExamples / "a-line-skirt.json", dir / "skirt.json");
  write_text(dir / "broken.json", "{\n  \"format\": \"sketchdrape/1\",\n  \"fabric\": denim\n}\n");
  write_text(dir / "m.csv",
             "sketch,id,/edge_length,/body/mesh,/output/images\n"
             "skirt.json,good,,,[]\n"
             "skirt.json,negative-edge,-0.01,,[]\n"
             "skirt.json,no-body,,bodies/missing.obj,[]\n"
             "broken.json,broken,,,\n");
  const fs::path out = dir / "out";
  const CommandResult r = run_sketchdrape("batch " + shell_quoted(dir / "m.csv") + " -o " +
                                          shell_quoted(out) + " --stage mesh -j 2");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("3 of 4 jobs did not finish"), std::string::npos) << r.output;
  const auto jobs = jobs_by_id(read_json(out / "batch.json"));
  ASSERT_EQ(jobs.size(), 4u);
  EXPECT_EQ(jobs.at("good")["status"], "done");
  EXPECT_EQ(jobs.at("negative-edge")["status"], "bad-input");
  EXPECT_EQ(jobs.at("negative-edge")["exit_code"], 2);
  const std::string edge_reason = jobs.at("negative-edge")["reason"];
  EXPECT_EQ(edge_reason.rfind("sketch.json: /edge_length", 0), 0u)
      << "paths in the job's folder are shown relative to it: " << edge_reason;
  EXPECT_NE(edge_reason.find("/edge_length: must be greater than zero"), std::string::npos)
      << edge_reason;
  const std::string body_reason = jobs.at("no-body")["reason"];
  EXPECT_EQ(jobs.at("no-body")["status"], "bad-input");
  EXPECT_NE(body_reason.find("missing.obj"), std::string::npos) << body_reason;
  EXPECT_EQ(jobs.at("broken")["status"], "bad-input");
  EXPECT_NE(jobs.at("broken")["reason"].get<std::string>().find("line 3"), std::string::npos)
      << jobs.at("broken")["reason"];
  EXPECT_FALSE(fs::exists(out / "jobs" / "negative-edge" / "done"));
  EXPECT_TRUE(fs::exists(out / "jobs" / "negative-edge" / "failed"));
  const std::string html = read_text(out / "index.html");
  EXPECT_NE(html.find("must be greater than zero"), std::string::npos);
  EXPECT_NE(html.find("<tr class=\"job bad-input\" data-id=\"negative-edge\""), std::string::npos);
}

// Trial 43 P10: a sketch naming a fabric file relative to its own folder, and a matrix value
// naming one relative to the manifest's, both mesh; before, every such job failed with "the
// fabric file does not exist" (the job's copy of the sketch lives in the job's folder).
TEST(BatchCommand, FabricFilesResolveAgainstTheSketchAndTheManifest) {
  const fs::path dir = fresh_batch_dir("fabric_files");
  fs::create_directories(dir / "sketches" / "fabrics");
  fs::create_directories(dir / "fabrics");
  fs::copy_file(fs::path(SD_SOURCE_DIR) / "data" / "fabrics" / "jersey.json",
                dir / "sketches" / "fabrics" / "mine.json");
  fs::copy_file(fs::path(SD_SOURCE_DIR) / "data" / "fabrics" / "silk.json",
                dir / "fabrics" / "other.json");
  json sketch = json::parse(read_text(kExamples / "a-line-skirt.json"), nullptr, true, true);
  sketch["fabric"] = "fabrics/mine.json";
  write_text(dir / "sketches" / "skirt.json", sketch.dump(2));
  write_text(dir / "m.json", R"({"format": "sketchdrape-batch/1", "set": {"/output/images": []},
      "jobs": [{"sketch": "sketches/skirt.json", "id": "own"},
               {"sketch": "sketches/skirt.json", "id": "override",
                "set": {"/fabric": "fabrics/other.json"}}]})");
  const fs::path out = dir / "out";
  const CommandResult r = run_sketchdrape("batch " + shell_quoted(dir / "m.json") + " -o " +
                                          shell_quoted(out) + " --stage mesh -j 2");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const auto jobs = jobs_by_id(read_json(out / "batch.json"));
  ASSERT_EQ(jobs.size(), 2u) << r.output;
  EXPECT_EQ(jobs.at("own")["status"], "done") << jobs.at("own");
  EXPECT_EQ(jobs.at("override")["status"], "done") << jobs.at("override");
}

TEST(BatchCommand, BadManifestExitsTwoBeforeRunningAnything) {
  const fs::path dir = fresh_batch_dir("bad_manifest");
  write_text(dir / "m.json", R"({"format": "sketchdrape-batch/1", "jobs": [
      {"sketch": ")" + (kExamples / "tshirt.json").string() +
                                 R"(", "matrix": {"/fabric": "denim"}}]})");
  const CommandResult r = run_sketchdrape("batch " + shell_quoted(dir / "m.json") + " -o " +
                                          shell_quoted(dir / "out") + " --stage mesh");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("m.json: /jobs/0/matrix/~1fabric: expected a non-empty list"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
  EXPECT_EQ(run_sketchdrape("batch " + shell_quoted(dir / "none.csv") + " -o " +
                            shell_quoted(dir / "out") + " --stage mesh")
                .exit_code,
            2);
  EXPECT_EQ(
      run_sketchdrape("batch " + shell_quoted(dir / "m.json") + " -o x --shard 4/3 --stage mesh")
          .exit_code,
      2);
  EXPECT_EQ(
      run_sketchdrape("batch " + shell_quoted(kExamples / "tshirt.json") + " -o x --stage simulate")
          .exit_code,
      2);
  EXPECT_EQ(run_sketchdrape("batch --collect " + shell_quoted(dir)).exit_code, 2);  // no plan there
}

TEST(BatchCommand, ShardsCoverTheBatchAndCollectBuildsTheSummary) {
  const fs::path dir = fresh_batch_dir("shards");
  const fs::path manifest = wardrobe(dir, {"jersey", "denim"});
  const fs::path out = dir / "out";
  std::multiset<std::string> ran;
  for (int i = 1; i <= 3; ++i) {
    const CommandResult r =
        run_sketchdrape("batch " + shell_quoted(manifest) + " -o " + shell_quoted(out) +
                        " --stage mesh --shard " + std::to_string(i) + "/3");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const json shard = read_json(out / "shards" / ("shard-" + std::to_string(i) + "-of-3.json"));
    EXPECT_EQ(shard["jobs"].size(), 2u);
    for (const auto& [id, row] : shard["jobs"].items()) ran.insert(id);
    EXPECT_FALSE(fs::exists(out / "batch.json")) << "shards leave the summary to --collect";
    if (i == 2) {  // shard 3 has not run: collect reports its jobs missing and exits 1
      const CommandResult partial = run_sketchdrape("batch --collect " + shell_quoted(out));
      EXPECT_EQ(partial.exit_code, 1) << partial.output;
      EXPECT_EQ(read_json(out / "batch.json")["counts"]["missing"], 2);
      fs::remove(out / "batch.json");
    }
  }
  EXPECT_EQ(ran.size(), 6u);
  EXPECT_EQ(std::set<std::string>(ran.begin(), ran.end()).size(), 6u) << "no job ran in two shards";
  const CommandResult collected = run_sketchdrape("batch --collect " + shell_quoted(out));
  ASSERT_EQ(collected.exit_code, 0) << collected.output;
  const json summary = read_json(out / "batch.json");
  EXPECT_EQ(summary["counts"]["done"], 6);
  for (const json& j : summary["jobs"]) EXPECT_EQ(j["images"].size(), 1u);
  // --list shows the same slices.
  const CommandResult list =
      run_sketchdrape("batch " + shell_quoted(manifest) + " --list --shard 2/3");
  EXPECT_EQ(list.exit_code, 0);
  EXPECT_EQ(std::count(list.output.begin(), list.output.end(), '\n'), 2);
}

// The default stage, `run` (mesh, simulate, images), when this build has it: two short drapes
// (0.1 s of simulated time) with their figures in the summary, then a re-run that reuses both.
TEST(BatchCommand, RunStageWhenTheBuildHasIt) {
  if (run_sketchdrape("run --help").exit_code != 0)
    GTEST_SKIP() << "SKIPPED: this build has no `run` command";
  const fs::path dir = fresh_batch_dir("run_stage");
  write_text(dir / "m.json",
             json{{"format", "sketchdrape-batch/1"},
                  {"set",
                   {{"/simulate/duration", 0.1},
                    {"/output/images", json::array({{{"view", "front"}, {"size", {120, 180}}}})}}},
                  {"jobs", json::array({{{"sketch", (kExamples / "a-line-skirt.json").string()},
                                         {"matrix", {{"/fabric", {"denim", "silk"}}}}}})}}
                 .dump());
  const fs::path out = dir / "out";
  const CommandResult r = run_sketchdrape("batch " + shell_quoted(dir / "m.json") + " -o " +
                                          shell_quoted(out) + " -j 2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  json summary = read_json(out / "batch.json");
  EXPECT_EQ(summary["stage"], "run");
  ASSERT_EQ(summary["jobs"].size(), 2u);
  for (const json& j : summary["jobs"]) {
    EXPECT_EQ(j["status"], "done") << j.dump();
    EXPECT_TRUE(j["figures"]["at_rest"].is_boolean()) << j["figures"].dump();
    EXPECT_GT(j["figures"]["vertices"].get<int>(), 50);
    EXPECT_GT(j["figures"]["steps"].get<int>(), 0);
    ASSERT_EQ(j["images"].size(), 1u);
    EXPECT_TRUE(fs::exists(out / j["images"][0].get<std::string>()));
  }
  const CommandResult again = run_sketchdrape("batch " + shell_quoted(dir / "m.json") + " -o " +
                                              shell_quoted(out) + " -j 2");
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_EQ(read_json(out / "batch.json")["counts"]["reused"], 2);
}

// A job whose simulation diverges: gravity of 1e9 m/s² makes a vertex exceed the simulator's
// speed limit even at the minimum step, so step control gives up and `run` exits 1. The job is
// recorded as failed with the simulator's reason; the other job of the batch finishes.
TEST(BatchFaults, DivergingSimulationFailsItsJobOnly) {
  if (run_sketchdrape("run --help").exit_code != 0)
    GTEST_SKIP() << "SKIPPED: this build has no `run` command";
  const fs::path dir = fresh_batch_dir("diverging");
  const json sheet = {{"format", "sketchdrape/1"},
                      {"sheet",
                       {{"size", {0.3, 0.3}},
                        {"resolution", {4, 4}},
                        {"orientation", "horizontal"},
                        {"pins", {"top-left", "top-right"}}}},
                      {"fabric", "cotton"},
                      {"simulate", {{"duration", 0.2}, {"solver", "cholmod"}}},
                      {"output", {{"images", json::array()}}}};
  write_text(dir / "sheet.json", sheet.dump(2));
  write_text(dir / "m.json",
             json{{"format", "sketchdrape-batch/1"},
                  {"jobs", json::array({{{"sketch", "sheet.json"}, {"id", "calm"}},
                                        {{"sketch", "sheet.json"},
                                         {"id", "diverging"},
                                         {"set", {{"/simulate/gravity", {0, -1e4, 0}}}}}})}}
                 .dump(2));
  const fs::path out = dir / "out";
  const CommandResult r = run_sketchdrape("batch " + shell_quoted(dir / "m.json") + " -o " +
                                          shell_quoted(out) + " -j 2");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("1 of 2 jobs did not finish"), std::string::npos) << r.output;
  const auto jobs = jobs_by_id(read_json(out / "batch.json"));
  ASSERT_EQ(jobs.size(), 2u);
  EXPECT_EQ(jobs.at("calm")["status"], "done") << jobs.at("calm").dump();
  EXPECT_GT(jobs.at("calm")["figures"]["steps"].get<int>(), 0);
  const json& bad = jobs.at("diverging");
  EXPECT_EQ(bad["status"], "failed") << bad.dump();
  EXPECT_EQ(bad["exit_code"], 1);
  const std::string reason = bad["reason"];
  EXPECT_NE(reason.find("the simulation failed"), std::string::npos) << reason;
  EXPECT_NE(reason.find("m/s (limit 50)"), std::string::npos) << reason;
  EXPECT_TRUE(fs::exists(out / "jobs" / "diverging" / "failed"));
  EXPECT_FALSE(fs::exists(out / "jobs" / "diverging" / "done"));
  EXPECT_FALSE(fs::exists(out / "jobs" / "diverging" / "report.json"))
      << "a failed run writes no outputs";
  EXPECT_NE(read_text(out / "index.html").find("<tr class=\"job failed\" data-id=\"diverging\""),
            std::string::npos);
}

// Starts the binary in its own process group (so the whole group can be killed).
pid_t start_in_new_group(const std::vector<std::string>& args, const fs::path& log) {
  const pid_t pid = fork();
  if (pid == 0) {
    setpgid(0, 0);
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 1);
    dup2(fd, 2);
    std::vector<char*> argv;
    std::vector<std::string> all = {SD_BINARY};
    all.insert(all.end(), args.begin(), args.end());
    for (std::string& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(SD_BINARY, argv.data());
    _exit(127);
  }
  setpgid(pid, pid);
  return pid;
}

// Polls a batch's output folder (every 25 ms, for up to 30 s) until one of its jobs has
// started, i.e. written its log; false if none did.
bool wait_until_a_job_starts(const fs::path& out) {
  for (int i = 0; i < 1200; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
    std::error_code ec;
    for (const auto& d : fs::directory_iterator(out / "jobs", ec))
      if (fs::exists(d.path() / "log.txt")) return true;
  }
  return false;
}

TEST(BatchFaults, SigkillMidwayThenResumeRedoesOnlyUnfinishedJobs) {
  const fs::path dir = fresh_batch_dir("sigkill");
  const fs::path manifest = wardrobe(dir, {"jersey", "denim", "silk"});  // 9 jobs
  const fs::path out = dir / "out";
  const std::vector<std::string> args = {
      "batch", manifest.string(), "-o", out.string(), "--stage", "mesh", "-j", "2"};
  const pid_t pid = start_in_new_group(args, dir / "first.log");
  // Wait until at least one job is done and another has started but is not done, then kill
  // the batch and its children at once.
  bool ready = false;
  for (int i = 0; i < 1200 && !ready; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
    int done = 0, started = 0;
    std::error_code ec;
    for (const auto& d : fs::directory_iterator(out / "jobs", ec)) {
      if (fs::exists(d.path() / "done"))
        ++done;
      else if (fs::exists(d.path() / "log.txt"))
        ++started;
    }
    ready = done >= 1 && started >= 1;
  }
  ASSERT_TRUE(ready) << read_text(dir / "first.log");
  ASSERT_EQ(kill(-pid, SIGKILL), 0);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status));
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // children reparented and killed

  const auto finished = marker_stamps(out);
  std::set<std::string> unfinished;
  for (const auto& d : fs::directory_iterator(out / "jobs"))
    if (!fs::exists(d.path() / "done")) unfinished.insert(d.path().filename().string());
  ASSERT_FALSE(finished.empty());
  ASSERT_FALSE(unfinished.empty());
  ASSERT_LT(finished.size(), 9u);
  // Make sure a half-written job looks like one: a stray temporary and a report without marker.
  const fs::path half = out / "jobs" / *unfinished.begin();
  write_text(half / ".garment.obj.tmp-99999-0", "partial");
  write_text(half / "report.json", "{\"totals\": {\"vertices\": -1}}");

  const CommandResult resumed = run_sketchdrape("batch " + shell_quoted(manifest) + " -o " +
                                                shell_quoted(out) + " --stage mesh -j 2");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  const json summary = read_json(out / "batch.json");
  ASSERT_EQ(summary["jobs"].size(), 9u);
  EXPECT_EQ(summary["counts"]["done"], 9);
  const auto after = marker_stamps(out);
  for (const json& j : summary["jobs"]) {
    const std::string id = j["id"];
    const bool was_done = finished.count(id) > 0;
    EXPECT_EQ(j["reused"], was_done) << id;
    if (was_done) {
      EXPECT_EQ(after.at(id), finished.at(id)) << id << " was recomputed";
    }
  }
  EXPECT_FALSE(fs::exists(half / ".garment.obj.tmp-99999-0"));
  EXPECT_GT(read_json(half / "report.json")["totals"]["vertices"].get<int>(), 0);
  EXPECT_EQ(summary["counts"]["reused"], static_cast<int>(finished.size()));
}

TEST(BatchFaults, SigtermStopsChildrenWritesTheSummaryAndResumes) {
  const fs::path dir = fresh_batch_dir("sigterm");
  const fs::path manifest = wardrobe(dir, {"jersey", "denim", "silk"});  // 9 jobs
  const fs::path out = dir / "out";
  const pid_t pid = start_in_new_group(
      {"batch", manifest.string(), "-o", out.string(), "--stage", "mesh", "-j", "2"},
      dir / "first.log");
  ASSERT_TRUE(wait_until_a_job_starts(out)) << read_text(dir / "first.log");
  ASSERT_EQ(kill(pid, SIGTERM), 0);  // the batch only: it must end its children itself
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status)) << read_text(dir / "first.log");
  EXPECT_EQ(WEXITSTATUS(status), 1);
  EXPECT_NE(read_text(dir / "first.log").find("the batch was stopped"), std::string::npos);
  // No child is left running: every job folder's log is closed and no mesh process remains in
  // the group.
  EXPECT_EQ(kill(-pid, 0), -1) << "a child of the stopped batch is still alive";
  const json summary = read_json(out / "batch.json");
  ASSERT_EQ(summary["jobs"].size(), 9u);
  int done = 0;
  for (const json& j : summary["jobs"]) {
    if (j["status"] == "done") {
      ++done;
      continue;
    }
    const std::string reason = j["reason"];
    EXPECT_TRUE(reason.find("interrupted") != std::string::npos || j["status"] == "missing")
        << j.dump();
    EXPECT_FALSE(fs::exists(out / "jobs" / j["id"].get<std::string>() / "failed"))
        << "an interrupted job is not recorded as failed";
  }
  EXPECT_LT(done, 9);
  const CommandResult resumed = run_sketchdrape("batch " + shell_quoted(manifest) + " -o " +
                                                shell_quoted(out) + " --stage mesh -j 2");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_EQ(read_json(out / "batch.json")["counts"]["done"], 9);
  EXPECT_EQ(read_json(out / "batch.json")["counts"]["reused"], done);
}

TEST(BatchFaults, TimeoutKillsSlowJobsAndARerunFinishesThem) {
  const fs::path dir = fresh_batch_dir("timeout");
  write_text(dir / "m.csv", "sketch,/fabric\n" + (kExamples / "tshirt.json").string() + ",denim\n" +
                                (kExamples / "tshirt.json").string() + ",silk\n");
  const fs::path out = dir / "out";
  // Meshing the t-shirt with its three 600x900 images takes far longer than 50 ms.
  const CommandResult slow =
      run_sketchdrape("batch " + shell_quoted(dir / "m.csv") + " -o " + shell_quoted(out) +
                      " --stage mesh -j 2 --timeout 0.05");
  EXPECT_EQ(slow.exit_code, 1) << slow.output;
  for (const json& j : read_json(out / "batch.json")["jobs"]) {
    EXPECT_EQ(j["status"], "failed");
    EXPECT_EQ(j["reason"], "timed out after 0.05 s (--timeout)");
    EXPECT_EQ(j["exit_code"], -1);
    EXPECT_FALSE(fs::exists(out / "jobs" / j["id"].get<std::string>() / "done"));
  }
  const CommandResult again = run_sketchdrape("batch " + shell_quoted(dir / "m.csv") + " -o " +
                                              shell_quoted(out) + " --stage mesh -j 2");
  EXPECT_EQ(again.exit_code, 0) << again.output;
  EXPECT_EQ(read_json(out / "batch.json")["counts"]["done"], 2);
}

TEST(BatchFaults, FullDiskEndsTheJobFailedWithAClearReason) {
  const fs::path dir = fresh_batch_dir("full_disk");
  fs::copy_file(kExamples / "tshirt.json", dir / "tshirt.json");
  write_text(dir / "m.json", R"({"format": "sketchdrape-batch/1", "jobs": [
      {"sketch": "tshirt.json", "id": "fits"},
      {"sketch": "tshirt.json", "id": "tiny-disk", "set": {"/fabric": "denim"}}],
      "set": {"/output/images": [{"view": "front", "size": [120, 180]}]}})");
  const fs::path out = dir / "out";
  const fs::path tiny = out / "jobs" / "tiny-disk";
  fs::create_directories(tiny);
  // A 32 KiB tmpfs holds the job's sketch and log but not its meshes and images. Without
  // CAP_SYS_ADMIN, fall back to a folder the job cannot write (only works for non-root).
  bool mounted = mount("tmpfs", tiny.c_str(), "tmpfs", 0, "size=32k") == 0;
  std::string expected = "No space left on device";
  if (!mounted) {
    if (geteuid() == 0) GTEST_SKIP() << "cannot mount a tmpfs and root ignores read-only folders";
    chmod(tiny.c_str(), 0555);
    expected = "Permission denied";
  }
  const CommandResult r = run_sketchdrape("batch " + shell_quoted(dir / "m.json") + " -o " +
                                          shell_quoted(out) + " --stage mesh");
  if (mounted)
    umount2(tiny.c_str(), MNT_DETACH);
  else
    chmod(tiny.c_str(), 0755);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  const auto jobs = jobs_by_id(read_json(out / "batch.json"));
  EXPECT_EQ(jobs.at("fits")["status"], "done");
  EXPECT_EQ(jobs.at("tiny-disk")["status"], "failed");
  const std::string reason = jobs.at("tiny-disk")["reason"];
  EXPECT_NE(reason.find(expected), std::string::npos) << reason;
  EXPECT_NE(reason.find("cannot write"), std::string::npos) << reason;
}

// The contact sheet in a real browser: every thumbnail loads from disk (no server), and the
// table has one row per job. Runs when Debian's chromium is installed (scripts/setup.sh).
// Width of a PNG from its IHDR chunk (big-endian at byte 16).
int png_width(const fs::path& png) {
  const std::string bytes = read_text(png);
  if (bytes.size() < 24) return -1;
  int width = 0;
  for (int i = 16; i < 20; ++i) width = width * 256 + static_cast<unsigned char>(bytes[i]);
  return width;
}

// Waits (at most 30 s) until no process of the group `pid` is left; true if none is.
bool group_ends(pid_t pid) {
  for (int i = 0; i < 300; ++i) {
    if (kill(-pid, 0) == -1 && errno == ESRCH) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return false;
}

// SIGKILL of the batch alone (not its group): its children die with it (PR_SET_PDEATHSIG), so
// nothing writes into the folder afterwards; a rerun started at once after editing the manifest
// gives every job outputs of the new input; a job whose output changed after its done marker
// (edited by hand, or written late) is redone, never reused.
TEST(BatchFaults, KillEditRerunLeavesNothingStale) {
  const fs::path dir = fresh_batch_dir("kill-edit-rerun");
  const fs::path manifest = wardrobe(dir, {"jersey", "denim"});  // 6 jobs
  // 24 pictures per job, so that a job is seen half-way through staging them.
  json slow = read_json(manifest);
  slow["set"]["/output/images"] = json::array();
  for (int i = 0; i < 24; ++i)
    slow["set"]["/output/images"].push_back({{"view", "front"}, {"size", {300, 450}}});
  write_text(manifest, slow.dump(2));
  const fs::path out = dir / "out";
  const pid_t pid = start_in_new_group(
      {"batch", manifest.string(), "-o", out.string(), "--stage", "mesh", "-j", "2"},
      dir / "first.log");
  // A job that is staging its outputs (a hidden temporary is there, its outputs are not).
  fs::path staging;
  for (int i = 0; i < 2400 && staging.empty(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
    std::error_code ec;
    for (const auto& d : fs::directory_iterator(out / "jobs", ec))
      for (const auto& f : fs::directory_iterator(d.path(), ec))
        if (f.path().filename().string().find(".tmp-") != std::string::npos &&
            !fs::exists(d.path() / "garment.obj"))
          staging = d.path();
  }
  ASSERT_FALSE(staging.empty()) << read_text(dir / "first.log");
  ASSERT_EQ(kill(pid, SIGKILL), 0);  // the batch process only
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(group_ends(pid)) << "a child outlived its SIGKILLed batch";
  // The child ended with its batch: it never committed its outputs, and removed its temporaries.
  EXPECT_FALSE(fs::exists(staging / "garment.obj")) << staging;
  EXPECT_FALSE(fs::exists(staging / "done")) << staging;
  for (const auto& f : fs::directory_iterator(staging))
    EXPECT_EQ(f.path().filename().string().find(".tmp-"), std::string::npos) << f.path();

  // Edit: every job's image becomes 140 px wide (same job ids, new inputs); rerun at once.
  json edited = read_json(manifest);
  edited["set"]["/output/images"] = json::array({{{"view", "front"}, {"size", {140, 210}}}});
  write_text(manifest, edited.dump(2));
  const CommandResult rerun = run_sketchdrape("batch " + shell_quoted(manifest) + " -o " +
                                              shell_quoted(out) + " --stage mesh -j 2");
  ASSERT_EQ(rerun.exit_code, 0) << rerun.output;
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // a late writer would show now
  const json summary = read_json(out / "batch.json");
  ASSERT_EQ(summary["jobs"].size(), 6u);
  for (const json& j : summary["jobs"]) {
    const fs::path job = out / "jobs" / j["id"].get<std::string>();
    EXPECT_EQ(j["status"], "done") << j.dump();
    EXPECT_EQ(png_width(job / "garment-front.png"), 140) << job;
    const json marker = read_json(job / "done");
    EXPECT_TRUE(marker["outputs"].contains("garment-front.png")) << marker.dump();
    EXPECT_TRUE(marker["outputs"].contains("sketch.json")) << marker.dump();
  }

  // An output changed after its marker: that job is redone, the others reused.
  const std::string tampered = summary["jobs"][0]["id"];
  write_text(out / "jobs" / tampered / "report.json", "{\"stale\": true}");
  const CommandResult again = run_sketchdrape("batch " + shell_quoted(manifest) + " -o " +
                                              shell_quoted(out) + " --stage mesh -j 2");
  ASSERT_EQ(again.exit_code, 0) << again.output;
  for (const json& j : read_json(out / "batch.json")["jobs"])
    EXPECT_EQ(j["reused"].get<bool>(), j["id"] != tampered) << j.dump();
  EXPECT_FALSE(read_json(out / "jobs" / tampered / "report.json").contains("stale"));
}

// Two batches on one folder: the second refuses with a sentence naming the first; the first
// finishes every job.
TEST(BatchFaults, SecondBatchOnTheSameFolderRefuses) {
  const fs::path dir = fresh_batch_dir("two-batches");
  const fs::path manifest = wardrobe(dir, {"jersey"});  // 3 jobs
  const fs::path out = dir / "out";
  const pid_t first = start_in_new_group(
      {"batch", manifest.string(), "-o", out.string(), "--stage", "mesh", "-j", "1"},
      dir / "first.log");
  ASSERT_TRUE(wait_until_a_job_starts(out)) << read_text(dir / "first.log");
  const CommandResult second = run_sketchdrape("batch " + shell_quoted(manifest) + " -o " +
                                               shell_quoted(out) + " --stage mesh -j 1");
  EXPECT_EQ(second.exit_code, 1) << second.output;
  EXPECT_NE(second.output.find("another batch (process " + std::to_string(first) + ")"),
            std::string::npos)
      << second.output;
  int status = 0;
  waitpid(first, &status, 0);
  ASSERT_TRUE(WIFEXITED(status)) << read_text(dir / "first.log");
  EXPECT_EQ(WEXITSTATUS(status), 0) << read_text(dir / "first.log");
  EXPECT_EQ(read_json(out / "batch.json")["counts"]["done"], 3);
  // Once the first has ended, the folder is free again: everything is reused.
  const CommandResult third = run_sketchdrape("batch " + shell_quoted(manifest) + " -o " +
                                              shell_quoted(out) + " --stage mesh -j 1");
  EXPECT_EQ(third.exit_code, 0) << third.output;
  EXPECT_EQ(read_json(out / "batch.json")["counts"]["reused"], 3);
}

// Shards of one folder with different counts (or a whole batch beside a shard) have overlapping
// slices: while shard 1/2 runs, 1/3 and an unsharded batch refuse with a sentence naming the
// running one and the count to use; 2/2 shares the folder; all is done in the end.
TEST(BatchFaults, ShardsOfAnotherCountOnTheSameFolderRefuse) {
  const fs::path dir = fresh_batch_dir("shard-counts");
  const fs::path manifest = wardrobe(dir, {"jersey", "denim"});  // 6 jobs, 3 per shard of 2
  const fs::path out = dir / "out";
  const pid_t first = start_in_new_group({"batch", manifest.string(), "-o", out.string(), "--stage",
                                          "mesh", "-j", "1", "--shard", "1/2"},
                                         dir / "first.log");
  ASSERT_TRUE(wait_until_a_job_starts(out)) << read_text(dir / "first.log");
  const std::string batch =
      "batch " + shell_quoted(manifest) + " -o " + shell_quoted(out) + " --stage mesh -j 1";
  const CommandResult thirds = run_sketchdrape(batch + " --shard 1/3");
  EXPECT_EQ(thirds.exit_code, 1) << thirds.output;
  EXPECT_NE(thirds.output.find("a batch in 2 shards is writing into"), std::string::npos)
      << thirds.output;
  EXPECT_NE(thirds.output.find("process " + std::to_string(first)), std::string::npos)
      << thirds.output;
  EXPECT_NE(thirds.output.find("--shard I/2"), std::string::npos) << thirds.output;
  const CommandResult whole = run_sketchdrape(batch);
  EXPECT_EQ(whole.exit_code, 1) << whole.output;
  EXPECT_NE(whole.output.find("a batch in 2 shards"), std::string::npos) << whole.output;
  // The other shard of the same count runs beside it.
  const CommandResult second = run_sketchdrape(batch + " --shard 2/2");
  EXPECT_EQ(second.exit_code, 0) << second.output;
  int status = 0;
  waitpid(first, &status, 0);
  ASSERT_TRUE(WIFEXITED(status)) << read_text(dir / "first.log");
  EXPECT_EQ(WEXITSTATUS(status), 0) << read_text(dir / "first.log");
  // Once both have ended, any count may run on the folder: everything is reused.
  const CommandResult after = run_sketchdrape(batch + " --shard 1/3");
  EXPECT_EQ(after.exit_code, 0) << after.output;
  const CommandResult collected = run_sketchdrape("batch --collect " + shell_quoted(out));
  EXPECT_EQ(collected.exit_code, 0) << collected.output;
  EXPECT_EQ(read_json(out / "batch.json")["counts"]["done"], 6);
}

TEST(ContactSheet, LoadsInHeadlessChromium) {
  const char* browser = "/usr/bin/chromium";
  if (!fs::exists(browser))
    GTEST_SKIP() << "SKIPPED: /usr/bin/chromium not installed (scripts/setup.sh installs it)";
  const fs::path dir = fresh_batch_dir("chromium");
  const fs::path manifest = wardrobe(dir, {"jersey", "denim"});
  write_text(dir / "broken.json", "{ not json");
  const fs::path out = dir / "out files";  // a space in the path, as users have
  const CommandResult r =
      run_sketchdrape("batch " + shell_quoted(manifest) + " " + shell_quoted(dir / "broken.json") +
                      " -o " + shell_quoted(out) + " --stage mesh -j 2");
  ASSERT_EQ(r.exit_code, 1) << r.output;  // the broken one fails, 6 are done
  const std::string command =
      std::string(browser) +
      " --headless --no-sandbox --disable-gpu --disable-quic --no-first-run"
      " --disable-background-networking --disable-component-update --disable-sync"
      " --user-data-dir=" +
      shell_quoted(dir / "profile") + " --virtual-time-budget=10000 --dump-dom " +
      shell_quoted("file://" + (out / "index.html").string()) + " 2>/dev/null";
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string dom;
  char buffer[4096];
  size_t n;
  while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) dom.append(buffer, n);
  pclose(pipe);
  ASSERT_FALSE(dom.empty()) << "chromium printed no DOM";
  std::smatch m;
  ASSERT_TRUE(std::regex_search(dom, m, std::regex("<body[^>]*>"))) << dom.substr(0, 2000);
  const std::string body = m.str();
  EXPECT_NE(body.find("data-images-settled=\"yes\""), std::string::npos) << body;
  EXPECT_NE(body.find("data-images-total=\"6\""), std::string::npos) << body;
  EXPECT_NE(body.find("data-images-loaded=\"6\""), std::string::npos) << body;
  EXPECT_NE(body.find("data-images-broken=\"0\""), std::string::npos) << body;
  size_t rows = 0;
  for (size_t at = dom.find("<tr class=\"job "); at != std::string::npos;
       at = dom.find("<tr class=\"job ", at + 1))
    ++rows;
  EXPECT_EQ(rows, 7u);
  EXPECT_NE(dom.find("<tr class=\"job bad-input\" data-id=\"broken\""), std::string::npos);
  EXPECT_NE(dom.find("6 thumbnails loaded"), std::string::npos);
}

}  // namespace
}  // namespace sd::test
