#pragma once
// Seams whose two sides rest at lengths too different for the drape to settle: a panel's `ease`
// scales its rest shape, so a seam between panels of different ease sews a longer side to a
// shorter one. A pattern maker eases the difference in; the simulator's mesh cannot buckle the
// longer side into ripples a few millimetres wide, so the seam holds it squeezed against the
// other side stretched, and past a few percent that row of cloth keeps moving (trial 38's
// strapless dress, bodice 0.95 sewn to a skirt at 1: docs/pattern.md, "Eased seams that keep
// moving").

#include <string>
#include <vector>

#include "garment/garment_mesh.hpp"
#include "scene/sketch_file.hpp"

namespace sd::app {

// Rest lengths of a seam's two sides may differ by at most this fraction of the longer one
// before `validate`, `mesh` and `run` warn. Measured on trial 38's strapless dress (bodice eased
// against a skirt at 1 along the hip seam; docs/pattern.md, "Eased seams that keep moving"): 3 %
// and 4 % come to rest (2.73 s, 3.27 s), as the A-line skirt's yokes at 3 % do; 5 % never does
// (one vertex under the seam cycles every 0.15 s at up to 14 cm/s, still after 8 s). The limit
// sits between the last that rests and the first that does not.
inline constexpr double kSeamEaseLimit = 0.045;

// One "<file>: /panels/N/ease: <sentence>" line per seam curve (mirror copies folded into their
// original) whose two sides' rest lengths differ by more than kSeamEaseLimit: the two panels and
// their eases, the curve, the difference in percent and millimetres, and the eases that would do.
// Gathered panels (ease with different warp and weft) are gathered on purpose and not judged.
std::vector<std::string> seam_ease_warnings(const scene::Sketch& sketch,
                                            const garment::Garment& garment);

}  // namespace sd::app
