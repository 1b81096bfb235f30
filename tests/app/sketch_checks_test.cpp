// The renderer's share of run's memory estimate (src/app/pipeline/sketch_checks.hpp): counted
// only when pictures are asked for, at the largest picture, and the check made just before
// rendering, which names what would take the process over its budget.

#include "src/app/pipeline/sketch_checks.hpp"

#include <gtest/gtest.h>

#include <string>

namespace sd::app {
namespace {

scene::Sketch sheet_with_output(const std::string& output) {
  return scene::parse_sketch(
      R"({"sheet": {"size": [1, 1], "resolution": [8, 8], "pins": ["top"]}, "output": )" + output +
          "}",
      "sheet.json");
}

TEST(SketchChecks, TheRendererIsCountedOnlyForPictures) {
  const scene::Sketch none = sheet_with_output(R"({"images": []})");
  EXPECT_EQ(run_renderer_memory(none, 0).total(), 0.0);
  // --frames alone: the sequence at the default image size.
  const RendererMemory frames = run_renderer_memory(none, 10);
  EXPECT_EQ(frames.width, 800);
  EXPECT_EQ(frames.height, 1200);
  EXPECT_GT(frames.library_bytes, 0.0);
  // The images the file does not list: front, back and left at 600x900.
  const RendererMemory defaults = run_renderer_memory(sheet_with_output("{}"), 0);
  EXPECT_EQ(defaults.width, 600);
  EXPECT_EQ(defaults.height, 900);
  // The largest of the listed images (by pixels, not by either side).
  const RendererMemory listed = run_renderer_memory(
      sheet_with_output(
          R"({"images": [{"view": "front", "size": [2000, 100]}, {"view": "back", "size": [500, 600]}]})"),
      0);
  EXPECT_EQ(listed.width, 500);
  EXPECT_EQ(listed.height, 600);
  EXPECT_GT(renderer_memory(1000, 1000).frame_bytes, renderer_memory(100, 100).frame_bytes);
  EXPECT_EQ(renderer_memory(1000, 1000).library_bytes, renderer_memory(100, 100).library_bytes);

  // The estimate of the run includes it (the sheet's 81 vertices are the same in both).
  const Eigen::MatrixX3i triangles(0, 3);
  const RunEstimate without = estimate_run(none, triangles, 81, 0);
  const RunEstimate with = estimate_run(sheet_with_output("{}"), triangles, 81, 0);
  EXPECT_DOUBLE_EQ(with.memory_bytes - without.memory_bytes, defaults.total());
}

TEST(SketchChecks, RenderingIsCheckedAgainstTheBudget) {
  const RendererMemory picture = renderer_memory(600, 900);
  const double resident = 72e6;  // an 8x8 sheet's process after its drape, OSMesa opened
  const double needs = resident + picture.frame_bytes;
  // Fits with a byte to spare; no budget (0) always fits.
  EXPECT_FALSE(rendering_over_budget(resident, picture, true, needs + 1, true));
  EXPECT_FALSE(rendering_over_budget(resident, picture, true, 0, false));
  // A budget just under what rendering takes: refused, naming the parts and the limit.
  const std::optional<std::string> over =
      rendering_over_budget(resident, picture, true, needs - 1e6, true);
  ASSERT_TRUE(over);
  EXPECT_NE(over->find("the process holds 72 MB and rendering 600x900 pictures takes about"),
            std::string::npos)
      << *over;
  EXPECT_NE(over->find("of --max-memory"), std::string::npos) << *over;
  EXPECT_EQ(over->find("OSMesa"), std::string::npos) << *over;  // already opened
  // OSMesa not opened yet (a failed drape's pictures in a run without any): its libraries too.
  const std::optional<std::string> unloaded =
      rendering_over_budget(resident, picture, false, needs + 1, false);
  ASSERT_TRUE(unloaded);
  EXPECT_NE(unloaded->find("OSMesa's libraries 50 MB"), std::string::npos) << *unloaded;
  EXPECT_NE(unloaded->find("a run may take of the memory available now"), std::string::npos)
      << *unloaded;
}

}  // namespace
}  // namespace sd::app
