#include "src/app/batch/batch_manifest.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "tests/batch/batch_test_util.hpp"

namespace sd::app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// A folder with two tiny "sketch" files (the manifest layer only needs them to exist).
fs::path manifest_dir(const std::string& name) {
  const fs::path dir = test::fresh_batch_dir(name);
  test::write_text(dir / "sketches" / "dress.json", R"({"format": "sketchdrape/1"})");
  test::write_text(dir / "sketches" / "skirt.json", R"({"format": "sketchdrape/1"})");
  return dir;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const ManifestError& e) {
    return e.what();
  }
  return "(no ManifestError)";
}

TEST(PointerPatch, NestsObjectsAndRejectsListIndices) {
  EXPECT_EQ(pointer_patch("/fabric", "denim"), json::parse(R"({"fabric": "denim"})"));
  EXPECT_EQ(pointer_patch("/body/height", 1.7), json::parse(R"({"body": {"height": 1.7}})"));
  EXPECT_EQ(pointer_patch("/a~1b/c~0d", 1), json::parse(R"({"a/b": {"c~d": 1}})"));
  EXPECT_THROW(pointer_patch("fabric", 1), std::invalid_argument);
  EXPECT_THROW(pointer_patch("", 1), std::invalid_argument);
  EXPECT_THROW(pointer_patch("/output/images/0/width", 1), std::invalid_argument);
  EXPECT_THROW(pointer_patch("/body//height", 1), std::invalid_argument);
}

TEST(CombinePatches, LaterWinsKeyByKeyAndKeepsNulls) {
  const json a = json::parse(R"({"fabric": "silk", "body": {"height": 1.6, "up": "+y"}})");
  const json b = json::parse(R"({"body": {"height": 1.8, "scale": null}, "edge_length": 0.02})");
  const json c = combine_patches(a, b);
  EXPECT_EQ(c, json::parse(R"({"fabric": "silk", "edge_length": 0.02,
                               "body": {"height": 1.8, "up": "+y", "scale": null}})"));
  // Applying the combined patch equals applying both in turn when both are objects.
  json doc1 = json::parse(R"({"fabric": "jersey", "body": {"mesh": "builtin", "scale": 0.01}})");
  json doc2 = doc1;
  doc1.merge_patch(a);
  doc1.merge_patch(b);
  doc2.merge_patch(c);
  EXPECT_EQ(doc1, doc2);
  EXPECT_FALSE(doc2["body"].contains("scale"));
}

TEST(PatchLeaves, SortedPointersWithListsAsLeaves) {
  const auto leaves = patch_leaves(json::parse(
      R"({"output": {"images": [{"view": "front"}]}, "body": {"height": 1.7}, "fabric": "denim"})"));
  ASSERT_EQ(leaves.size(), 3u);
  EXPECT_EQ(leaves[0].first, "/body/height");
  EXPECT_EQ(leaves[1].first, "/fabric");
  EXPECT_EQ(leaves[2].first, "/output/images");
  EXPECT_TRUE(leaves[2].second.is_array());
  EXPECT_TRUE(patch_leaves(json::object()).empty());
}

TEST(JsonManifest, RowsOverridesSetsAndMatrixCrossProduct) {
  const fs::path dir = manifest_dir("json_rows");
  const std::string text = R"({
    // comments are allowed, as in sketch files
    "format": "sketchdrape-batch/1",
    "overrides": {"edge_length": 0.04},
    "jobs": [
      "sketches/skirt.json",
      {"sketch": "sketches/dress.json", "id": "dress-silk", "overrides": {"fabric": "silk"}},
      {"sketch": "sketches/dress.json", "set": {"/body/height": 1.55},
       "matrix": {"/fabric": ["denim", "wool", "jersey"], "/simulate/time_step": [0.01, 0.02]}}
    ]})";
  std::vector<BatchJob> jobs = parse_json_manifest(text, "m.json", dir);
  ASSERT_EQ(jobs.size(), 1u + 1u + 6u);
  EXPECT_EQ(jobs[0].sketch, dir / "sketches" / "skirt.json");
  EXPECT_EQ(jobs[0].overrides, json::parse(R"({"edge_length": 0.04})"));
  EXPECT_EQ(jobs[0].id_overrides, json::object()) << "batch-wide overrides stay out of ids";
  EXPECT_EQ(jobs[1].id, "dress-silk");
  EXPECT_EQ(jobs[1].overrides, json::parse(R"({"edge_length": 0.04, "fabric": "silk"})"));
  EXPECT_EQ(jobs[1].id_overrides, json::parse(R"({"fabric": "silk"})"));
  std::set<std::pair<std::string, double>> combos;
  for (size_t i = 2; i < jobs.size(); ++i) {
    EXPECT_EQ(jobs[i].overrides["body"]["height"], 1.55);
    EXPECT_EQ(jobs[i].overrides["edge_length"], 0.04);
    combos.emplace(jobs[i].overrides["fabric"].get<std::string>(),
                   jobs[i].overrides["simulate"]["time_step"].get<double>());
    EXPECT_NE(jobs[i].origin.find("/jobs/2 (combination"), std::string::npos) << jobs[i].origin;
  }
  EXPECT_EQ(combos.size(), 6u);  // every fabric with every time step, once
}

