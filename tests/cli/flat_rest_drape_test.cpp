// Every example, and two designs, draped from flat cloth ("rest": "flat", docs/pattern.md) with
// `sketchdrape run` as a designer runs it (images off): it comes to rest within its drape time,
// with no vertex inside the body and no fold through another, hangs from the shoulders or the waist
// where the shaped drape does, and its cloth is stretched from the pattern by no more than the
// flattening had to stretch it. The arms-lowering t-shirt, whose body moves until 2 s of its 3 s,
// drapes for 6 s. From flat cloth the body-vertex springs are released at no load
// (fade_carried_push, the flat rest's default; docs/pattern.md, "Drapes that do not rest"):
// without it the arms-lowering t-shirt's hem, the Collada top's collar and the Collada pencil
// skirt's hem by the knee cycle and never rest. The tiered skirt's gathered tier starts with its
// ease ramped in and buckling compression (the gathered flat drape's defaults, docs/pattern.md).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "tests/cli/run_command.hpp"

namespace sd::test {
namespace {

namespace fs = std::filesystem;

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in, nullptr, true, /*ignore_comments=*/true);
}

// The highest vertex of an OBJ file (m).
double top_of(const fs::path& obj) {
  std::ifstream in(obj);
  std::string line;
  double top = -std::numeric_limits<double>::infinity();
  while (std::getline(in, line)) {
    if (!line.starts_with("v ")) continue;
    std::istringstream s(line.substr(2));
    double x, y, z;
    s >> x >> y >> z;
    top = std::max(top, y);
  }
  return top;
}

// The drape's top must end within [top_min, top_max] (m): the bounds the shaped drapes keep
// (tests/cli/examples_drape_test.cpp): a garment sliding off the waist ends below the hips
// (0.86 m), one sliding off the shoulders below the armpits (1.22 m).
struct FlatExample {
  std::string name;
  double top_min, top_max;
  bool adaptive = false;
  std::string folder = "data/examples";  // or data/designs
  double duration = 0.0;                 // s; 0: the file's
  double strain_max = 0.10;              // the largest strain against the pattern in any piece
  double strain_mean = 0.035;            // the largest of the pieces' mean strains
};

class FlatRestDrape : public ::testing::TestWithParam<FlatExample> {};

TEST_P(FlatRestDrape, ComesToRestHangingWhereTheShapedDrapeDoes) {
  const FlatExample& example = GetParam();
  const fs::path dir = fs::temp_directory_path() / "sd_flat_rest_drape" /
                       (example.name + (example.adaptive ? "-adaptive" : ""));
  fs::remove_all(dir);
  fs::create_directories(dir);
  nlohmann::json sketch =
      read_json(fs::path(SD_SOURCE_DIR) / example.folder / (example.name + ".json"));
  // The Collada human comes with Debian's assimp-testmodels; without it the design cannot run.
  const nlohmann::json& body = sketch.contains("body") ? sketch["body"] : nlohmann::json();
  const nlohmann::json mesh = body.is_object() ? body.value("mesh", nlohmann::json()) : body;
  if (mesh.is_string() && mesh.get<std::string>().starts_with("/") &&
      !fs::exists(mesh.get<std::string>()))
    GTEST_SKIP() << "the design's body is not installed: " << mesh.get<std::string>();
  sketch["output"] = {{"images", nlohmann::json::array()}};
  sketch["simulate"]["rest"] = "flat";
  // With adaptive detail the mesh keeps refining where folds move, and the shaped t-shirt is not
  // at rest within its time either (docs/collision.md): 3 s, and nearly still at the end as the
  // examples drape test asks of its adaptive runs.
  if (example.adaptive) {
    sketch["simulate"]["adaptive"] = {{"enabled", true}, {"max_level", 1}};
    sketch["simulate"]["duration"] = 3.0;
  }
  if (example.duration > 0.0) sketch["simulate"]["duration"] = example.duration;
  const fs::path sketch_path = dir / (example.name + ".json");
  std::ofstream(sketch_path) << sketch.dump(2);
  const CommandResult ran =
      run_sketchdrape("-q run " + sketch_path.string() + " -o " + (dir / "run").string());
  ASSERT_EQ(ran.exit_code, 0) << ran.output;

  const nlohmann::json report = read_json(dir / "run" / "report.json");
  EXPECT_EQ(report["rest_shape"], "flat");
  if (!example.adaptive) {
    EXPECT_TRUE(report["at_rest"].get<bool>())
        << "not at rest after " << report["sim_time"] << " s: " << report["rest"].dump();
  } else if (!report["at_rest"].get<bool>()) {
    // Kinetic energy per kilogram below 1e-4 J/kg: an rms speed under 1.4 cm/s.
    EXPECT_LT(report["rest"]["kinetic_per_kg_final_J_kg"].get<double>(), 1e-4);
  }
  EXPECT_EQ(report["penetrating_vertices_final"].get<int>(), 0);
  EXPECT_EQ(report["piercing_body_vertices_final"].get<int>(), 0);
  EXPECT_EQ(report["self_intersections_final"].get<int>(), 0);
  if (example.adaptive) {
    EXPECT_GT(report["adaptive"]["splits"].get<int>(), 0);
  }
  // Strain against the pattern: the flattening stretches the examples' pieces by 5.8-9.7 % at
  // their 95th percentile (docs/pattern.md), so a drape that let every piece relax to its cut
  // shape stays well within that. Means under 3.5 %: the A-line skirt's yokes are cut 3 % small
  // ("ease": 0.97) and so sit stretched by that much (measured 3.1 %; the others 0.1-1.0 %).
  // With adaptive detail a few refined triangles under the arms are squeezed between arm and
  // body (measured up to 26 % in the sleeves after 3 s; docs/pattern.md): only means there.
  for (const auto& group : report["strain"]) {
    if (!example.adaptive) {
      EXPECT_LT(group["strain_max"].get<double>(), example.strain_max) << group["group"];
    }
    EXPECT_LT(group["strain_mean"].get<double>(), example.strain_mean) << group["group"];
  }
  const double top = top_of(dir / "run" / "drape.obj");
  EXPECT_GE(top, example.top_min) << "the garment slid down";
  EXPECT_LE(top, example.top_max);
  fs::remove_all(dir);
}

