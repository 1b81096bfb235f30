#pragma once
// Partitions of an n-sided region into grid blocks (internal to the patch filler; see
// docs/meshing.md for the reasoning):
//  * the Nasri partition: a centre of valence n joined to a point on every side, n grids;
//  * the same on a "layout polygon" whose corners are moved: some real corners dropped (they
//    become side vertices of valence 3, cost 1 each) and some side vertices promoted to
//    corners (valence 2, cost 1 each), searched for the least total cost;
//  * the Yasseen et al. (2010) large-length partition with distorted 4-sided regions.

#include <Eigen/Core>
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
  int irregular = 0;         // vertices of the loop and the centre left irregular
  int flat = 0;              // layout corners at positions flagged in PositionCosts::flat
  int checks = 0;            // feasibility checks best_layout spent finding it
};

// What it costs (in valence deviation) for each loop position to become a layout corner
// (gaining no edge into the polygon) or a layout side vertex (gaining one).
struct PositionCosts {
  std::vector<int> as_corner;
  std::vector<int> as_side;
  // Optional (empty = none flagged): 1 where a layout corner would leave a single quad with
  // the boundary's own angle there, flat (180°) or reflex. Among layouts of equal cost the
  // search prefers fewer flagged corners.
  std::vector<char> flat;
  // Optional (empty = not offered): the cost as a *reflex* layout vertex (gaining two edges into
  // the polygon, three quads), used only by the rectilinear layouts (rectilinear_layout.hpp).
  std::vector<int> as_reflex;
  // Optional (empty = unknown): how far the boundary turns at each position, in quarter turns
  // to the left (+1 at a square convex corner, −1 at a square concave one), measured from its
  // points. Among rectilinear layouts of equal cost the search prefers the one whose lattice
  // walk turns where the boundary does (rectilinear_layout.hpp).
  std::vector<double> turn;
};

// The least costly layout found: cost = |n' − 4| (the centre) + the position costs. Searches
// corner sets in order of a lower bound on their cost, at most `budget` feasibility checks;
// always returns a layout for a loop of >= 4 positions (a triangle or a single quad at worst).
PolygonLayout best_layout(const PositionCosts& costs, int budget);

// A lower bound on the cost of any layout best_layout can return for these costs (the cost a
// layout with the cheapest possible corners would have), ignoring kFoldPenalty: so a caller
// can skip a search that cannot beat what it already has.
int layout_cost_lower_bound(const PositionCosts& costs);

// Fills the polygon whose boundary loop (vertex ids, counter-clockwise) is `loop`.
void fill_polygon(QuadMeshBuilder& builder, std::span<const int> loop, const PolygonLayout& layout);

// Position costs of a region's own boundary: real corners want to stay corners. Every side
// vertex is flagged flat (straight sides); real corners are not.
PositionCosts region_costs(std::span<const int> side_counts);

// Padding (after Takayama et al. 2014), one side at a time. A *strip* along side i of a region
// is a row of l_i quads between the side and a chain from the vertex before corner i to the
// vertex after corner i+1; the region left over has the same number of sides, side i replaced
// by the chain (same count) and sides i−1, i+1 one edge shorter. Corners i and i+1 keep
// valence 2 (one quad each), every other vertex of side i gets valence 3, and the two vertices
// that become the left-over region's corners get valence 3 when they stay its corners: so a
// strip costs nothing, and a layout corner the left-over region promotes on the chain is an
// interior vertex of valence 3 instead of a boundary vertex of valence 2 (flat or folded
// quad). Strips on all sides make a full padding ring.
struct LoopVertex {
  int id = -1;           // vertex id in the builder (or -1 when only planning)
  int outside = 0;       // edges it has outside the current region
  int regular = 3;       // its regular valence in the whole fill
  bool exposed = false;  // on the region's boundary with a flat or reflex angle: valence 2 here
                         // would leave one quad with that angle
  bool reflex = false;   // ... and that quad would be folded
  double turn = 0;       // the boundary's turn there, quarter turns (PositionCosts::turn)
};

struct StripRegion {
  std::vector<LoopVertex> loop;  // counter-clockwise
  std::vector<int> corners;      // loop position of corner i, side i from corner i to i+1
  int fixed_cost = 0;            // distortion of the vertices already enclosed by strips
  int fixed_irregular = 0;
  int folded = 0;         // enclosed vertices of valence 2 where the boundary is reflex
  int flat = 0;           // ... flat or reflex
  bool measured = false;  // the loop's `turn`s are measured (else PositionCosts::turn is empty)

  // Adds a strip along side `side`; false (nothing changed) when a neighbouring side has fewer
  // than 2 edges or the loop would shrink below 4 vertices. With a builder, creates the chain's
  // vertices (one edge length inwards of the side about `normal`, parallelogram points next to the
  // corners) and the strip's quads.
  bool strip(int side, QuadMeshBuilder* builder = nullptr,
             const Eigen::Vector3d& normal = Eigen::Vector3d::UnitZ());

  // Position costs of the current loop (a reflex position with no outside edge costs
  // kFoldPenalty more as a corner, so that layouts avoid folding first).
  PositionCosts costs() const;
};

// Added to the corner cost of a position where a layout corner would fold a quad.
constexpr int kFoldPenalty = 64;

// Fills the region with the Yasseen et al. (2010) large-length partition: spokes from a
// centre as in Nasri's partition, large sides absorbed by distorted regions, merged distorted
// regions filled by best_layout. `sides[i]` are the vertex ids of side i (corner i to corner
// i+1). Returns false (builder untouched) when the partition does not apply: n divisible by 4,
// every d_i already >= 1, half-integer distances, or nothing left but distorted regions.
bool fill_yasseen(QuadMeshBuilder& builder, const std::vector<std::vector<int>>& sides, int budget);

}  // namespace sd::meshing::detail
