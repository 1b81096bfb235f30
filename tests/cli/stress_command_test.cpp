// `sketchdrape stress` end to end: the reduced matrix holds (every case finite, within its
// bounds, the NaN starts refused), its JSON is complete, and a case made impossible (no step
// halving allowed under 100 g) makes the command fail — so this test can fail.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

#include "tests/cli/run_command.hpp"

namespace sd::test {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

fs::path fresh_dir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("sd_stress_test_" + std::to_string(::getpid())) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

json read_json(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return json::parse(s.str());
}

TEST(StressCommand, QuickMatrixHoldsAndItsJsonListsEveryCaseFinite) {
  const fs::path dir = fresh_dir("quick");
  const CommandResult list = run_sketchdrape("stress --quick --list");
  ASSERT_EQ(list.exit_code, 0) << list.output;
  const long listed = std::count(list.output.begin(), list.output.end(), '\n');

  const CommandResult r = run_sketchdrape("stress --quick -o '" + dir.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json report = read_json(dir / "stress.json");
  EXPECT_EQ(report["format"], "sketchdrape/1 stress report");
  EXPECT_EQ(report["matrix"], "quick");
  EXPECT_TRUE(report["diverged"].empty()) << report["diverged"].dump();
  ASSERT_EQ(static_cast<long>(report["cases"].size()), listed);

  std::set<std::string> families;
  for (const json& c : report["cases"]) {
    const std::string id = c["id"];
    families.insert(c["family"].get<std::string>());
    EXPECT_NE(r.output.find(id), std::string::npos) << "the table lists " << id;
    EXPECT_TRUE(c["ok"].get<bool>()) << id << ": " << c["reason"];
    EXPECT_TRUE(c["finite"].get<bool>()) << id;
    if (c["family"] == "nan") {
      // A non-finite start is refused with a sentence, never simulated.
      EXPECT_EQ(c["status"], "rejected") << id;
      EXPECT_EQ(c["steps"], 0) << id;
      EXPECT_FALSE(c["reason"].get<std::string>().empty()) << id;
      continue;
    }
    EXPECT_EQ(c["status"], "stable") << id << ": " << c["reason"];
    EXPECT_TRUE(c["ran_to_end"].get<bool>()) << id;
    EXPECT_GT(c["steps"].get<int>(), 0) << id;
    EXPECT_TRUE(c["at_rest"].get<bool>() ||
                std::abs(c["sim_time"].get<double>() - c["duration"].get<double>()) < 1e-9)
        << id;
    EXPECT_LE(c["max_strain"].get<double>(), c["strain_bound"].get<double>()) << id;
    EXPECT_LE(c["max_speed"].get<double>(), c["speed_bound"].get<double>()) << id;
    EXPECT_LE(c["energy_final_growth_j"].get<double>(), c["energy_bound_j"].get<double>()) << id;
    EXPECT_GE(c["energy_peak_growth_j"].get<double>(), c["energy_final_growth_j"].get<double>())
        << id;
    EXPECT_GT(c["energy_scale_j"].get<double>(), 0.0) << id;
    EXPECT_GE(c["dt_min_used"].get<double>(), c["min_dt"].get<double>() * (1 - 1e-12)) << id;
    EXPECT_LE(c["dt_min_used"].get<double>(), c["dt"].get<double>() * (1 + 1e-12)) << id;
    EXPECT_GE(c["attempts"].get<int>(), c["steps"].get<int>() + c["retries"].get<int>()) << id;
    // Forced churn changes the mesh before every step; tiny thresholds on some of them.
    if (c["parameters"].value("churn", "") == "forced") {
      EXPECT_EQ(c["topology_changes"].get<int>(), c["steps"].get<int>()) << id;
    }
    if (c["family"] == "churn") {
      EXPECT_GT(c["topology_changes"].get<int>(), 0) << id;
    }
    if (c["family"] == "body") {
      EXPECT_GT(c["contacts_max"].get<int>(), 0) << id;
    }
    if (c["family"] == "self-contact") {
      EXPECT_EQ(c["self_intersections_final"].get<int>(), 0) << id;
    }
  }
  // Every family but `sliver`, whose cases all diverge today (docs/stress.md).
  EXPECT_EQ(families, (std::set<std::string>{"stiffness", "undamped", "churn", "body", "pins",
                                             "gravity", "nan", "stretch", "self-contact"}));
}

// 100 g with a 1/10 s step: the first step's free fall alone (98 m/s) breaks the 50 m/s speed
// limit, and with the minimum step raised to the step itself step control cannot halve.
TEST(StressCommand, ImpossibleCaseMakesItExitNonZero) {
  const fs::path dir = fresh_dir("impossible");
  const std::string id = "gravity-x100-h1/10-ie-cholmod";
  const CommandResult r =
      run_sketchdrape("stress --case " + id + " --min-dt 1 -o '" + dir.string() + "'");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("diverged or failed: " + id), std::string::npos) << r.output;
  const json report = read_json(dir / "stress.json");
  ASSERT_EQ(report["cases"].size(), 1u);
  const json& c = report["cases"][0];
  EXPECT_EQ(c["id"], id);
  EXPECT_FALSE(c["ok"].get<bool>());
  EXPECT_EQ(c["status"], "failed");
  EXPECT_FALSE(c["ran_to_end"].get<bool>());
  EXPECT_TRUE(c["finite"].get<bool>()) << "the state is left at the last good step";
  EXPECT_NE(c["reason"].get<std::string>().find("m/s"), std::string::npos) << c["reason"];
  EXPECT_EQ(report["diverged"], json::array({id}));

  // The same case with step control free to halve holds: the failure above is the option's.
  const CommandResult normal = run_sketchdrape("stress --case " + id + " --json");
  EXPECT_EQ(normal.exit_code, 0) << normal.output;
}

TEST(StressCommand, BadOptionsExitTwo) {
  EXPECT_EQ(run_sketchdrape("stress --case no-such-case").exit_code, 2);
  EXPECT_EQ(run_sketchdrape("stress --quick --min-dt -1").exit_code, 2);
  EXPECT_EQ(run_sketchdrape("stress --quick --json -o /tmp/x").exit_code, 2);
  const CommandResult message = run_sketchdrape("stress --case no-such-case");
  EXPECT_NE(message.output.find("--list"), std::string::npos) << message.output;
}

}  // namespace
}  // namespace sd::test
