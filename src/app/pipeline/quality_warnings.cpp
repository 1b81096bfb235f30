#include "src/app/pipeline/quality_warnings.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

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
  // Told here, once per command, with the gate's (not counted by --strict: quality_gate.hpp).
  for (const garment::QualityWarning& w :
       garment::merged_seam_vertex_warnings(garment, landmarks ? &*landmarks : nullptr))
    spdlog::warn("{}: {}", sketch.file, w.message);
  return warnings;
}

std::string flattening_failure(const garment::Garment& garment,
                               const garment::GarmentRequest& sketch, const garment::Body& body,
                               const garment::PatternError& refusal) {
  const std::string& panel = refusal.panel();
  std::string error = refusal.what();
  if (refusal.placed()) {
    const std::string at = garment::point_text(refusal.where());
    if (const size_t found = error.find(at); found != std::string::npos) {
      try {
        const garment::BodyLandmarks landmarks = garment::find_landmarks(body.mesh);
        error.insert(found + at.size(), ", near the " + landmarks.nearest(refusal.where()).name);
      } catch (const std::runtime_error&) {
        // Not a standing figure: the place alone.
      }
    }
  }
  const std::string original =
      panel.ends_with(".mirror") ? panel.substr(0, panel.size() - 7) : panel;
  // The panel's curves used as written: the ones that can pass through a leg.
  std::vector<std::string> as_written;
  for (const garment::PanelSpec& spec : sketch.panels)
    if (spec.id == original)
      for (const std::string& id : spec.boundary) {
        const std::string base = id.ends_with(".mirror") ? id.substr(0, id.size() - 7) : id;
        for (const garment::CurveSpec& curve : sketch.curves)
          if (curve.id == base && !curve.on_body) as_written.push_back("'" + id + "'");
      }
  for (const garment::QualityWarning& w : quality_warnings(garment, sketch, body)) {
    if (w.kind != "inside_body" || w.panel != original) continue;
    return fmt::format(
        "{}; but {} quad(s) of panel '{}' lie inside the body before the drape (the deepest "
        "{:.1f} mm below the skin{}): the likely cause is a curve drawn through the body{}, not "
        "the panel's shape; move that curve out from the body first",
        error, w.count, original, 1e3 * w.worst,
        w.landmark.empty() ? std::string() : ", near the " + w.landmark,
        as_written.empty() ? std::string()
                           : fmt::format(" (of its curves with \"on_body\": false, {})",
                                         fmt::join(as_written, ", ")));
  }
  return error;
}

std::string strict_failure(const std::string& file,
                           const std::vector<garment::QualityWarning>& warnings,
                           size_t unused_curves, size_t half_mirrored) {
  if (warnings.empty() && unused_curves == 0 && half_mirrored == 0) return "";
  std::vector<std::string> parts;
  if (!warnings.empty())
    parts.push_back(fmt::format("{} mesh quality warning(s)", warnings.size()));
  if (unused_curves > 0) parts.push_back(fmt::format("{} curve(s) in no panel", unused_curves));
  if (half_mirrored > 0)
    parts.push_back(
        fmt::format("{} curve(s) whose mirror copy borders fewer panels", half_mirrored));
  return fmt::format("{}: {} and --strict", file, fmt::join(parts, ", "));
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
