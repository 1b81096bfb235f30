#include "garment/crossing_advice.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace sd::garment {
namespace {

// Two walls face each other when their normals are more than 120° apart (crease_wall.cpp).
constexpr double kFacingWalls = -0.5;
// A crease is narrow under this many offsets: the offset surfaces of its walls merge well before
// the floor (crease_wall.cpp's kNarrowCrease).
constexpr double kNarrowCrease = 2.5;
// m: a ray starts this far out of the wall it leaves, so as not to hit it again.
constexpr double kRayStart = 1e-6;

}  // namespace

std::optional<double> crease_width(const BodySurface& body, const Eigen::Vector3d& where,
                                   double reach) {
  const SurfacePoint near = body.closest_point(where);
  const auto across = body.first_hit(near.position + kRayStart * near.normal, near.normal);
  if (!across || across->normal.dot(near.normal) > kFacingWalls || across->distance > reach)
    return std::nullopt;
  return across->distance;
}

GarmentRequest with_offset_at_most(const GarmentRequest& sketch, double offset) {
  GarmentRequest trial = sketch;
  trial.offset = std::min(trial.offset, offset);
  for (CurveSpec& c : trial.curves) c.offset = std::min(c.offset, offset);
  return trial;
}

void advise_crossings_in_creases(
    std::vector<QualityWarning>& warnings, const GarmentRequest& sketch, const BodySurface& body,
    const std::function<std::size_t(const GarmentRequest&)>& warnings_with) {
  double offset = sketch.offset;
  for (const CurveSpec& c : sketch.curves)
    if (c.on_body) offset = std::max(offset, c.offset);
  std::optional<double> offered;  // the offset that helps, tried once for all warnings
  bool tried = false;
  const std::size_t now = warnings.size();
  for (QualityWarning& w : warnings) {
    if (w.kind != "self_intersection" ||
        w.message.find("passes through panel") == std::string::npos)
      continue;
    const auto width = crease_width(body, w.where, kNarrowCrease * offset);
    if (!width) continue;
    if (!tried) {
      tried = true;
      for (const double smaller : {offset - 0.0025, offset - 0.005, 0.01}) {
        const double mm = std::floor(1e3 * smaller) / 1e3;
        if (mm <= 0.0 || mm >= offset) continue;
        if (warnings_with(with_offset_at_most(sketch, mm)) < now) {
          offered = mm;
          break;
        }
      }
    }
    std::string advice = fmt::format(
        "; the two lie in a crease of the body {:.1f} cm across (the gap between the arm and the "
        "torso, or between the legs), less than {:g} times the curves' offset of {:.1f} cm: the "
        "offset surfaces of its two walls merge there and both panels lie on one wall",
        100 * *width, kNarrowCrease, 100 * offset);
    if (offered)
      advice += fmt::format(
          "; an \"offset\" of {:.1f} cm (the file's, and every curve's that is larger) meshes "
          "the garment with fewer warnings; give the panels \"ease\" for room instead",
          100 * *offered);
    else
      advice +=
          "; draw these panels' curves nearer the body (a smaller \"offset\") and give "
          "them \"ease\" for room, or end the seams away from the crease";
    // The general advice (smoother curves, a corner) is not what clears a crease's crossing.
    if (const std::size_t from = w.message.find(": smooth the curves there");
        from != std::string::npos)
      if (const std::size_t to = w.message.find("; ", from); to != std::string::npos)
        w.message.erase(from, to - from);
    const std::size_t at = w.message.find(';');
    w.message.insert(at == std::string::npos ? w.message.size() : at, advice);
  }
}

}  // namespace sd::garment
