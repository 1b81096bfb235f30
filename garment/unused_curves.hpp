#pragma once
// Curves of a sketch that no panel uses: meshed into nothing, so a panel the designer meant to
// draw is missing, or a boundary list names another curve than meant (trial 40, P5: a curve
// drawn exactly over a panel's edge and named by no panel was silently ignored).

#include <string>
#include <vector>

#include "garment/garment_mesh.hpp"
#include "garment/garment_request.hpp"

namespace sd::garment {

// One "<file>: /curves/N: curve '<id>' is in no panel: ..." line per curve of `sketch` that is
// on no panel's outline in `garment` (a curve used only by a mirror copy, as '<id>.mirror',
// counts as used), in file order. `validate --strict` and `mesh --strict` count them.
std::vector<std::string> unused_curve_warnings(const GarmentRequest& sketch,
                                               const Garment& garment);

}  // namespace sd::garment
