// sketchdrape run from a clean environment (no OMP_THREAD_LIMIT, no OPENBLAS_NUM_THREADS): the
// program starts once and still runs CHOLMOD's OpenMP loops and OpenBLAS on one thread. And a
// garment drape gives the same bits on one thread as on two.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/cli/run_command.hpp"

namespace sd::test {
namespace {

namespace fs = std::filesystem;

std::string write_sheet(const std::string& name, const std::string& solver) {
  const fs::path dir = fs::temp_directory_path() / "sd_solver_threads_test" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "sheet.json") << R"({"format": "sketchdrape/1",
 "sheet": {"size": [1.0, 1.0], "resolution": [24, 24], "orientation": "horizontal",
           "centre": [0.0, 1.2, 0.0], "pins": ["top-left", "top-right"]},
 "fabric": "cotton",
 "simulate": {"duration": 0.2, "time_step": 0.05, "stop_at_rest": false, "solver": ")"
                                    << solver << R"("},
 "output": {"images": [], "mesh": "drape.obj"}})";
  return dir.string();
}

// The -v line that names what the solver libraries see: had the program set the variables and
// started itself again, it would read them as 1, not unset.
std::string library_line(const std::string& dir) {
  const CommandResult run =
      run_sketchdrape_with_env("env -u OMP_THREAD_LIMIT -u OPENBLAS_NUM_THREADS -u OMP_NUM_THREADS",
                               "run " + dir + "/sheet.json -o " + dir + "/out -v");
  EXPECT_EQ(run.exit_code, 0) << run.output;
  const size_t at = run.output.find("solver libraries:");
  if (at == std::string::npos) return run.output;
  return run.output.substr(at, run.output.find('\n', at) - at);
}

TEST(SolverThreads, CholmodRunStartsOnceWithOneOpenMpAndOneBlasThread) {
  const std::string line = library_line(write_sheet("cholmod", "cholmod"));
  EXPECT_NE(line.find("OMP_THREAD_LIMIT unset, OPENBLAS_NUM_THREADS unset"), std::string::npos)
      << line;
  EXPECT_NE(line.find("asking for 4 threads gets 1,"), std::string::npos) << line;
  // 1 with Debian's OpenBLAS; 0 if the BLAS alternative is another library.
  EXPECT_TRUE(line.find("OpenBLAS runs 1") != std::string::npos ||
              line.find("OpenBLAS runs 0") != std::string::npos)
      << line;
}

TEST(SolverThreads, PcgRunStartsOnce) {
  const std::string line = library_line(write_sheet("pcg", "pcg"));
  EXPECT_NE(line.find("OMP_THREAD_LIMIT unset, OPENBLAS_NUM_THREADS unset"), std::string::npos)
      << line;
}

// A user's OMP_THREAD_LIMIT above 1 without OMP_WAIT_POLICY is warned of (CHOLMOD's OpenMP
// threads would spin while they wait: docs/cli.md, "Threads"); with the policy set, or a limit
// of 1, it is not.
TEST(SolverThreads, AnOpenMpLimitAboveOneWithoutAWaitPolicyIsWarnedOf) {
  const std::string dir = write_sheet("wait_policy", "cholmod");
  const std::string run = "run " + dir + "/sheet.json -o " + dir + "/out";
  const CommandResult spinning = run_sketchdrape_with_env(
      "env -u OMP_WAIT_POLICY -u OPENBLAS_NUM_THREADS OMP_THREAD_LIMIT=2 OMP_NUM_THREADS=2", run);
  EXPECT_EQ(spinning.exit_code, 0) << spinning.output;
  EXPECT_NE(spinning.output.find("set OMP_WAIT_POLICY=passive"), std::string::npos)
      << spinning.output;
  const CommandResult passive = run_sketchdrape_with_env(
      "env -u OPENBLAS_NUM_THREADS OMP_THREAD_LIMIT=2 OMP_NUM_THREADS=2 OMP_WAIT_POLICY=passive",
      run);
  EXPECT_EQ(passive.exit_code, 0) << passive.output;
  EXPECT_EQ(passive.output.find("OMP_WAIT_POLICY"), std::string::npos) << passive.output;
  const CommandResult one =
      run_sketchdrape_with_env("env -u OMP_WAIT_POLICY OMP_THREAD_LIMIT=1", run);
  EXPECT_EQ(one.exit_code, 0) << one.output;
  EXPECT_EQ(one.output.find("OMP_WAIT_POLICY"), std::string::npos) << one.output;
}

// The first 0.4 s of the adaptive long-sleeve tee at 2 cm (about 2,100 vertices: the splits of
// its landing, body contact, self-contact springs and the fail-safe's continuous queries) at
// --threads 1 and 2: every parallel loop joins its chunks in order (docs/simulator.md,
// "Threads"), so the drape is the same to the last byte.
TEST(SolverThreads, AdaptiveGarmentDrapeIsTheSameBitsOnOneAndTwoThreads) {
  const fs::path dir = fs::temp_directory_path() / "sd_solver_threads_test" / "tee";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ifstream in(fs::path(SD_SOURCE_DIR) / "data/designs/long-sleeve-tee.json");
  nlohmann::json sketch = nlohmann::json::parse(in, nullptr, true, /*ignore_comments=*/true);
  sketch["edge_length"] = 0.02;
  sketch["simulate"]["adaptive"] = true;
  sketch["simulate"]["duration"] = 0.4;
  sketch["simulate"]["stop_at_rest"] = false;
  sketch["output"] = {{"images", nlohmann::json::array()}, {"mesh", "drape.obj"}};
  std::ofstream(dir / "tee.json") << sketch.dump(1);
  std::string drapes[2];
  for (int threads : {1, 2}) {
    const fs::path out = dir / ("out" + std::to_string(threads));
    const CommandResult run = run_sketchdrape("--threads " + std::to_string(threads) + " run " +
                                              (dir / "tee.json").string() + " -o " + out.string());
    ASSERT_EQ(run.exit_code, 0) << run.output;
    std::ifstream mesh(out / "drape.obj", std::ios::binary);
    drapes[threads - 1].assign(std::istreambuf_iterator<char>(mesh), {});
  }
  ASSERT_GT(drapes[0].size(), 100000u);  // about 2,100 vertices and 4,100 faces
  EXPECT_TRUE(drapes[0] == drapes[1]);
}

}  // namespace
}  // namespace sd::test