TEST(JsonManifest, ListOfSketchesTimesMatrix) {
  const fs::path dir = manifest_dir("json_sketch_list");
  const auto jobs = parse_json_manifest(R"({"format": "sketchdrape-batch/1", "jobs": [
      {"sketch": ["sketches/dress.json", "sketches/skirt.json"],
       "matrix": {"/fabric": ["a", "b", "c"]}}]})",
                                        "m.json", dir);
  EXPECT_EQ(jobs.size(), 6u);
  EXPECT_EQ(std::count_if(jobs.begin(), jobs.end(),
                          [](const BatchJob& j) { return j.sketch.filename() == "skirt.json"; }),
            3);
}

TEST(JsonManifest, RelativeFileOverridesResolveAgainstTheManifest) {
  const fs::path dir = manifest_dir("json_paths");
  const auto jobs = parse_json_manifest(R"({"format": "sketchdrape-batch/1", "jobs": [
      {"sketch": "sketches/dress.json", "set": {"/body/mesh": "bodies/tall.obj"}},
      {"sketch": "sketches/dress.json", "overrides": {"body": "builtin", "garment_mesh": "/abs/g.obj"}}]})",
                                        "m.json", dir);
  EXPECT_EQ(jobs[0].overrides["body"]["mesh"], (dir / "bodies" / "tall.obj").string());
  EXPECT_EQ(jobs[1].overrides["body"], "builtin");
  EXPECT_EQ(jobs[1].overrides["garment_mesh"], "/abs/g.obj");
}

// Trial 43 P10: a fabric file in an override (a matrix value here) resolves against the
// manifest's folder like a body; presets stay names.
TEST(JsonManifest, RelativeFabricFileOverridesResolveAgainstTheManifest) {
  const fs::path dir = manifest_dir("json_fabric_paths");
  const auto jobs = parse_json_manifest(R"({"format": "sketchdrape-batch/1", "jobs": [
      {"sketch": "sketches/dress.json",
       "matrix": {"/fabric": ["denim", "fabrics/viscose.json", "/abs/silk.json"]}}]})",
                                        "m.json", dir);
  std::set<std::string> fabrics;
  for (const BatchJob& j : jobs) fabrics.insert(j.overrides["fabric"].get<std::string>());
  EXPECT_EQ(fabrics, (std::set<std::string>{"denim", (dir / "fabrics" / "viscose.json").string(),
                                            "/abs/silk.json"}));
}

