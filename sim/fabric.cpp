#include "sim/fabric.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "sim/edit_distance.hpp"
#include "sim/fabric_ranges.hpp"
#include "sim/strict_json.hpp"

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
    message << "fabric '" << fabric << "': " << what << " is " << value
            << (*unit != '\0' ? " " : "") << unit << " but must be "
            << (bound == Bound::positive ? "greater than zero" : "zero or more") << " and finite";
    throw InvalidFabricError(message.str(), std::string("/") + key);
  }
}

struct ConstantSpec {
  const char* key;
  const char* unit;
  double FabricParameters::*field;
};

// A unit a constant may also be given in, with its conversion to the SI unit: value × scale,
// or for a strain at a standard load (KES-F EMT, FAST E100, in %) load / (value / 100), the
// secant stiffness up to that load.
struct UnitSpec {
  const char* key;
  const char* unit;
  double scale;      // SI per unit; 0 for a strain at a load
  double load;       // N/m, the standard load of a strain unit
  const char* what;  // where the unit comes from, for the error message
};

constexpr UnitSpec kOtherUnits[] = {
    {"area_density", "g/m^2", 1e-3, 0.0, "FAST W"},
    {"area_density", "mg/cm^2", 1e-2, 0.0, "KES-F W"},
    // 500 gf/cm = 490.3 N/m, the KES-F tensile test's maximum load.
    {"stretch_warp", "% EMT", 0.0, 490.3, "KES-F EMT, strain at 500 gf/cm"},
    {"stretch_weft", "% EMT", 0.0, 490.3, "KES-F EMT, strain at 500 gf/cm"},
    // 100 gf/cm = 98.07 N/m, FAST-3's extensibility load.
    {"stretch_warp", "% E100", 0.0, 98.07, "FAST E100, strain at 100 gf/cm"},
    {"stretch_weft", "% E100", 0.0, 98.07, "FAST E100, strain at 100 gf/cm"},
    // 1 gf/cm per degree = 0.9807 N/m × 57.30 per radian.
    {"shear", "gf/cm/deg", 0.9807 * 57.2958, 0.0, "KES-F G"},
    // 1 gf·cm²/cm = 9.807e-3 N × 0.01 m.
    {"bend", "gf*cm^2/cm", 9.807e-5, 0.0, "KES-F B"},
    {"bend", "uN*m", 1e-6, 0.0, "FAST B"},
    {"thickness", "mm", 1e-3, 0.0, "KES-F or FAST T"},
};

// "N*m, gf*cm^2/cm (KES-F B) or uN*m (FAST B)": the units `key` accepts.
std::string accepted_units(const ConstantSpec& spec) {
  std::vector<std::string> units = {spec.unit};
  for (const UnitSpec& other : kOtherUnits)
    if (std::string_view(other.key) == spec.key)
      units.push_back(std::string(other.unit) + " (" + other.what + ")");
  std::string text = units.front();
  for (size_t i = 1; i < units.size(); ++i)
    text += (i + 1 == units.size() ? " or " : ", ") + units[i];
  return text;
}

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

// The units a tensile curve's points may be written in: strain as a fraction ("1") or in percent
// (KES-F, FAST), stress in N/m or gf/cm (KES-F's tensile load per centimetre of width).
struct CurveUnit {
  const char* name;
  double scale;  // to the SI quantity
};
constexpr CurveUnit kStrainUnits[] = {{"1", 1.0}, {"%", 0.01}};
constexpr CurveUnit kStressUnits[] = {{"N/m", 1.0}, {"gf/cm", 0.9807}};

// The known key a designer most likely meant by `key`: a close spelling, or a known key that
// `key` is one word of ("density" for "area_density", "tensile" for "tensile_warp").
std::string_view meant_key(std::string_view key, const std::vector<std::string_view>& known) {
  std::string_view best;
  size_t best_distance = 3;  // suggest only close spellings
  for (std::string_view k : known)
    if (const size_t d = edit_distance(key, k); d < best_distance) best = k, best_distance = d;
  if (!best.empty() || key.empty()) return best;
  for (std::string_view k : known)
    if ((k.size() > key.size() && k.ends_with(key) && k[k.size() - key.size() - 1] == '_') ||
        (k.size() > key.size() && k.starts_with(key) && k[key.size()] == '_'))
      return k;
  return {};
}

