// `sketchdrape validate` as a user reads it: what the one line says, and what is printed with a
// refusal.

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>

#include "garment/body.hpp"
#include "tests/cli/hip_tube_obj.hpp"
#include "tests/cli/run_command.hpp"

namespace {

namespace fs = std::filesystem;
using sd::test::CommandResult;
using sd::test::run_sketchdrape;
using sd::test::write_hip_tube_obj;

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

// Trial 39, P7: a fabric file whose "name" holds BEL, ANSI colour escapes and U+202E (the
// right-to-left override) rang the terminal and turned it red from validate's "ok" line, and
// U+202E was echoed raw in every message. Nothing of it reaches the terminal raw, in the ok line
// or in an error; each is quoted as an escape.
TEST(ValidateCommand, NoControlOrBidiCharacterOfTheFileReachesTheTerminal) {
  const fs::path dir = fs::temp_directory_path() / "sd-validate-printable";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string name = "lin\\u0007\\u001b[31mRED\\u001b[0m \\u202eevil";
  const auto fabric = [&](double friction) {
    // Trial 39's linen in KES-F units (its h60-fabric-ctrl-name.json).
    return R"({"name": ")" + name + R"(", "area_density": {"value": 180, "unit": "g/m^2"},
      "stretch_warp": {"value": 3.27, "unit": "% EMT"},
      "stretch_weft": {"value": 4.086, "unit": "% EMT"},
      "shear": {"value": 1.0677, "unit": "gf/cm/deg"},
      "bend": {"value": 0.204, "unit": "gf*cm^2/cm"}, "damping": {"value": 0.001, "unit": "s"},
      "bend_damping": {"value": 0.05, "unit": "s"}, "thickness": {"value": 0.4, "unit": "mm"},
      "friction": {"value": )" +
           std::to_string(friction) + R"(, "unit": "1"}})";
  };
  std::ofstream(dir / "linen.json") << fabric(0.4);
  std::ofstream(dir / "odd.json") << fabric(30);
  for (const char* f : {"linen.json", "odd.json"})
    std::ofstream(dir / (std::string("sheet-") + f))
        << R"({"sheet": {"size": [0.2, 0.2], "resolution": [4, 4]}, "fabric": ")" << f << "\"}";
  // An id with U+202E: refused, quoted.
  std::ofstream(dir / "bidi.json") << "{\"curves\": [{\"id\": \"side\xe2\x80\xae"
                                      "edis\", \"view\": \"front\", "
                                      "\"points\": [[0, 1], [0.1, 1]]}], \"panels\": []}";
  const auto raw = [](const std::string& out) {
    return out.find('\x07') != std::string::npos || out.find('\x1b') != std::string::npos ||
           out.find("\xe2\x80\xae") != std::string::npos;
  };
  const CommandResult ok = run_sketchdrape("validate " + (dir / "sheet-linen.json").string());
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_FALSE(raw(ok.output)) << ok.output;
  EXPECT_NE(ok.output.find("fabric lin\\x07\\x1b[31mRED\\x1b[0m \\u202eevil)"), std::string::npos)
      << ok.output;
  const CommandResult odd = run_sketchdrape("validate " + (dir / "sheet-odd.json").string());
  EXPECT_EQ(odd.exit_code, 2) << odd.output;
  EXPECT_FALSE(raw(odd.output)) << odd.output;
  EXPECT_NE(odd.output.find("\\u202eevil"), std::string::npos) << odd.output;
  const CommandResult bidi = run_sketchdrape("validate " + (dir / "bidi.json").string());
  EXPECT_EQ(bidi.exit_code, 2) << bidi.output;
  EXPECT_FALSE(raw(bidi.output)) << bidi.output;
  EXPECT_NE(bidi.output.find("id 'side\\u202eedis'"), std::string::npos) << bidi.output;
  fs::remove_all(dir);
}

