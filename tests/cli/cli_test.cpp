#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <set>
#include <string>

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

// Each outline of a slice says which part of the figure it is (docs/cli.md promises legs, arms and
// torso): the built-in body's knees, hips with the hands beside them, and head.
TEST(Cli, InfoSliceNamesEachOutlinesPart) {
  const CommandResult r =
      run_sketchdrape("info builtin --json --slice 0.5 --slice 0.9 --slice 1.6");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  const auto parts = [&](size_t slice) {
    std::multiset<std::string> names;
    for (const auto& outline : j["slices"][slice]["outlines"]) {
      const std::string part = outline["part"];
      const double x = outline["centroid"][0];
      // The body's left is +x.
      if (part.starts_with("left")) {
        EXPECT_GT(x, 0) << part;
      }
      if (part.starts_with("right")) {
        EXPECT_LT(x, 0) << part;
      }
      names.insert(part);
    }
    return names;
  };
  EXPECT_EQ(parts(0), (std::multiset<std::string>{"left leg", "right leg"}));
  EXPECT_EQ(parts(1), (std::multiset<std::string>{"left arm", "right arm", "torso"}));
  EXPECT_EQ(parts(2), (std::multiset<std::string>{"head"}));
  const CommandResult text = run_sketchdrape("info builtin --slice 0.5");
  EXPECT_NE(text.output.find("  left leg "), std::string::npos) << text.output;
}

TEST(Cli, InfoOnMissingFileExitsTwoWithSentence) {
  const CommandResult r = run_sketchdrape("info /nonexistent/body.obj");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("does not exist"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace sd::test
