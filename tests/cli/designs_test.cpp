// The design corpus (data/designs/): garments written from the docs, on the built-in body and
// on a second one (Debian's Collada human). Each meshes under `mesh --strict` (no quality
// warning) with no folded quad and every quad's aspect ratio below 10; most drape to rest with
// no cloth vertex inside the body, and the skirts that span the legs have no slice dent deeper
// than 3 cm (docs/garment.md, "Panel surfaces"). data/designs/repro/ (not read here) holds the
// attempts that do not pass the gate and the simulator's reproducers.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "src/render/image.hpp"
#include "tests/cli/run_command.hpp"

namespace sd::test {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> design_names() {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(fs::path(SD_SOURCE_DIR) / "data/designs"))
    if (entry.path().extension() == ".json") names.push_back(entry.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in, nullptr, true, /*ignore_comments=*/true);
}

// The design without images, in a directory of its own (the bodies are absolute or builtin).
fs::path staged_design(const std::string& name, const fs::path& dir) {
  fs::remove_all(dir);
  fs::create_directories(dir);
  nlohmann::json sketch = read_json(fs::path(SD_SOURCE_DIR) / "data/designs" / (name + ".json"));
  sketch["output"] = {{"images", nlohmann::json::array()}};
  const fs::path path = dir / (name + ".json");
  std::ofstream(path) << sketch.dump(2);
  return path;
}

bool body_available(const std::string& name) {
  const nlohmann::json sketch =
      read_json(fs::path(SD_SOURCE_DIR) / "data/designs" / (name + ".json"));
  const nlohmann::json body = sketch.value("body", nlohmann::json("builtin"));
  const std::string mesh =
      body.is_string() ? body.get<std::string>() : body.value("mesh", "builtin");
  return mesh == "builtin" || fs::exists(mesh);
}

std::string test_name(const ::testing::TestParamInfo<std::string>& param_info) {
  std::string name = param_info.param;
  for (char& c : name)
    if (c == '-') c = '_';
  return name;
}

class Design : public ::testing::TestWithParam<std::string> {};

TEST_P(Design, MeshesWithoutQualityWarnings) {
  const std::string& name = GetParam();
  if (!body_available(name)) GTEST_SKIP() << "the design's body is not installed";
  const fs::path dir = fs::temp_directory_path() / "sd_designs" / name;
  const fs::path sketch = staged_design(name, dir);
  // (The cropped jacket was allowed `self_intersection` until 27 November: its back crossed its
  // back sleeve in 13 triangle pairs in the narrow crease under the left arm, where both lay on
  // the arm's wall; docs/garment.md, "Narrow creases"; and then `junction_in_cleft` for its
  // underarm junction in that crease, until the cleft test learnt that its panels follow the
  // crease, each on its own wall: garment/body_clefts.hpp.)
  const CommandResult meshed =
      run_sketchdrape("-q mesh --strict " + sketch.string() + " -o " + (dir / "mesh").string());
  ASSERT_EQ(meshed.exit_code, 0) << meshed.output;
  const nlohmann::json report = read_json(dir / "mesh" / "report.json");
  for (const nlohmann::json& warning : report["warnings"]) ADD_FAILURE() << warning.dump(2);
  for (const nlohmann::json& panel : report["panels"]) {
    EXPECT_EQ(panel["quality"]["inverted_quads"].get<int>(), 0) << panel["id"];
    EXPECT_LT(panel["quality"]["max_aspect_ratio"].get<double>(), 10.0) << panel["id"];
  }
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Corpus, Design, ::testing::ValuesIn(design_names()), test_name);

