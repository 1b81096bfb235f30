#include "scene/sketch_file.hpp"

#include <gtest/gtest.h>

#include <string>

namespace sd::scene {
using namespace garment;  // the garment request's types and SketchError

namespace {

const char* kMinimal = R"({
  // comments are allowed
  "curves": [ { "id": "a", "points": [[0, 1], [0.1, 1.2]] },
              { "id": "b", "points3d": [[0, 1, 0], [0.1, 1, 0]], "on_body": false, "edges": 4 } ],
  "panels": [ { "id": "p", "boundary": ["a", "b", "a.mirror"], "mirror": true } ]
})";

// The error a text produces, or "" when it parses.
SketchError error_of(const std::string& text) {
  try {
    parse_sketch(text, "test.json");
  } catch (const SketchError& e) {
    return e;
  }
  return SketchError("", "", "");
}

TEST(SketchFile, MinimalFileGetsDefaults) {
  const Sketch s = parse_sketch(kMinimal, "test.json");
  EXPECT_EQ(s.body.mesh, "builtin");
  EXPECT_DOUBLE_EQ(s.edge_length, 0.03);
  EXPECT_DOUBLE_EQ(s.offset, 0.01);
  EXPECT_EQ(s.relax_iterations, 10);
  ASSERT_EQ(s.curves.size(), 2u);
  EXPECT_EQ(s.curves[0].view.kind, ViewKind::kFront);
  EXPECT_DOUBLE_EQ(s.curves[0].offset, 0.01);  // the file's offset
  EXPECT_TRUE(s.curves[0].smooth);
  EXPECT_FALSE(s.curves[1].on_body);
  EXPECT_EQ(*s.curves[1].edges, 4);
  EXPECT_TRUE(s.curves[1].is_3d());
  EXPECT_EQ(s.panels[0].fabric, "jersey");
  EXPECT_TRUE(s.panels[0].mirror);
  EXPECT_DOUBLE_EQ(s.simulate.duration, 3.0);
  EXPECT_EQ(s.simulate.integrator, "implicit-euler");
  EXPECT_EQ(s.simulate.solver, "auto");  // chosen from the scene (sim/automatic_settings.hpp)
  EXPECT_TRUE(s.simulate.time_step_auto);
  EXPECT_FALSE(s.simulate.pin_above.has_value());
  EXPECT_TRUE(s.simulate.check_body_vertices);
  EXPECT_FALSE(s.simulate.fade_carried_push.has_value());  // unset: the rest shape's default
  EXPECT_FALSE(s.body.motion.has_value());
  EXPECT_EQ(s.output.mesh, "garment.obj");
  EXPECT_TRUE(s.output.images.empty());
  EXPECT_FALSE(s.output.images_listed);
  EXPECT_FALSE(s.sheet.has_value());
}

TEST(SketchFile, SheetSceneNeedsNoCurvesAndHasNoBody) {
  const Sketch s = parse_sketch(R"({
    "format": "sketchdrape/1",
    // a sheet scene
    "sheet": {"size": [0.5, 2], "resolution": [8, 32], "orientation": "horizontal",
              "centre": [0, 1.5, 0], "pins": ["top-left", "right"]},
    "simulate": {"pin_above": 1.4},
    "output": {"images": []}
  })",
                                "sheet.json");
  ASSERT_TRUE(s.sheet.has_value());
  EXPECT_EQ(s.sheet->size, Eigen::Vector2d(0.5, 2));
  EXPECT_EQ(s.sheet->columns, 8);
  EXPECT_EQ(s.sheet->rows, 32);
  EXPECT_TRUE(s.sheet->horizontal);
  EXPECT_EQ(s.sheet->pins, (std::vector<std::string>{"top-left", "right"}));
  EXPECT_EQ(s.body.mesh, "none");
  EXPECT_DOUBLE_EQ(*s.simulate.pin_above, 1.4);
  EXPECT_TRUE(s.output.images_listed);
  EXPECT_TRUE(s.output.images.empty());
}

