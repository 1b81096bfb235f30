#include "sim/cantilever.hpp"

#include <cmath>
#include <numbers>

namespace sd::sim {

double peirce_bending_length(double overhang, double chord_deg) {
  const auto peirce = [](double degrees) {
    const double theta = degrees * std::numbers::pi / 180.0;
    return std::cbrt(std::cos(0.5 * theta) / (8.0 * std::tan(theta)));
  };
  // Peirce's formula gives 1.019·l/2 at 41.5°, where the standard (and the elastica) say l/2:
  // scaled so that the standard's angle gives its bending length exactly.
  return 0.5 * overhang * peirce(chord_deg) / peirce(41.5);
}

CantileverMeasure measure_cantilever(const SheetScene& sheet, const Eigen::MatrixX3d& rest,
                                     const Eigen::MatrixX3d& positions, int clamp_lines) {
  CantileverMeasure m;
  m.clamp_lines = clamp_lines;
  const int last = clamp_lines - 1;  // the clamp's last line of vertices (row from the top)
  Eigen::Vector3d clamp = Eigen::Vector3d::Zero(), tip = Eigen::Vector3d::Zero();
  Eigen::Vector3d clamp_rest = Eigen::Vector3d::Zero(), tip_rest = Eigen::Vector3d::Zero();
  for (int c = 0; c <= sheet.columns; ++c) {
    clamp += positions.row(sheet.vertex(last, c)).transpose() / (sheet.columns + 1);
    tip += positions.row(sheet.vertex(sheet.rows, c)).transpose() / (sheet.columns + 1);
    clamp_rest += rest.row(sheet.vertex(last, c)).transpose() / (sheet.columns + 1);
    tip_rest += rest.row(sheet.vertex(sheet.rows, c)).transpose() / (sheet.columns + 1);
  }
  m.overhang = (tip_rest - clamp_rest).norm();
  // Below the horizontal, measured along the strip's direction at rest (a tip curled back past
  // the clamp reads beyond 90°).
  Eigen::Vector3d out = tip_rest - clamp_rest;
  out.y() = 0.0;
  out.normalize();
  const Eigen::Vector3d along = tip - clamp;
  m.chord_deg = std::atan2(-along.y(), along.dot(out)) * 180.0 / std::numbers::pi;
  m.bending_length = peirce_bending_length(m.overhang, m.chord_deg);
  return m;
}

}  // namespace sd::sim
