#include "sim/fabric.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <string>

namespace sd::sim {
namespace {

TEST(Fabric, EveryShippedPresetLoadsAndValidates) {
  const auto names = fabric_preset_names();
  for (const char* required : {"cotton", "denim", "silk", "jersey", "wool", "polyester"})
    EXPECT_NE(std::find(names.begin(), names.end(), required), names.end()) << required;
  for (const std::string& name : names) {
    const FabricParameters fabric = fabric_preset(name);
    EXPECT_EQ(fabric.name, name);
    EXPECT_NO_THROW(fabric.validate());
    // Plausible ranges for real fabrics (SI): 30-600 g/m², 1e2-1e5 N/m, 1e-7-1e-3 N·m.
    EXPECT_GT(fabric.area_density, 0.03);
    EXPECT_LT(fabric.area_density, 0.6);
    EXPECT_GT(fabric.stretch_weft, 1e2);
    EXPECT_LT(fabric.stretch_warp, 1e5);
    EXPECT_GT(fabric.bend, 1e-7);
    EXPECT_LT(fabric.bend, 1e-3);
  }
  // Denim is heavier and stiffer in bending than silk.
  EXPECT_GT(fabric_preset("denim").bend, 10 * fabric_preset("silk").bend);
  EXPECT_GT(fabric_preset("denim").area_density, fabric_preset("silk").area_density);
}

TEST(Fabric, PresetFilesOnDiskMatchTheEmbeddedCopies) {
  for (const std::string& name : fabric_preset_names()) {
    const FabricParameters on_disk =
        load_fabric_file(std::string(SD_SOURCE_DIR) + "/data/fabrics/" + name + ".json");
    EXPECT_DOUBLE_EQ(on_disk.stretch_warp, fabric_preset(name).stretch_warp) << name;
  }
}

TEST(Fabric, UnknownPresetNamesTheKnownOnes) {
  try {
    fabric_preset("velvet");
    FAIL() << "no error";
  } catch (const UnknownFabricError& error) {
    EXPECT_NE(std::string(error.what()).find("velvet"), std::string::npos);
    EXPECT_NE(std::string(error.what()).find("cotton"), std::string::npos);
  }
  EXPECT_THROW(fabric_preset("velvet"), std::invalid_argument);
}

TEST(Fabric, BadConstantsAreRejectedWithASentence) {
  FabricParameters fabric;
  fabric.stretch_warp = -1.0;
  try {
    fabric.validate();
    FAIL() << "no error";
  } catch (const InvalidFabricError& error) {
    EXPECT_NE(std::string(error.what()).find("warp stretch stiffness"), std::string::npos);
  }
  fabric = FabricParameters{};
  fabric.area_density = 0.0;
  EXPECT_THROW(fabric.validate(), InvalidFabricError);
  fabric = FabricParameters{};
  fabric.bend = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(fabric.validate(), InvalidFabricError);
  fabric = FabricParameters{};
  fabric.damping = -0.1;
  EXPECT_THROW(fabric.validate(), std::invalid_argument);
}

TEST(Fabric, ParsingChecksUnitsAndShape) {
  EXPECT_THROW(parse_fabric_json("{", "x.json"), InvalidFabricError);
  EXPECT_THROW(parse_fabric_json("[]", "x.json"), InvalidFabricError);
  std::string text(R"({"name": "t",
    "area_density": {"value": 0.1, "unit": "oz/yd^2"}})");
  try {
    parse_fabric_json(text, "x.json");
    FAIL() << "no error";
  } catch (const InvalidFabricError& error) {
    EXPECT_NE(std::string(error.what()).find("/area_density"), std::string::npos);
    EXPECT_NE(std::string(error.what()).find("kg/m^2"), std::string::npos);
  }
}

// KES-F and FAST measurements are converted with their units: cotton's preset written in KES-F
// units (W 13 mg/cm², EMT 5 % and 8 %, G 0.8 gf/cm/deg, B 0.1 gf·cm²/cm, T 0.3 mm) gives its SI
// constants; FAST's g/m², E100 and uN·m too. A unit the constant does not take names the ones it
// does, and a strain of zero is refused at its value.
TEST(Fabric, KesAndFastUnitsAreConverted) {
  const auto fabric = [](const std::string& w, const std::string& k, const std::string& g,
                         const std::string& b, const std::string& t) {
    return R"({"name": "t", "area_density": )" + w + R"(, "stretch_warp": )" + k +
           R"(, "stretch_weft": )" + k + R"(, "shear": )" + g + R"(, "bend": )" + b +
           R"(, "damping": {"value": 0.001, "unit": "s"},
               "bend_damping": {"value": 0.05, "unit": "s"},
               "friction": {"value": 0.3, "unit": "1"}, "thickness": )" +
           t + "}";
  };
  const FabricParameters kes = parse_fabric_json(
      fabric(R"({"value": 13.0, "unit": "mg/cm^2"})", R"({"value": 5.0, "unit": "% EMT"})",
             R"({"value": 0.8, "unit": "gf/cm/deg"})", R"({"value": 0.1, "unit": "gf*cm^2/cm"})",
             R"({"value": 0.3, "unit": "mm"})"),
      "kes.json");
  EXPECT_NEAR(kes.area_density, 0.130, 1e-12);
  EXPECT_NEAR(kes.stretch_warp, 9806.0, 1e-9);  // 490.3 N/m over 5 %
  EXPECT_NEAR(kes.shear, 0.8 * 0.9807 * 57.2958, 1e-9);
  EXPECT_NEAR(kes.bend, 9.807e-6, 1e-18);
  EXPECT_NEAR(kes.thickness, 3e-4, 1e-15);
  const FabricParameters fast = parse_fabric_json(
      fabric(R"({"value": 130.0, "unit": "g/m^2"})", R"({"value": 1.0, "unit": "% E100"})",
             R"({"value": 45.0, "unit": "N/m"})", R"({"value": 9.81, "unit": "uN*m"})",
             R"({"value": 0.3, "unit": "mm"})"),
      "fast.json");
  EXPECT_NEAR(fast.area_density, 0.130, 1e-12);
  EXPECT_NEAR(fast.stretch_weft, 9807.0, 1e-9);  // 98.07 N/m over 1 %
  EXPECT_NEAR(fast.bend, 9.81e-6, 1e-18);
  try {
    parse_fabric_json(
        fabric(R"({"value": 13.0, "unit": "mg/cm^2"})", R"({"value": 0.0, "unit": "% EMT"})",
               R"({"value": 45, "unit": "N/m"})", R"({"value": 0.1, "unit": "gf*cm^2/cm"})",
               R"({"value": 0.3, "unit": "mm"})"),
        "zero.json");
    FAIL() << "a zero EMT was accepted";
  } catch (const InvalidFabricError& error) {
    EXPECT_EQ(error.pointer(), "/stretch_warp/value");
    EXPECT_NE(std::string(error.what()).find("zero.json"), std::string::npos);
  }
  try {
    parse_fabric_json(
        fabric(R"({"value": 13.0, "unit": "mg/cm^2"})", R"({"value": 5.0, "unit": "% EMT"})",
               R"({"value": 45, "unit": "N/m"})", R"({"value": 0.1, "unit": "gf*cm"})",
               R"({"value": 0.3, "unit": "mm"})"),
        "unit.json");
    FAIL() << "an unknown unit was accepted";
  } catch (const InvalidFabricError& error) {
    EXPECT_EQ(error.pointer(), "/bend");
    EXPECT_NE(std::string(error.what()).find("N*m, gf*cm^2/cm (KES-F B) or uN*m (FAST B)"),
              std::string::npos)
        << error.what();
  }
}