// Trial 39, P13: gravity pointing up drew no word (the cloth fell off the body, and the advice
// was about a snugger fit). It is warned, with Earth's; sideways gravity is not.
TEST(ValidateCommand, GravityPointingUpIsWarned) {
  const fs::path dir = fs::temp_directory_path() / "sd-validate-gravity";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const auto validate = [&](const std::string& gravity) {
    std::ofstream(dir / "sheet.json")
        << R"({"sheet": {"size": [0.2, 0.2], "resolution": [4, 4]}, "fabric": "cotton",
              "simulate": {"gravity": )"
        << gravity << "}}";
    return run_sketchdrape("validate " + (dir / "sheet.json").string());
  };
  const CommandResult up = validate("[0, 9.81, 0]");
  EXPECT_EQ(up.exit_code, 0) << up.output;
  EXPECT_NE(up.output.find("sheet.json: /simulate/gravity: gravity [0, 9.81, 0] m/s² points "
                           "straight up"),
            std::string::npos)
      << up.output;
  EXPECT_NE(up.output.find("Earth's gravity is [0, -9.81, 0]"), std::string::npos) << up.output;
  EXPECT_NE(up.output.find("; 1 warning(s)"), std::string::npos) << up.output;
  const CommandResult slanted = validate("[9.81, 9.81, 0]");
  EXPECT_NE(slanted.output.find("points 45° above the horizontal"), std::string::npos)
      << slanted.output;
  const CommandResult sideways = validate("[9.81, 0, 0]");
  EXPECT_EQ(sideways.output.find("/simulate/gravity"), std::string::npos) << sideways.output;
  fs::remove_all(dir);
}

// Trial 39, P5: the shorts' merged seam vertex was told 4 times by validate (once per build of
// the garment), with no file, panel or place. Now once, in the quality gate's form: the file,
// the panel, the curve of its seam and its place (not counted by --strict: no sketch change
// removes it, docs/sketch-format.md "Merged seam vertices").
TEST(ValidateCommand, AMergedSeamVertexIsToldOnceWithItsPlace) {
  const CommandResult v =
      run_sketchdrape("validate " + std::string(SD_SOURCE_DIR) + "/data/examples/shorts.json");
  EXPECT_EQ(v.exit_code, 0) << v.output;
  const std::string said = "lay in only two quads, folded onto each other";
  const size_t at = v.output.find(said);
  ASSERT_NE(at, std::string::npos) << v.output;
  EXPECT_EQ(v.output.find(said, at + 1), std::string::npos) << "told twice:\n" << v.output;
  const size_t line = v.output.rfind('\n', at) + 1;
  const std::string text = v.output.substr(line, v.output.find('\n', at) - line);
  EXPECT_EQ(text.rfind("warning: ", 0), 0u) << text;
  EXPECT_NE(text.find("shorts.json: panel '"), std::string::npos) << text;
  EXPECT_NE(text.find("on curve '"), std::string::npos) << text;
  EXPECT_NE(text.find(" m, near the "), std::string::npos) << text;
  EXPECT_EQ(v.output.find("seam vertex(es)"), std::string::npos) << v.output;
}

// The trapeze dress of trial 35 with assimp's duck given as its body: the refusal spoke of a
// curve crossing itself; it says first that the body has no landmarks, so is no standing figure.
TEST(ValidateCommand, ABodyThatIsNoFigureIsNamedFirst) {
  const std::string duck = "/usr/share/assimp/models/Collada/duck.dae";
  if (!fs::exists(duck)) GTEST_SKIP() << "assimp's test models are not installed";
  const fs::path dir = fs::temp_directory_path() / "sd-validate-duck";
  fs::create_directories(dir);
  std::ifstream in(std::string(SD_SOURCE_DIR) + "/data/examples/tshirt.json");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // The t-shirt example on the duck (its "body" key replaced; the file has no other).
  const size_t at = text.find("\"body\"");
  ASSERT_NE(at, std::string::npos);
  const size_t end = text.find_first_of(",\n", text.find(':', at));
  text.replace(at, end - at, "\"body\": \"" + duck + "\"");
  std::ofstream(dir / "duck.json") << text;
  const CommandResult v = run_sketchdrape("validate " + (dir / "duck.json").string());
  EXPECT_EQ(v.exit_code, 2) << v.output;
  EXPECT_NE(v.output.find("the body '" + duck + "' has no landmarks (cannot find"),
            std::string::npos)
      << v.output;
  EXPECT_NE(v.output.find("is it the right body file? With it, "), std::string::npos) << v.output;
  fs::remove_all(dir);
}

