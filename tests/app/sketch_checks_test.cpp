// The renderer's share of run's memory estimate (src/app/pipeline/sketch_checks.hpp): counted
// only when pictures are asked for, at the largest picture, and the check made just before
// rendering, which names what would take the process over its budget.

#include "src/app/pipeline/sketch_checks.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <string>

#include "garment/sketch_error.hpp"
#include "sim/cholmod_solver.hpp"
#include "sim/constraint_filter.hpp"
#include "sim/fabric.hpp"
#include "sim/factor_size.hpp"
#include "sim/sheet.hpp"
#include "src/app/pipeline/cloth_scene.hpp"

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
  sim::ClothInput cloth;
  cloth.rest_positions = Eigen::MatrixX3d::Zero(81, 3);
  cloth.triangles.resize(0, 3);
  const RunEstimate without = estimate_run(none, cloth, {}, 0);
  const RunEstimate with = estimate_run(sheet_with_output("{}"), cloth, {}, 0);
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

// The factor CHOLMOD's analysis makes of the model's system (values: the identity on the
// diagonal, so that the numeric factorisation succeeds; the analysis reads only the pattern), as
// in tests/sim/factor_size_test.cpp.
double solver_factor_bytes(const sim::ClothInput& input, const sim::ClothModelOptions& options) {
  const sim::ClothModel model =
      sim::build_cloth_model(input, sim::fabric_preset("cotton"), options);
  sim::SparseMatrixR a = model.pattern.zero_matrix;
  for (int i = 0; i < model.vertex_count; ++i)
    for (int k = 0; k < 3; ++k) a.coeffRef(3 * i + k, 3 * i + k) = 1.0;
  sim::CholmodSolver solver;
  EXPECT_TRUE(solver.factorize(a, sim::ConstraintFilter(model.vertex_count)));
  return solver.analysed_size().bytes;
}

// The memory check predicts the factor of the model the run builds: with the diamond membrane
// (bending across the 4-8 mesh's quads) the diamonds' 13-vertex couplings are in it, and the
// estimate's factor is the solver's within the figures docs/cli.md gives ("Limits": bytes 12-23 %
// above what the solver allocates; sim's FactorSize tests allow 0.95-1.5). Predicted from the
// triangles alone, as the check did before, it was 0.47-0.58 of the solver's entries: this test
// failed with a ratio near 0.5.
TEST(SketchChecks, TheFactorEstimateKnowsTheDiamonds) {
  const scene::Sketch sketch = scene::parse_sketch(
      R"({"sheet": {"size": [1, 1], "resolution": [40, 30], "pins": ["top"]},
          "simulate": {"bending": "hinges"}, "output": {"images": []}})",
      "sheet.json");
  sim::SheetSpec spec;
  spec.columns = 40;
  spec.rows = 30;
  const sim::ClothInput cloth = sim::build_sheet(spec).input;
  for (const bool diamonds : {false, true}) {
    SCOPED_TRACE(diamonds ? "diamond membrane" : "plain membrane");
    sim::ClothModelOptions options;
    options.bend_model = sim::BendModel::hinges;
    options.diamond_membrane = diamonds;
    const RunEstimate estimate = estimate_run(sketch, cloth, options, 0);
    const double solver = solver_factor_bytes(cloth, options);
    ASSERT_GT(solver, 0.0);
    EXPECT_GE(estimate.factor_bytes / solver, 0.95);
    EXPECT_LE(estimate.factor_bytes / solver, 1.5);
    EXPECT_EQ(estimate.vertices, 41.0 * 31.0);
  }
  // The diamonds' pairs roughly double the factor: the check's memory grows with them.
  sim::ClothModelOptions plain, with_diamonds;
  plain.bend_model = with_diamonds.bend_model = sim::BendModel::hinges;
  with_diamonds.diamond_membrane = true;
  EXPECT_GT(estimate_run(sketch, cloth, with_diamonds, 0).factor_bytes,
            1.5 * estimate_run(sketch, cloth, plain, 0).factor_bytes);
}

