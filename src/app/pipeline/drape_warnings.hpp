#pragma once
// The warnings `run` gives about a drape that finished (not a failure): the cloth still moving
// at the end, and a garment that slid below where it was drawn. Each is worded for the garment
// at hand: the panel and the place that move, the curve that should hold the garment up.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "garment/garment_mesh.hpp"

namespace sd::app {

// The garment's highest opening: the outline curves (edges on one quad only) whose mean height
// is within 3 cm of the highest one's (a skirt's front and back waist, a strapless top's upper
// edge), the panels they bound (mirror copies folded into their panel) and their mean point, m.
struct TopOpening {
  std::vector<std::string> curves;
  std::vector<std::string> panels;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
};

// nullopt when the garment has no opening (a closed bag) or its outline names no curve.
std::optional<TopOpening> top_opening(const garment::Garment& garment);

// "<file>: the garment settled 4.2 cm below where it was drawn ...": what slid, what should hold
// it (the top opening's curves and panels, near `landmark` when known) and how to make it grip.
std::string settled_warning(const std::string& file, double drop_m,
                            const std::optional<TopOpening>& opening, const std::string& landmark);

// Where a drape that ended without reaching at rest still moves: its fastest vertex.
struct StillMoving {
  double speed = 0.0;  // m/s
  Eigen::Vector3d at = Eigen::Vector3d::Zero();
  std::string panel;     // the group of a triangle around it; empty when unknown
  std::string landmark;  // the nearest body landmark; empty without a standing body
  int moving = 0;        // vertices faster than the at-rest speed
  int vertices = 0;
};

// "<file>: the drape did not come to rest in 3.0 s: ..." with the at-rest limits and what to try.
std::string not_at_rest_warning(const std::string& file, double duration_s, double rest_speed,
                                double rest_window_s, const StillMoving& where);

}  // namespace sd::app