// The docs' patch on `body`, written to dir/name: `width` m wide and 0.2 m tall from `bottom`
// m up (the chest by default).
std::string write_patch_sketch(const fs::path& dir, const std::string& name,
                               const std::string& body, double width = 0.2, double bottom = 1.1) {
  fs::create_directories(dir);
  const double l = -width / 2, r = width / 2, b = bottom, t = bottom + 0.2;
  std::ofstream(dir / name) << fmt::format(
      R"({{"format": "sketchdrape/1", "body": {},
    "curves": [
      {{"id": "top", "view": "front", "points": [[{l}, {t}], [{r}, {t}]]}},
      {{"id": "right", "view": "front", "points": [[{r}, {t}], [{r}, {b}]]}},
      {{"id": "bottom", "view": "front", "points": [[{r}, {b}], [{l}, {b}]]}},
      {{"id": "left", "view": "front", "points": [[{l}, {b}], [{l}, {t}]]}}],
    "panels": [{{"id": "patch", "boundary": ["top", "right", "bottom", "left"]}}]}})",
      body, fmt::arg("l", l), fmt::arg("r", r), fmt::arg("t", t), fmt::arg("b", b));
  return (dir / name).string();
}

// An upside-down body (trial 44, P18): `info` said "give "up": "-z"", the sketch's error that
// the body has no landmarks dropped it. The built-in body is Z-up; given "-z" it stands on its
// head, and a patch between its legs (where the patch at the chest would be on the standing
// body) misses it: the refusal gives the "up" that stands it on its feet.
TEST(ValidateCommand, AnUpsideDownBodyIsSaidToBeOne) {
  const fs::path dir = fs::temp_directory_path() / "sd-validate-upside-down";
  const CommandResult v = run_sketchdrape(
      "validate " +
      write_patch_sketch(dir, "patch.json", R"({"mesh": "builtin", "up": "-z"})", 0.04, 1.45));
  EXPECT_EQ(v.exit_code, 2) << v.output;
  EXPECT_NE(v.output.find("has no landmarks"), std::string::npos) << v.output;
  EXPECT_NE(v.output.find("the figure looks upside down (it has landmarks once turned over): "
                          "give \"up\": \"+z\""),
            std::string::npos)
      << v.output;
  EXPECT_EQ(v.output.find("is it the right body file?"), std::string::npos) << v.output;
  fs::remove_all(dir);
}

// Two figures in one body file (trial 44, P3: the Collada human twice, a scene with a second
// mannequin): the pair is wider than tall, so the up axis was inferred along the width, and
// the refusal spoke only of "facing". It says the file holds two figure-sized meshes and which
// up axis was inferred, and why. Here the built-in body twice, 1.2 m apart along x, in metres.
TEST(ValidateCommand, TwoFiguresInOneBodyFileAreSaidToBeTwo) {
  const fs::path dir = fs::temp_directory_path() / "sd-validate-two-figures";
  fs::create_directories(dir);
  const sd::garment::Body one = sd::garment::load_body("builtin");
  {
    std::ofstream obj(dir / "two.obj");
    for (const double dx : {-0.6, 0.6})
      for (Eigen::Index v = 0; v < one.mesh.vertex_count(); ++v)
        obj << "v " << one.mesh.vertices(v, 0) + dx << ' ' << one.mesh.vertices(v, 1) << ' '
            << one.mesh.vertices(v, 2) << '\n';
    for (const Eigen::Index first : {Eigen::Index{1}, 1 + one.mesh.vertex_count()})
      for (Eigen::Index f = 0; f < one.mesh.face_count(); ++f)
        obj << "f " << first + one.mesh.faces(f, 0) << ' ' << first + one.mesh.faces(f, 1) << ' '
            << first + one.mesh.faces(f, 2) << '\n';
  }
  const CommandResult v = run_sketchdrape(
      "validate " + write_patch_sketch(dir, "patch.json", R"({"mesh": "two.obj", "scale": 1})"));
  EXPECT_EQ(v.exit_code, 2) << v.output;
  EXPECT_NE(v.output.find("the file holds 2 separate meshes apart from each other"),
            std::string::npos)
      << v.output;
  EXPECT_NE(v.output.find("the up axis was inferred as +x because the file is longest along x"),
            std::string::npos)
      << v.output;
  fs::remove_all(dir);
}

