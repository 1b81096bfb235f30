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

// One "<file>: /panels/N: curve 'shoulder' is a seam between 'front' and 'back', but its copy
// 'shoulder.mirror' borders only 'front.mirror': is "mirror": true missing on panel 'back'?" line
// per curve whose mirror copy borders fewer panels than the curve itself (trial 42, P9: a blouse
// with "mirror": true left off its back validated "ok" with the right back missing). The path is
// the panel that borders the curve while its copy has no mirror copy of that panel. Counted by
// `validate --strict` and `mesh --strict` with the curves in no panel.
std::vector<std::string> half_mirrored_warnings(const GarmentRequest& sketch,
                                                const Garment& garment);

}  // namespace sd::garment
