// The sketch file's adaptive settings: "simulate": {"adaptive": true | false | {...}} parses into
// scene::SimulateSpec (bool kept, object values over sim::AdaptiveSettings's defaults) and
// bad values fail with their JSON path.
#include <gtest/gtest.h>

#include <string>

#include "scene/sketch_file.hpp"

namespace sd::scene {
using namespace garment;  // the garment request's types and SketchError

namespace {

// A minimal sketch (as tests/garment) with the given "adaptive" value.
std::string sketch_with(const std::string& adaptive) {
  return R"({
    "curves": [ { "id": "a", "points": [[0, 1], [0.1, 1.2]] },
                { "id": "b", "points3d": [[0, 1, 0], [0.1, 1, 0]], "on_body": false, "edges": 4 } ],
    "panels": [ { "id": "p", "boundary": ["a", "b", "a.mirror"], "mirror": true } ],
    "simulate": { "adaptive": )" +
         adaptive + R"( } })";
}

// The JSON path and sentence of the error the text produces ("" when it parses).
std::string error_of(const std::string& adaptive) {
  try {
    parse_sketch(sketch_with(adaptive), "test.json");
  } catch (const SketchError& e) {
    return std::string(e.json_path()) + ": " + e.sentence();
  }
  return "";
}

TEST(AdaptiveSketch, BoolAndObjectForms) {
  EXPECT_TRUE(parse_sketch(sketch_with("true"), "t.json").simulate.adaptive);
  EXPECT_FALSE(parse_sketch(sketch_with("false"), "t.json").simulate.adaptive);
  const Sketch defaults = parse_sketch(sketch_with("{}"), "t.json");
  EXPECT_TRUE(defaults.simulate.adaptive);
  // Unset values are the simulator's defaults (the settings are sim's own type).
  const sim::AdaptiveSettings sim_defaults;
  const sim::AdaptiveSettings& d = defaults.simulate.adaptive_settings;
  EXPECT_EQ(d.refine_threshold, sim_defaults.refine_threshold);
  EXPECT_EQ(d.coarsen_threshold, sim_defaults.coarsen_threshold);
  EXPECT_EQ(d.steady_rate, sim_defaults.steady_rate);
  EXPECT_EQ(d.min_lifetime, sim_defaults.min_lifetime);
  EXPECT_EQ(d.min_level, sim_defaults.min_level);
  EXPECT_EQ(d.max_level, sim_defaults.max_level);
  EXPECT_EQ(d.max_vertices, sim_defaults.max_vertices);
  EXPECT_EQ(d.merge_batch, sim_defaults.merge_batch);
  EXPECT_EQ(d.even_levels, sim_defaults.even_levels);
  EXPECT_EQ(d.target_levels, sim_defaults.target_levels);
  EXPECT_EQ(d.lookahead, sim_defaults.lookahead);
  EXPECT_EQ(d.change_interval, sim_defaults.change_interval);
  const Sketch s = parse_sketch(
      sketch_with(R"({"enabled": true, "refine_threshold": 0.004, "coarsen_threshold": 0.001,
                      "steady_rate": 0.1, "min_lifetime": 0.5, "min_level": 1, "max_level": 5,
                      "max_vertices": 800, "merge_batch": 0.1, "even_levels": true,
                      "target_levels": true, "lookahead": 0.1, "change_interval": 0.05})"),
      "t.json");
  const sim::AdaptiveSettings& a = s.simulate.adaptive_settings;
  EXPECT_TRUE(s.simulate.adaptive);
  EXPECT_DOUBLE_EQ(a.refine_threshold, 0.004);
  EXPECT_DOUBLE_EQ(a.coarsen_threshold, 0.001);
  EXPECT_DOUBLE_EQ(a.steady_rate, 0.1);
  EXPECT_DOUBLE_EQ(a.min_lifetime, 0.5);
  EXPECT_EQ(a.min_level, 1);
  EXPECT_EQ(a.max_level, 5);
  EXPECT_EQ(a.max_vertices, 800);
  EXPECT_DOUBLE_EQ(a.merge_batch, 0.1);
  EXPECT_TRUE(a.even_levels);
  EXPECT_TRUE(a.target_levels);
  EXPECT_DOUBLE_EQ(a.lookahead, 0.1);
  EXPECT_DOUBLE_EQ(a.change_interval, 0.05);
  EXPECT_FALSE(parse_sketch(sketch_with(R"({"enabled": false})"), "t.json").simulate.adaptive);
}

TEST(AdaptiveSketch, BadValuesNameTheirPath) {
  EXPECT_EQ(error_of(R"("yes")").rfind("/simulate/adaptive: expected true, false or an object", 0),
            0u);
  EXPECT_EQ(
      error_of(R"({"refine_threshold": -1})").rfind("/simulate/adaptive/refine_threshold:", 0), 0u);
  EXPECT_EQ(error_of(R"({"refine_threshold": 0.001, "coarsen_threshold": 0.002})")
                .rfind("/simulate/adaptive/coarsen_threshold: the coarsen threshold", 0),
            0u);
  EXPECT_EQ(error_of(R"({"max_level": 2.5})").rfind("/simulate/adaptive/max_level:", 0), 0u);
  EXPECT_EQ(error_of(R"({"max_level": 31})").rfind("/simulate/adaptive/max_level: levels go", 0),
            0u);
  EXPECT_EQ(
      error_of(R"({"min_level": 4, "max_level": 3})").rfind("/simulate/adaptive/max_level:", 0),
      0u);
  EXPECT_EQ(error_of(R"({"max_vertices": -3})").rfind("/simulate/adaptive/max_vertices:", 0), 0u);
  EXPECT_EQ(error_of(R"({"merge_batch": 1})").rfind("/simulate/adaptive/merge_batch: the merge", 0),
            0u);
  EXPECT_EQ(error_of(R"({"merge_batch": -0.1})").rfind("/simulate/adaptive/merge_batch:", 0), 0u);
  EXPECT_EQ(error_of(R"({"steady_rate": -0.1})").rfind("/simulate/adaptive/steady_rate:", 0), 0u);
  EXPECT_EQ(error_of(R"({"enabled": 1})").rfind("/simulate/adaptive/enabled:", 0), 0u);
  EXPECT_EQ(error_of(R"({"even_levels": "yes"})").rfind("/simulate/adaptive/even_levels:", 0), 0u);
  EXPECT_EQ(error_of(R"({"target_levels": 1})").rfind("/simulate/adaptive/target_levels:", 0), 0u);
  EXPECT_EQ(error_of(R"({"lookahead": -0.1})").rfind("/simulate/adaptive/lookahead:", 0), 0u);
  EXPECT_EQ(error_of(R"({"lookahead": 1})")
                .rfind("/simulate/adaptive/lookahead: a refinement lookahead of 1 s is outside", 0),
            0u);
  EXPECT_EQ(error_of(R"({"change_interval": 100})")
                .rfind("/simulate/adaptive/change_interval: an interval between mesh changes", 0),
            0u);
  EXPECT_EQ(error_of(R"({"lookahead": 0, "change_interval": 0.999})"), "");
  EXPECT_EQ(error_of(R"({"refine": 0.1})").rfind("/simulate/adaptive", 0), 0u);  // unknown key
  EXPECT_EQ(error_of(R"({"max_vertices": 0})"), "");
  // A value against the simulator's default is left to run (AdaptiveSettings::validate): the
  // file is read as written.
  EXPECT_EQ(error_of(R"({"coarsen_threshold": 0.003})"), "");
  EXPECT_EQ(error_of(R"({"min_level": 8})"), "");
}

}  // namespace
}  // namespace sd::scene
