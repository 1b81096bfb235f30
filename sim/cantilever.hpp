#pragma once
// The cantilever test's measures (ASTM D1388; Peirce 1930): a horizontal strip held along one
// end bends under its weight; the chord from the edge of the clamp to the free end falls 41.5°
// below the horizontal when the overhang is twice the bending length c = (B/ρg)^(1/3).
// docs/fabrics.md, "Cantilever". `bench --textile` and `run` of a cantilever scene measure alike.

#include <Eigen/Core>

#include "sim/sheet.hpp"

namespace sd::sim {

// Peirce's bending length from the chord angle θ (degrees) of an overhang l (m); l/2 at 41.5°.
double peirce_bending_length(double overhang, double chord_deg);

struct CantileverMeasure {
  int clamp_lines = 0;          // lines of vertices held ("top:N")
  double overhang = 0.0;        // m, from the clamp's last line to the free end, at rest
  double chord_deg = 0.0;       // the chord's angle below the horizontal, degrees
  double bending_length = 0.0;  // m, Peirce's c from the chord (l/2 at 41.5°)
};

// The measures of a horizontal rectangular sheet built by build_sheet (grid numbering, `sheet`)
// and held along its top edge by its first `clamp_lines` lines of vertices, at `positions` (#V
// by 3): the chord from the mean of the clamp's last line to the mean of the free end's line.
CantileverMeasure measure_cantilever(const SheetScene& sheet, const Eigen::MatrixX3d& rest,
                                     const Eigen::MatrixX3d& positions, int clamp_lines);

}  // namespace sd::sim
