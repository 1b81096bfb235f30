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

// Trial 35: `sketchdrape drape FILE` said "A subcommand is required" (one was there, unknown) and
// `run FILE --duration 5` "The following arguments were not expected: 5 --duration". The unknown
// word is named with the likely command, the commands are listed in the order of a design's work,
// and an option that is a sketch file's setting says where it goes.
TEST(Cli, UnknownCommandAndOptionSayWhatToWriteInstead) {
  const CommandResult drape = run_sketchdrape("drape sketch.json");
  EXPECT_EQ(drape.exit_code, 2) << drape.output;
  EXPECT_NE(drape.output.find("unknown command 'drape' (did you mean 'run'?); the commands are "
                              "info, validate, mesh, pattern, run, batch,"),
            std::string::npos)
      << drape.output;
  const CommandResult typo = run_sketchdrape("valdiate sketch.json");
  EXPECT_NE(typo.output.find("(did you mean 'validate'?)"), std::string::npos) << typo.output;
  const CommandResult none = run_sketchdrape("-q");
  EXPECT_EQ(none.exit_code, 2) << none.output;
  EXPECT_NE(none.output.find("a command is required: sketchdrape COMMAND ..., one of info, "
                             "validate, mesh"),
            std::string::npos)
      << none.output;
  const std::string sketch = std::string(SD_SOURCE_DIR) + "/data/examples/tshirt.json";
  const CommandResult duration = run_sketchdrape("run " + sketch + " --duration 5");
  EXPECT_EQ(duration.exit_code, 2) << duration.output;
  EXPECT_NE(duration.output.find("'run' has no option --duration: that is a setting of the sketch "
                                 "file, \"simulate\": {\"duration\": SECONDS}"),
            std::string::npos)
      << duration.output;
  // --help lists them in the same order (each at the start of its line).
  const CommandResult help = run_sketchdrape("--help");
  ASSERT_NE(help.output.find("\n  stress "), std::string::npos) << help.output;
  EXPECT_LT(help.output.find("\n  validate "), help.output.find("\n  stress ")) << help.output;
  EXPECT_LT(help.output.find("\n  mesh "), help.output.find("\n  fill ")) << help.output;
}

// Trial 36: an extra file, a number out of range and a missing file came as CLI11's raw text,
// the only errors without "error:"; `mesh FILE -o ''` wrote into the working directory.
TEST(Cli, EveryCommandLineMistakeIsAnErrorSentence) {
  const std::string sketch = std::string(SD_SOURCE_DIR) + "/data/examples/tshirt.json";
  const CommandResult extra = run_sketchdrape("validate " + sketch + " extra.json");
  EXPECT_EQ(extra.exit_code, 2) << extra.output;
  EXPECT_NE(extra.output.find("error: "), std::string::npos) << extra.output;
  EXPECT_NE(extra.output.find("extra.json"), std::string::npos) << extra.output;
  EXPECT_NE(extra.output.find("`sketchdrape validate --help` says what it takes"),
            std::string::npos)
      << extra.output;
  const CommandResult frames = run_sketchdrape("run " + sketch + " --frames 1e308");
  EXPECT_EQ(frames.exit_code, 2) << frames.output;
  EXPECT_NE(frames.output.find("error: "), std::string::npos) << frames.output;
  // --frames is a rate: its range says per what (trial 39, P15: read as a count "bounded by
  // 0.001"); a global option's mistake points to the program's --help, not the command's.
  const CommandResult negative = run_sketchdrape("run " + sketch + " --frames -1");
  EXPECT_NE(negative.output.find("--frames: -1 is outside 0.001 .. 1000 pictures per simulated "
                                 "second"),
            std::string::npos)
      << negative.output;
  const CommandResult threads = run_sketchdrape("--threads 0 validate " + sketch);
  EXPECT_EQ(threads.exit_code, 2) << threads.output;
  EXPECT_NE(threads.output.find("; `sketchdrape --help` says what it takes"), std::string::npos)
      << threads.output;
  const CommandResult missing = run_sketchdrape("validate");
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
  EXPECT_NE(missing.output.find("error: "), std::string::npos) << missing.output;
  for (const std::string command : {"mesh", "run", "pattern"}) {
    const CommandResult empty = run_sketchdrape(command + " " + sketch + " -o ''");
    EXPECT_EQ(empty.exit_code, 2) << command << ": " << empty.output;
    EXPECT_NE(empty.output.find("an empty name is no place to write"), std::string::npos)
        << command << ": " << empty.output;
  }
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

// `info` says which way the figure faces by its head (docs/bodies.md, Normalisation): the
// built-in body's face reaches 7.5 cm forward of its neck, its skull 3 cm back (lean 0.43; 0.3
// leaves room for a slice's change of the neck's base). Given --facing that turns it round,
// `info` refuses it with the facing that is right (exit 2), as a sketch does at /body/facing.
TEST(Cli, InfoSaysWhichWayTheFigureFaces) {
  const CommandResult r = run_sketchdrape("info builtin --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_TRUE(j["facing_cues"]["head"]["found"].get<bool>());
  EXPECT_GT(j["facing_cues"]["head"]["lean"].get<double>(), 0.3);
  EXPECT_FALSE(j["facing_cues"]["backwards"].get<bool>());
  const CommandResult text = run_sketchdrape("info builtin");
  EXPECT_NE(text.output.find("facing      its head reaches"), std::string::npos) << text.output;
  EXPECT_EQ(text.output.find("faces backwards"), std::string::npos) << text.output;
  const CommandResult turned = run_sketchdrape("info builtin --facing +y");
  EXPECT_EQ(turned.exit_code, 2) << turned.output;
  EXPECT_NE(turned.output.find("faces backwards"), std::string::npos) << turned.output;
  EXPECT_NE(turned.output.find("give \"facing\": \"-y\""), std::string::npos) << turned.output;
}

// Trial 39, P14: a figure facing +x read by the convention (facing -y, Z up) has no landmarks,
// and `info` said only that landmarks need a standing figure. The built-in body (Z up, facing
// -y) read with --facing +x is such a figure: told that it looks turned, with the facings to
// try, along the axis that is neither its up nor the facing it was read with.
TEST(Cli, InfoSaysATurnedFigureLooksTurned) {
  const CommandResult r = run_sketchdrape("info builtin --facing +x");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("landmarks   none: cannot find the body's "), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("the figure looks turned: it is "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("so its arms run front to back"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(": try --facing +y or -y\n"), std::string::npos) << r.output;
  // Facing the convention's way: no such hint.
  EXPECT_EQ(run_sketchdrape("info builtin").output.find("looks turned"), std::string::npos);
}

// A slice height that is not a number or misses the figure is a usage mistake (exit 2 with a
// sentence), not an empty answer: the built-in body spans 0 .. 1.75 m.
TEST(Cli, InfoSliceOutsideTheBodyOrNotANumberExitsTwo) {
  for (const char* height : {"nan", "99", "-5"}) {
    const CommandResult r = run_sketchdrape(std::string("info builtin --slice ") + height);
    EXPECT_EQ(r.exit_code, 2) << height << ": " << r.output;
    EXPECT_NE(r.output.find("error:"), std::string::npos) << r.output;
  }
  const CommandResult above = run_sketchdrape("info builtin --slice 99");
  EXPECT_NE(above.output.find("outside the body"), std::string::npos) << above.output;
}

TEST(Cli, InfoOnMissingFileExitsTwoWithSentence) {
  const CommandResult r = run_sketchdrape("info /nonexistent/body.obj");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("does not exist"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace sd::test