// A folder given as the fabric (trial 35: "fabrics" and "fabrics/" were called unknown presets).
TEST(ValidateCommand, AFolderAsTheFabricIsSaidToBeOne) {
  const fs::path dir = fs::temp_directory_path() / "sd-validate-fabric-folder";
  fs::create_directories(dir / "fabrics");
  for (const std::string name : {"fabrics", "fabrics/"}) {
    std::ofstream(dir / "sheet.json")
        << R"({"sheet": {"size": [0.2, 0.2], "resolution": [4, 4]}, "fabric": ")" + name + R"("})";
    const CommandResult v = run_sketchdrape("validate " + (dir / "sheet.json").string());
    EXPECT_EQ(v.exit_code, 2) << v.output;
    EXPECT_NE(v.output.find("/fabric: '" + name +
                            "' is a folder, not a fabric: name a fabric file in it "
                            "(\"fabrics/NAME.json\", relative to the sketch) or a preset (cotton,"),
              std::string::npos)
        << v.output;
  }
  fs::remove_all(dir);
}

// Trial 36, P13: absolute points written for another body. The built-in body's capelet moved
// onto the Collada human (and the human's tank top onto the built-in body) is warned, before
// anything else fails, with the written point that moved farthest, by its path, and the advice
// to write points relative to landmarks; each design on its own body is not. The built-in tank
// top on the human fails earlier, a curve folded by the snap, and that error says it too.
TEST(ValidateCommand, PointsWrittenForAnotherBodySayHowFarTheyMoved) {
  const std::string human = "/usr/share/assimp/models/Collada/human.zae";
  if (!fs::exists(human)) GTEST_SKIP() << "assimp-testmodels' human.zae is not installed";
  const fs::path dir = fs::temp_directory_path() / "sd-validate-moved";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const auto validate = [&](const std::string& design, const nlohmann::json& body) {
    std::ifstream in(std::string(SD_SOURCE_DIR) + "/data/designs/" + design + ".json");
    nlohmann::json sketch = nlohmann::json::parse(in, nullptr, true, /*ignore_comments=*/true);
    if (!body.is_null()) sketch["body"] = body;
    sketch["output"] = {{"images", nlohmann::json::array()}};
    const fs::path file = dir / (design + (body.is_null() ? "" : "-moved") + ".json");
    std::ofstream(file) << sketch.dump(2);
    return run_sketchdrape("validate " + file.string());
  };
  const std::string said = "likely written for another body";
  const nlohmann::json on_human = {{"mesh", human}};
  for (const auto& [design, body] :
       {std::pair<std::string, nlohmann::json>{"capelet", on_human},
        std::pair<std::string, nlohmann::json>{"tank-human", "builtin"}}) {
    const CommandResult own = validate(design, nullptr);
    EXPECT_EQ(own.exit_code, 0) << own.output;
    EXPECT_EQ(own.output.find(said), std::string::npos) << own.output;
    const CommandResult other = validate(design, body);
    const size_t warning = other.output.find(said);
    ASSERT_NE(warning, std::string::npos) << other.output;
    EXPECT_NE(other.output.find("/points3d/"), std::string::npos) << other.output;
    EXPECT_NE(other.output.find("moved more than 6 cm"), std::string::npos) << other.output;
    EXPECT_NE(other.output.find("near the "), std::string::npos) << other.output;
    EXPECT_NE(other.output.find("relative to a landmark"), std::string::npos) << other.output;
    // Before any error the moved curves lead to.
    const size_t error = other.output.find("error:");
    if (error != std::string::npos) {
      EXPECT_LT(warning, error) << other.output;
    }
  }
  const CommandResult folded = validate("tank-top", on_human);
  EXPECT_EQ(folded.exit_code, 2) << folded.output;
  EXPECT_NE(folded.output.find("moved farthest"), std::string::npos) << folded.output;
  EXPECT_NE(folded.output.find(said), std::string::npos) << folded.output;
  fs::remove_all(dir);
}

