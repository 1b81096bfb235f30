#pragma once
// The textile study of `sketchdrape bench --textile` (docs/fabrics.md, "The textile bench"):
// for every preset, Peirce's cantilever (ASTM D1388) and the Cusick drape (ISO 9073-9) at three
// resolutions each, with the quadratic bending: the cantilever settled by the static solver, the
// drape dynamic with the buckling compression (several specimens). The cantilever's
// predicted bending length is c = (B/ρg)^(1/3) and its chord at overhang 2c is 41.5°; the
// simulated bending length is Peirce's c ∝ l·(cos(θ/2) / (8·tan θ))^(1/3) from the chord θ,
// scaled to give l/2 at 41.5° (ASTM D1388's fixed-angle reading).

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "sim/cantilever.hpp"
#include "sim/cloth_model.hpp"
#include "sim/fabric.hpp"

namespace sd::app {

struct TextileOptions {
  std::vector<std::string> fabrics;                // empty: every preset
  std::vector<int> cantilever_cells = {4, 8, 16};  // cells along the overhang 2c
  std::vector<int> cusick_cells = {16, 20, 30};    // cells across the 30 cm disc
  // When not empty, the Cusick resolutions per fabric instead: cells per bending length c/l
  // (docs/fabrics.md, "Convergence follows the cells per bending length"; 2.5 and 3).
  std::vector<double> cusick_cells_per_c;
  int cusick_specimens = 3;  // drapes per point, each from its own random lift (their mean)
  // The specimen's warp turned by these angles (degrees, about the vertical) against the disc's
  // mesh, whose sectors and core square have a fourfold layout: each angle is its own point. A
  // converged DC does not depend on it (docs/fabrics.md, "Cusick drape").
  std::vector<double> cusick_grain_deg = {0.0};
  // The membrane and clamp options of both tests; unset: ClothModelOptions' defaults.
  std::optional<bool> diamond_membrane;
  std::optional<bool> clamp_ghost_points;
  // The drape's rest rule (sim::SimulationSettings::rest_speed, m/s) and its longest run (s).
  double cusick_rest_speed = 5.0e-3;
  double cusick_duration = 8.0;
};

// The model options a textile study measures with: ClothModelOptions' defaults, with the
// diamond membrane and the clamp's ghost points as `options` sets them.
sim::ClothModelOptions textile_model_options(const TextileOptions& options);

struct CantileverPoint {
  std::string fabric;
  int cells = 0;
  double predicted_c = 0.0;  // m
  double simulated_c = 0.0;  // m, Peirce's formula from the chord
  double chord_deg = 0.0;    // the continuum's is 41.5
  bool converged = false;
  double seconds = 0.0;
};

struct CusickPoint {
  std::string fabric;
  int cells = 0;
  int vertices = 0;
  double grain_deg = 0.0;          // the warp's turn against the mesh (TextileOptions)
  double drape_coefficient = 0.0;  // the mean over the specimens
  double dc_min = 0.0;
  double dc_max = 0.0;
  int specimens = 0;
  int nodes = 0;           // the mean over the specimens, rounded
  bool converged = false;  // every specimen's drape came to rest
  double rest_time = 0.0;  // s, the latest simulated time a specimen came to rest (or stopped)
  double seconds = 0.0;
};

// A preset by name, or a fabric file (a path: with a '/' or ending in .json). Throws
// sim::UnknownFabricError or sim::InvalidFabricError.
sim::FabricParameters textile_fabric(const std::string& fabric);

// Cells across the 30 cm Cusick disc for at least `per_c` cells per bending length
// c = (B/ρg)^(1/3): ⌈0.30 m · per_c / c⌉, at least 4.
int cusick_cells_for(const sim::FabricParameters& fabric, double per_c);

CantileverPoint run_cantilever(const std::string& fabric, int cells,
                               const TextileOptions& options = {});
// The Cusick drape of `specimens` discs, dynamic with the buckling compression, to rest, the
// warp turned by `grain_deg` against the mesh.
CusickPoint run_cusick(const std::string& fabric, int cells, int specimens,
                       const TextileOptions& options = {}, double grain_deg = 0.0);

// Peirce's bending length from the chord angle θ (degrees) of an overhang l (m); l/2 at 41.5°.
using sim::peirce_bending_length;

// Every fabric × resolution; `note` is called with a line after each point.
void run_textile(const TextileOptions& options, std::vector<CantileverPoint>& cantilevers,
                 std::vector<CusickPoint>& drapes,
                 const std::function<void(const std::string&)>& note);

std::string textile_table(const std::vector<CantileverPoint>& cantilevers,
                          const std::vector<CusickPoint>& drapes);
std::string cantilever_csv(const std::vector<CantileverPoint>& cantilevers);
std::string cusick_csv(const std::vector<CusickPoint>& drapes);
// gnuplot script drawing textile-cantilever.png and textile-cusick.png from the two CSVs (the
// converged static solves and the drapes at rest only; the Cusick means with their range).
std::string textile_gnuplot();

}  // namespace sd::app
