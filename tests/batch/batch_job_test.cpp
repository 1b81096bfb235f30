#include "src/app/batch/batch_job.hpp"

#include <gtest/gtest.h>

#include "src/app/pipeline/sha256.hpp"
#include "tests/batch/batch_test_util.hpp"

namespace sd::app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// A sketch with comments and a relative body path, next to its body file.
fs::path sketch_dir(const std::string& name) {
  const fs::path dir = test::fresh_batch_dir(name);
  test::write_text(dir / "bodies" / "b.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  test::write_text(dir / "s.json", R"({
    // a comment, as sketch files allow
    "format": "sketchdrape/1",
    "body": {"mesh": "bodies/b.obj", "height": 1.7},
    "fabric": "jersey",
    "curves": [{"id": "c", "points": [[0, 1], [1, 1]]}]
  })");
  return dir;
}

BatchJob job_for(const fs::path& dir, const json& overrides) {
  return {"s", dir / "s.json", overrides, "test", overrides};
}

TEST(PlanJob, MergesOverridesAndMakesBodyPathAbsolute) {
  const fs::path dir = sketch_dir("plan_merge");
  FileDigests files;
  const PlannedJob p = plan_job(
      job_for(dir, json::parse(R"({"fabric": "denim", "body": {"height": null, "up": "+z"}})")),
      "mesh", "1.0", files);
  ASSERT_TRUE(p.document) << p.input_error;
  const json& d = *p.document;
  EXPECT_EQ(d["fabric"], "denim");
  EXPECT_EQ(d["body"]["mesh"], (dir / "bodies" / "b.obj").string());
  EXPECT_FALSE(d["body"].contains("height"));  // null deletes (RFC 7386)
  EXPECT_EQ(d["body"]["up"], "+z");
  EXPECT_EQ(d["curves"][0]["id"], "c");  // untouched parts stay
  EXPECT_EQ(p.inputs_hash.size(), 64u);
}

// Trial 43 P10: a fabric file named relative to the sketch was left relative, so the job's copy
// of the sketch (in the job's folder) named a file that is not there and every such job failed.
TEST(PlanJob, MakesFabricFilePathsAbsoluteAndCountsTheirContents) {
  const fs::path dir = sketch_dir("plan_fabric_file");
  test::write_text(dir / "fabrics" / "mine.json", R"({"name": "mine"})");
  std::string text = test::read_text(dir / "s.json");
  text.replace(text.find("\"jersey\""), 8, "\"fabrics/mine.json\"");
  text.replace(text.find("\"curves\""), 0,
               R"("panels": [{"id": "p", "fabric": "fabrics/mine.json"},
                             {"id": "q", "fabric": "denim"}, {"id": "r", "fabric": "linnen"}],
               )");
  test::write_text(dir / "s.json", text);
  auto plan = [&](const json& overrides) {
    FileDigests files;  // fresh, so a changed fabric file is read again
    return plan_job(job_for(dir, overrides), "mesh", "1.0", files);
  };
  const PlannedJob p = plan(json::object());
  ASSERT_TRUE(p.document) << p.input_error;
  const std::string absolute = (dir / "fabrics" / "mine.json").string();
  EXPECT_EQ((*p.document)["fabric"], absolute);
  EXPECT_EQ((*p.document)["panels"][0]["fabric"], absolute);
  EXPECT_EQ((*p.document)["panels"][1]["fabric"], "denim") << "a preset stays a preset";
  EXPECT_EQ((*p.document)["panels"][2]["fabric"], "linnen")
      << "an unknown name is not a path: its error quotes it as written";
  // The fabric file's contents count toward the digest, as a body file's do.
  test::write_text(dir / "fabrics" / "mine.json", R"({"name": "mine, changed"})");
  EXPECT_NE(p.inputs_hash, plan(json::object()).inputs_hash);
  // An inline fabric (an object) is no path.
  const PlannedJob inline_fabric = plan(json::parse(R"({"fabric": {"name": "x"}})"));
  ASSERT_TRUE(inline_fabric.document) << inline_fabric.input_error;
  EXPECT_EQ((*inline_fabric.document)["fabric"], json::parse(R"({"name": "x"})"));
}