// Refuses the keys of `object` (at `pointer`) not in `known`, as the sketch reader does: a
// misspelt constant would otherwise be dropped silently (a "frictoin" next to the default
// "friction") or reported only as the correct key missing. Every unknown key is named, each
// with what it probably meant (trial 41, P11: {"preset": "cotton", "density": 0} named only
// 'density' and offered no 'area_density').
void check_fabric_keys(const nlohmann::json& object, const std::string& where,
                       const std::string& pointer, const std::vector<std::string_view>& known) {
  std::vector<std::string> unknown;
  bool all_placed = true;  // every unknown key has a suggestion
  for (const auto& [key, value] : object.items()) {
    if (std::find(known.begin(), known.end(), key) != known.end()) continue;
    std::string text = "'" + key + "'";
    if (const std::string_view best = meant_key(key, known); !best.empty()) {
      text += " (did you mean '" + std::string(best) + "'?)";
    } else if (key == "preset" || key == "base" || key == "based_on" || key == "fabric") {
      // A preset with changes is a natural guess; it does not exist.
      text +=
          " (a fabric object cannot start from a preset and change some of its constants: it "
          "gives every constant itself; copy data/fabrics/<preset>.json, change it and give "
          "its path instead)";
    } else {
      all_placed = false;
    }
    unknown.push_back(text);
  }
  if (unknown.empty()) return;
  std::string sentence = unknown.size() == 1 ? "unknown key " : "unknown keys ";
  for (size_t i = 0; i < unknown.size(); ++i)
    sentence += (i == 0 ? "" : (i + 1 == unknown.size() ? " and " : ", ")) + unknown[i];
  if (!all_placed) {
    sentence += " (known keys here: ";
    for (size_t i = 0; i < known.size(); ++i)
      sentence += std::string(i == 0 ? "" : ", ") + std::string(known[i]);
    sentence += ")";
  }
  // The path of the first (in the order the JSON reader gives them, alphabetical).
  std::string first;
  for (const auto& [key, value] : object.items())
    if (std::find(known.begin(), known.end(), key) == known.end()) {
      first = key;
      break;
    }
  throw InvalidFabricError(where + ": " + pointer + "/" + first + ": " + sentence,
                           pointer + "/" + first);
}

template <size_t N>
double curve_unit_scale(const nlohmann::json& curve, const char* key, const CurveUnit (&units)[N],
                        const std::string& where, const std::string& pointer) {
  std::string names;
  for (size_t i = 0; i < N; ++i)
    names += std::string(i == 0 ? "" : (i + 1 == N ? " or " : ", ")) + "\"" + units[i].name + "\"";
  const std::string at = pointer + "/" + key;
  if (!curve.contains(key) || !curve[key].is_string())
    throw InvalidFabricError(where + ": " + at + " must be given: " + names, at);
  const std::string unit = curve[key].get<std::string>();
  for (const CurveUnit& u : units)
    if (unit == u.name) return u.scale;
  throw InvalidFabricError(where + ": " + at + " is \"" + unit + "\" but must be " + names, at);
}

// {"strain_unit": "%", "stress_unit": "gf/cm", "points": [[0, 0], [1.2, 50], ...]}: a tensile
// curve from (0, 0) with strain and stress both strictly increasing (a curve that falls or
// stays flat would let the cloth stretch without limit under a constant load).
TensileCurve parse_tensile_curve(const nlohmann::json& curve, const std::string& where,
                                 const std::string& pointer) {
  if (!curve.is_object())
    throw InvalidFabricError(where + ": " + pointer +
                                 " must be an object {\"strain_unit\", \"stress_unit\", "
                                 "\"points\": [[strain, stress], ...]}",
                             pointer);
  check_fabric_keys(curve, where, pointer, {"strain_unit", "stress_unit", "points", "source"});
  const double strain_scale = curve_unit_scale(curve, "strain_unit", kStrainUnits, where, pointer);
  const double stress_scale = curve_unit_scale(curve, "stress_unit", kStressUnits, where, pointer);
  const std::string points_at = pointer + "/points";
  if (!curve.contains("points") || !curve["points"].is_array() || curve["points"].size() < 2)
    throw InvalidFabricError(
        where + ": " + points_at +
            " must list at least two [strain, stress] points, the first [0, 0]",
        points_at);
  TensileCurve result;
  const nlohmann::json& points = curve["points"];
  for (size_t i = 0; i < points.size(); ++i) {
    const std::string at = points_at + "/" + std::to_string(i);
    const nlohmann::json& p = points[i];
    if (!p.is_array() || p.size() != 2 || !p[0].is_number() || !p[1].is_number())
      throw InvalidFabricError(where + ": " + at + " must be a pair [strain, stress] of numbers",
                               at);
    const double strain = p[0].get<double>() * strain_scale;
    const double stress = p[1].get<double>() * stress_scale;
    if (!std::isfinite(strain) || !std::isfinite(stress) || strain < 0.0 || stress < 0.0)
      throw InvalidFabricError(where + ": " + at +
                                   " has a negative or non-finite value: a tensile curve's strains "
                                   "and stresses are zero or more",
                               at);
    if (i == 0 && (strain != 0.0 || stress != 0.0))
      throw InvalidFabricError(where + ": " + at + " must be [0, 0]: the curve starts unloaded",
                               at);
    if (i > 0 && !(strain > result.strain.back()))
      throw InvalidFabricError(where + ": " + at +
                                   ": the strain does not increase (each point's "
                                   "strain must be greater than the one before)",
                               at);
    if (i > 0 && !(stress > result.stress.back()))
      throw InvalidFabricError(where + ": " + at +
                                   ": the stress does not increase with the "
                                   "strain (the curve must rise: a falling or flat segment lets "
                                   "the fabric stretch without limit)",
                               at);
    result.strain.push_back(strain);
    result.stress.push_back(stress);
  }
  return result;
}

}  // namespace