TEST(SketchFile, SheetMistakesNameTheirPath) {
  const auto error_of = [](const std::string& text) {
    try {
      parse_sketch(text, "bad.json");
    } catch (const SketchError& e) {
      return std::string(e.json_path()) + ": " + e.sentence();
    }
    return std::string("no error");
  };
  EXPECT_EQ(error_of(R"({"sheet": {"pins": ["middle"]}})").rfind("/sheet/pins/0: unknown pin", 0),
            0u);
  EXPECT_EQ(error_of(R"({"sheet": {"resolution": [0, 4]}})").rfind("/sheet/resolution/0", 0), 0u);
  EXPECT_EQ(error_of(R"({"sheet": {"size": [1, -1]}})").rfind("/sheet/size/1", 0), 0u);
  EXPECT_EQ(error_of(R"({"sheet": {}, "panels": []})").rfind("/sheet: a sheet scene has no", 0),
            0u);
  EXPECT_EQ(error_of(R"({"sheet": {"orientation": "diagonal"}})").rfind("/sheet/orientation", 0),
            0u);
  EXPECT_EQ(error_of(R"({"body": {"motion": {"duration": 0}}})").rfind("/body/motion/duration", 0),
            0u);
  EXPECT_EQ(error_of(R"({"body": {"motion": {"start": -1}}})").rfind("/body/motion/start", 0), 0u);
  EXPECT_EQ(error_of(R"({"body": {"motion": {"speed": 1}}})").rfind("/body/motion", 0), 0u);
  EXPECT_EQ(error_of(R"({"body": {"mesh": "none", "motion": {}}})").rfind("/body/motion", 0), 0u);
  // Poses: a list of {time, mesh} in time order, of the body's own file.
  const auto poses = [&](const std::string& motion) {
    return error_of(R"({"body": {"mesh": "b.obj", "motion": )" + motion + "}}");
  };
  EXPECT_EQ(poses(R"({"type": "poses"})").rfind("/body/motion: a \"poses\" motion needs", 0), 0u);
  EXPECT_EQ(
      poses(R"({"type": "poses", "poses": []})").rfind("/body/motion/poses: expected a list", 0),
      0u);
  EXPECT_EQ(poses(R"({"type": "poses", "poses": [{"time": 0, "mesh": "p.obj"}]})")
                .rfind("/body/motion/poses/0/time", 0),
            0u);
  EXPECT_EQ(poses(R"({"type": "poses", "poses": [{"time": 1}]})")
                .rfind("/body/motion/poses/0: a pose needs", 0),
            0u);
  EXPECT_EQ(poses(R"({"type": "poses", "poses": [{"time": 1, "mesh": "p.obj"},
                                                  {"time": 1, "mesh": "q.obj"}]})")
                .rfind("/body/motion/poses/1/time: the poses must come in time order", 0),
            0u);
  EXPECT_EQ(poses(R"({"type": "poses", "poses": [{"time": 1, "mesh": "p.obj"}], "degrees": 5})")
                .rfind("/body/motion/degrees", 0),
            0u);
  EXPECT_EQ(error_of(R"({"body": {"motion": {"type": "poses",
                                               "poses": [{"time": 1, "mesh": "p.obj"}]}}})")
                .rfind("/body/motion/poses: the poses must be meshes of the same body", 0),
            0u);
  EXPECT_EQ(poses(R"({"type": "walk"})").rfind("/body/motion/type: 'walk' is not a body motion", 0),
            0u);
}

