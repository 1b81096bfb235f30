// `sketchdrape validate` as a user reads it: what the one line says, and what is printed with a
// refusal.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "tests/cli/run_command.hpp"

namespace {

namespace fs = std::filesystem;
using sd::test::CommandResult;
using sd::test::run_sketchdrape;

// A hem drawn through the legs with a pattern asked for (trial 34): the panel cannot be
// flattened, but the cause is the cloth inside the body, not a cap that seams would split. The
// gate's inside_body warning is printed before the refusal, and the refusal names the cause.
TEST(ValidateCommand, PanelThroughTheBodyIsBlamedOnTheCurveNotItsShape) {
  const CommandResult v = run_sketchdrape("validate " + std::string(SD_SOURCE_DIR) +
                                          "/tests/cli/sketches/hem-through-legs.json");
  EXPECT_EQ(v.exit_code, 2) << v.output;
  const size_t warning = v.output.find("lie inside the body before the drape");
  const size_t error = v.output.find("cannot be cut from flat cloth");
  ASSERT_NE(warning, std::string::npos) << v.output;
  ASSERT_NE(error, std::string::npos) << v.output;
  EXPECT_LT(warning, error) << "the gate's warning comes first";
  EXPECT_NE(v.output.find("the likely cause is a curve drawn through the body", error),
            std::string::npos)
      << v.output;
}

// A sheet scene's line names the sheet and then its fabric, not the fabric as the sheet's name
// (trial 34: "ok (sheet fabrics/viscose-crepe.json: 95 vertices, ...").
TEST(ValidateCommand, SheetLineNamesTheFabricOnce) {
  const fs::path dir = fs::temp_directory_path() / "sd-validate-sheet";
  fs::create_directories(dir);
  std::ofstream(dir / "sheet.json")
      << R"({"sheet": {"size": [0.2, 0.2], "resolution": [4, 4]}, "fabric": "cotton"})";
  const CommandResult v = run_sketchdrape("validate " + (dir / "sheet.json").string());
  EXPECT_EQ(v.exit_code, 0) << v.output;
  EXPECT_NE(v.output.find(": ok (sheet: 25 vertices, 32 triangles, fabric "), std::string::npos)
      << v.output;
  EXPECT_EQ(v.output.find("sheet cotton"), std::string::npos) << v.output;
  fs::remove_all(dir);
}

}  // namespace