TensileCurve::Point TensileCurve::at(double e) const {
  // The segment ε lies on (the last one beyond the curve's end), and the energy up to its start.
  Point p;
  size_t i = 0;
  for (; i + 2 < strain.size() && e > strain[i + 1]; ++i)
    p.energy += 0.5 * (stress[i] + stress[i + 1]) * (strain[i + 1] - strain[i]);
  p.tangent = (stress[i + 1] - stress[i]) / (strain[i + 1] - strain[i]);
  const double d = e - strain[i];
  p.stress = stress[i] + p.tangent * d;
  p.energy += stress[i] * d + 0.5 * p.tangent * d * d;
  return p;
}

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
  // A curve built in code (the parser checks its own with the point's path): the shape
  // TensileCurve::at relies on.
  for (const auto& [key, curve] :
       {std::pair{"tensile_warp", &tensile_warp}, std::pair{"tensile_weft", &tensile_weft}}) {
    if (curve->empty() && curve->stress.empty()) continue;
    bool ok = curve->strain.size() >= 2 && curve->strain.size() == curve->stress.size() &&
              curve->strain[0] == 0.0 && curve->stress[0] == 0.0;
    for (size_t i = 1; ok && i < curve->strain.size(); ++i)
      ok = std::isfinite(curve->strain[i]) && std::isfinite(curve->stress[i]) &&
           curve->strain[i] > curve->strain[i - 1] && curve->stress[i] > curve->stress[i - 1];
    if (!ok)
      throw InvalidFabricError("fabric '" + name + "': the " + key +
                                   " curve must start at (0, 0) and rise in both strain and "
                                   "stress over at least two points",
                               std::string("/") + key);
  }
}

namespace {

// For a constant written in its SI unit and refused by its range: "; if you meant 135 g/m^2
// (FAST W), write "unit": "g/m^2"", for the other units that read it within the usual range of
// apparel fabrics (else within the physical range); empty when none does.
std::string unit_slip_hint(const nlohmann::json& document, const std::string& pointer) {
  if (pointer.size() < 2) return "";
  const std::string key = pointer.substr(1);
  const ConstantSpec* spec = nullptr;
  for (const ConstantSpec& s : kConstants)
    if (key == s.key) spec = &s;
  if (spec == nullptr || !document.contains(key) || !document[key].is_object()) return "";
  const nlohmann::json& entry = document[key];
  if (!entry.contains("unit") || entry["unit"] != spec->unit || !entry["value"].is_number())
    return "";
  const double value = entry["value"].get<double>();
  for (const int wanted : {2, 1}) {
    std::string hint;
    for (const UnitSpec& other : kOtherUnits) {
      if (std::string_view(other.key) != key || !(other.scale > 0.0)) continue;
      if (physical_range_fit(key, value * other.scale) != wanted) continue;
      std::ostringstream reading;
      reading << (hint.empty() ? "" : "; or") << " " << value << " " << other.unit << " ("
              << other.what << "), write \"unit\": \"" << other.unit << "\"";
      hint += reading.str();
    }
    if (!hint.empty()) return "; if you meant" + hint;
  }
  return "";
}

}  // namespace