// A cotton preset with a tensile curve added under `key` (the JSON text of the curve).
std::string cotton_with(const std::string& key, const std::string& curve) {
  return R"({"name": "c", "area_density": {"value": 0.13, "unit": "kg/m^2"},
             "stretch_warp": {"value": 9810, "unit": "N/m"},
             "stretch_weft": {"value": 6130, "unit": "N/m"},
             "shear": {"value": 45, "unit": "N/m"}, "bend": {"value": 9.81e-6, "unit": "N*m"},
             "damping": {"value": 0.001, "unit": "s"}, "bend_damping": {"value": 0.05, "unit": "s"},
             "friction": {"value": 0.3, "unit": "1"}, "thickness": {"value": 3e-4, "unit": "m"},
             ")" +
         key + R"(": )" + curve + "}";
}

// A key the fabric schema does not have is refused at its pointer with the nearest known key,
// at every level (the fabric, a constant, a tensile curve): a misspelt constant would otherwise
// be dropped, its preset default used without a word.
TEST(Fabric, UnknownKeysAreRefusedWithTheNearestKnownOne) {
  const auto refusal = [](const std::string& text) {
    try {
      parse_fabric_json(text, "x.json");
    } catch (const InvalidFabricError& e) {
      return e.pointer() + " | " + e.what();
    }
    return std::string("no error");
  };
  const std::string top = refusal(cotton_with("frictoin", R"({"value": 0.5, "unit": "1"})"));
  EXPECT_EQ(top.substr(0, top.find(" | ")), "/frictoin") << top;
  EXPECT_NE(top.find("x.json: /frictoin: unknown key 'frictoin' (did you mean 'friction'?)"),
            std::string::npos)
      << top;
  const std::string entry =
      refusal(cotton_with("tensile_warp", R"({"strain_unit": "%", "stress_unit": "N/m",
                                             "pionts": [[0, 0], [1, 10]]})"));
  EXPECT_EQ(entry.substr(0, entry.find(" | ")), "/tensile_warp/pionts") << entry;
  EXPECT_NE(entry.find("did you mean 'points'?"), std::string::npos) << entry;
  std::string constant = cotton_with("note", R"("a note")");
  constant.replace(constant.find(R"("unit": "N*m")"), 13, R"("unit": "N*m", "vlaue": 1)");
  const std::string value = refusal(constant);
  EXPECT_EQ(value.substr(0, value.find(" | ")), "/bend/vlaue") << value;
  EXPECT_NE(value.find("did you mean 'value'?"), std::string::npos) << value;
  // Far from every key: the known ones are listed instead.
  const std::string far = refusal(cotton_with("colour", R"("blue")"));
  EXPECT_NE(far.find("known keys here: name, description, note"), std::string::npos) << far;
  // The presets' own keys (description, note, a constant's source) are known.
  for (const std::string& name : fabric_preset_names()) EXPECT_NO_THROW(fabric_preset(name));
}