// Drapes: the two straight skirts (which also must not dent between the legs) and the designs
// added with them, each to rest with no cloth vertex inside the body. Wall time of each drape,
// measured on the 2-core machine loaded by parallel builds (26 November 2026): pencil 6 s,
// straight-skirt-human 10 s, one-shoulder-top 4 s, trousers-human 6 s, wrap-skirt 7 s,
// long-sleeve-tee 10 s, jumpsuit-human 8 s, vest-collar 8 s, tee-dress-human 14 s, capelet 8 s,
// circle-skirt 23 s, vest 6 s, vest-human 2 s, raglan-top 7 s, cape-hood 11 s,
// aline-dress-human 12 s, tee-human 3 s, cowl-top 1.4 s of CPU, boat-top 4 s, tank-human 4 s,
// culottes 9 s, tank-top 2 s, gored-skirt 10 s, pencil-skirt-human 11-16 s (26 November; 2 s of
// CPU), collar-top-human 6 s (1.2 s of CPU),
// hooded-top 7 s (3.3 s of CPU), cropped-jacket 27 s at load 10 (7.6 s of CPU, one thread),
// cotton-shift-dress 3 s on a quiet machine (3.5 s of CPU, 25 s wall at load 10),
// wide-leg-trousers 18 s at load 7 (3.3 s of CPU), hip-cape 24 s (6.2 s of CPU),
// capelet-human 29 s (3.4 s of CPU), yoke-flared-skirt 6.9 s of CPU (its free flared panels dent
// 7.2 cm between the legs near the hem, so it is not with the straight skirts):
// about 250 s in all; and the long garments below.
class DesignDrape : public ::testing::TestWithParam<std::string> {};

nlohmann::json drape(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / "sd_designs_drape" / name;
  const fs::path sketch = staged_design(name, dir);
  const CommandResult ran =
      run_sketchdrape("-q run " + sketch.string() + " -o " + (dir / "run").string());
  EXPECT_EQ(ran.exit_code, 0) << ran.output;
  nlohmann::json report =
      ran.exit_code == 0 ? read_json(dir / "run" / "report.json") : nlohmann::json();
  fs::remove_all(dir);
  return report;
}

void expect_at_rest_outside_the_body(const nlohmann::json& report) {
  ASSERT_FALSE(report.is_null());
  EXPECT_TRUE(report["at_rest"].get<bool>());
  EXPECT_EQ(report["penetrating_vertices_final"].get<int>(), 0);
  // At rest bounds how far the cloth moved over the window (a vertex chattering in place between
  // contacts may still have a speed): the drift, at most rest_speed·rest_window.
  EXPECT_LE(report["rest"]["drift_m"].get<double>(), report["rest"]["drift_limit_m"].get<double>());
  // The kinetic energy's mean over the window (a patch chattering in place may pass the limit
  // at single steps).
  EXPECT_LT(report["rest"]["kinetic_per_kg_window_mean_J_kg"].get<double>(),
            report["rest"]["kinetic_per_kg_limit_J_kg"].get<double>());
}

TEST_P(DesignDrape, RestsOutsideTheBodyWithoutADentBetweenTheLegs) {
  const std::string& name = GetParam();
  if (!body_available(name)) GTEST_SKIP() << "the design's body is not installed";
  const nlohmann::json report = drape(name);
  expect_at_rest_outside_the_body(report);
  // A top has no slice dent (none of it is below the crotch): null in report.json.
  if (!report.is_null() && !report["slice_dent"].is_null()) {
    EXPECT_LE(report["slice_dent"]["depth_m"].get<double>(), 0.03);
  }
}

const std::vector<std::string> straight_skirts = {"pencil-skirt", "straight-skirt-human",
                                                  "wrap-skirt", "pencil-skirt-human",
                                                  "pencil-skirt-plain"};

INSTANTIATE_TEST_SUITE_P(Skirts, DesignDrape, ::testing::ValuesIn(straight_skirts), test_name);

class DesignDrapeTop : public ::testing::TestWithParam<std::string> {};

TEST_P(DesignDrapeTop, RestsOutsideTheBody) {
  const std::string& name = GetParam();
  if (!body_available(name)) GTEST_SKIP() << "the design's body is not installed";
  expect_at_rest_outside_the_body(drape(name));
}

