// The sketch file's adaptive settings: "simulate": {"adaptive": true | false | {...}} parses into
// garment::SimulateSpec (bool kept, object values optional over the simulator's defaults) and
// bad values fail with their JSON path.
#include <gtest/gtest.h>

#include <string>

#include "scene/sketch_file.hpp"

namespace sd::garment {
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
  EXPECT_FALSE(defaults.simulate.adaptive_settings.refine_threshold.has_value());
  EXPECT_FALSE(defaults.simulate.adaptive_settings.max_level.has_value());
  const Sketch s = parse_sketch(
      sketch_with(R"({"enabled": true, "refine_threshold": 0.004, "coarsen_threshold": 0.001,
                      "steady_rate": 0.1, "min_lifetime": 0.5, "min_level": 1, "max_level": 5,
                      "max_vertices": 800, "merge_batch": 0.1, "even_levels": true})"),
      "t.json");
  const AdaptiveSpec& a = s.simulate.adaptive_settings;
  EXPECT_TRUE(s.simulate.adaptive);
  EXPECT_DOUBLE_EQ(*a.refine_threshold, 0.004);
  EXPECT_DOUBLE_EQ(*a.coarsen_threshold, 0.001);
  EXPECT_DOUBLE_EQ(*a.steady_rate, 0.1);
  EXPECT_DOUBLE_EQ(*a.min_lifetime, 0.5);
  EXPECT_EQ(*a.min_level, 1);
  EXPECT_EQ(*a.max_level, 5);
  EXPECT_EQ(*a.max_vertices, 800);
  EXPECT_DOUBLE_EQ(*a.merge_batch, 0.1);
  EXPECT_TRUE(*a.even_levels);
  EXPECT_FALSE(defaults.simulate.adaptive_settings.even_levels.has_value());
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
  EXPECT_EQ(error_of(R"({"refine": 0.1})").rfind("/simulate/adaptive", 0), 0u);  // unknown key
  EXPECT_EQ(error_of(R"({"max_vertices": 0})"), "");
}

}  // namespace
}  // namespace sd::garment
