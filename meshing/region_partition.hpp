#pragma once
// Partitions of an n-sided region into grid blocks (internal to the patch filler; see
// docs/meshing.md for the reasoning):
//  * the Nasri partition: a centre of valence n joined to a point on every side, n grids;
//  * the same on a "layout polygon" whose corners are moved: some real corners dropped (they
//    become side vertices of valence 3, cost 1 each) and some side vertices promoted to
//    corners (valence 2, cost 1 each), searched for the least total cost;
//  * the Yasseen et al. (2010) large-length partition with distorted 4-sided regions.

#include <optional>
#include <span>
#include <vector>

#include "meshing/quad_layout.hpp"

namespace sd::meshing::detail {

// Spoke lengths d_j of the Nasri partition of a polygon with these side edge counts:
// arcs_j = d_{j-1} + d_{j+1}, every d_j >= 1 and integer. For a polygon whose corner count is
// a multiple of 4 the system is singular; when solvable, its free parameters are chosen to make
// the smallest d_j as large as possible. nullopt when no such d exists. arcs.size() >= 3.
std::optional<std::vector<int>> nasri_spokes(std::span<const int> arcs);

// The Nasri/Yasseen closed-form distances (DESIGN.md) for n odd or n/2 odd, as
// twice their value (so that half-integers stay exact): 2 d_i.
std::vector<int> nasri_distances_doubled(std::span<const int> lengths);

struct PolygonLayout {
  std::vector<int> corners;  // loop positions of the layout corners, increasing
  std::vector<int> spokes;   // Nasri spoke lengths d_j; empty for a single grid block
  int cost = 0;              // the distortion this layout causes, from the position costs
};

// What it costs (in valence deviation) for each loop position to become a layout corner
// (gaining no edge into the polygon) or a layout side vertex (gaining one).
struct PositionCosts {
  std::vector<int> as_corner;
  std::vector<int> as_side;
};

// The least costly layout found: cost = |n' − 4| (the centre) + the position costs. Searches
// corner sets in order of a lower bound on their cost, at most `budget` feasibility checks;
// always returns a layout for a loop of >= 4 positions (a triangle or a single quad at worst).
PolygonLayout best_layout(const PositionCosts& costs, int budget);

// Fills the polygon whose boundary loop (vertex ids, counter-clockwise) is `loop`.
void fill_polygon(QuadMeshBuilder& builder, std::span<const int> loop,
                  const PolygonLayout& layout);

// Position costs of a region's own boundary: real corners want to stay corners.
PositionCosts region_costs(std::span<const int> side_counts);

// Fills the region with the Yasseen et al. (2010) large-length partition: spokes from a
// centre as in Nasri's partition, large sides absorbed by distorted regions, merged distorted
// regions filled by best_layout. `sides[i]` are the vertex ids of side i (corner i to corner
// i+1). Returns false (builder untouched) when the partition does not apply: n divisible by 4,
// every d_i already >= 1, half-integer distances, or nothing left but distorted regions.
bool fill_yasseen(QuadMeshBuilder& builder, const std::vector<std::vector<int>>& sides,
                  int budget);

}  // namespace sd::meshing::detail