TEST(JsonManifest, ErrorsNameTheFileThePathAndWhatIsWrong) {
  const fs::path dir = manifest_dir("json_errors");
  auto parse = [&](const std::string& text) {
    return error_of([&] { parse_json_manifest(text, "m.json", dir); });
  };
  EXPECT_EQ(parse(R"({"format": "sketchdrape-batch/1", "jobs": [{"sketch": "nope.json"}]})")
                .find("m.json: /jobs/0/sketch: there is no sketch file 'nope.json'"),
            0u);
  EXPECT_NE(parse(R"({"format": "sketchdrape-batch/1", "jobs": [{"sketch": "sketches/dress.json",
              "matrix": {"/fabric": "denim"}}]})")
                .find("m.json: /jobs/0/matrix/~1fabric: expected a non-empty list"),
            std::string::npos);
  EXPECT_NE(parse(R"({"format": "sketchdrape-batch/1", "jobs": [{"sketch": "sketches/dress.json",
              "set": {"/output/images/0": 1}}]})")
                .find("m.json: /jobs/0/set/~1output~1images~10: the pointer '/output/images/0' "
                      "indexes into a list"),
            std::string::npos);
  EXPECT_NE(parse(R"({"format": "sketchdrape-batch/1", "jobs": [{"sketch": "sketches/dress.json",
              "id": "x", "matrix": {"/fabric": ["a", "b"]}}]})")
                .find("/jobs/0/id: this row makes 2 jobs"),
            std::string::npos);
  EXPECT_NE(parse(R"({"format": "sketchdrape-batch/1", "jobs": [{"sketch": "sketches/dress.json",
              "overides": {}}]})")
                .find("/jobs/0/overides: unknown key 'overides'"),
            std::string::npos);
  EXPECT_NE(parse(R"({"format": "sketchdrape-batch/1", "jobs": [{"sketch": "sketches/dress.json",
              "id": "../escape"}]})")
                .find("cannot be a folder name"),
            std::string::npos);
  EXPECT_NE(
      parse(R"({"format": "sketchdrape-batch/1", "jobs": []})").find("/jobs: a manifest needs"),
      std::string::npos);
  EXPECT_NE(parse("{ not json").find("m.json: the file is not valid JSON"), std::string::npos);
}

TEST(CsvManifest, PointerColumnsJsonCellsQuotingAndComments) {
  const fs::path dir = manifest_dir("csv");
  const std::string text =
      "# fabrics and sizes\n"
      "sketch,id,/fabric,/body/height,/output/images\r\n"
      "sketches/dress.json,,denim,1.62,\n"
      "sketches/dress.json,tall-one,\"silk, washed\",1.80,\"[{\"\"view\"\": \"\"front\"\"}]\"\n"
      "\n"
      "sketches/skirt.json,,true,,\n";
  const auto jobs = parse_csv_manifest(text, "m.csv", dir);
  ASSERT_EQ(jobs.size(), 3u);
  EXPECT_EQ(jobs[0].overrides, json::parse(R"({"fabric": "denim", "body": {"height": 1.62}})"));
  EXPECT_EQ(jobs[0].origin, "m.csv:3");
  EXPECT_EQ(jobs[1].id, "tall-one");
  EXPECT_EQ(jobs[1].overrides["fabric"], "silk, washed");
  EXPECT_EQ(jobs[1].overrides["output"]["images"][0]["view"], "front");
  EXPECT_EQ(jobs[2].overrides, json::parse(R"({"fabric": true})"));  // JSON when it parses
  EXPECT_EQ(jobs[2].origin, "m.csv:6");
}

TEST(CsvManifest, ErrorsNameLineAndColumn) {
  const fs::path dir = manifest_dir("csv_errors");
  auto parse = [&](const std::string& text) {
    return error_of([&] { parse_csv_manifest(text, "m.csv", dir); });
  };
  EXPECT_NE(parse("fabric,sketch\nx,sketches/dress.json\n")
                .find("m.csv: line 1, column 1: 'fabric' is not a column name"),
            std::string::npos);
  EXPECT_NE(parse("/fabric\ndenim\n").find("needs a 'sketch' column"), std::string::npos);
  EXPECT_NE(parse("sketch,/fabric\nsketches/dress.json\n")
                .find("m.csv: line 2: 1 fields, but the header has 2"),
            std::string::npos);
  EXPECT_NE(parse("sketch,/fabric\nsketches/none.json,x\n")
                .find("line 2, column sketch: there is no sketch file"),
            std::string::npos);
  EXPECT_NE(parse("sketch,/fabric\nsketches/dress.json,\"open\n").find("not closed"),
            std::string::npos);
  EXPECT_NE(parse("sketch,/list/3\n").find("indexes into a list"), std::string::npos);
  EXPECT_NE(parse("sketch\n").find("no jobs"), std::string::npos);
}