// A tensile curve in KES-F units (% strain, gf/cm) is converted to SI, and its energy, stress
// and tangent are the integral, the piecewise-linear interpolation and the segment's slope
// (beyond the last point the last slope continues).
TEST(Fabric, TensileCurveIsConvertedAndInterpolated) {
  const FabricParameters f =
      parse_fabric_json(cotton_with("tensile_warp",
                                    R"({"strain_unit": "%", "stress_unit": "gf/cm",
                      "points": [[0, 0], [1, 10], [3, 110]], "source": "a made-up curve"})"),
                        "curve.json");
  EXPECT_TRUE(f.tensile_weft.empty());
  ASSERT_EQ(f.tensile_warp.strain.size(), 3u);
  EXPECT_NEAR(f.tensile_warp.strain[2], 0.03, 1e-15);
  EXPECT_NEAR(f.tensile_warp.stress[1], 9.807, 1e-12);
  const double s1 = 9.807, s2 = 110 * 0.9807;  // N/m at 1 % and 3 %
  const double k1 = s1 / 0.01, k2 = (s2 - s1) / 0.02;
  TensileCurve::Point p = f.tensile_warp.at(0.005);
  EXPECT_NEAR(p.stress, 0.5 * s1, 1e-12);
  EXPECT_NEAR(p.tangent, k1, 1e-9);
  EXPECT_NEAR(p.energy, 0.5 * k1 * 0.005 * 0.005, 1e-15);
  p = f.tensile_warp.at(0.02);
  EXPECT_NEAR(p.stress, s1 + k2 * 0.01, 1e-12);
  EXPECT_NEAR(p.tangent, k2, 1e-9);
  EXPECT_NEAR(p.energy, 0.5 * s1 * 0.01 + s1 * 0.01 + 0.5 * k2 * 0.01 * 0.01, 1e-14);
  p = f.tensile_warp.at(0.04);  // past the end: the last slope
  EXPECT_NEAR(p.stress, s2 + k2 * 0.01, 1e-12);
  EXPECT_NEAR(p.tangent, k2, 1e-9);
  // The energy is the integral of the stress: a central difference of W gives σ.
  for (double e : {0.002, 0.0101, 0.025, 0.05}) {
    const double h = 1e-7;
    EXPECT_NEAR((f.tensile_warp.at(e + h).energy - f.tensile_warp.at(e - h).energy) / (2 * h),
                f.tensile_warp.at(e).stress, 1e-6)
        << e;
  }
}