// Trousers and the jumpsuit dent between the legs by design (they go round each leg), the
// dresses' bodices are tops (the A-line dress's skirt dents 3.7 cm between the legs), and the
// circle skirt's hem flutes are folds the dent measure counts (docs/garment.md): only rest and
// penetration are checked.
const std::vector<std::string> other_designs = {
    "one-shoulder-top",  "long-sleeve-tee", "trousers-human",
    "jumpsuit-human",    "vest-collar",     "tee-dress-human",
    "capelet",           "circle-skirt",    "vest",
    "vest-human",        "raglan-top",      "cape-hood",
    "aline-dress-human", "tee-human",       "cowl-top",
    "boat-top",          "tank-human",      "culottes",
    "tank-top",          "gored-skirt",     "collar-top-human",
    "hooded-top",        "cropped-jacket",  "cotton-shift-dress",
    "wide-leg-trousers", "hip-cape",        "capelet-human",
    "yoke-flared-skirt"};

INSTANTIATE_TEST_SUITE_P(Corpus, DesignDrapeTop, ::testing::ValuesIn(other_designs), test_name);

// Long free skirts, which swung past 6 s before garments had a duration that follows their length
// and the drift-based rest test (issue 18's fifth round, docs/simulator.md): rest and
// penetration. Wall time at load 10-11 on the 2 cores: maxi-dress 62 s, gored-midi-skirt 63 s,
// long-aline-skirt-human 57 s, slit-maxi-skirt 68 s (and pencil-skirt-plain 9 s above); the whole
// of designs_tests took 105 s wall at -j2 and load 4-8.
const std::vector<std::string> long_garments = {"maxi-dress", "gored-midi-skirt",
                                                "long-aline-skirt-human", "slit-maxi-skirt"};

INSTANTIATE_TEST_SUITE_P(Long, DesignDrapeTop, ::testing::ValuesIn(long_garments), test_name);

// The tiered skirt's lower tier, cut with "ease": {"weft": 1.5} (half as long again round the
// body as the seam it hangs from) gathers into that seam. Drawn with the isotropic "ease": 1.15
// of the trial that asked for gathers (trial 34, item 5), the tier only grows and bulges. Counted
// on the row of tier-2 vertices next to the tier seam (those sharing a triangle with a seam
// vertex), sorted by angle about the body's axis: the turns of their distance from the axis, in
// and out by more than 5 mm (so the mesh's noise does not count). Measured (27 November, edge
// 2.5 cm, 56 vertices in the row): gathered 27, isotropic 13, the same with 3 mm and 10 mm.
int gather_turns(const fs::path& obj) {
  std::ifstream in(obj);
  std::string line, group;
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::pair<std::array<int, 3>, std::string>> faces;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string tag;
    s >> tag;
    if (tag == "g") {
      s >> group;
    } else if (tag == "v") {
      Eigen::Vector3d p;
      s >> p.x() >> p.y() >> p.z();
      vertices.push_back(p);
    } else if (tag == "f") {
      std::array<int, 3> f{};
      for (int& index : f) {
        std::string token;
        s >> token;
        index = std::stoi(token.substr(0, token.find('/'))) - 1;
      }
      faces.emplace_back(f, group);
    }
  }
  const auto in_tier = [](const std::string& g, const char* tier) { return g.rfind(tier, 0) == 0; };
  std::vector<char> tier1(vertices.size(), 0), tier2(vertices.size(), 0), row(vertices.size(), 0);
  for (const auto& [f, g] : faces)
    for (int v : f) {
      if (in_tier(g, "tier1")) tier1[static_cast<size_t>(v)] = 1;
      if (in_tier(g, "tier2")) tier2[static_cast<size_t>(v)] = 1;
    }
  const auto on_seam = [&](int v) {
    return tier1[static_cast<size_t>(v)] && tier2[static_cast<size_t>(v)];
  };
  for (const auto& [f, g] : faces)
    if (in_tier(g, "tier2") && std::any_of(f.begin(), f.end(), on_seam))
      for (int v : f)
        if (!on_seam(v)) row[static_cast<size_t>(v)] = 1;
  std::vector<std::pair<double, double>> around;  // (angle, distance from the axis)
  for (size_t v = 0; v < vertices.size(); ++v)
    if (row[v]) {
      const double x = vertices[v].x(), z = vertices[v].z() - 0.01;  // the axis: x = 0, z = 0.01
      around.emplace_back(std::atan2(z, x), std::hypot(x, z));
    }
  std::sort(around.begin(), around.end());
  constexpr double kHysteresis = 0.005;  // m
  int turns = 0, direction = 0;
  double extreme = around.empty() ? 0.0 : around.front().second;
  for (int pass = 0; pass < 2; ++pass)  // twice round, so the loop closes; the first primes
    for (const auto& [angle, r] : around) {
      if (direction >= 0) {  // rising (or not yet known): a fall from the peak by more turns
        if (r > extreme) {
          extreme = r;
        } else if (extreme - r > kHysteresis) {
          turns += pass == 1 && direction > 0;
          direction = -1;
          extreme = r;
        }
      }
      if (direction <= 0) {  // falling (or not yet known): a rise from the trough turns
        if (r < extreme) {
          extreme = r;
        } else if (r - extreme > kHysteresis) {
          turns += pass == 1 && direction < 0;
          direction = 1;
          extreme = r;
        }
      }
    }
  return turns;
}

