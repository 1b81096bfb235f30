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
    "area_density": {"value": 0.1, "unit": "g/m^2"}})");
  try {
    parse_fabric_json(text, "x.json");
    FAIL() << "no error";
  } catch (const InvalidFabricError& error) {
    EXPECT_NE(std::string(error.what()).find("/area_density"), std::string::npos);
    EXPECT_NE(std::string(error.what()).find("kg/m^2"), std::string::npos);
  }
}

}  // namespace
}  // namespace sd::sim