// A curve built in code is checked by validate() too (TensileCurve::at needs its shape).
TEST(Fabric, ValidateChecksTensileCurvesBuiltInCode) {
  FabricParameters f;
  f.tensile_weft.strain = {0.0, 0.01};
  f.tensile_weft.stress = {0.0, 5.0};
  EXPECT_NO_THROW(f.validate());
  f.tensile_weft.stress = {0.0};  // sizes differ
  EXPECT_THROW(f.validate(), InvalidFabricError);
  f.tensile_weft.stress = {0.0, -1.0};  // falls
  EXPECT_THROW(f.validate(), InvalidFabricError);
  f.tensile_weft = {};
  f.tensile_warp.strain = {0.01};
  f.tensile_warp.stress = {1.0};
  try {
    f.validate();
    FAIL() << "a one-point curve was accepted";
  } catch (const InvalidFabricError& e) {
    EXPECT_EQ(e.pointer(), "/tensile_warp");
  }
}

// A bad curve is refused at its JSON path with a sentence: not an object, a unit that is not
// one of the listed, too few points, not starting at [0, 0], a negative value, a strain that
// does not increase, a stress that falls (non-monotone).
TEST(Fabric, BadTensileCurvesAreRefusedAtTheirPath) {
  struct Case {
    std::string curve, pointer, words;
  };
  const std::string units = R"("strain_unit": "1", "stress_unit": "N/m", )";
  for (const Case& c : {
           Case{"[1, 2]", "/tensile_weft", "must be an object"},
           Case{R"({"strain_unit": "mm", "stress_unit": "N/m", "points": [[0, 0], [1, 1]]})",
                "/tensile_weft/strain_unit", "\"1\" or \"%\""},
           Case{R"({"strain_unit": "%", "stress_unit": "N", "points": [[0, 0], [1, 1]]})",
                "/tensile_weft/stress_unit", "\"N/m\" or \"gf/cm\""},
           Case{"{" + units + R"("points": [[0, 0]]})", "/tensile_weft/points", "at least two"},
           Case{"{" + units + R"("points": [[0.01, 0], [0.02, 5]]})", "/tensile_weft/points/0",
                "must be [0, 0]"},
           Case{"{" + units + R"("points": [[0, 0], [0.01, -5]]})", "/tensile_weft/points/1",
                "negative"},
           Case{"{" + units + R"("points": [[0, 0], [0.02, 5], [0.01, 8]]})",
                "/tensile_weft/points/2", "strain does not increase"},
           Case{"{" + units + R"("points": [[0, 0], [0.01, 5], [0.02, 4]]})",
                "/tensile_weft/points/2", "stress does not increase"},
           Case{"{" + units + R"("points": [[0, 0], [0.01]]})", "/tensile_weft/points/1",
                "pair [strain, stress]"},
       }) {
    try {
      parse_fabric_json(cotton_with("tensile_weft", c.curve), "bad.json");
      FAIL() << "accepted: " << c.curve;
    } catch (const InvalidFabricError& error) {
      EXPECT_EQ(error.pointer(), c.pointer) << c.curve << ": " << error.what();
      EXPECT_NE(std::string(error.what()).find(c.words), std::string::npos) << error.what();
      EXPECT_NE(std::string(error.what()).find("bad.json"), std::string::npos) << error.what();
    }
  }
}

}  // namespace
}  // namespace sd::sim