TEST(GatheredTier, FoldsUnderItsSeamMoreThanAnIsotropicEaseAndRests) {
  const fs::path dir = fs::temp_directory_path() / "sd_designs_drape" / "gathers";
  std::map<std::string, int> turns;
  for (const std::string variant : {"gathered", "isotropic"}) {
    const fs::path sketch = staged_design("tiered-skirt", dir / variant);
    nlohmann::json j = read_json(sketch);
    if (variant == "isotropic")
      for (nlohmann::json& panel : j["panels"])
        if (panel["id"].get<std::string>().rfind("tier2", 0) == 0) panel["ease"] = 1.15;
    std::ofstream(sketch) << j.dump(2);
    const CommandResult ran =
        run_sketchdrape("-q run " + sketch.string() + " -o " + (dir / variant / "run").string());
    ASSERT_EQ(ran.exit_code, 0) << variant << ": " << ran.output;
    expect_at_rest_outside_the_body(read_json(dir / variant / "run" / "report.json"));
    turns[variant] = gather_turns(dir / variant / "run" / "drape.obj");
  }
  // Half the measured difference (27 against 13).
  EXPECT_GE(turns["gathered"], turns["isotropic"] + 7)
      << "gathered " << turns["gathered"] << ", isotropic " << turns["isotropic"];
  fs::remove_all(dir);
}

// The length of a garment's hem: its boundary edges within 8 cm of its lowest vertex (a skirt's
// hem hangs lower than any other free edge). Gathered cloth that folds into flutes below its
// seam carries its cut width down to the hem, so the hem grows from its drawn length towards
// the gather; squeezed flat, it stays near the drawn one.
double hem_length(const fs::path& obj) {
  std::ifstream in(obj);
  std::string line;
  std::vector<Eigen::Vector3d> vertices;
  std::map<std::pair<int, int>, int> edges;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string tag;
    s >> tag;
    if (tag == "v") {
      Eigen::Vector3d p;
      s >> p.x() >> p.y() >> p.z();
      vertices.push_back(p);
    } else if (tag == "f") {
      std::vector<int> f;
      std::string token;
      while (s >> token) f.push_back(std::stoi(token.substr(0, token.find('/'))) - 1);
      for (size_t k = 0; k < f.size(); ++k) ++edges[std::minmax(f[k], f[(k + 1) % f.size()])];
    }
  }
  double lowest = 1e300;
  for (const auto& [edge, count] : edges)
    lowest = std::min({lowest, vertices[static_cast<size_t>(edge.first)].y(),
                       vertices[static_cast<size_t>(edge.second)].y()});
  double length = 0;
  for (const auto& [edge, count] : edges) {
    const Eigen::Vector3d& a = vertices[static_cast<size_t>(edge.first)];
    const Eigen::Vector3d& b = vertices[static_cast<size_t>(edge.second)];
    if (count == 1 && a.y() < lowest + 0.08 && b.y() < lowest + 0.08) length += (a - b).norm();
  }
  return length;
}