// Trial 38, problem 2: the strapless dress's bodice ("ease": 0.95) is sewn to its skirt (ease 1)
// along the hip seams, whose two sides then rest 5 % apart: its drape never came to rest (one
// vertex under the seam cycling every 0.15 s, docs/pattern.md "Eased seams that keep moving").
// validate warns about each seam (mirror copies folded in) at the bodice's ease, with the
// percentage and the eases that would do; at 0.96 (4 %, which rests at 3.27 s) it says nothing.
TEST(ValidateCommand, SeamWithEasesFivePercentApartIsWarned) {
  const fs::path sketch = fs::path(SD_SOURCE_DIR) / "tests/cli/sketches/strapless-dress-eased.json";
  const CommandResult v = run_sketchdrape("validate " + sketch.string());
  EXPECT_EQ(v.exit_code, 0) << v.output;
  for (const std::string curve : {"hip_f", "hip_b"}) {
    const size_t at = v.output.find("sewn along curve '" + curve + "'");
    ASSERT_NE(at, std::string::npos) << curve << "\n" << v.output;
    const size_t line = v.output.rfind('\n', at) + 1;
    const std::string warning = v.output.substr(line, v.output.find('\n', at) - line);
    EXPECT_NE(warning.find("/ease: panels 'bodice_"), std::string::npos) << warning;
    EXPECT_NE(warning.find("(ease 0.95) and 'skirt_"), std::string::npos) << warning;
    EXPECT_NE(warning.find("rest 5.0 %"), std::string::npos) << warning;
    EXPECT_NE(warning.find("an ease of at most 0.99"), std::string::npos) << warning;
    EXPECT_NE(warning.find("at least 0.96"), std::string::npos) << warning;
  }
  EXPECT_EQ(v.output.find(".mirror' (ease"), std::string::npos) << "mirror copies folded in";
  EXPECT_EQ(v.output.find("sewn along curve 'side'"), std::string::npos) << "equal eases";

  const fs::path dir = fs::temp_directory_path() / "sd-validate-seam-ease";
  fs::create_directories(dir);
  std::ifstream in(sketch);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (size_t at = text.find("\"ease\": 0.95"); at != std::string::npos;
       at = text.find("\"ease\": 0.95", at))
    text.replace(at, 12, "\"ease\": 0.96");
  std::ofstream(dir / "ease096.json") << text;
  const CommandResult close = run_sketchdrape("validate " + (dir / "ease096.json").string());
  EXPECT_EQ(close.exit_code, 0) << close.output;
  EXPECT_EQ(close.output.find("sewn along curve"), std::string::npos) << close.output;
  fs::remove_all(dir);
}