FabricParameters parse_fabric_json(std::string_view text, const std::string& origin) {
  nlohmann::json document;
  try {
    // A key given twice, or nesting deeper than a fabric needs, is refused at its path as in a
    // sketch (trial 39, P1: a file with "friction" 0.4 then 30 was read as 30 without a word).
    const sim::StrictJsonCallback strict(
        [&origin](const std::string& path, const std::string& sentence) {
          throw InvalidFabricError(origin + ": " + path + ": " + sentence, path);
        },
        "a fabric file", 5);
    document = nlohmann::json::parse(text, strict, true, /*ignore_comments=*/true);
  } catch (const nlohmann::json::parse_error& error) {
    // As a sketch's syntax error is said: where, then the parser's words without its exception
    // name (trial 43, P16: "[json.exception.parse_error.101] parse error at line 1, ...").
    std::string detail = error.what(), where;
    if (const size_t bracket = detail.find("] ");
        detail.starts_with("[json.exception") && bracket != std::string::npos)
      detail = detail.substr(bracket + 2);
    if (detail.starts_with("parse error at ")) {
      const size_t colon = detail.find(": ");
      if (colon != std::string::npos) {
        where = detail.substr(15, colon - 15) + ": ";
        detail = detail.substr(colon + 2);
      }
    }
    throw InvalidFabricError(origin + ": " + where + "the file is not valid JSON (" + detail + ")");
  }
  if (!document.is_object()) throw InvalidFabricError(origin + ": a fabric must be a JSON object");
  FabricParameters fabric;
  {
    std::vector<std::string_view> known = {"name", "description", "note", "tensile_warp",
                                           "tensile_weft"};
    for (const ConstantSpec& spec : kConstants) known.emplace_back(spec.key);
    check_fabric_keys(document, origin, "", known);
  }
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
    check_fabric_keys(entry, origin, pointer, {"value", "unit", "source", "note"});
    const double value = entry["value"].get<double>();
    const std::string unit =
        entry.contains("unit") && entry["unit"].is_string() ? entry["unit"].get<std::string>() : "";
    const UnitSpec* other = nullptr;
    for (const UnitSpec& candidate : kOtherUnits)
      if (std::string_view(candidate.key) == spec.key && unit == candidate.unit) other = &candidate;
    if (unit != spec.unit && other == nullptr)
      throw InvalidFabricError(
          origin + ": " + pointer + " must be given in " + accepted_units(spec), pointer);
    if (other == nullptr) {
      fabric.*spec.field = value;
    } else if (other->scale > 0.0) {
      fabric.*spec.field = value * other->scale;
    } else {
      if (!(value > 0.0 && std::isfinite(value)))
        throw InvalidFabricError(origin + ": " + pointer + " is a strain of " +
                                     std::to_string(value) + " % (" + other->what +
                                     ") but must be greater than zero and finite",
                                 pointer + "/value");
      fabric.*spec.field = other->load / (value / 100.0);
    }
  }
  for (const auto& [key, curve] : {std::pair{"tensile_warp", &fabric.tensile_warp},
                                   std::pair{"tensile_weft", &fabric.tensile_weft}})
    if (document.contains(key))
      *curve = parse_tensile_curve(document[key], origin, std::string("/") + key);
  try {
    fabric.validate();
    check_physical_range(fabric);
  } catch (const InvalidFabricError& e) {
    // The constant's key in the file (the sketch's error names the sketch's own path), and the
    // unit it was likely meant in when written in the SI unit (trial 43, P16: a FAST weight of
    // 135 typed with "kg/m^2" was refused with the range alone).
    throw InvalidFabricError(origin + ": " + (e.pointer().empty() ? "" : e.pointer() + ": ") +
                                 e.what() + unit_slip_hint(document, e.pointer()),
                             e.pointer());
  }
  return fabric;
}

FabricParameters load_fabric_file(const std::string& path) {
  // The absolute path and the reason: a relative name is resolved against the sketch's folder,
  // which is not always the folder the designer thinks of.
  namespace fs = std::filesystem;
  std::error_code error;
  fs::path shown = fs::absolute(path, error);
  if (error) shown = path;
  shown = shown.lexically_normal();
  const auto fail = [&](const std::string& reason) {
    throw InvalidFabricError("cannot read fabric file '" + shown.string() + "': " + reason);
  };
  const fs::file_status status = fs::status(path, error);
  if (status.type() == fs::file_type::not_found) fail("it does not exist");
  if (error) fail(error.message());
  if (fs::is_directory(status)) fail("it is a folder, not a file");
  if (!fs::is_regular_file(status)) fail("it is not a regular file");
  std::ifstream file(path);
  if (!file) fail(std::string(std::strerror(errno)) + " (check the file's permissions)");
  std::ostringstream text;
  text << file.rdbuf();
  // Named as given, without "a/../" (a sketch in mistakes/ naming "../fabrics/x.json").
  return parse_fabric_json(text.str(), fs::path(path).lexically_normal().string());
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
