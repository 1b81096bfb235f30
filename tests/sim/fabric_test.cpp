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

}  // namespace
}  // namespace sd::sim
