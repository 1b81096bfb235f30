// `sketchdrape bench` as a user runs it, on the tiny grid (seconds): the CSV has every run and
// the promised columns, the error falls with resolution and with the step, the reference is
// computed once and then read from the cache (and recomputed when the scene changes), plots are
// written when gnuplot is installed. Also the error definition and the trace format directly.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "src/app/bench/bench_scaling.hpp"
#include "src/app/bench/bench_study.hpp"
#include "src/app/bench/bench_textile.hpp"
#include "tests/cli/run_command.hpp"

namespace {

namespace fs = std::filesystem;
using sd::test::run_sketchdrape;

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / "sd_bench_test" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

nlohmann::json read_json(const fs::path& path) {
  return nlohmann::json::parse(read_text(path));
}

// CSV with quoted fields ("a, b" and "" escapes), one vector per line.
std::vector<std::vector<std::string>> parse_csv(const std::string& text) {
  std::vector<std::vector<std::string>> rows(1);
  std::string field;
  bool quoted = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
        field += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        field += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      rows.back().push_back(field);
      field.clear();
    } else if (c == '\n') {
      rows.back().push_back(field);
      field.clear();
      rows.emplace_back();
    } else {
      field += c;
    }
  }
  if (rows.back().empty()) rows.pop_back();
  return rows;
}

// The CSV as maps from column name to value, one per run id (scene/run).
std::map<std::string, std::map<std::string, std::string>> csv_by_run(const fs::path& path) {
  const auto rows = parse_csv(read_text(path));
  std::map<std::string, std::map<std::string, std::string>> out;
  for (size_t r = 1; r < rows.size(); ++r) {
    std::map<std::string, std::string> row;
    for (size_t c = 0; c < rows[0].size() && c < rows[r].size(); ++c) row[rows[0][c]] = rows[r][c];
    out[row["scene"] + "/" + (row["note"].rfind("reference", 0) == 0 ? "reference" : row["run"])] =
        row;
  }
  return out;
}

double rms(const std::map<std::string, std::map<std::string, std::string>>& runs,
           const std::string& id) {
  const auto it = runs.find("hanging-sheet/" + id);
  if (it == runs.end()) {
    ADD_FAILURE() << "no row " << id;
    return NAN;
  }
  EXPECT_EQ(it->second.at("status"), "ok") << id << ": " << it->second.at("note");
  return std::stod(it->second.at("rms_error_m"));
}

bool has_gnuplot() {
  return std::system("command -v gnuplot >/dev/null 2>&1") == 0;
}

const std::vector<std::string> kColumns = {"scene",
                                           "run",
                                           "mesh",
                                           "level",
                                           "threshold_mm",
                                           "integrator",
                                           "solver",
                                           "dt_s",
                                           "families",
                                           "status",
                                           "wall_s",
                                           "cpu_s",
                                           "process_cpu_s",
                                           "peak_rss_mb",
                                           "rss_before_run_mb",
                                           "vertices_max",
                                           "triangles_max",
                                           "steps",
                                           "retries",
                                           "linear_solves",
                                           "cg_iterations_mean",
                                           "rms_error_m",
                                           "max_error_m",
                                           "final_rms_error_m",
                                           "energy_error_j",
                                           "energy_error_relative",
                                           "pareto",
                                           "note"};