TEST(SketchFile, ReadsEverySection) {
  const Sketch s = parse_sketch(R"({
    "format": "sketchdrape/1",
    "body": { "mesh": "b.obj", "height": 1.6, "up": "+z", "scale": 0.01,
              "motion": { "type": "arms-lowering", "degrees": -5, "start": 0.5, "duration": 2 } },
    "edge_length": 0.02, "offset": 0.005, "junction_tolerance": 0.01, "corner_angle": 50,
    "relax_iterations": 3, "fabric": "denim",
    "curves": [ { "id": "c", "view": { "camera": { "eye": [0, 1, 3], "target": [0, 1, 0], "fov": 30 } },
                  "points": [[0, 0], [0.1, 0]], "offset": 0.02, "smooth": false, "closed": false,
                  "edge_length": 0.01 } ],
    "panels": [ { "id": "p", "boundary": ["c"], "fabric": "silk", "edge_length": 0.015, "ease": 1.1 },
                { "id": "q", "boundary": ["c"] } ],
    "join": [ { "id": "pq", "panels": ["p", "q"] } ],
    "simulate": { "duration": 2, "adaptive": false, "time_step": 0.01, "integrator": "implicit-euler",
                  "solver": "cholmod", "stop_at_rest": false, "gravity": [0, -9.8, 0],
                  "check_body_vertices": false, "fade_carried_push": true },
    "output": { "images": [ { "view": "back", "size": [640, 480], "wireframe": true },
                            { "view": "three-quarter" } ],
                "mesh": "g.glb", "report": false, "wireframe": true }
  })",
                                "x.json", "/base");
  EXPECT_EQ(s.resolve(s.body.mesh), std::filesystem::path("/base/b.obj"));
  EXPECT_DOUBLE_EQ(*s.body.height, 1.6);
  ASSERT_TRUE(s.body.motion.has_value());
  EXPECT_DOUBLE_EQ(s.body.motion->degrees, -5);
  EXPECT_DOUBLE_EQ(s.body.motion->start, 0.5);
  EXPECT_DOUBLE_EQ(s.body.motion->duration, 2);
  const Sketch posed = parse_sketch(R"({"format": "sketchdrape/1", "sheet": {},
    "body": {"mesh": "rest.obj", "motion": {"type": "poses", "poses": [
      {"time": 0.5, "mesh": "up.obj"}, {"time": 1.5, "mesh": "down.obj"}]}}})",
                                    "x.json", "/base");
  ASSERT_TRUE(posed.body.motion.has_value());
  EXPECT_EQ(posed.body.motion->type, "poses");
  ASSERT_EQ(posed.body.motion->poses.size(), 2u);
  EXPECT_DOUBLE_EQ(posed.body.motion->poses[1].time, 1.5);
  EXPECT_EQ(posed.resolve(posed.body.motion->poses[1].mesh),
            std::filesystem::path("/base/down.obj"));
  EXPECT_EQ(posed.body.motion->poses[1].json_path, "/body/motion/poses/1");
  EXPECT_EQ(s.curves[0].view.kind, ViewKind::kCamera);
  EXPECT_DOUBLE_EQ(s.curves[0].view.camera.fov_degrees, 30);
  EXPECT_FALSE(s.curves[0].smooth);
  EXPECT_DOUBLE_EQ(*s.panels[0].edge_length, 0.015);
  EXPECT_DOUBLE_EQ(s.panels[0].ease.warp, 1.1);  // a number: the same both ways
  EXPECT_DOUBLE_EQ(s.panels[0].ease.weft, 1.1);
  EXPECT_EQ(s.joins[0].panels.size(), 2u);
  EXPECT_EQ(s.simulate.solver, "cholmod");
  EXPECT_FALSE(s.simulate.time_step_auto);  // the file's 0.01 s
  EXPECT_DOUBLE_EQ(s.simulate.time_step, 0.01);
  EXPECT_DOUBLE_EQ(s.simulate.gravity.y(), -9.8);
  EXPECT_FALSE(s.simulate.check_body_vertices);                        // the default is on
  EXPECT_EQ(s.simulate.fade_carried_push, std::optional<bool>(true));  // unset by default
  ASSERT_EQ(s.output.images.size(), 2u);
  EXPECT_EQ(s.output.images[0].view, "back");
  EXPECT_EQ(s.output.images[0].width, 640);
  EXPECT_EQ(s.output.images[1].view, "three-quarter");
  EXPECT_EQ(s.output.mesh, "g.glb");
}

