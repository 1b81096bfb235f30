#pragma once
// The garment quality gate (garment/quality_gate.hpp) as `validate` and `mesh` show it: one
// warning line per problem on stderr and a list for report.json.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "garment/body.hpp"
#include "garment/panel_flattening.hpp"
#include "garment/quality_gate.hpp"

namespace sd::app {

// Runs the gate with the body's landmarks (none when the body is not a standing figure) and
// logs each warning.
std::vector<garment::QualityWarning> quality_warnings(const garment::Garment& garment,
                                                      const garment::GarmentRequest& sketch,
                                                      const garment::Body& body);

// The message of a panel that cannot be flattened (`error`), after the gate's warnings are
// logged: when cloth of that panel (or of its original, for a mirror copy) lies inside the body
// before the drape, a curve drawn through the body is the likely cause (a hem through the legs
// makes a panel that bends round them), and the message says so. A refusal at one place is
// told the body's landmark nearest it.
std::string flattening_failure(const garment::Garment& garment,
                               const garment::GarmentRequest& sketch, const garment::Body& body,
                               const garment::PatternError& error);

// What `validate --strict` and `mesh --strict` count: the gate's warnings and the curves in no
// panel (garment/unused_curves.hpp; logged by the garment stage). Empty when there are none,
// else the failure's sentence: "<file>: 2 mesh quality warning(s), 1 curve(s) in no panel and
// --strict". `half_mirrored`: the curves whose mirror copy borders fewer panels
// (garment::half_mirrored_warnings).
std::string strict_failure(const std::string& file,
                           const std::vector<garment::QualityWarning>& warnings,
                           size_t unused_curves, size_t half_mirrored = 0);

nlohmann::json warnings_json(const std::vector<garment::QualityWarning>& warnings);

}  // namespace sd::app