TEST(BenchCommand, TinyGridMeasuresErrorsAndReusesTheCachedReference) {
  const fs::path dir = fresh_dir("tiny");
  const std::string args =
      "-q bench --grid tiny -o " + (dir / "out").string() + " --cache " + (dir / "cache").string();
  const auto first = run_sketchdrape(args);
  ASSERT_EQ(first.exit_code, 0) << first.output;

  // Every run and the reference, with the promised columns.
  const auto rows = parse_csv(read_text(dir / "out/bench.csv"));
  ASSERT_FALSE(rows.empty());
  EXPECT_EQ(rows[0], kColumns);
  const sd::app::BenchScene scene =
      sd::app::build_bench_scene("hanging-sheet", sd::app::BenchGrid::tiny);
  const sd::app::BenchPlan plan = sd::app::bench_plan(scene, sd::app::BenchGrid::tiny);
  EXPECT_EQ(rows.size(), plan.runs.size() + 2);  // header + reference + runs
  for (size_t r = 1; r < rows.size(); ++r) EXPECT_EQ(rows[r].size(), kColumns.size()) << r;
  auto runs = csv_by_run(dir / "out/bench.csv");
  for (const sd::app::BenchConfig& c : plan.runs) {
    const auto& row = runs["hanging-sheet/" + c.id()];
    EXPECT_EQ(row.at("status"), "ok") << c.id() << ": " << row.at("note");
    EXPECT_GT(std::stod(row.at("peak_rss_mb")), 1.0) << c.id();
    EXPECT_GT(std::stod(row.at("cpu_s")), 0.0) << c.id();
    EXPECT_GE(std::stod(row.at("max_error_m")), std::stod(row.at("rms_error_m"))) << c.id();
  }

  // Resolution: level 1 (a quarter of level 3's triangles) against level 3, same step. At 1/60 s
  // the step's error dominates on this falling sheet, so only the order is asserted.
  EXPECT_GT(rms(runs, "fixed-L1-ie-cholmod-60"), rms(runs, "fixed-L3-ie-cholmod-60"));
  // Step: the same mesh at 1/30, 1/60 and 1/120 s.
  EXPECT_GT(rms(runs, "fixed-L3-ie-cholmod-30"), rms(runs, "fixed-L3-ie-cholmod-60"));
  EXPECT_GT(rms(runs, "fixed-L3-ie-cholmod-60"), rms(runs, "fixed-L3-ie-cholmod-120"));
  // PCG solves the same system as CHOLMOD to its tolerance: the same error within 20 %.
  EXPECT_NEAR(rms(runs, "fixed-L3-ie-pcg-60"), rms(runs, "fixed-L3-ie-cholmod-60"),
              0.2 * rms(runs, "fixed-L3-ie-cholmod-60"));

  const nlohmann::json report = read_json(dir / "out/bench.json");
  EXPECT_FALSE(report["scenes"][0]["reference"]["cached"].get<bool>());
  EXPECT_EQ(report["scenes"][0]["runs"].size(), plan.runs.size());
  const std::string key = report["scenes"][0]["reference"]["key"];
  EXPECT_TRUE(fs::exists(dir / "cache" / (key + ".bin")));
  EXPECT_NE(first.output.find("defaults:"), std::string::npos) << first.output;
  // The sketch defaults are run (the automatic rule: a sheet without a body or self-contact gets
  // the IC(0) PCG at 1/20 s, at 1/60 s with --frames) and placed against the front and the error
  // band (1.5x the same mesh's error at 1/60 s with CHOLMOD).
  EXPECT_EQ(runs["hanging-sheet/fixed-L3-ie-pcg-20"].at("status"), "ok");
  EXPECT_EQ(runs["hanging-sheet/fixed-L3-ie-pcg-60"].at("status"), "ok");
  EXPECT_NE(first.output.find("the sketch default (automatic: fixed L3, IE, PCG, 1/20 s"),
            std::string::npos)
      << first.output;
  EXPECT_NE(first.output.find("the default with --frames (automatic: fixed L3, IE, PCG, 1/60 s"),
            std::string::npos)
      << first.output;
  // At 1/60 s the PCG solves to 1e-3 what CHOLMOD solves exactly (the same error within 20 %,
  // below), so the default with --frames is within the band.
  EXPECT_NE(first.output.find("within the error band"), std::string::npos) << first.output;

  if (has_gnuplot()) {
    const std::string png = read_text(dir / "out/bench_hanging-sheet.png");
    ASSERT_GT(png.size(), 1000u);
    EXPECT_EQ(png.substr(1, 3), "PNG");
    EXPECT_NE(read_text(dir / "out/bench_hanging-sheet.svg").find("<svg"), std::string::npos);
    EXPECT_TRUE(report["plots"].get<bool>());
  } else {
    EXPECT_FALSE(fs::exists(dir / "out/bench_hanging-sheet.png"));
    EXPECT_NE(first.output.find("gnuplot is not installed"), std::string::npos);
  }

  // Second run: the reference comes from the cache, and the errors are the same to the bit.
  const auto second = run_sketchdrape(args);
  ASSERT_EQ(second.exit_code, 0) << second.output;
  const nlohmann::json again = read_json(dir / "out/bench.json");
  EXPECT_TRUE(again["scenes"][0]["reference"]["cached"].get<bool>());
  EXPECT_EQ(again["scenes"][0]["reference"]["key"], key);
  const auto runs_again = csv_by_run(dir / "out/bench.csv");
  EXPECT_EQ(runs_again.at("hanging-sheet/reference").at("note"), "reference (cached)");
  for (const sd::app::BenchConfig& c : plan.runs)
    EXPECT_EQ(runs_again.at("hanging-sheet/" + c.id()).at("rms_error_m"),
              runs.at("hanging-sheet/" + c.id()).at("rms_error_m"))
        << c.id();
  if (!HasFailure()) fs::remove_all(dir);
}

