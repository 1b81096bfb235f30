#include "sim/fabric_ranges.hpp"

#include <sstream>
#include <string>
#include <vector>

namespace sd::sim {
namespace {

// What real fabrics measure, per constant (docs/fabrics.md, "Physical ranges", gives the
// sources): outside [lowest, highest] no woven or knitted fabric has the value (an error: the
// drape would fail or mean nothing), outside [usual_low, usual_high] few apparel fabrics do (a
// warning: possible, but more likely a unit slip).
struct PhysicalRange {
  const char* key;
  const char* what;
  const char* unit;
  double FabricParameters::*field;
  double lowest, usual_low, usual_high, highest;
  const char* usual;  // the usual range in the designer's terms, with its source
};

constexpr PhysicalRange kRanges[] = {
    {"area_density", "area density", "kg/m^2", &FabricParameters::area_density, 0.005, 0.02, 0.8,
     3.0,
     "apparel fabrics weigh 0.02-0.8 kg/m^2 (20 g/m^2 chiffon to 800 g/m^2 coating wool); "
     "nothing woven or knitted is below 5 g/m^2 or above 3 kg/m^2"},
    {"stretch_warp", "warp stretch stiffness", "N/m", &FabricParameters::stretch_warp, 20.0, 300.0,
     1e5, 1e7,
     "apparel fabrics measure 300-100000 N/m (KES-F EMT 160 % to 0.5 % at 500 gf/cm: stretch "
     "knits to tight wovens); below 20 N/m a 1 m drop of 200 g/m^2 cloth would stretch 10 % "
     "under its own weight, above 1e7 N/m it is stiffer than steel foil"},
    {"stretch_weft", "weft stretch stiffness", "N/m", &FabricParameters::stretch_weft, 20.0, 300.0,
     1e5, 1e7,
     "apparel fabrics measure 300-100000 N/m (KES-F EMT 160 % to 0.5 % at 500 gf/cm: stretch "
     "knits to tight wovens); below 20 N/m a 1 m drop of 200 g/m^2 cloth would stretch 10 % "
     "under its own weight, above 1e7 N/m it is stiffer than steel foil"},
    {"shear", "shear stiffness", "N/m", &FabricParameters::shear, 0.0, 3.0, 600.0, 1e4,
     "apparel fabrics measure 3-600 N/m (KES-F G 0.05-10 gf/cm/deg); above 10000 N/m a fabric "
     "could not shear to follow a body at all"},
    {"bend", "bending rigidity", "N*m", &FabricParameters::bend, 0.0, 4e-7, 5e-4, 1e-2,
     "apparel fabrics measure 4e-7 to 5e-4 N*m (KES-F B 0.004-5 gf*cm^2/cm: sheer silk to heavy "
     "denim); above 1e-2 N*m it is stiffer than cardboard"},
    {"damping", "damping", "s", &FabricParameters::damping, 0.0, 0.0, 0.01, 1.0,
     "the presets use 0.001 s; from 1 s on even the slowest stretch of a garment is damped "
     "hundreds of times past critical and the cloth creeps like dough"},
    {"bend_damping", "bend damping", "s", &FabricParameters::bend_damping, 0.0, 0.0, 0.5, 10.0,
     "the presets use 0.05 s; from 10 s on folds would take minutes to fall"},
    {"friction", "friction", "", &FabricParameters::friction, 0.0, 0.0, 1.5, 2.0,
     "fabric on skin measures about 0.2-1.0 dry and up to 1.5 on moist skin; above 2 no fabric "
     "grips skin, and the contacts fling the cloth"},
    {"thickness", "thickness", "m", &FabricParameters::thickness, 1e-5, 5e-5, 5e-3, 0.02,
     "apparel fabrics are 0.05-5 mm thick (KES-F/FAST T); nothing is thinner than one fibre "
     "(0.01 mm) or thicker than 2 cm"},
};

// The range's explanation as a sentence of its own.
std::string sentence_case(std::string text) {
  if (!text.empty() && text[0] >= 'a' && text[0] <= 'z') text[0] = static_cast<char>(text[0] - 32);
  return text;
}

// "30" or "0.0005": short, with the unit after a space when there is one.
std::string value_text(double value, const char* unit) {
  std::ostringstream text;
  text << value << (*unit != '\0' ? " " : "") << unit;
  return text.str();
}

}  // namespace

void check_physical_range(const FabricParameters& fabric) {
  // Finite and of the right sign, but no fabric has it (friction 30 crashed the drape at 1.66 s;
  // a warp stiffness of 0.5 N/m let a top sag 5.5 cm).
  for (const PhysicalRange& r : kRanges) {
    const double value = fabric.*r.field;
    if (value >= r.lowest && value <= r.highest) continue;
    std::ostringstream message;
    message << "fabric '" << fabric.name << "': " << r.what << " is " << value_text(value, r.unit)
            << ", which no real fabric has: it must lie between " << value_text(r.lowest, r.unit)
            << " and " << value_text(r.highest, r.unit) << ". " << sentence_case(r.usual);
    throw InvalidFabricError(message.str(), std::string("/") + r.key);
  }
}

int physical_range_fit(std::string_view key, double value) {
  for (const PhysicalRange& r : kRanges) {
    if (key != r.key) continue;
    if (!(value >= r.lowest && value <= r.highest)) return 0;
    return value >= r.usual_low && value <= r.usual_high ? 2 : 1;
  }
  return -1;
}

std::vector<FabricNote> unusual_constants(const FabricParameters& fabric) {
  std::vector<FabricNote> notes;
  for (const PhysicalRange& r : kRanges) {
    const double value = fabric.*r.field;
    if (value >= r.usual_low && value <= r.usual_high) continue;
    std::ostringstream message;
    message << "fabric '" << fabric.name << "': " << r.what << " " << value_text(value, r.unit)
            << " is unusual: " << r.usual << "; check the value and its unit";
    notes.push_back({std::string("/") + r.key, message.str()});
  }
  return notes;
}

}  // namespace sd::sim