// Trial 37's flounce skirt (data/designs/repro/flounce-skirt-human.json: a hip yoke and a flounce
// gathered round the body) drapes at 1.6 and at 2.0, the largest gather a file may ask for,
// starting gathered with the buckling compression (src/app/pipeline/cloth_scene.hpp, gathered;
// with the linear compression it failed at t = 0.0004 s at 1.6), comes to rest outside the body,
// and each mirror pair strains alike: at weft 1.5 the trial's yoke reached 58 % on one half and
// 93 % on the other while the linear compression threw the skirt about. Its hem is longer than
// drawn: the flounce hangs in flutes, not squeezed flat.
nlohmann::json flounce_drape(const std::string& variant, double weft, const std::string& rest) {
  const fs::path dir = fs::temp_directory_path() / "sd_designs_drape" / "flounce" / variant;
  fs::remove_all(dir);
  fs::create_directories(dir);
  nlohmann::json sketch =
      read_json(fs::path(SD_SOURCE_DIR) / "data/designs/repro/flounce-skirt-human.json");
  sketch["output"] = {{"images", nlohmann::json::array()}};
  for (nlohmann::json& panel : sketch["panels"])
    if (panel["id"].get<std::string>().rfind("flounce", 0) == 0) panel["ease"] = {{"weft", weft}};
  sketch["simulate"]["rest"] = rest;
  sketch["simulate"]["duration"] = 20.0;  // as the tiered skirt's; the run stops at rest
  std::ofstream(dir / "flounce.json") << sketch.dump(2);
  const CommandResult meshed = run_sketchdrape("-q mesh " + (dir / "flounce.json").string() +
                                               " -o " + (dir / "mesh").string());
  EXPECT_EQ(meshed.exit_code, 0) << meshed.output;
  const CommandResult ran = run_sketchdrape("-q run " + (dir / "flounce.json").string() + " -o " +
                                            (dir / "run").string());
  EXPECT_EQ(ran.exit_code, 0) << variant << ": " << ran.output;
  nlohmann::json report = read_json(dir / "run" / "report.json");
  report["hem_drawn_m"] = hem_length(dir / "mesh" / "garment.obj");
  report["hem_draped_m"] = hem_length(dir / "run" / "drape.obj");
  if (!::testing::Test::HasFailure()) fs::remove_all(dir);
  return report;
}

void expect_mirror_halves_alike(const nlohmann::json& report) {
  std::map<std::string, nlohmann::json> strain;
  for (const nlohmann::json& group : report["strain"])
    strain[group["group"].get<std::string>()] = group;
  int pairs = 0;
  for (const auto& [name, group] : strain) {
    if (!strain.contains(name + ".mirror")) continue;
    const nlohmann::json& mirror = strain[name + ".mirror"];
    ++pairs;
    // Measured (27 November, shaped 1.6 on the Collada human, at rest at 14.1 s): the mean
    // strains of a pair differ by 0.4 % at most, the largest stretches by 2.3 % (flounce_back:
    // 1.3 % and 3.6 %). strain_max is not compared: it is one triangle's worst, and the rows at
    // the gathered seam hold the gather as buckled compression, which costs the same at any
    // depth (0.40 and 0.70 on flounce_front's pair). The trial's yoke pair, 0.58 and 0.93, had
    // the mean 0.036 and stretch_max 0.45 and 0.46: one triangle's worst in a drape thrown about.
    EXPECT_NEAR(group["strain_mean"].get<double>(), mirror["strain_mean"].get<double>(), 0.02)
        << name;
    EXPECT_NEAR(group["stretch_max"].get<double>(), mirror["stretch_max"].get<double>(), 0.04)
        << name;
  }
  EXPECT_EQ(pairs, 6);
}

