#include "garment/unused_curves.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <map>
#include <set>

namespace sd::garment {

std::vector<std::string> unused_curve_warnings(const GarmentRequest& sketch,
                                               const Garment& garment) {
  std::set<std::string, std::less<>> used;
  for (const GarmentPanel& panel : garment.panels)
    for (const std::string& id : panel.curves)
      used.insert(id.ends_with(".mirror") ? id.substr(0, id.size() - 7) : id);
  std::vector<std::string> warnings;
  for (const CurveSpec& curve : sketch.curves) {
    if (used.contains(curve.id)) continue;
    warnings.push_back(fmt::format(
        "{}: {}: curve '{}' is in no panel: a forgotten panel or a typo in a boundary list? (a "
        "curve no panel names is not part of the garment; delete it if it was only a guide)",
        sketch.file, curve.json_path, printable(curve.id)));
  }
  return warnings;
}

std::vector<std::string> half_mirrored_warnings(const GarmentRequest& sketch,
                                                const Garment& garment) {
  // Panels bordering each curve (a mirror copy under its own id, "front.mirror").
  std::map<std::string, std::set<std::string>, std::less<>> bordered;
  for (const GarmentPanel& panel : garment.panels)
    for (const std::string& id : panel.curves) bordered[id].insert(panel.id);
  std::vector<std::string> warnings;
  for (const CurveSpec& curve : sketch.curves) {
    const auto original = bordered.find(curve.id);
    const auto copy = bordered.find(curve.id + ".mirror");
    if (original == bordered.end() || copy == bordered.end()) continue;
    if (copy->second.size() >= original->second.size()) continue;
    // The panel of the original whose copy does not border the curve's copy.
    const PanelSpec* lacking = nullptr;
    for (const std::string& panel : original->second) {
      if (panel.ends_with(".mirror") || copy->second.contains(panel + ".mirror") ||
          copy->second.contains(panel))
        continue;
      for (const PanelSpec& spec : sketch.panels)
        if (spec.id == panel && !spec.mirror && lacking == nullptr) lacking = &spec;
    }
    if (lacking == nullptr) continue;
    const auto quoted = [](const std::set<std::string>& ids) {
      std::vector<std::string> out;
      for (const std::string& id : ids) out.push_back("'" + printable(id) + "'");
      return out;
    };
    warnings.push_back(fmt::format(
        "{}: {}: curve '{}' is a seam between {}, but its copy '{}.mirror' borders only {}: is "
        "\"mirror\": true missing on panel '{}'? (without it that half of the garment is open "
        "there)",
        sketch.file, lacking->json_path, printable(curve.id),
        fmt::join(quoted(original->second), " and "), printable(curve.id),
        fmt::join(quoted(copy->second), " and "), printable(lacking->id)));
  }
  return warnings;
}

}  // namespace sd::garment
