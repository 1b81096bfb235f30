#include "sim/fabric.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <utility>

namespace sd::sim {
namespace detail {
const std::vector<std::pair<std::string_view, std::string_view>>& embedded_fabric_presets();
}

namespace {

enum class Bound { positive, non_negative };

void check_constant(const std::string& fabric, const char* key, const char* what, double value,
                    Bound bound, const char* unit) {
  const bool ok = std::isfinite(value) && (bound == Bound::positive ? value > 0.0 : value >= 0.0);
  if (!ok) {
    std::ostringstream message;
    message << "fabric '" << fabric << "': " << what << " is " << value << " " << unit
            << " but must be " << (bound == Bound::positive ? "greater than zero" : "zero or more")
            << " and finite";
    throw InvalidFabricError(message.str(), std::string("/") + key);
  }
}

struct ConstantSpec {
  const char* key;
  const char* unit;
  double FabricParameters::*field;
};

constexpr ConstantSpec kConstants[] = {
    {"area_density", "kg/m^2", &FabricParameters::area_density},
    {"stretch_warp", "N/m", &FabricParameters::stretch_warp},
    {"stretch_weft", "N/m", &FabricParameters::stretch_weft},
    {"shear", "N/m", &FabricParameters::shear},
    {"bend", "N*m", &FabricParameters::bend},
    {"damping", "s", &FabricParameters::damping},
    {"bend_damping", "s", &FabricParameters::bend_damping},
    {"friction", "1", &FabricParameters::friction},
    {"thickness", "m", &FabricParameters::thickness},
};

}  // namespace

void FabricParameters::validate() const {
  check_constant(name, "area_density", "area density", area_density, Bound::positive, "kg/m^2");
  check_constant(name, "stretch_warp", "warp stretch stiffness", stretch_warp, Bound::positive,
                 "N/m");
  check_constant(name, "stretch_weft", "weft stretch stiffness", stretch_weft, Bound::positive,
                 "N/m");
  check_constant(name, "shear", "shear stiffness", shear, Bound::non_negative, "N/m");
  check_constant(name, "bend", "bending rigidity", bend, Bound::non_negative, "N*m");
  check_constant(name, "damping", "damping", damping, Bound::non_negative, "s");
  check_constant(name, "bend_damping", "bend damping", bend_damping, Bound::non_negative, "s");
  check_constant(name, "friction", "friction", friction, Bound::non_negative, "");
  check_constant(name, "thickness", "thickness", thickness, Bound::positive, "m");
}

FabricParameters parse_fabric_json(std::string_view text, const std::string& origin) {
  nlohmann::json document;
  try {
    document = nlohmann::json::parse(text, nullptr, true, /*ignore_comments=*/true);
  } catch (const nlohmann::json::parse_error& error) {
    throw InvalidFabricError(origin + ": not valid JSON (" + error.what() + ")");
  }
  if (!document.is_object()) throw InvalidFabricError(origin + ": a fabric must be a JSON object");
  FabricParameters fabric;
  if (document.contains("name")) {
    if (!document["name"].is_string())
      throw InvalidFabricError(origin + ": /name must be a string", "/name");
    fabric.name = document["name"].get<std::string>();
  }
  for (const ConstantSpec& spec : kConstants) {
    const std::string pointer = std::string("/") + spec.key;
    if (!document.contains(spec.key))
      throw InvalidFabricError(origin + ": " + pointer + " is missing (expected {\"value\": ..., " +
                                   "\"unit\": \"" + spec.unit + "\"})",
                               pointer);
    const nlohmann::json& entry = document[spec.key];
    if (!entry.is_object() || !entry.contains("value") || !entry["value"].is_number())
      throw InvalidFabricError(origin + ": " + pointer + " must be an object with a numeric value",
                               pointer);
    if (!entry.contains("unit") || entry["unit"] != spec.unit)
      throw InvalidFabricError(origin + ": " + pointer + " must be given in " + spec.unit, pointer);
    fabric.*spec.field = entry["value"].get<double>();
  }
  try {
    fabric.validate();
  } catch (const InvalidFabricError& e) {
    throw InvalidFabricError(origin + ": " + e.what(), e.pointer());
  }
  return fabric;
}

FabricParameters load_fabric_file(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw InvalidFabricError("cannot read fabric file '" + path + "'");
  std::ostringstream text;
  text << file.rdbuf();
  return parse_fabric_json(text.str(), path);
}

FabricParameters fabric_preset(std::string_view name) {
  for (const auto& [preset, text] : detail::embedded_fabric_presets())
    if (preset == name) return parse_fabric_json(text, "fabric preset '" + std::string(name) + "'");
  std::string known;
  for (const std::string& preset : fabric_preset_names())
    known += (known.empty() ? "" : ", ") + preset;
  throw UnknownFabricError("unknown fabric '" + std::string(name) + "' (known fabrics: " + known +
                           ")");
}

std::vector<std::string> fabric_preset_names() {
  std::vector<std::string> names;
  for (const auto& entry : detail::embedded_fabric_presets()) names.emplace_back(entry.first);
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace sd::sim