// Trial 40, P5: a curve drawn exactly over a panel's edge and named by no panel (a forgotten
// panel, or a boundary list that names another curve than meant) was silently ignored. It is
// warned once with its path and id, counted in the line, and --strict fails on it (validate and
// mesh: a designer would want to know); the same file without the curve is clean.
TEST(ValidateCommand, ACurveInNoPanelIsWarnedAndStrictCountsIt) {
  const fs::path dir = fs::temp_directory_path() / "sd-validate-unused-curve";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string curves = R"(
    { "id": "top", "view": "front", "points": [[-0.1, 1.3], [0.1, 1.3]] },
    { "id": "right", "view": "front", "points": [[0.1, 1.3], [0.1, 1.1]] },
    { "id": "bottom", "view": "front", "points": [[0.1, 1.1], [-0.1, 1.1]] },
    { "id": "left", "view": "front", "points": [[-0.1, 1.1], [-0.1, 1.3]] })";
  const std::string panels =
      R"("panels": [{ "id": "patch", "boundary": ["top", "right", "bottom", "left"] }])";
  std::ofstream(dir / "dart.json") << R"({"curves": [)" << curves << R"(,
    { "id": "dart", "view": "front", "points": [[0.1, 1.28], [0.1, 1.12]] }], )"
                                   << panels << "}";
  std::ofstream(dir / "clean.json") << R"({"curves": [)" << curves << "], " << panels << "}";
  const std::string file = (dir / "dart.json").string();
  const CommandResult v = run_sketchdrape("validate " + file);
  EXPECT_EQ(v.exit_code, 0) << v.output;
  const std::string said =
      "/curves/4: curve 'dart' is in no panel: a forgotten panel or a typo "
      "in a boundary list?";
  const size_t at = v.output.find(said);
  ASSERT_NE(at, std::string::npos) << v.output;
  EXPECT_EQ(v.output.find(said, at + 1), std::string::npos) << "told twice:\n" << v.output;
  EXPECT_NE(v.output.find("; 1 warning(s)"), std::string::npos) << v.output;
  const CommandResult strict = run_sketchdrape("validate --strict " + file);
  EXPECT_EQ(strict.exit_code, 1) << strict.output;
  EXPECT_NE(strict.output.find(file + ": 1 curve(s) in no panel and --strict"), std::string::npos)
      << strict.output;
  const CommandResult mesh =
      run_sketchdrape("mesh --strict " + file + " -o " + (dir / "out").string());
  EXPECT_EQ(mesh.exit_code, 1) << mesh.output;
  EXPECT_NE(mesh.output.find(said), std::string::npos) << mesh.output;
  const CommandResult clean = run_sketchdrape("validate --strict " + (dir / "clean.json").string());
  EXPECT_EQ(clean.exit_code, 0) << clean.output;
  EXPECT_EQ(clean.output.find("in no panel"), std::string::npos) << clean.output;
  fs::remove_all(dir);
}