// The hem of trial 37's flounce (on its own variant body) measured against its drawn 1.46 m:
// squeezed flat, 1.26 times (shaped, buckling, weft 1.6) and 1.28 (flat, weft 1.5, the trial's);
// starting gathered, 1.56 and 1.46. Half-way.
constexpr double kFlutedHem = 1.37;

// A gathered drape that is not at rest within its 20 s still must not be thrown about: the
// trial's flounce at 1.5 still moved at 1.2 m/s after 4 s. Measured at 20 s (27 November): the
// flat 1.5 drape 0.55 cm/s, the shaped 2.0 one 10.7 cm/s (docs/pattern.md, "Gathers that start
// gathered"): about twice those.
void expect_calm_outside_the_body(const nlohmann::json& report, double speed) {
  EXPECT_EQ(report["penetrating_vertices_final"].get<int>(), 0);
  if (!report["at_rest"].get<bool>()) {
    EXPECT_LT(report["rest"]["speed_final_m_s"].get<double>(), speed);
  }
}

TEST(GatheredFlounce, DrapesAtOnePointSixToRestAndAtTwoWithMirrorHalvesAlike) {
  if (!fs::exists("/usr/share/assimp/models/Collada/human.zae"))
    GTEST_SKIP() << "the Collada human is not installed";
  for (const double weft : {1.6, 2.0}) {
    const nlohmann::json report = flounce_drape("shaped-" + std::to_string(weft), weft, "shaped");
    SCOPED_TRACE(weft);
    if (weft == 1.6) {
      expect_at_rest_outside_the_body(report);  // at rest at 8.18 s (round 42: 14.07 s)
    } else {
      expect_calm_outside_the_body(report, 0.2);
    }
    EXPECT_EQ(report["compression"], "buckling");
    expect_mirror_halves_alike(report);
    EXPECT_GT(report["hem_draped_m"].get<double>(),
              kFlutedHem * report["hem_drawn_m"].get<double>());
  }
}

TEST(GatheredFlounce, FromFlatClothFoldsIntoFlutes) {
  if (!fs::exists("/usr/share/assimp/models/Collada/human.zae"))
    GTEST_SKIP() << "the Collada human is not installed";
  const nlohmann::json report = flounce_drape("flat-1.5", 1.5, "flat");
  expect_calm_outside_the_body(report, 0.012);
  expect_mirror_halves_alike(report);
  EXPECT_GT(report["hem_draped_m"].get<double>(), kFlutedHem * report["hem_drawn_m"].get<double>());
}

const std::vector<std::string> gathered_designs = {"tiered-skirt"};

// Every design in data/designs is draped by one of the lists above: a design added to the
// corpus without a drape would only be meshed.
TEST(DesignCorpus, EveryDesignIsDraped) {
  std::vector<std::string> draped = straight_skirts;
  draped.insert(draped.end(), other_designs.begin(), other_designs.end());
  draped.insert(draped.end(), long_garments.begin(), long_garments.end());
  draped.insert(draped.end(), gathered_designs.begin(), gathered_designs.end());
  std::sort(draped.begin(), draped.end());
  std::vector<std::string> designs = design_names();
  std::sort(designs.begin(), designs.end());
  EXPECT_EQ(draped, designs);
}

