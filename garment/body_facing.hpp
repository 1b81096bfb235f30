#pragma once
// Which way a normalised standing figure (metres, +Y up, meant to face +Z) really faces, from the
// two parts of a person that are not alike front and back: the head, whose face, chin and nose
// reach farther in front of the neck than the skull reaches behind it, and the feet, whose toes
// reach farther in front of the ankles than the heels reach behind. A body given the wrong
// "facing" (or an "up" whose convention picks the wrong one) is turned to face -Z, its landmarks
// are still found (on its back), and every curve drawn for its front then misses.
// docs/bodies.md ("Which way the figure faces") gives the measured numbers.

#include <optional>
#include <string>

#include "garment/body_landmarks.hpp"
#include "meshing/tri_mesh.hpp"

namespace sd::garment {

// How far a part reaches in front of (+Z) and behind (-Z) the body part it grows from, m.
struct FacingCue {
  double ahead = 0.0;
  double behind = 0.0;
  bool found = false;  // the part is there (a head above the neck, feet longer than ankles)
  // (ahead - behind) / (ahead + behind): near +0.4 for a figure facing +Z, -0.4 turned round.
  double lean() const;
};

struct FacingCues {
  FacingCue head;  // the head's front and back beyond the neck's, above the neck's base
  FacingCue feet;  // the feet's toes and heels beyond the ankles, both feet together
  // Every cue that was found says the figure faces -Z (lean below -kFacingLean), and one was.
  bool backwards() const;
};

// Lean beyond which a cue says the figure faces one way: the built-in mannequin's head leans
// 0.43, the Collada human's 0.40 and its feet 0.41, so 0.2 is half the smallest.
inline constexpr double kFacingLean = 0.2;

FacingCues facing_cues(const meshing::TriMesh& body, const BodyLandmarks& landmarks);

// A normalised figure deeper (along Z) than wide (along X): a figure facing +X or -X in a file
// read as facing the convention's way, its arms then running front to back (trial 39's Collada
// human re-exported Z up facing +X: 1.05 m deep, 0.43 m wide). Its depth and width in m; nullopt
// when it is wider than deep, as a standing figure facing +Z is.
struct TurnedFigure {
  double depth = 0.0, width = 0.0;
};
std::optional<TurnedFigure> looks_turned(const meshing::TriMesh& body);

}  // namespace sd::garment
