#include "src/app/pipeline/quality_warnings.hpp"

#include <spdlog/spdlog.h>

#include <optional>
#include <stdexcept>

namespace sd::app {

std::vector<garment::QualityWarning> quality_warnings(const garment::Garment& garment,
                                                      const garment::GarmentRequest& sketch,
                                                      const garment::Body& body) {
  std::optional<garment::BodyLandmarks> landmarks;
  try {
    landmarks = garment::find_landmarks(body.mesh);
  } catch (const std::runtime_error&) {
    // Not a standing figure (a dress form, a test sphere): places are given without a landmark.
  }
  std::vector<garment::QualityWarning> warnings =
      garment::check_quality_tried(garment, sketch, body.mesh, landmarks ? &*landmarks : nullptr);
  for (const garment::QualityWarning& w : warnings) spdlog::warn("{}: {}", sketch.file, w.message);
  return warnings;
}

nlohmann::json warnings_json(const std::vector<garment::QualityWarning>& warnings) {
  nlohmann::json out = nlohmann::json::array();
  for (const garment::QualityWarning& w : warnings)
    out.push_back({{"panel", w.panel},
                   {"kind", w.kind},
                   {"count", w.count},
                   {"worst", w.worst},
                   {"where", {w.where.x(), w.where.y(), w.where.z()}},
                   {"landmark", w.landmark},
                   {"message", w.message}});
  return out;
}

}  // namespace sd::app