TEST(PlanJob, DigestChangesWithEveryInputAndOnlyThen) {
  const fs::path dir = sketch_dir("plan_digest");
  auto digest = [&](const json& overrides, const std::string& stage, const std::string& version) {
    FileDigests files;  // fresh, so a changed body file is read again
    return plan_job(job_for(dir, overrides), stage, version, files).inputs_hash;
  };
  const std::string base = digest(json::object(), "mesh", "1.0");
  EXPECT_EQ(base, digest(json::object(), "mesh", "1.0"));
  EXPECT_EQ(base, digest(json::parse(R"({"fabric": "jersey"})"), "mesh", "1.0"))
      << "an override that changes nothing leaves the merged document and digest alone";
  EXPECT_NE(base, digest(json::parse(R"({"fabric": "denim"})"), "mesh", "1.0"));
  EXPECT_NE(base, digest(json::object(), "run", "1.0"));
  EXPECT_NE(base, digest(json::object(), "mesh", "1.1"));
  // Whitespace and comments in the sketch do not matter; values do.
  std::string text = test::read_text(dir / "s.json");
  test::write_text(dir / "s.json", "\n\n" + text);
  EXPECT_EQ(base, digest(json::object(), "mesh", "1.0"));
  // The body file's contents count, not only its path.
  test::write_text(dir / "bodies" / "b.obj", "v 0 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_NE(base, digest(json::object(), "mesh", "1.0"));
}

TEST(PlanJob, SketchThatIsNotJsonIsAnInputErrorWithLineAndColumn) {
  const fs::path dir = test::fresh_batch_dir("plan_bad_json");
  test::write_text(dir / "s.json", "{\n  \"format\": \"sketchdrape/1\",\n  \"fabric\": denim\n}\n");
  FileDigests files;
  const PlannedJob p =
      plan_job({"s", dir / "s.json", json::object(), "t", json::object()}, "mesh", "1", files);
  EXPECT_FALSE(p.document);
  EXPECT_NE(p.input_error.find("line 3"), std::string::npos) << p.input_error;
  EXPECT_EQ(p.inputs_hash.size(), 64u);
}

TEST(FileDigests, UnreadableFileHasAStableReasonInsteadOfADigest) {
  FileDigests files;
  const std::string d = files.digest("/nonexistent/body.obj");
  EXPECT_EQ(d.rfind("unreadable: ", 0), 0u);
  EXPECT_EQ(&files.digest("/nonexistent/body.obj"), &files.digest("/nonexistent/body.obj"));
}

JobRecord record(const std::string& status, const std::string& hash) {
  JobRecord r;
  r.status = status;
  r.exit_code = status == "done" ? 0 : 1;
  r.reason = status == "done" ? "" : "it broke";
  r.wall_time_s = 1.5;
  r.inputs_hash = hash;
  r.stage = "mesh";
  r.version = "1.0";
  r.finished_at = utc_timestamp();
  return r;
}

TEST(DoneMarker, OnlyAValidDoneMarkerWithTheSameDigestCounts) {
  const fs::path dir = test::fresh_batch_dir("marker");
  EXPECT_FALSE(job_is_done(dir, "abc"));
  write_job_record(dir, record("done", "abc"));
  EXPECT_TRUE(fs::exists(dir / kDoneMarker));
  EXPECT_TRUE(job_is_done(dir, "abc"));
  EXPECT_FALSE(job_is_done(dir, "abd"));  // changed inputs
  // A damaged (half-written by hand, truncated) marker is not taken for done.
  const std::string text = test::read_text(dir / kDoneMarker);
  test::write_text(dir / kDoneMarker, text.substr(0, text.size() / 2));
  EXPECT_FALSE(job_is_done(dir, "abc"));
  EXPECT_FALSE(read_job_record(dir));
  // A done marker that says "failed" is damaged too.
  test::write_text(dir / kDoneMarker, record_to_json(record("failed", "abc")).dump());
  EXPECT_FALSE(job_is_done(dir, "abc"));
}

// The marker binds the outputs to the inputs: an output changed, removed or listed with
// another digest after the marker was written makes the job not done; the log, the markers
// and hidden temporaries are not outputs.
TEST(DoneMarker, BindsTheOutputsAsTheyWere) {
  const fs::path dir = test::fresh_batch_dir("marker_outputs");
  test::write_text(dir / "sketch.json", "{}");
  test::write_text(dir / "report.json", "{\"quads\": 12}");
  test::write_text(dir / "frames" / "frame-0000-front.png", "png");
  test::write_text(dir / kJobLog, "info: meshed");
  test::write_text(dir / ".report.json.tmp-1-0", "partial");
  JobRecord done = record("done", "h");
  done.outputs = digest_job_outputs(dir);
  ASSERT_EQ(done.outputs.size(), 3u);
  EXPECT_EQ(done.outputs.count("frames/frame-0000-front.png"), 1u);
  EXPECT_EQ(done.outputs.at("report.json"), sha256_hex("{\"quads\": 12}"));
  write_job_record(dir, done);
  EXPECT_TRUE(job_is_done(dir, "h"));
  EXPECT_EQ(read_job_record(dir)->outputs, done.outputs);
  test::write_text(dir / kJobLog, "info: a later line");  // not an output
  EXPECT_TRUE(job_is_done(dir, "h"));
  test::write_text(dir / "report.json", "{\"quads\": 13}");  // written after the marker
  EXPECT_FALSE(job_is_done(dir, "h"));
  test::write_text(dir / "report.json", "{\"quads\": 12}");
  EXPECT_TRUE(job_is_done(dir, "h"));
  fs::remove(dir / "frames" / "frame-0000-front.png");
  EXPECT_FALSE(job_is_done(dir, "h"));
}

TEST(DoneMarker, FailedRecordReplacesDoneAndBack) {
  const fs::path dir = test::fresh_batch_dir("marker_swap");
  write_job_record(dir, record("done", "h"));
  write_job_record(dir, record("failed", "h"));
  EXPECT_FALSE(fs::exists(dir / kDoneMarker));
  ASSERT_TRUE(read_job_record(dir));
  EXPECT_EQ(read_job_record(dir)->status, "failed");
  EXPECT_EQ(read_job_record(dir)->reason, "it broke");
  EXPECT_FALSE(job_is_done(dir, "h"));
  write_job_record(dir, record("done", "h"));
  EXPECT_FALSE(fs::exists(dir / kFailedMarker));
  EXPECT_TRUE(job_is_done(dir, "h"));
  const JobRecord back = record_from_json(record_to_json(record("failed", "x")));
  EXPECT_EQ(back.exit_code, 1);
  EXPECT_EQ(back.wall_time_s, 1.5);
}

TEST(CleanJobFolder, RemovesMarkersOutputsAndTemporariesButKeepsTheFolder) {
  const fs::path dir = test::fresh_batch_dir("clean");
  write_job_record(dir, record("done", "h"));
  test::write_text(dir / "report.json", "{}");
  test::write_text(dir / ".garment.obj.tmp-123-0", "partial");
  test::write_text(dir / "sub" / "x.png", "png");
  clean_job_folder(dir);
  EXPECT_TRUE(fs::is_directory(dir));
  EXPECT_TRUE(fs::is_empty(dir));
  clean_job_folder(dir / "new");  // created when missing
  EXPECT_TRUE(fs::is_directory(dir / "new"));
}

TEST(FailureReason, LastErrorLineElseLastLine) {
  const fs::path dir = test::fresh_batch_dir("reason");
  test::write_text(dir / "a.txt",
                   "info: meshing\nerror: first\nwarning: w\nerror: s.json: /fabric: bad\n\n");
  EXPECT_EQ(failure_reason_from_log(dir / "a.txt"), "s.json: /fabric: bad");
  test::write_text(dir / "b.txt", "info: one\nterminate called after throwing\n");
  EXPECT_EQ(failure_reason_from_log(dir / "b.txt"), "terminate called after throwing");
  EXPECT_EQ(failure_reason_from_log(dir / "missing.txt"), "");
}

}  // namespace
}  // namespace sd::app
