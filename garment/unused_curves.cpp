#include "garment/unused_curves.hpp"

#include <fmt/format.h>

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

}  // namespace sd::garment
