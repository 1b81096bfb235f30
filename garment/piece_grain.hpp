#pragma once
// Long narrow pattern pieces (a strap, a waistband, a tie) laid across the grain. The grain of a
// piece follows its panel's `grain` (the body's vertical by default), which says nothing about
// the piece's own shape: a waistband or a collar round the neck takes the vertical's projection,
// which runs across it. (A strap over the shoulder does not: the vertical runs up it on the front
// and the back alike, and flatten_garment takes the line its warp runs along: trial 39, P18.) Cut
// so, a piece stretches along its length, where the weft gives more than the warp. A bias cut is
// the exception, and a panel whose grain is turned on purpose is not questioned.

#include <string>

#include "garment/garment_mesh.hpp"
#include "garment/panel_flattening.hpp"

namespace sd::garment {

// The extent of a flat piece along and across its long axis, and where that axis lies.
struct PieceShape {
  double length = 0.0;     // m, along the long axis (the piece's 2D outline's extent)
  double width = 0.0;      // m, across it
  double angle_deg = 0.0;  // the long axis from the grain line (+y), counter-clockwise, −90 .. 90
};

// The long axis of the piece's triangles by their area's second moments (a piece's principal
// axes: a bent strap's runs along its chord).
PieceShape piece_shape(const FlatPanel& piece);

struct PieceGrainLimits {
  // A piece at least this many times longer than it is wide is a long narrow one. A strap or a
  // waistband is 8-25 times; over the examples and designs the most elongated other piece (a
  // trouser leg, a sleeve) is 3.1 times (docs/pattern.md, "Straps across the grain").
  double min_length_ratio = 4.0;
  // Its long axis more than this off the grain line (degrees) is across it: 30° halfway between
  // along the grain and on the bias.
  double max_angle_deg = 30.0;
};

// The sentence for a long narrow piece of `panel` laid across the grain (its panel's grain not
// turned on purpose): the piece, its size, the angle, and the "grain" turn that lays it along;
// "" when it is not.
std::string cross_grain_warning(const FlatPanel& piece, const GarmentPanel& panel,
                                const PieceGrainLimits& limits = {});

}  // namespace sd::garment
