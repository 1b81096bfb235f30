#pragma once
// The warnings `run` gives about a drape that finished (not a failure): the cloth still moving
// at the end, a garment that slid below where it was drawn, and a panel left stretched far
// beyond what cloth at rest on a body stretches. Each is worded for the garment
// at hand: the panel and the place that move, the curve that should hold the garment up.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "garment/garment_mesh.hpp"

namespace sd::app {

// The garment's highest opening: the outline curves (edges on one quad only) whose mean height
// is within 3 cm of the highest one's (a skirt's front and back waist, a strapless top's upper
// edge), the panels they bound (mirror copies folded into their panel) and their mean point, m.
struct TopOpening {
  std::vector<std::string> curves;
  std::vector<std::string> panels;
  // The panels sewn to those (not among them; mirror copies named by their original) with their
  // ease, gathered ones (warp and weft apart) left out: easing the opening's panels in, the
  // seams to these keep within kSeamEaseLimit only if they follow (trial 43, P6).
  std::vector<std::pair<std::string, double>> sewn_to;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
};

// nullopt when the garment has no opening (a closed bag) or its outline names no curve.
std::optional<TopOpening> top_opening(const garment::Garment& garment);

// How much lower a garment hangs because its top opening's panels are eased above 1: cloth
// ease times larger than drawn, hung from that opening, reaches (ease − 1) times farther down, so
// its centre of mass (drawn `hang_m` below the opening) drops by about (ease − 1)·hang_m. The
// larger of warp and weft ease of each panel, the largest over the opening's panels; 0 when none
// is above 1. (A blouse eased 1.08 settles 4.3 cm lower: docs/sketch-format.md, "ease".)
double ease_drop(const TopOpening& opening, const std::vector<garment::PanelSpec>& panels,
                 double hang_m);

// "<file>: the garment settled 4.2 cm below where it was drawn ...": what slid, what should hold
// it (the top opening's curves and panels, near `landmark` when known) and how to make it grip.
// `eased_m` (from ease_drop) is the part of the drop the panels' ease accounts for, said as such.
std::string settled_warning(const std::string& file, double drop_m,
                            const std::optional<TopOpening>& opening, const std::string& landmark,
                            double eased_m = 0.0);

// Where a drape that ended without reaching at rest still moves: its fastest vertex.
struct StillMoving {
  double speed = 0.0;  // m/s
  Eigen::Vector3d at = Eigen::Vector3d::Zero();
  std::string panel;     // the group of a triangle around it; empty when unknown
  std::string landmark;  // the nearest body landmark; empty without a standing body
  int moving = 0;        // vertices faster than the at-rest speed
  int vertices = 0;
  bool flat_rest = false;  // draped from the flat pattern ("rest": "flat")
  double rest_ramp = 0.0;  // s, simulate.rest_ramp
  // Whether the drape was in a still stretch when the time ran out (drift within the at-rest
  // bound, but for less than the window): its length and the largest drift so far.
  double still_s = 0.0;  // s; 0: the last step moved
  double drift_m = 0.0;
  // The mean kinetic energy over the run's last quarter divided by its mean over the quarter
  // before (kinetic_energy_trend); 0 when not known (a run shorter than kSustainedFrom).
  double kinetic_trend = 0.0;
};

// A run at least this long (s) whose kinetic energy did not fall by half from the third quarter
// of the run to the last (kSustainedTrend) moves in a sustained way, not settling, so a longer
// duration does not help (trial 42's gathered peplum on the adaptive mesh: a mean kinetic energy
// of 6e-5 J/kg from 5 to 60 s; docs/adaptive.md, "A gathered panel that never rests"). 30 s is
// the duration a gathered garment is given (settle_time.hpp, kGatheredSettleDuration); the
// slowest garment of the corpus rests at 21.65 s. Shorter runs are not judged: trial 42's trumpet
// skirt ended its 10 s with a trend of 1.1 (a slow creep at a steady energy) and rested at
// 12.64 s.
inline constexpr double kSustainedFrom = 30.0;
inline constexpr double kSustainedTrend = 0.5;

// The mean of `kinetic` over the samples with times in the last quarter of [0, duration_s],
// divided by its mean over the quarter before; 0 when duration_s < kSustainedFrom, when either
// quarter holds no sample, or when the earlier quarter's mean is 0. `time` and `kinetic` are the
// per-step samples (sim::SimulationReport::energy), of the same length.
double kinetic_energy_trend(const std::vector<double>& time, const std::vector<double>& kinetic,
                            double duration_s);

// "<file>: the drape did not come to rest in 3.0 s: ..." with the at-rest limits and what to try:
// from the flat pattern without a rest ramp, "rest_ramp": 1 first (docs/pattern.md, "Drape time
// and the rest ramp"), else a longer duration and a snugger fit; a sustained motion
// (kinetic_trend at least kSustainedTrend) is said to be one, and no longer duration offered.
std::string not_at_rest_warning(const std::string& file, double duration_s, double rest_speed,
                                double rest_window_s, const StillMoving& where);

// A panel stretched more than this (σ₁ − 1 of a triangle, against its rest shape) at the end of
// a drape is pulled, not resting: garments at rest stretch by their own weight ρgL/K ≈ 0.02 % (a
// linen, 1 m) and by their fit a few percent (the examples 0.2-2 %, the design corpus and
// shaped drapes up to 5 % at the longest automatic step, flat-rest drapes against their
// pattern below 10 %: docs/simulator.md, tests/cli/flat_rest_drape_test.cpp), while a woven
// reaches its KES EMT strain, 0.5-10 %, only under a firm 500 gf/cm pull (docs/fabrics.md).
// 15 % is 1.5 times the flat-rest bound and beyond any woven's EMT; trial 35's strapless back,
// caught in the seat's cleft, ended at 45 %.
inline constexpr double kOverstretched = 0.15;

// "<file>: panel 'bodice_back' ends stretched 45 % ...": the panel (a mirror copy folded into
// its panel), the place and landmark of its most stretched triangle, and what to change (when
// the drape did not come to rest, that first: the cloth is pulled as it moves).
std::string overstretched_warning(const std::string& file, const std::string& panel, double stretch,
                                  const Eigen::Vector3d& at, const std::string& landmark,
                                  bool at_rest);

}  // namespace sd::app
