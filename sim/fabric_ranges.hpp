#pragma once
// What real fabrics measure: each constant's physical range (outside it no woven or knitted
// fabric has the value: an error) and the usual range of apparel fabrics (outside it a warning).
// The ranges and their sources: docs/fabrics.md, "Physical ranges".

#include <string>
#include <string_view>
#include <vector>

#include "sim/fabric.hpp"

namespace sd::sim {

// A constant a real fabric can have but few apparel fabrics do (a warning, not an error).
struct FabricNote {
  std::string pointer;   // "/friction", as InvalidFabricError::pointer
  std::string sentence;  // "fabric 'x': friction 1.8 is unusual (...); check ..."
};

// Throws InvalidFabricError (pointer "/friction") for the first constant outside its physical
// range. parse_fabric_json applies it to every preset, fabric file and inline fabric; a fabric
// built in code is not held to it (the stress matrix scales cotton's stiffness by 1e6).
void check_physical_range(const FabricParameters& fabric);

// How `value` (in the SI unit) of constant `key` ("area_density") compares with what fabrics
// measure: 2 within the usual range of apparel fabrics, 1 within the physical range only, 0
// outside it; -1 for a key without a range. For the unit a slip was likely typed in.
int physical_range_fit(std::string_view key, double value);

// The constants inside their physical range but outside apparel fabrics' usual one.
std::vector<FabricNote> unusual_constants(const FabricParameters& fabric);

}  // namespace sd::sim