// The file's text with `from` replaced by `to` (once; the test fails when it is not there).
std::string replaced(const fs::path& file, const std::string& from, const std::string& to) {
  std::ifstream in(file);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// Trial 41, P1: a kimono blouse whose underarm curve is drawn from the cuff up into the armpit
// (data/designs/repro/kimono-armpit-crease.json). `validate` said "ok" and only `pattern` refused
// the back, "like a nearly closed cap", which sent the designer to seams and darts. The gate now
// says the panel turns back on itself there, and the refusal says the panel is folded into a
// crease of the body, where, and near which landmark.
TEST(ValidateCommand, APanelFoldedIntoTheArmpitIsWarnedAndPatternSaysWhere) {
  const std::string file =
      std::string(SD_SOURCE_DIR) + "/data/designs/repro/kimono-armpit-crease.json";
  const CommandResult v = run_sketchdrape("validate " + file);
  EXPECT_EQ(v.exit_code, 0) << v.output;
  for (const std::string panel : {"front", "back"})
    EXPECT_NE(v.output.find("panel '" + panel + "': the panel turns back on itself"),
              std::string::npos)
        << panel << "\n"
        << v.output;
  const fs::path dir = fs::temp_directory_path() / "sd-validate-crease";
  fs::remove_all(dir);
  const CommandResult p = run_sketchdrape("pattern " + file + " -o " + dir.string());
  EXPECT_EQ(p.exit_code, 2) << p.output;
  EXPECT_NE(p.output.find("cannot be cut from flat cloth: it is drawn folded into a crease of "
                          "the body, where its surface turns back on itself"),
            std::string::npos)
      << p.output;
  EXPECT_NE(p.output.find("m, near the left_armpit)"), std::string::npos) << p.output;
  EXPECT_EQ(p.output.find("nearly closed cap"), std::string::npos) << p.output;
  fs::remove_all(dir);
}

// Trial 42, P5, again in trial 43 (data/designs/repro/wrap-dress-listed-corners.json, the wrap
// dress's try 4): every corner of 'front_over' is listed, yet its sliver (5.4°) was told "a
// boundary corner there is too sharp or not listed in \"corners\"". The sliver lies 9.2 cm down
// the 19° wedge where 'wrap' leaves the neckline, 3 edges from the corner: a listed corner was
// looked for within 2 edges only. A narrow corner's reach is 1 / sin(half its angle) edges.
TEST(ValidateCommand, ASliverAtANarrowListedCornerIsToldTheCornerIsListed) {
  const std::string file =
      std::string(SD_SOURCE_DIR) + "/data/designs/repro/wrap-dress-listed-corners.json";
  const CommandResult v = run_sketchdrape("validate " + file);
  EXPECT_EQ(v.exit_code, 0) << v.output;
  EXPECT_NE(v.output.find("panel 'front_over': 1 quad(s) have a corner below 10° (the smallest "
                          "5.4°) at the corner where 'wrap' begins (the outline turns 161° there), "
                          "which \"corners\" already lists"),
            std::string::npos)
      << v.output;
  EXPECT_EQ(v.output.find("not listed in"), std::string::npos) << v.output;
}

// Trial 43, P4 (data/designs/repro/tiered-dress-wrist-point-human.json): a hip point written
// from the built-in body's hanging left wrist ("drawn_on": "builtin") lands 10 cm off the Collada
// human, whose arms are held higher, and was told to give points relative to a landmark, which it
// was. Now it is told its landmark, where that is on this body, and, a limb's landmark, the torso
// landmark nearest the point as drawn with the offset from it. Also P15 (an offset typed in mm):
// tests/garment/bad/landmark-offset-millimetres.json.
TEST(ValidateCommand, ALandmarkPointOffTheBodyIsToldItsLandmarkAndATorsoOne) {
  if (!fs::exists("/usr/share/assimp/models/Collada/human.zae"))
    GTEST_SKIP() << "assimp-testmodels' human.zae is not installed";
  const std::string file =
      std::string(SD_SOURCE_DIR) + "/data/designs/repro/tiered-dress-wrist-point-human.json";
  const CommandResult v = run_sketchdrape("validate " + file);
  EXPECT_EQ(v.exit_code, 2) << v.output;
  EXPECT_NE(v.output.find("/curves/9/points3d: curve 'hipline_b' is written 10.2 cm off the body"),
            std::string::npos)
      << v.output;
  EXPECT_NE(v.output.find("The point is relative to 'left_wrist', which on this body is at "
                          "(0.441, 1.026, 0.053) m, 15.2 cm from it: a landmark of a limb moves "
                          "with the limb's pose"),
            std::string::npos)
      << v.output;
  EXPECT_NE(v.output.find("relative to a torso landmark, here {\"at\": \"hips\", \"offset\": "
                          "[0.182, 0.014, -0.124]}"),
            std::string::npos)
      << v.output;
  EXPECT_EQ(v.output.find("points given relative to a landmark of the body they were drawn on"),
            std::string::npos)
      << v.output;
}

// Trial 41, P4: "rest": "flat" is accepted per panel and per file by every command; a flat rest
// whose panel cannot be flattened is refused at the key that asked for it (the file's
// /simulate/rest was refused at /panels/1/rest, a key the file did not have, and read as the
// per-panel key being refused), saying that the key is fine and the piece is not.
TEST(ValidateCommand, RestPerPanelIsAcceptedAndARefusalNamesTheKeyThatAskedForIt) {
  const fs::path dir = fs::temp_directory_path() / "sd-validate-rest";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "patch.json") << R"({"curves": [
    { "id": "top", "view": "front", "points": [[-0.1, 1.3], [0.1, 1.3]] },
    { "id": "right", "view": "front", "points": [[0.1, 1.3], [0.1, 1.1]] },
    { "id": "bottom", "view": "front", "points": [[0.1, 1.1], [-0.1, 1.1]] },
    { "id": "left", "view": "front", "points": [[-0.1, 1.1], [-0.1, 1.3]] }],
    "panels": [{ "id": "patch", "boundary": ["top", "right", "bottom", "left"], "rest": "flat" }],
    "simulate": { "pin_above": 1.29, "duration": 0.05 }})";
  const std::string patch = (dir / "patch.json").string();
  for (const std::string command : {"validate", "mesh", "run", "pattern"}) {
    const CommandResult r = run_sketchdrape(
        command + " " + patch + (command == "validate" ? "" : " -o " + (dir / command).string()));
    EXPECT_EQ(r.exit_code, 0) << command << "\n" << r.output;
  }
  const fs::path crease = fs::path(SD_SOURCE_DIR) / "data/designs/repro/kimono-armpit-crease.json";
  std::ofstream(dir / "file-wide.json")
      << replaced(crease, "\"simulate\": { \"check_body_vertices\": true }",
                  "\"simulate\": { \"check_body_vertices\": true, \"rest\": \"flat\" }");
  std::ofstream(dir / "per-panel.json")
      << replaced(crease, "{ \"id\": \"front\",", "{ \"id\": \"front\", \"rest\": \"flat\",");
  const CommandResult wide = run_sketchdrape("validate " + (dir / "file-wide.json").string());
  EXPECT_EQ(wide.exit_code, 2) << wide.output;
  EXPECT_NE(wide.output.find("/simulate/rest: panel 'front' rests flat (the file's \"simulate\": "
                             "{\"rest\": \"flat\"})"),
            std::string::npos)
      << wide.output;
  EXPECT_EQ(wide.output.find("/panels/0/rest"), std::string::npos) << wide.output;
  const CommandResult own = run_sketchdrape("mesh " + (dir / "per-panel.json").string() + " -o " +
                                            (dir / "out").string());
  EXPECT_EQ(own.exit_code, 2) << own.output;
  EXPECT_NE(own.output.find("/panels/0/rest: panel 'front' rests flat (its \"rest\": \"flat\")"),
            std::string::npos)
      << own.output;
  EXPECT_NE(own.output.find("or give it \"rest\": \"shaped\" to drape it as drawn"),
            std::string::npos)
      << own.output;
  fs::remove_all(dir);
}