// The quality gate: the godet skirt example's back has a quad 2.12 times the edge length, which
// validate reports with its place and landmark and --strict turns into exit code 1. (This was
// the shorts' back, 4 quads up to 2.21 times, until round 43's finishing ranked the smoothing by
// the gate's measures: the shorts pass --strict now, docs/meshing.md.)
TEST(QualityGateCli, StrictMakesWarningsFail) {
  const std::string godet = (fs::path(SD_SOURCE_DIR) / "data/examples/godet-skirt.json").string();
  const CommandResult plain = run_sketchdrape("validate " + godet);
  EXPECT_EQ(plain.exit_code, 0) << plain.output;
  EXPECT_NE(plain.output.find("panel 'back': 1 quad(s) have sides outside"), std::string::npos)
      << plain.output;
  EXPECT_NE(plain.output.find("near the "), std::string::npos) << plain.output;
  EXPECT_NE(plain.output.find("mesh quality warning(s)"), std::string::npos) << plain.output;
  const CommandResult strict = run_sketchdrape("validate --strict " + godet);
  EXPECT_EQ(strict.exit_code, 1) << strict.output;
}

// A drape that cannot succeed (gravity 1,000 times the Earth's, the largest a file may ask for:
// within 3 s a vertex is too fast even at the smallest step) says where and why and leaves the
// last accepted state to look at.
TEST(DesignDrapeFailure, SaysWhereAndWritesTheLastState) {
  const fs::path dir = fs::temp_directory_path() / "sd_designs_failure";
  fs::remove_all(dir);
  fs::create_directories(dir);
  nlohmann::json sketch = read_json(fs::path(SD_SOURCE_DIR) / "data/designs/pencil-skirt.json");
  sketch["output"] = {{"images", nlohmann::json::array()}};
  sketch["simulate"]["gravity"] = {0.0, -10000.0, 0.0};
  std::ofstream(dir / "fails.json") << sketch.dump(2);
  const CommandResult ran =
      run_sketchdrape("run " + (dir / "fails.json").string() + " -o " + (dir / "run").string());
  EXPECT_EQ(ran.exit_code, 1) << ran.output;
  EXPECT_NE(ran.output.find("in panel '"), std::string::npos) << ran.output;
  // One error, the run's, and no advice on the fit of a drape that broke (trial 39, P13: the
  // simulator's raw line came first, and "the garment settled ... slid" after a blow-up).
  EXPECT_EQ(ran.output.find("sim: t = "), std::string::npos) << ran.output;
  EXPECT_EQ(ran.output.find("error:"), ran.output.rfind("error:")) << ran.output;
  EXPECT_EQ(ran.output.find("settled"), std::string::npos) << ran.output;
  EXPECT_NE(ran.output.find(", near the "), std::string::npos) << ran.output;
  EXPECT_NE(ran.output.find("m/s (limit 50)"), std::string::npos) << ran.output;
  EXPECT_TRUE(fs::exists(dir / "run" / "drape-failed.obj"));
  // The place is marked in red (a hue no panel colour, skin or shadow has) in the views that see
  // it.
  int red_pixels = 0;
  for (const char* view : {"front", "back", "left", "right"}) {
    const fs::path png = dir / "run" / (std::string("drape-failed-") + view + ".png");
    ASSERT_TRUE(fs::exists(png)) << png;
    std::ifstream in(png, std::ios::binary);
    std::stringstream bytes;
    bytes << in.rdbuf();
    const render::Image image = render::decode_png(bytes.str());
    for (size_t i = 0; i + 3 < image.rgba.size(); i += 4) {
      const int r = image.rgba[i], g = image.rgba[i + 1], b = image.rgba[i + 2];
      if (r > 80 && r > 5 * g / 2 && r > 5 * b / 2) ++red_pixels;
    }
  }
  EXPECT_GT(red_pixels, 100);
  EXPECT_FALSE(fs::exists(dir / "run" / "report.json"));  // no drape, so no run report
  fs::remove_all(dir);
}

}  // namespace
}  // namespace sd::test
