#pragma once
// What real fabrics measure: each constant's physical range (outside it no woven or knitted
// fabric has the value: an error) and the usual range of apparel fabrics (outside it a warning).
// The ranges and their sources: docs/fabrics.md, "Physical ranges".

#include <string>
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

// The constants inside their physical range but outside apparel fabrics' usual one.
std::vector<FabricNote> unusual_constants(const FabricParameters& fabric);

}  // namespace sd::sim
