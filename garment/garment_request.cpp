#include "garment/garment_request.hpp"

namespace sd::garment {

std::string ViewSpec::name() const {
  switch (kind) {
    case ViewKind::kFront:
      return "front";
    case ViewKind::kBack:
      return "back";
    case ViewKind::kLeft:
      return "left";
    case ViewKind::kRight:
      return "right";
    case ViewKind::kCamera:
      return "camera";
  }
  return "?";
}

void GarmentRequest::fail(const std::string& json_path, const std::string& sentence) const {
  throw SketchError(file, json_path, sentence);
}

const CurveSpec* GarmentRequest::find_curve(std::string_view id) const {
  for (const CurveSpec& c : curves)
    if (c.id == id) return &c;
  return nullptr;
}

const PanelSpec* GarmentRequest::find_panel(std::string_view id) const {
  for (const PanelSpec& p : panels)
    if (p.id == id) return &p;
  return nullptr;
}

std::filesystem::path GarmentRequest::resolve(const std::string& relative) const {
  const std::filesystem::path p(relative);
  return p.is_absolute() ? p : base_dir / p;
}

}  // namespace sd::garment
