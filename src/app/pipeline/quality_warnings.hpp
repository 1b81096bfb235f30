#pragma once
// The garment quality gate (garment/quality_gate.hpp) as `validate` and `mesh` show it: one
// warning line per problem on stderr and a list for report.json.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "garment/body.hpp"
#include "garment/quality_gate.hpp"

namespace sd::app {

// Runs the gate with the body's landmarks (none when the body is not a standing figure) and
// logs each warning.
std::vector<garment::QualityWarning> quality_warnings(const garment::Garment& garment,
                                                      const garment::GarmentRequest& sketch,
                                                      const garment::Body& body);

// The message of a panel that cannot be flattened (`error`, from garment::PatternError), after
// the gate's warnings are logged: when cloth of that panel (or of its original, for a mirror
// copy) lies inside the body before the drape, a curve drawn through the body is the likely
// cause (a hem through the legs makes a panel that bends round them), and the message says so.
std::string flattening_failure(const garment::Garment& garment,
                               const garment::GarmentRequest& sketch, const garment::Body& body,
                               const std::string& panel, const std::string& error);

nlohmann::json warnings_json(const std::vector<garment::QualityWarning>& warnings);

}  // namespace sd::app