// "ease": {"warp": a, "weft": b} scales the two directions apart (a gathered panel); a factor
// left out is 1.
TEST(SketchFile, EaseObjectGivesWarpAndWeft) {
  const auto ease = [](const std::string& value) {
    return parse_sketch(R"({"format": "sketchdrape/1",
      "curves": [{ "id": "c", "view": "front", "points": [[0, 1], [0.1, 1], [0.1, 1.1]] }],
      "panels": [{ "id": "p", "boundary": ["c"], "ease": )" +
                            value + R"( }]})",
                        "test.json")
        .panels[0]
        .ease;
  };
  EXPECT_EQ(ease(R"({"weft": 1.5})"), (garment::PanelEase{1.0, 1.5}));
  EXPECT_EQ(ease(R"({"warp": 0.9, "weft": 1.25})"), (garment::PanelEase{0.9, 1.25}));
  EXPECT_TRUE(ease("1.2").isotropic());
  EXPECT_FALSE(ease(R"({"warp": 1.2})").isotropic());
  EXPECT_THROW(ease(R"({})"), garment::SketchError);
  EXPECT_THROW(ease(R"({"weft": 2.5})"), garment::SketchError);
  EXPECT_THROW(ease(R"({"weft": "1.5"})"), garment::SketchError);
  EXPECT_THROW(ease(R"([1, 1.5])"), garment::SketchError);
}

// An ease typed as a percentage (trial 42, P3): every reading that gives a factor in range is
// offered, "x % looser" (the sentence's own 1.05 = 5 % looser) up to 100 and "x % of the size"
// from 50 to 200, so that 50 is told 1.5 as well as 0.5 and 5 or 8 are told 1.05 or 1.08.
TEST(SketchFile, EaseTypedAsPercentageIsToldEachReading) {
  const auto error = [](const std::string& value) -> std::string {
    try {
      (void)parse_sketch(R"({"format": "sketchdrape/1",
        "curves": [{ "id": "c", "view": "front", "points": [[0, 1], [0.1, 1], [0.1, 1.1]] }],
        "panels": [{ "id": "p", "boundary": ["c"], "ease": )" +
                             value + R"( }]})",
                         "test.json");
    } catch (const garment::SketchError& e) {
      return e.what();
    }
    return "accepted";
  };
  const std::string looser = "% looser, write";
  const std::string of_size = "% of the size as designed, write";
  const std::string five = error("5");
  EXPECT_NE(five.find("; if you meant 5 % looser, write 1.05"), std::string::npos) << five;
  EXPECT_EQ(five.find(of_size), std::string::npos) << five;
  const std::string eight = error(R"({"weft": 8})");
  EXPECT_NE(eight.find("ease 8 along the weft is outside"), std::string::npos) << eight;
  EXPECT_NE(eight.find("; if you meant 8 % looser, write 1.08"), std::string::npos) << eight;
  const std::string fifty = error("50");
  EXPECT_NE(fifty.find("; if you meant 50 % looser, write 1.5; if you meant 50 % of the size as "
                       "designed, write 0.5"),
            std::string::npos)
      << fifty;
  const std::string hundred_eight = error("108");
  EXPECT_NE(hundred_eight.find("; if you meant 108 % of the size as designed, write 1.08"),
            std::string::npos)
      << hundred_eight;
  EXPECT_EQ(hundred_eight.find(looser), std::string::npos) << hundred_eight;
  // No reading fits: 2.5 % looser is 1.025, but 250 is neither.
  EXPECT_NE(error("2.5").find("; if you meant 2.5 % looser, write 1.025"), std::string::npos);
  const std::string far = error("250");
  EXPECT_EQ(far.find("if you meant"), std::string::npos) << far;
  EXPECT_EQ(error("0.3").find("if you meant"), std::string::npos);
}

TEST(SketchFile, SolverAndStepMayBeAutomatic) {
  const Sketch s = parse_sketch(R"({"format": "sketchdrape/1",
      "sheet": {"size": [1, 1], "resolution": [4, 4]},
      "simulate": {"solver": "auto", "time_step": "auto"}})",
                                "auto.json");
  EXPECT_EQ(s.simulate.solver, "auto");
  EXPECT_TRUE(s.simulate.time_step_auto);
  const Sketch given = parse_sketch(R"({"format": "sketchdrape/1",
      "sheet": {"size": [1, 1], "resolution": [4, 4]},
      "simulate": {"solver": "pcg", "time_step": 0.02}})",
                                    "given.json");
  EXPECT_EQ(given.simulate.solver, "pcg");
  EXPECT_FALSE(given.simulate.time_step_auto);
  EXPECT_DOUBLE_EQ(given.simulate.time_step, 0.02);
}