// A manifest named as a job's sketch (the manifest itself, another JSON manifest, a CSV one) is
// refused where it is named; it had run as a job that failed with "sketch.json: /jobs: unknown
// key 'jobs' (did you mean 'join'?)".
TEST(JsonManifest, AManifestIsNotASketch) {
  const fs::path dir = manifest_dir("manifest_as_sketch");
  const std::string self = R"({"format": "sketchdrape-batch/1", "jobs": ["self.json"]})";
  test::write_text(dir / "self.json", self);
  test::write_text(dir / "other.json",
                   R"({"format": "sketchdrape-batch/1", "jobs": ["sketches/dress.json"]})");
  test::write_text(dir / "rows.csv", "sketch\nsketches/dress.json\n");
  EXPECT_EQ(error_of([&] { parse_json_manifest(self, "self.json", dir); }),
            "self.json: /jobs/0: 'self.json' is a batch manifest, not a sketch file; a manifest's "
            "jobs name sketch files (give another manifest to batch as an input of its own)");
  EXPECT_NE(error_of([&] {
              parse_json_manifest(
                  R"({"format": "sketchdrape-batch/1", "jobs": [{"sketch": ["sketches/dress.json",
                  "other.json"]}]})",
                  "m.json", dir);
            }).find("'other.json' is a batch manifest, not a sketch file"),
            std::string::npos);
  EXPECT_NE(error_of([&] {
              parse_csv_manifest("sketch\nrows.csv\n", "m.csv", dir);
            }).find("m.csv: line 2, column sketch: 'rows.csv' is a CSV manifest"),
            std::string::npos);
}

BatchJob job(const std::string& sketch, const json& overrides) {
  return {"", fs::path("/data") / sketch, overrides, "test", overrides};
}