nlohmann::json sheet_sketch(const std::string& fabric) {
  return {{"format", "sketchdrape/1"},
          {"sheet",
           {{"size", {0.5, 0.5}},
            {"resolution", {6, 6}},
            {"orientation", "horizontal"},
            {"pins", {"top-left", "top-right"}}}},
          {"fabric", fabric},
          {"simulate", {{"duration", 0.3}}}};
}

TEST(BenchCommand, SketchSceneReferenceIsRecomputedWhenTheSceneChanges) {
  const fs::path dir = fresh_dir("sketch");
  const fs::path sketch = dir / "sheet.json";
  std::ofstream(sketch) << sheet_sketch("cotton").dump(2);
  const std::string args = "-q bench --grid tiny --scene " + sketch.string() + " -o " +
                           (dir / "out").string() + " --cache " + (dir / "cache").string() +
                           " --json";
  const auto cached_flag = [&] {
    const auto result = run_sketchdrape(args);
    EXPECT_EQ(result.exit_code, 0) << result.output;
    const nlohmann::json printed = nlohmann::json::parse(result.output);  // --json: only JSON
    EXPECT_EQ(printed["scenes"][0]["name"], "sheet");
    EXPECT_EQ(printed["scenes"][0]["duration_s"], 0.3);  // the file's duration, under the grid's
    return printed["scenes"][0]["reference"]["cached"].get<bool>();
  };
  EXPECT_FALSE(cached_flag());
  EXPECT_TRUE(cached_flag());
  std::ofstream(sketch) << sheet_sketch("denim").dump(2);  // another fabric: another reference
  EXPECT_FALSE(cached_flag());
  EXPECT_TRUE(cached_flag());
  int cached_files = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir / "cache")) ++cached_files;
  EXPECT_EQ(cached_files, 2);
  if (!HasFailure()) fs::remove_all(dir);
}

