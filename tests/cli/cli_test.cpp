#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "tests/cli/run_command.hpp"

namespace sd::test {
namespace {

TEST(Cli, VersionAndHelp) {
  const CommandResult version = run_sketchdrape("--version");
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_NE(version.output.find("sketchdrape "), std::string::npos);
  const CommandResult help = run_sketchdrape("info --help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.output.find("BODY"), std::string::npos);
}

TEST(Cli, UnknownSubcommandIsUsageError) {
  EXPECT_EQ(run_sketchdrape("no-such-command").exit_code, 2);
  EXPECT_EQ(run_sketchdrape("").exit_code, 2);
}

TEST(Cli, InfoBuiltinReportsYUpAndHeight) {
  const CommandResult r = run_sketchdrape("info builtin --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["normalised"]["up_axis"], "+y");
  EXPECT_NEAR(j["normalised"]["height_m"].get<double>(), 1.75, 1e-9);
  EXPECT_EQ(j["raw"]["up_axis"], "+z");
  EXPECT_NEAR(j["raw"]["height"].get<double>(), 10.72, 0.01);
  EXPECT_TRUE(j["topology"]["closed"].get<bool>());
}

TEST(Cli, InfoOnMissingFileExitsTwoWithSentence) {
  const CommandResult r = run_sketchdrape("info /nonexistent/body.obj");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("does not exist"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace sd::test