TEST(JobIds, ReadableDeterministicAndSanitised) {
  EXPECT_EQ(generated_job_id(job("dress.json", json::object())), "dress");
  EXPECT_EQ(generated_job_id(
                job("dress.json", json::parse(R"({"fabric": "denim", "body": {"height": 1.7}})"))),
            "dress_height=1.7_fabric=denim");
  EXPECT_EQ(generated_job_id(
                job("dress.json", json::parse(R"({"body": {"mesh": "/bodies/tall woman.obj"}})"))),
            "dress_mesh=tall-woman");
  const std::string with_list = generated_job_id(
      job("dress.json", json::parse(R"({"output": {"images": [{"view": "left"}]}})")));
  EXPECT_EQ(with_list.rfind("dress_images=", 0), 0u);
  EXPECT_EQ(with_list.size(),
            std::string("dress_images=").size() + 6);  // a short digest of the list
  const std::string longer = generated_job_id(
      job("dress.json",
          json::parse(
              R"({"fabric": "a-very-long-fabric-name-that-goes-on-and-on", "offset": 0.0123456789,
          "edge_length": 0.0123456789, "junction_tolerance": 0.0123456789})")));
  EXPECT_LE(longer.size(), 80u);
  EXPECT_GT(longer.size(), 70u);
  EXPECT_EQ(
      longer,
      generated_job_id(job(
          "dress.json",
          json::parse(
              R"({"fabric": "a-very-long-fabric-name-that-goes-on-and-on", "offset": 0.0123456789,
          "edge_length": 0.0123456789, "junction_tolerance": 0.0123456789})"))));
}

TEST(JobIds, CollisionsGetDigestsDuplicatesAndClashingExplicitIdsAreErrors) {
  // Two sketches with the same stem in different folders.
  std::vector<BatchJob> jobs = {job("a/dress.json", json::object()),
                                job("b/dress.json", json::object()),
                                job("skirt.json", json::object())};
  assign_job_ids(jobs);
  EXPECT_EQ(jobs[2].id, "skirt");
  EXPECT_NE(jobs[0].id, jobs[1].id);
  EXPECT_EQ(jobs[0].id.rfind("dress-", 0), 0u);
  EXPECT_TRUE(std::is_sorted(jobs.begin(), jobs.end(),
                             [](const BatchJob& a, const BatchJob& b) { return a.id < b.id; }));

  std::vector<BatchJob> same = {job("dress.json", json::object()),
                                job("dress.json", json::object())};
  EXPECT_NE(error_of([&] { assign_job_ids(same); }).find("is the same as the one at"),
            std::string::npos);

  std::vector<BatchJob> clash = {job("dress.json", json::object()),
                                 job("skirt.json", json::object())};
  clash[0].id = clash[1].id = "mine";
  EXPECT_NE(error_of([&] { assign_job_ids(clash); }).find("the job id 'mine' is also used"),
            std::string::npos);
}

TEST(Shards, EverySliceTogetherCoversEachJobExactlyOnce) {
  std::vector<BatchJob> jobs;
  for (int i = 0; i < 23; ++i) jobs.push_back(job("dress.json", json{{"offset", i}}));
  assign_job_ids(jobs);
  for (int n : {1, 2, 3, 5, 23, 40}) {
    std::multiset<std::string> seen;
    size_t largest = 0, smallest = jobs.size();
    for (int i = 1; i <= n; ++i) {
      const auto slice = shard_slice(jobs, i, n);
      largest = std::max(largest, slice.size());
      smallest = std::min(smallest, slice.size());
      for (const BatchJob& j : slice) seen.insert(j.id);
    }
    EXPECT_EQ(seen.size(), jobs.size()) << n;
    for (const BatchJob& j : jobs) EXPECT_EQ(seen.count(j.id), 1u) << n;
    EXPECT_LE(largest - smallest, 1u) << "round robin keeps slices within one job of each other";
  }
  // Round robin by position in the sorted list.
  const auto second_of_three = shard_slice(jobs, 2, 3);
  EXPECT_EQ(second_of_three[0].id, jobs[1].id);
  EXPECT_EQ(second_of_three[1].id, jobs[4].id);
  EXPECT_THROW(shard_slice(jobs, 0, 3), std::invalid_argument);
  EXPECT_THROW(shard_slice(jobs, 4, 3), std::invalid_argument);
}

TEST(Shards, ParseShard) {
  EXPECT_EQ(parse_shard("2/3"), std::make_pair(2, 3));
  EXPECT_EQ(parse_shard("1/1"), std::make_pair(1, 1));
  for (const char* bad : {"0/3", "4/3", "3", "a/b", "1/0", "1/3x", "/3", ""})
    EXPECT_THROW(parse_shard(bad), std::invalid_argument) << bad;
}

TEST(LoadBatchJobs, SketchFilesAndManifestsTogetherSortedById) {
  const fs::path dir = manifest_dir("load");
  test::write_text(dir / "m.json", R"({"format": "sketchdrape-batch/1", "jobs": [
      {"sketch": "sketches/dress.json", "matrix": {"/fabric": ["denim", "silk"]}}]})");
  test::write_text(dir / "m.csv", "sketch,/edge_length\nsketches/skirt.json,0.05\n");
  const auto jobs = load_batch_jobs({(dir / "sketches" / "skirt.json").string(),
                                     (dir / "m.json").string(), (dir / "m.csv").string()});
  std::vector<std::string> ids;
  for (const BatchJob& j : jobs) ids.push_back(j.id);
  EXPECT_EQ(ids, (std::vector<std::string>{"dress_fabric=denim", "dress_fabric=silk", "skirt",
                                           "skirt_edge_length=0.05"}));
  EXPECT_NE(error_of([&] {
              load_batch_jobs({(dir / "nothing.json").string()});
            }).find("there is no such file"),
            std::string::npos);
}

// Trial 42, P8: the manifest of docs/batch.md without its "format" line was run as a sketch whose
// job failed with "sketch.json: /jobs: unknown key 'jobs' (did you mean 'join'?)". It is a bad
// manifest (exit code 2, nothing runs), named as such.
TEST(LoadBatchJobs, AManifestWithoutItsFormatIsABadManifest) {
  const fs::path dir = manifest_dir("no-format");
  test::write_text(dir / "noformat.json", R"({"jobs": ["sketches/dress.json"]})");
  const std::string input = (dir / "noformat.json").string();
  EXPECT_EQ(error_of([&] { load_batch_jobs({input}); }),
            input +
                ": it has \"jobs\" like a batch manifest but no \"format\": "
                "\"sketchdrape-batch/1\"");
  test::write_text(dir / "wrong.json",
                   R"({"format": "sketchdrape/1", "jobs": ["sketches/dress.json"]})");
  const std::string wrong = (dir / "wrong.json").string();
  EXPECT_EQ(error_of([&] { load_batch_jobs({wrong}); }),
            wrong +
                ": it has \"jobs\" like a batch manifest but its \"format\" is "
                "\"sketchdrape/1\", not \"sketchdrape-batch/1\"");
}

}  // namespace
}  // namespace sd::app