TEST(BenchCommand, BadInputExitsWithTwoAndWritesNothing) {
  const fs::path dir = fresh_dir("bad");
  const auto unknown =
      run_sketchdrape("bench --grid tiny --scene no-such-scene -o " + (dir / "out").string());
  EXPECT_EQ(unknown.exit_code, 2) << unknown.output;
  EXPECT_NE(unknown.output.find("unknown scene 'no-such-scene'"), std::string::npos)
      << unknown.output;
  const auto grid = run_sketchdrape("bench --grid huge -o " + (dir / "out").string());
  EXPECT_EQ(grid.exit_code, 2) << grid.output;
  EXPECT_NE(grid.output.find("--grid must be tiny, quick or full"), std::string::npos)
      << grid.output;
  const auto both = run_sketchdrape("bench --quick --grid full -o " + (dir / "out").string());
  EXPECT_EQ(both.exit_code, 2) << both.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

// The error definition on hand-made traces: a rigid shift by d gives RMS = max = d, and the
// energy difference is measured against the reference's range.
TEST(BenchError, ShiftedTraceHasTheShiftAsError) {
  sd::app::BenchTrace reference;
  for (int s = 0; s < 4; ++s) {
    reference.times.push_back(0.1 * s);
    reference.positions.push_back(Eigen::MatrixX3d::Random(50, 3));
    reference.energy.push_back(10.0 - s);  // range 3 J
  }
  EXPECT_EQ(sd::app::bench_error(reference, reference).rms_m, 0.0);
  sd::app::BenchTrace run = reference;
  for (size_t s = 1; s < run.positions.size(); ++s) {
    run.positions[s].col(1).array() += 0.004 * static_cast<double>(s);  // 4, 8, 12 mm
    run.energy[s] += 0.3;
  }
  const sd::app::BenchError e = sd::app::bench_error(run, reference);
  EXPECT_EQ(e.samples, 3);
  EXPECT_NEAR(e.rms_m, std::sqrt((16.0 + 64.0 + 144.0) / 3.0) * 1e-3, 1e-12);
  EXPECT_NEAR(e.max_m, 0.012, 1e-12);
  EXPECT_NEAR(e.final_rms_m, 0.012, 1e-12);
  EXPECT_NEAR(e.energy_j, 0.3, 1e-12);
  EXPECT_NEAR(e.energy_relative, 0.1, 1e-12);

  // The trace survives its binary form exactly.
  run.failed = false;
  run.cpu_s = 1.25;
  run.steps = 17;
  const sd::app::BenchTrace back = sd::app::deserialize_trace(sd::app::serialize_trace(run));
  ASSERT_EQ(back.positions.size(), run.positions.size());
  for (size_t s = 0; s < run.positions.size(); ++s) EXPECT_EQ(back.positions[s], run.positions[s]);
  EXPECT_EQ(back.energy, run.energy);
  EXPECT_EQ(back.cpu_s, 1.25);
  EXPECT_EQ(back.steps, 17);
  EXPECT_THROW(sd::app::deserialize_trace("not a trace"), std::runtime_error);
}

// `bench --scaling` on small sheets: every size runs in its own child, the CSV, table and JSON
// agree, the vertex counts are (N+1)², and each point's time is its report's.
TEST(BenchScaling, SmallSheetsGiveEveryPointAndAFit) {
  const fs::path dir = fresh_dir("scaling");
  const auto result =
      run_sketchdrape("bench --scaling --sizes 4 8 --steps 2 --json -o " + (dir / "out").string());
  ASSERT_EQ(result.exit_code, 0) << result.output;
  for (const char* name : {"scaling.csv", "scaling.md", "scaling.json"})
    EXPECT_TRUE(fs::exists(dir / "out" / name)) << name;
  const nlohmann::json json = read_json(dir / "out" / "scaling.json");
  ASSERT_EQ(json.at("points").size(), 6u);  // 2 sizes × 3 solvers
  for (const auto& p : json.at("points")) {
    const int n = p.at("quads_per_side").get<int>();
    EXPECT_EQ(p.at("vertices").get<int>(), (n + 1) * (n + 1));
    EXPECT_EQ(p.at("status"), "ok") << p.dump();
    EXPECT_EQ(p.at("steps").get<int>(), 2);
    EXPECT_GT(p.at("step_s").get<double>(), 0.0);
    // CPU per step: the run's CPU less a one-step run's, over the extra step. On sheets this
    // small it is within the noise of process start-up (it can come out negative), so only its
    // presence and scale are checked here; the fit skips points that are not positive.
    EXPECT_LT(std::abs(p.at("cpu_step_s").get<double>()), 1.0);
    EXPECT_GT(p.at("peak_rss_mb").get<double>(), 1.0);
  }
  ASSERT_EQ(json.at("fits").size(), 3u);
  for (const auto& f : json.at("fits")) {
    int positive = 0;
    for (const auto& p : json.at("points"))
      positive += p.at("solver") == f.at("solver") && p.at("cpu_step_s").get<double>() > 0.0;
    EXPECT_EQ(f.at("points").get<int>(), positive);
    EXPECT_TRUE(std::isfinite(f.at("exponent").get<double>()));
  }
  const auto rows = parse_csv(read_text(dir / "out" / "scaling.csv"));
  EXPECT_EQ(rows.front().front(), "quads_per_side");
}

TEST(BenchScaling, BadSizesAndSolversAreRefusedBeforeAnyRun) {
  const fs::path dir = fresh_dir("scaling-bad");
  for (const std::string args : {"--sizes 1", "--sizes 4 5000", "--solver lu", "--steps 1"}) {
    const auto result =
        run_sketchdrape("bench --scaling " + args + " -o " + (dir / "out").string());
    EXPECT_EQ(result.exit_code, 2) << args << "\n" << result.output;
    EXPECT_FALSE(fs::exists(dir / "out")) << args;
  }
}

// `bench --textile` on denim, coarse (seconds): every point is written; the cantilever's
// bending length from Peirce's formula is near the predicted one (16 cells: chord within 1.5° of
// 41.5°, c within 3 %), the drape (two dynamic specimens) lies between hanging and flat. A name
// that is not a preset is refused before any run.
TEST(BenchTextile, DenimCantileverAndDrapeAreWrittenWithTheirMeasures) {
  const fs::path dir = fresh_dir("textile");
  const auto result = run_sketchdrape(
      "bench --textile --fabric denim --cantilever-cells 8 16 --cusick-cells 12 "
      "--cusick-specimens 2 --json -o " +
      (dir / "out").string());
  ASSERT_EQ(result.exit_code, 0) << result.output;
  for (const char* name :
       {"textile.md", "textile.json", "textile-cantilever.csv", "textile-cusick.csv", "textile.gp"})
    EXPECT_TRUE(fs::exists(dir / "out" / name)) << name;
  const nlohmann::json json = read_json(dir / "out" / "textile.json");
  ASSERT_EQ(json.at("cantilever").size(), 2u);
  const auto& fine = json.at("cantilever").at(1);
  EXPECT_EQ(fine.at("cells").get<int>(), 16);
  EXPECT_NEAR(fine.at("predicted_c_m").get<double>(), 0.0292, 2e-4);
  EXPECT_NEAR(fine.at("chord_deg").get<double>(), 41.5, 1.5);
  EXPECT_NEAR(fine.at("simulated_c_m").get<double>() / fine.at("predicted_c_m").get<double>(), 1.0,
              0.03);
  ASSERT_EQ(json.at("cusick").size(), 1u);
  const auto& drape = json.at("cusick").at(0);
  const double dc = drape.at("drape_coefficient").get<double>();
  EXPECT_GT(dc, 0.0);
  EXPECT_LT(dc, 1.0);
  // The mean of two dynamic drapes (each from its own random lift), both at rest, within their
  // range.
  EXPECT_EQ(drape.at("specimens").get<int>(), 2);
  EXPECT_TRUE(drape.at("converged").get<bool>());
  EXPECT_LE(drape.at("drape_coefficient_min").get<double>(), dc);
  EXPECT_GE(drape.at("drape_coefficient_max").get<double>(), dc);
  const auto bad = run_sketchdrape("bench --textile --fabric tweed -o " + (dir / "bad").string());
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_FALSE(fs::exists(dir / "bad"));
}

// `--fabric` also takes a fabric file (docs/fabrics.md): a copy of the denim preset with half its
// bending rigidity measures as such (c = (B/ρg)^(1/3) is 2^(-1/3) of denim's), named by its
// "name" and path;
// a file that is not a valid fabric exits 2 with the file's error and writes nothing.
TEST(BenchTextile, FabricFilesAreMeasuredLikePresets) {
  const fs::path dir = fresh_dir("textile-file");
  fs::create_directories(dir);
  nlohmann::json denim = read_json(fs::path(SD_SOURCE_DIR) / "data/fabrics/denim.json");
  denim["bend"]["value"] = 0.5 * denim["bend"]["value"].get<double>();
  denim["name"] = "soft-denim";
  const fs::path soft = dir / "soft-denim.json";
  std::ofstream(soft) << denim.dump(1);
  const auto result = run_sketchdrape("bench --textile --fabric " + soft.string() +
                                      " --cantilever-cells 8 --cusick-cells 8 "
                                      "--cusick-specimens 1 --json -o " +
                                      (dir / "out").string());
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const nlohmann::json json = read_json(dir / "out" / "textile.json");
  ASSERT_EQ(json.at("cantilever").size(), 1u);
  const auto& strip = json.at("cantilever").at(0);
  // Named by the file's own "name", the file after it (trial 37).
  EXPECT_EQ(strip.at("fabric").get<std::string>(), "soft-denim (" + soft.string() + ")");
  EXPECT_NEAR(strip.at("predicted_c_m").get<double>(), 0.02924 * std::cbrt(0.5), 2e-4);
  EXPECT_NEAR(strip.at("chord_deg").get<double>(), 41.5, 4.0);  // 8 cells: 42.8° for the presets
  nlohmann::json broken = denim;
  broken["bend"]["unit"] = "furlong";
  const fs::path bad = dir / "broken.json";
  std::ofstream(bad) << broken.dump(1);
  const auto refused =
      run_sketchdrape("bench --textile --fabric " + bad.string() + " -o " + (dir / "bad").string());
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_NE(refused.output.find("/bend must be given in N*m"), std::string::npos) << refused.output;
  EXPECT_FALSE(fs::exists(dir / "bad"));
}

// The membrane options and the specimen's grain are set per study and written with its points:
// `--diamond-membrane on --ghost-points on` appear as the study's "model", each `--cusick-grain`
// angle is its own point (the warp turned against the disc's mesh: denim's warp is 1.7 times as
// stiff as its weft, so the drape differs), each at rest with the time it rested by. A value
// other than on or off exits 2 and writes nothing.
TEST(BenchTextile, MembraneOptionsAndGrainAreWrittenWithEachPoint) {
  const fs::path dir = fresh_dir("textile-options");
  const auto result = run_sketchdrape(
      "bench --textile --fabric denim --cantilever-cells 8 --cusick-cells 10 --cusick-grain 0 45 "
      "--cusick-specimens 1 --diamond-membrane on --ghost-points on --json -o " +
      (dir / "out").string());
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const nlohmann::json json = read_json(dir / "out" / "textile.json");
  EXPECT_TRUE(json.at("model").at("diamond_membrane").get<bool>());
  EXPECT_TRUE(json.at("model").at("clamp_ghost_points").get<bool>());
  ASSERT_EQ(json.at("cusick").size(), 2u);
  for (int k = 0; k < 2; ++k) {
    const auto& drape = json.at("cusick").at(k);
    EXPECT_EQ(drape.at("grain_deg").get<double>(), k == 0 ? 0.0 : 45.0);
    EXPECT_TRUE(drape.at("converged").get<bool>());
    EXPECT_GT(drape.at("rest_time_s").get<double>(), 0.25);  // at least one rest window
    EXPECT_LT(drape.at("rest_time_s").get<double>(), 8.0);
  }
  EXPECT_NE(json.at("cusick").at(0).at("drape_coefficient").get<double>(),
            json.at("cusick").at(1).at("drape_coefficient").get<double>());
  const auto bad = run_sketchdrape("bench --textile --fabric denim --diamond-membrane maybe -o " +
                                   (dir / "bad").string());
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_FALSE(fs::exists(dir / "bad"));
}

// `--cusick-cells-per-c` picks each fabric's Cusick resolutions from its bending length
// c = (B/ρg)^(1/3): the fewest cells across the 30 cm disc that give at least that many cells
// per c (silk, c = 1.493 cm: 41 and 51 for 2 and 2.5; denim, 2.924 cm: 21 and 26). It cannot be
// given with --cusick-cells (exit 2, nothing written).
TEST(BenchTextile, CusickCellsFollowTheBendingLength) {
  for (const std::string& name : sd::sim::fabric_preset_names()) {
    const sd::sim::FabricParameters fabric = sd::app::textile_fabric(name);
    const double c = std::cbrt(fabric.bend / (fabric.area_density * 9.81));
    for (const double per_c : {2.0, 2.5}) {
      const int cells = sd::app::cusick_cells_for(fabric, per_c);
      EXPECT_GE(cells * c / 0.30, per_c) << name;
      EXPECT_LT((cells - 1) * c / 0.30, per_c) << name;
    }
  }
  EXPECT_EQ(sd::app::cusick_cells_for(sd::app::textile_fabric("silk"), 2.0), 41);
  EXPECT_EQ(sd::app::cusick_cells_for(sd::app::textile_fabric("silk"), 2.5), 51);
  EXPECT_EQ(sd::app::cusick_cells_for(sd::app::textile_fabric("denim"), 2.0), 21);
  EXPECT_EQ(sd::app::cusick_cells_for(sd::app::textile_fabric("denim"), 2.5), 26);
  const fs::path dir = fresh_dir("textile-per-c");
  const auto both = run_sketchdrape(
      "bench --textile --fabric denim --cusick-cells 12 --cusick-cells-per-c 2 -o " +
      (dir / "out").string());
  EXPECT_EQ(both.exit_code, 2) << both.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

// 41.5° at overhang l reads c = l/2 (the standard); a stiffer strip (smaller angle) reads a
// longer bending length, as Peirce's formula: c ∝ (cos(θ/2)/tan θ)^(1/3).
TEST(BenchTextile, PeirceBendingLengthAtTheStandardAngleIsHalfTheOverhang) {
  EXPECT_NEAR(sd::app::peirce_bending_length(0.04, 41.5), 0.02, 1e-15);
  const double ratio =
      sd::app::peirce_bending_length(0.04, 30.0) / sd::app::peirce_bending_length(0.04, 41.5);
  const double r = std::numbers::pi / 180;
  EXPECT_NEAR(
      ratio,
      std::cbrt(std::cos(15 * r) / std::tan(30 * r) / (std::cos(20.75 * r) / std::tan(41.5 * r))),
      1e-12);
}

// The fit is ordinary least squares in log-log: exact on a power law.
TEST(BenchScaling, FitRecoversAPowerLawAndTheMemoryPerVertex) {
  std::vector<sd::app::ScalingPoint> points;
  for (int n : {32, 64, 128, 256}) {
    sd::app::ScalingPoint p;
    p.quads_per_side = n;
    p.solver = "pcg";
    p.vertices = (n + 1) * (n + 1);
    p.status = "ok";
    p.steps = 10;
    p.cpu_step_s = 2e-3 * std::pow(p.vertices / 1000.0, 1.25);
    p.peak_rss_mb = 80.0 + 3.0 * p.vertices / 1024.0;  // 3 KB per vertex over 80 MB
    points.push_back(p);
  }
  points.push_back(points.front());
  points.back().solver = "cholmod";  // one point only: no fit
  const sd::app::ScalingFit fit = sd::app::fit_scaling("pcg", points);
  EXPECT_EQ(fit.points, 4);
  EXPECT_NEAR(fit.exponent, 1.25, 1e-12);
  EXPECT_NEAR(fit.coefficient_s, 2e-3, 1e-12);
  EXPECT_NEAR(fit.kb_per_vertex, 3.0, 1e-9);
  EXPECT_NEAR(fit.base_memory_mb, 80.0, 1e-9);
  EXPECT_EQ(sd::app::fit_scaling("cholmod", points).points, 1);
}

}  // namespace
