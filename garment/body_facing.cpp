#include "garment/body_facing.hpp"

#include <algorithm>
#include <limits>
#include <vector>

namespace sd::garment {

double FacingCue::lean() const {
  const double sum = ahead + behind;
  return sum > 0.0 ? (ahead - behind) / sum : 0.0;
}

bool FacingCues::backwards() const {
  if (!head.found && !feet.found) return false;
  for (const FacingCue* cue : {&head, &feet})
    if (cue->found && !(cue->lean() < -kFacingLean)) return false;
  return true;
}

namespace {

// The head: slices from the neck's base to the top, of the outlines across the median plane (the
// arms and, on a detailed head, the eyes are apart from it). The face reaches forward of the
// neck's front below it (the chin over the throat, the nose), the skull back over the nape. On the
// built-in mannequin the front steps from z = 0.029 m at y = 1.52 to 0.081 at 1.54 (the chin) and
// 0.102 at 1.62 (the nose), the back from -0.068 at 1.54 to -0.097 at 1.64: 7.5 cm ahead, 3.0 cm
// behind (slices 7 mm apart). Hair gathered at the back (a bun) would reach behind: the feet then
// overrule it.
FacingCue head_cue(const meshing::TriMesh& body, const BodyLandmarks& landmarks) {
  FacingCue cue;
  const Landmark* neck = landmarks.find("neck_base");
  if (neck == nullptr) return cue;
  const double height = landmarks.height;
  const double step = 0.004 * height;  // as find_landmarks: 7 mm on a 1.75 m figure
  double lowest_front = std::numeric_limits<double>::infinity();
  double highest_back = -std::numeric_limits<double>::infinity();
  int slices = 0;
  for (double y = neck->position.y() + step + 1e-7 * height; y < 0.995 * height; y += step) {
    double front = -std::numeric_limits<double>::infinity();
    double back = std::numeric_limits<double>::infinity();
    for (const SliceOutline& o : slice_body(body, y))
      if (o.min.x() <= 0.0 && o.max.x() >= 0.0) {
        front = std::max(front, o.max.z());
        back = std::min(back, o.min.z());
      }
    if (!(front > back)) continue;
    ++slices;
    lowest_front = std::min(lowest_front, front);
    highest_back = std::max(highest_back, back);
    cue.ahead = std::max(cue.ahead, front - lowest_front);
    cue.behind = std::max(cue.behind, highest_back - back);
  }
  // A head is several slices tall (the built-in one 36) and reaches out somewhere.
  cue.found = slices >= 5 && cue.ahead + cue.behind > 0.005 * height;
  return cue;
}

// The feet: for each ankle, the outline under it in the slices from the floor to the ankle; the
// toes reach ahead of the ankle's centre, the heel behind. The Collada human's feet reach 16.4 cm
// ahead of the ankles and 6.9 cm behind. A figure whose legs end in stumps
// (the built-in mannequin: 4.8 cm front to back at the bottom, the leg 7.9 cm deep above) has no
// feet: a foot is at least 8 % of the height long (people's are 14-16 %).
FacingCue feet_cue(const meshing::TriMesh& body, const BodyLandmarks& landmarks) {
  FacingCue cue;
  const double height = landmarks.height;
  const double step = 0.004 * height;
  bool both = true;
  for (const char* name : {"left_ankle", "right_ankle"}) {
    const Landmark* ankle = landmarks.find(name);
    if (ankle == nullptr) return cue;
    double toe = -std::numeric_limits<double>::infinity();
    double heel = std::numeric_limits<double>::infinity();
    for (double y = step + 1e-7 * height; y < ankle->position.y(); y += step) {
      const std::vector<SliceOutline> outlines = slice_body(body, y);
      const SliceOutline* under = nullptr;
      for (const SliceOutline& o : outlines)
        if (o.min.x() <= ankle->position.x() && o.max.x() >= ankle->position.x() &&
            (under == nullptr || o.girth > under->girth))
          under = &o;
      if (under == nullptr) continue;
      toe = std::max(toe, under->max.z());
      heel = std::min(heel, under->min.z());
    }
    if (!(toe > heel) || toe - heel < 0.08 * height) both = false;
    if (!(toe > heel)) continue;
    cue.ahead += std::max(0.0, toe - ankle->position.z()) / 2;
    cue.behind += std::max(0.0, ankle->position.z() - heel) / 2;
  }
  cue.found = both;
  return cue;
}

}  // namespace

FacingCues facing_cues(const meshing::TriMesh& body, const BodyLandmarks& landmarks) {
  return {head_cue(body, landmarks), feet_cue(body, landmarks)};
}

std::optional<TurnedFigure> looks_turned(const meshing::TriMesh& body) {
  if (body.vertex_count() == 0) return std::nullopt;
  const double width = body.vertices.col(0).maxCoeff() - body.vertices.col(0).minCoeff();
  const double depth = body.vertices.col(2).maxCoeff() - body.vertices.col(2).minCoeff();
  if (!(depth > width)) return std::nullopt;
  return TurnedFigure{depth, width};
}

}  // namespace sd::garment
