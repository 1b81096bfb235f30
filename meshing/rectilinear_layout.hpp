#pragma once
// Quad layouts without an interior irregular vertex (internal to the patch filler; see
// docs/meshing.md, "Rectilinear layouts").
//
// A quad mesh of a disk whose interior vertices all have valence 4 develops onto the integer
// grid: every boundary vertex turns by t = 3 − (its valence inside the polygon) quarter turns,
// +1 at a layout corner (no edge inwards), 0 at a side vertex (one edge inwards), −1 at a
// reflex vertex (two edges inwards, three quads), and the turns add up to 4. Conversely, for any
// turns with Σ t = 4 whose lattice walk closes without touching itself, the unit cells inside
// the walk are such a mesh. The Nasri/shifted-corner layouts never put two edges inwards at a
// boundary vertex; these layouts do, which is what small skewed regions need: (1,2,3,1,3) is an
// L-shape with one vertex of valence 4 on its last side (distortion 1 = |n − 4|).

#include <optional>
#include <span>
#include <vector>

#include "meshing/quad_layout.hpp"
#include "meshing/region_partition.hpp"

namespace sd::meshing::detail {

// The most quarter turns of change a search looks for (a plain region of n sides needs |4 − n|).
constexpr int kMaxTurnShift = 4;

struct RectilinearLayout {
  std::vector<int> turns;  // per loop position: +1, 0 or −1; Σ = 4
  int cost = 0;            // Σ of the position costs of the chosen turns
  int irregular = 0;       // positions with a nonzero cost
  int flat = 0;            // layout corners (t = +1) at positions flagged flat
  int cells = 0;     // quads: for a boundary of S edges, more quads is a rounder lattice polygon
  int shortest = 0;  // the shortest straight run of the walk, in edges
  // With PositionCosts::turn: how far the walk's heading strays from the boundary's, Σ over the
  // edges of (lattice heading − boundary heading − their mean difference)², in quarter turns².
  double mismatch = 0;
  int checks = 0;  // budget units spent
};

// The cheapest rectilinear layout of the loop whose cost is at most `max_cost` (ties: fewest
// irregular vertices, fewest flat corners, least heading mismatch when the boundary's turns are
// known, most quads, longest shortest run), searching turn
// changes from each position's cheapest turn in order of added cost; every candidate change
// looked at takes one unit of `budget` (decremented). Regions that need more than
// kMaxTurnShift quarter turns of change (e.g. n >= 9 plain sides) are not searched. Needs
// PositionCosts::as_reflex; nullopt when nothing that cheap exists (or was found).
std::optional<RectilinearLayout> best_rectilinear_layout(const PositionCosts& costs, int max_cost,
                                                         int& budget);

// Fills the polygon whose boundary loop (vertex ids, counter-clockwise) is `loop` with the unit
// cells of the layout's lattice polygon. Interior vertices start at the mean of the linear
// interpolations between the boundary vertices their grid row and column end at.
void fill_rectilinear(QuadMeshBuilder& builder, std::span<const int> loop,
                      std::span<const int> turns);

}  // namespace sd::meshing::detail
