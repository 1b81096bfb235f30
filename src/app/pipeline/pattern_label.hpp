#pragma once
// Where a pattern piece's label fits: the piece's name and two lines of figures, placed beside
// the grain line, across it or at the piece's middle, horizontal or turned a quarter along a
// narrow piece, or turned along a slanted or bent strip, at the largest type size (up to 9 mm)
// whose text block lies inside the piece's sewing line. A gore or a waistband 4 cm wide gets its
// label along its length instead of spilling over its neighbours on the sheet.

#include <Eigen/Core>
#include <string>
#include <vector>

namespace sd::app {

struct LabelText {
  std::string title;               // the piece's name, bold
  std::vector<std::string> lines;  // the figures below it, at 0.75 of the title's size
};

struct LabelPlacement {
  Eigen::Vector2d anchor = Eigen::Vector2d::Zero();  // mm, SVG frame (y down): the title's start
  double size = 0;                                   // mm, the title's font size
  // Turned anticlockwise by this many degrees about the anchor, −90 < turn ≤ 90 (never upside
  // down): 0 across the sheet, 90 along a piece (reads upwards), else along a slanted strip.
  double turn_deg = 0;
  bool centred = false;  // text-anchor middle (else start)
  bool fits = false;     // the whole block lies inside the outline
};

// Approximate width (mm) of `text` at `size` mm in a sans-serif face: 0.56 em a character
// (0.6 bold), the mean advance of Latin text in DejaVu Sans / Liberation Sans, which Chromium
// and Inkscape fall back to; a multi-byte UTF-8 character counts once.
double text_width(const std::string& text, double size, bool bold);

// `outline`: the piece's sewing line (mm, SVG frame), closed, first point not repeated.
// `grain_a`, `grain_b`: the grain line's ends (mm, SVG frame). Sizes from 9 mm down to 2 mm are
// tried, each beside the grain line, then at the centroid (across, then a quarter turned), then
// centred on points along the middle of the piece turned along its nearest side (a strap cut
// slanted or bent across the sheet: trial 39's shortalls strap got 2 mm text at its centroid);
// when none fits, the smallest at the centroid is returned with `fits` false.
LabelPlacement place_label(const Eigen::MatrixX2d& outline, const Eigen::Vector2d& grain_a,
                           const Eigen::Vector2d& grain_b, const LabelText& text);

}  // namespace sd::app
