#pragma once
// The garment quality gate (garment/quality_gate.hpp) as `validate` and `mesh` show it: one
// warning line per problem on stderr and a list for report.json.

#include <nlohmann/json.hpp>
#include <vector>

#include "garment/body.hpp"
#include "garment/quality_gate.hpp"

namespace sd::app {

// Runs the gate with the body's landmarks (none when the body is not a standing figure) and
// logs each warning.
std::vector<garment::QualityWarning> quality_warnings(const garment::Garment& garment,
                                                      const garment::GarmentRequest& sketch,
                                                      const garment::Body& body);

nlohmann::json warnings_json(const std::vector<garment::QualityWarning>& warnings);

}  // namespace sd::app