// Trial 41, P10: an imported garment's counts were the √3 4-8 mesh's, given as the file's
// ("garment mesh: 600 vertices, 1152 triangles" for a file of 216 vertices and 192 quads). The
// file's own come first now, in validate's line and in the reports of mesh and run.
TEST(ValidateCommand, AnImportedGarmentIsCountedAsItsFileHasIt) {
  const fs::path dir = fs::temp_directory_path() / "sd-validate-imported";
  fs::remove_all(dir);
  fs::create_directories(dir);
  write_hip_tube_obj(dir / "tube.obj");
  std::ofstream(dir / "tube.json")
      << R"({"garment_mesh": "tube.obj", "simulate": {"duration": 0.05, "pin_above": 0.94}})";
  const std::string file = (dir / "tube.json").string();
  const CommandResult v = run_sketchdrape("validate " + file);
  EXPECT_EQ(v.exit_code, 0) << v.output;
  EXPECT_NE(v.output.find("ok (garment mesh: 216 vertices, 384 triangles (its 192 faces split); "
                          "draped as a 4-8 mesh of 600 vertices and 1152 triangles"),
            std::string::npos)
      << v.output;
  const CommandResult m = run_sketchdrape("mesh " + file + " -o " + (dir / "mesh").string());
  ASSERT_EQ(m.exit_code, 0) << m.output;
  const nlohmann::json meshed = nlohmann::json::parse(std::ifstream(dir / "mesh/report.json"));
  EXPECT_EQ(meshed["totals"]["vertices"], 216);
  EXPECT_EQ(meshed["totals"]["triangles"], 384);
  EXPECT_EQ(meshed["totals"]["file_faces"], 192);
  const CommandResult r = run_sketchdrape("run " + file + " -o " + (dir / "run").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json ran = nlohmann::json::parse(std::ifstream(dir / "run/report.json"));
  ASSERT_TRUE(ran.contains("imported")) << ran.dump(1);
  EXPECT_EQ(ran["imported"]["vertices"], 216);
  EXPECT_EQ(ran["imported"]["triangles"], 384);
  EXPECT_EQ(ran["imported"]["file_faces"], 192);
  EXPECT_EQ(ran["imported"]["triangles_48"], ran["triangles"]);
  fs::remove_all(dir);
}

}  // namespace