std::string test_name(const ::testing::TestParamInfo<FlatExample>& info) {
  std::string name = info.param.name + (info.param.adaptive ? "_adaptive" : "");
  for (char& c : name)
    if (c == '-') c = '_';
  return name;
}

INSTANTIATE_TEST_SUITE_P(
    Examples, FlatRestDrape,
    ::testing::Values(FlatExample{"a-line-skirt", 1.02, 1.06},
                      FlatExample{"godet-skirt", 0.98, 1.06}, FlatExample{"shorts", 0.97, 1.06},
                      FlatExample{"sleeveless-dress", 1.47, 1.52},
                      FlatExample{"tshirt", 1.47, 1.53},
                      // Flat rest with adaptive detail (pattern
                      // coordinates carried to every level).
                      FlatExample{"tshirt", 1.47, 1.53, true},
                      // Two designs written from the docs alone for
                      // issue 19; their shaped drapes end with the top
                      // at 1.495 m and 1.024 m (the gored skirt's waist
                      // settles 3.5 cm below where it is drawn).
                      FlatExample{"tank-top", 1.47, 1.52, false, "data/designs"},
                      FlatExample{"gored-skirt", 1.00, 1.06, false, "data/designs"},
                      // At rest at 4.65 s. The lowered arms press the sleeves' backs and the
                      // back's sides onto the body: 13.4-14.7 % at most there (13.7-13.8 %
                      // without the fade; under 8.3 % elsewhere; means 1.1-2.4 %).
                      FlatExample{"tshirt-arms-lowering", 1.47, 1.53, false, "data/examples", 6.0,
                                  0.16}),
    test_name);

// Two designs on the Collada human that rest from flat cloth only with the fade, the flat rest's
// default (27 November, round 8: not at rest in 10 s without it, a body-vertex spring caught
// and dropped every 16 steps under the collar's back and at the hem by the left knee; with it
// at rest at 3.58 s and 2.82 s). Their shaped drapes end with the top at 1.437 m and 1.031 m;
// the flat ones within 2 cm of that (1.438 m, 1.051 m: the skirt's pattern, short over the
// seat, holds it higher), so ±3 cm. The top's backs are stretched 9.2 % at most over the
// shoulder blades, where its pattern's stretch is largest (means 1.0-2.7 %).
INSTANTIATE_TEST_SUITE_P(
    Designs, FlatRestDrape,
    ::testing::Values(FlatExample{"collar-top-human", 1.41, 1.47, false, "data/designs", 0.0, 0.12},
                      FlatExample{"pencil-skirt-human", 1.00, 1.06, false, "data/designs"},
                      // A tier gathered 1.5 : 1 (`"ease": {"weft": 1.5}`): the gathered flat
                      // drape's ramp and buckling compression (docs/pattern.md, "Gathered
                      // pieces"); at rest at 13.5 s of its 20 s, its top 1.051 m (the shaped
                      // drape's waist). The tier is sewn a third shorter round the body than it
                      // is cut, so its strain against the pattern is that compression: 36.6 % at
                      // most, piece means up to 12.1 % (the other pieces under 10 % and 3.5 %).
                      FlatExample{"tiered-skirt", 1.02, 1.07, false, "data/designs", 0.0, 0.40,
                                  0.15}),
    test_name);

}  // namespace
}  // namespace sd::test