TEST(SketchFile, ErrorsCarryFilePathAndSentence) {
  struct Case {
    const char* text;
    const char* path;
    const char* fragment;
  };
  const Case cases[] = {
      {R"({"curves": [{"id": "a", "points": [[0, 1], [1, 1]], "ofset": 1}], "panels": []})",
       "/curves/0/ofset", "did you mean 'offset'?"},
      {R"({"curves": [{"id": "a", "points": [["NaN", 1], [1, 1]]}], "panels": [{"id": "p", "boundary": ["a"]}]})",
       "/curves/0/points/0/0", "expected a number"},
      {R"({"curves": [{"id": "a", "points": [[0, 1], [1, -1e400]]}], "panels": [{"id": "p", "boundary": ["a"]}]})",
       "/curves/0/points/1/1", "-1e400 is not finite"},
      {R"({"curves": [{"id": "a", "points": [[0, 1], [1, 1]]}], "panels": [{"id": "p", "boundary": ["b"]}]})",
       "/panels/0/boundary/0", "curve 'b' is not defined"},
      {R"({"curves": [{"id": "a", "points": [[0, 1], [1, 1]]}], "panels": []})", "/panels",
       "the list of panels is empty"},
      {R"({"curves": [{"id": "a", "view": "side", "points": [[0, 1], [1, 1]]}], "panels": []})",
       "/curves/0/view", "no view called 'side'"},
      {R"({"curves": [{"id": "a", "points": [[0, 1], [0, 1]]}], "panels": []})",
       "/curves/0/points/1", "repeats the point before it"},
      {R"({"curves": [{"id": "a", "points": [[0, 1], [1, 1]], "points3d": [[0, 0, 0], [1, 0, 0]]}]})",
       "/curves/0", "exactly one of"},
      {R"({"format": "sketchdrape/2", "curves": []})", "/format", "reads format"},
      {R"({"curves": [{"id": "a", "points": [[0, 1], [1, 1]]}], "panels": [{"id": "p", "boundary": ["a"]}],
          "output": {"images": [{"size": [10, 100]}]}})",
       "/output/images/0/size/0", "at least 16"},
      {R"({"curves": [{"id": "a b", "points": [[0, 1], [1, 1]]}], "panels": []})", "/curves/0/id",
       "may only use ASCII letters"},
      {R"({"curves": [{"id": "a", "points": [[0, 1], [1, 1]]}], "panels": [{"id": "p", "boundary": ["a"]}],
          "join": [{"id": "j", "panels": ["p", "p.mirror"]}]})",
       "/join/0/panels/1", "has no mirror copy"},
      {R"({"sheet": {"size": [1, 1], "resolution": [4, 4]}, "simulate": {"time_step": "fast"}})",
       "/simulate/time_step", "or \"auto\""},
      {R"({"sheet": {"size": [1, 1], "resolution": [4, 4]}, "simulate": {"solver": "lu"}})",
       "/simulate/solver", "use \"auto\" (the default), \"pcg\", \"pcg-two-level\" or \"cholmod\""},
  };
  for (const Case& c : cases) {
    const SketchError e = error_of(c.text);
    EXPECT_EQ(e.file(), "test.json") << c.text;
    EXPECT_EQ(e.json_path(), c.path) << e.what();
    EXPECT_NE(std::string(e.what()).find(c.fragment), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind(std::string("test.json: ") + c.path + ": ", 0), 0u)
        << e.what();
  }
}

TEST(SketchFile, SyntaxErrorGivesLineAndColumn) {
  const SketchError e = error_of("{\n  \"curves\": [\n    {\"id\": }\n]}");
  EXPECT_TRUE(e.json_path().empty());
  EXPECT_NE(std::string(e.what()).find("line 3"), std::string::npos) << e.what();
}

TEST(SketchFile, OverflowMarkerDoesNotTouchStringsOrComments) {
  // "1e999" inside a string and a comment is not a number and must stay as written.
  const Sketch s = parse_sketch(R"({ // 1e999 in a comment
    "fabric": "1e999",
    "curves": [{"id": "a", "points": [[0, 1], [1, 1]]}], "panels": [{"id": "p", "boundary": ["a"]}]})",
                                "t.json");
  EXPECT_EQ(s.fabric, "1e999");
}

TEST(SketchFile, MissingFileIsSketchError) {
  try {
    load_sketch("/nonexistent/sketch.json");
    FAIL();
  } catch (const SketchError& e) {
    EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos);
  }
}

}  // namespace
}  // namespace sd::scene

namespace sd::scene {
namespace {

// "fabric" may be an object (the constants inline): kept as JSON text for the simulator to check,
// named by its "name" ("custom" without one).
TEST(SketchFile, FabricMayBeGivenInline) {
  const std::string curves =
      R"("curves": [{"id": "a", "points": [[0, 1], [1, 1]]}], "panels": [{"id": "p", "boundary": ["a"]}])";
  const Sketch named = parse_sketch(
      R"({"fabric": {"name": "twill", "bend": {"value": 1e-5, "unit": "N*m"}}, )" + curves + "}",
      "t.json");
  EXPECT_EQ(named.fabric, "twill");
  EXPECT_EQ(named.panels[0].fabric, "twill");
  EXPECT_NE(named.fabric_inline.find("\"bend\""), std::string::npos);
  const Sketch unnamed = parse_sketch(R"({"fabric": {}, )" + curves + "}", "t.json");
  EXPECT_EQ(unnamed.fabric, "custom");
  const Sketch preset = parse_sketch(R"({"fabric": "silk", )" + curves + "}", "t.json");
  EXPECT_TRUE(preset.fabric_inline.empty());
}

}  // namespace
}  // namespace sd::scene