// The options the check is given are the scene's own (those build_scene_model builds with), the
// sheet's before it is built included: the sketch's bending or its kind's default.
TEST(SketchChecks, TheEstimateUsesTheScenesModelOptions) {
  const scene::Sketch quadratic = sheet_with_output(R"({"images": []})");
  EXPECT_EQ(scene_bend_model(quadratic), sim::BendModel::quadratic);
  const ClothScene scene = build_cloth_scene(quadratic);
  const sim::ClothModelOptions options = scene_model_options(scene);
  EXPECT_EQ(options.bend_model, sim::BendModel::quadratic);
  const std::optional<RunEstimate> before = estimate_before_building(quadratic, 0);
  ASSERT_TRUE(before);
  EXPECT_DOUBLE_EQ(before->factor_bytes, sim::predict_factor_size(scene.input, options).bytes);
  EXPECT_DOUBLE_EQ(estimate_run(quadratic, scene.input, options, 0).factor_bytes,
                   before->factor_bytes);
}

// The message when what does not shrink with the cloth (the process, 26 MB, and the renderer)
// exceeds the budget: no vertex count is offered (trial 42, P7: "about 4 vertices would fit"
// under --max-memory 1MB), the budget this run needs is.
std::string refusal(const scene::Sketch& sketch, const RunLimits& limits) {
  const std::optional<RunEstimate> estimate = estimate_before_building(sketch, 0, limits);
  if (!estimate) return "no estimate";
  try {
    check_run_fits(sketch, *estimate, limits, 0);
  } catch (const garment::SketchError& e) {
    return e.what();
  }
  return "fits";
}

TEST(SketchChecks, NoClothFitsBesideThePictures) {
  RunLimits tiny;
  tiny.max_memory_bytes = 1e6;
  // The file lists no images: the run's three 600x900 ones, 129 MB with OSMesa.
  const scene::Sketch pictures = sheet_with_output("{}");
  const std::string with = refusal(pictures, tiny);
  EXPECT_NE(with.find("the pictures alone need 129 MB (600x900: OSMesa's libraries 50 MB, the "
                      "OpenGL context and its framebuffers 79 MB) and the process 26 MB before "
                      "any cloth, more than the 1 MB of --max-memory, so no cloth fits beside "
                      "them: give --max-memory 180 MB or more (this run is estimated at 156 MB)"),
            std::string::npos)
      << with;
  EXPECT_NE(with.find("\"images\": []"), std::string::npos) << with;
  EXPECT_EQ(with.find("would fit"), std::string::npos) << with;
  // What it offers passes this check (and, with a tenth to spare, the run: the CLI tests).
  RunLimits offered;
  offered.max_memory_bytes = 180e6;
  EXPECT_EQ(refusal(pictures, offered), "fits");

  // Without pictures the process alone (26 MB) is over 1 MB: said, with what the run needs.
  const scene::Sketch none = sheet_with_output(R"({"images": []})");
  const std::string bare = refusal(none, tiny);
  EXPECT_NE(bare.find("the process alone needs 26 MB before any cloth, more than the 1 MB of "
                      "--max-memory, so no cloth fits: give --max-memory 30 MB or more (this "
                      "run is estimated at 27 MB)"),
            std::string::npos)
      << bare;
  EXPECT_EQ(bare.find("would fit"), std::string::npos) << bare;

  // The pictures leave no room, but without them a smaller cloth would fit: a 128x128 sheet
  // (432 MB with its quadratic bending, 561 MB with the pictures) under 150 MB.
  const scene::Sketch large = scene::parse_sketch(
      R"({"sheet": {"size": [1, 1], "resolution": [128, 128], "pins": ["top"]}, "output": {}})",
      "large.json");
  RunLimits mid;
  mid.max_memory_bytes = 150e6;
  const std::string both = refusal(large, mid);
  EXPECT_NE(both.find("so no cloth fits beside them"), std::string::npos) << both;
  EXPECT_NE(both.find("without them the run still needs about 432 MB, and about"),
            std::string::npos)
      << both;

  // Room for the pictures and some cloth: the size that fits is offered, as before.
  RunLimits roomy;
  roomy.max_memory_bytes = 300e6;
  const std::string fits_smaller = refusal(large, roomy);
  EXPECT_NE(fits_smaller.find("quads would fit"), std::string::npos) << fits_smaller;
  EXPECT_EQ(fits_smaller.find("no cloth fits"), std::string::npos) << fits_smaller;
}

}  // namespace
}  // namespace sd::app