namespace sd::scene {
namespace {

// Sheet pins take clamps of several lines of vertices ("top:3"), checked against the resolution.
TEST(SketchFile, SheetClampPins) {
  const auto sheet = [](const std::string& pin) {
    return R"({"sheet": {"resolution": [4, 6], "pins": [")" + pin + R"("]}})";
  };
  EXPECT_EQ(parse_sketch(sheet("top:3"), "t.json").sheet->pins.front(), "top:3");
  EXPECT_EQ(parse_sketch(sheet("left:5"), "t.json").sheet->pins.front(), "left:5");
  for (const std::string bad : {"top:8", "left:6", "top:0", "top:", "top:1.5", "middle:2"}) {
    try {
      parse_sketch(sheet(bad), "t.json");
      ADD_FAILURE() << bad << " was accepted";
    } catch (const SketchError& e) {
      EXPECT_EQ(e.json_path(), "/sheet/pins/0") << bad;
    }
  }
}

}  // namespace
namespace {

// A disc sheet (the Cusick test's specimen) held by a clamp at its centre; a disc's size and
// resolution are given twice alike, and only "centre:R" pins it.
TEST(SketchFile, DiscSheetWithACentreClamp) {
  const auto sheet = [](const std::string& body) { return R"({"sheet": {)" + body + "}}"; };
  const Sketch sketch = parse_sketch(sheet(R"("shape": "disc", "size": [0.3, 0.3],
      "resolution": [20, 20], "pins": ["centre:0.09"])"),
                                     "t.json");
  ASSERT_TRUE(sketch.sheet);
  EXPECT_TRUE(sketch.sheet->disc);
  EXPECT_EQ(sketch.sheet->pins.front(), "centre:0.09");
  EXPECT_FALSE(parse_sketch(sheet(R"("pins": ["centre:0.2"])"), "t.json").sheet->disc);
  struct Bad {
    std::string body, path;
  };
  for (const Bad& bad :
       {Bad{R"("shape": "circle")", "/sheet/shape"},
        Bad{R"("shape": "disc", "size": [0.3, 0.2])", "/sheet/size"},
        Bad{R"("shape": "disc", "resolution": [20, 10])", "/sheet/resolution"},
        Bad{R"("shape": "disc", "resolution": [2, 2])", "/sheet/resolution"},
        Bad{R"("shape": "disc", "pins": ["top"])", "/sheet/pins/0"},
        Bad{R"("shape": "disc", "size": [0.3, 0.3], "pins": ["centre:0.2"])", "/sheet/pins/0"},
        Bad{R"("pins": ["centre:x"])", "/sheet/pins/0"},
        Bad{R"("pins": ["centre:-0.1"])", "/sheet/pins/0"}}) {
    try {
      parse_sketch(sheet(bad.body), "t.json");
      ADD_FAILURE() << bad.body << " was accepted";
    } catch (const SketchError& e) {
      EXPECT_EQ(e.json_path(), bad.path) << bad.body;
    }
  }
}

}  // namespace
}  // namespace sd::scene

namespace sd::scene {
namespace {

// A corner clamp "top-left:R" (metres) is kept as written; a radius that is not a number, not
// positive, or more than half the sheet's shorter side is refused at the pin's path.
TEST(SketchFile, SheetCornerClampPins) {
  const auto sheet = [](const std::string& pin) {
    return R"({"sheet": {"size": [1.0, 0.6], "resolution": [8, 8], "pins": [")" + pin + R"("]}})";
  };
  EXPECT_EQ(parse_sketch(sheet("top-left:0.02"), "t.json").sheet->pins.front(), "top-left:0.02");
  EXPECT_EQ(parse_sketch(sheet("bottom-right:0.3"), "t.json").sheet->pins.front(),
            "bottom-right:0.3");
  for (const std::string bad : {"top-left:0", "top-right:-0.02", "bottom-left:x",
                                "top-left:", "top-left:0.31", "top-left:2cm", "top-centre:0.02"}) {
    try {
      parse_sketch(sheet(bad), "t.json");
      ADD_FAILURE() << bad << " was accepted";
    } catch (const SketchError& e) {
      EXPECT_EQ(e.json_path(), "/sheet/pins/0") << bad;
      if (bad != "top-centre:0.02") {
        EXPECT_NE(std::string(e.what()).find("corner clamp"), std::string::npos) << e.what();
      }
    }
  }
}

}  // namespace
}  // namespace sd::scene
