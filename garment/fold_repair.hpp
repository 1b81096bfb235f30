#pragma once
// The last repair of a filled panel that still has folded quads: local changes of the quads at
// each fold, kept only when the panel's quality measure (meshing::measure_quality, the one the
// garment ranks fills by) improves. The folds that survive the filler, the smoothing and the
// unfolding along the body (docs/garment.md, "Folds at a panel's corners") sit at a boundary
// vertex whose angle the quads share badly:
//  * a boundary vertex in one quad at about 180° or more: a plan whose corner was moved along the
//    boundary by one vertex ("shifted-corners": the silk skirt's yoke at the hip, the shorts'
//    back at the crotch). No position of the interior mends it; turning the edge between the
//    folded quad and a neighbour (the hexagon of the two quads split along one of its other two
//    diagonals) moves the quad corner back to the panel's corner or gives the vertex a second
//    quad;
//  * a boundary vertex whose two quads split its angle unevenly (36° and 155° at the shell top's
//    back neck), so that the wide one folds: a turn there too, in the corpus.
// The other candidate, the interior around the fold smoothed towards the mean of its
// neighbours and lifted onto the surface, is tried as well. A corner that turns more than 180°
// in one quad on a saddle of the body (shirt-human's armpit) is not reached (docs/garment.md).

#include <Eigen/Core>
#include <functional>
#include <span>

#include "meshing/quad_mesh.hpp"

namespace sd::garment {

struct FoldRepairResult {
  int folded_before = 0;  // inverted quads by meshing::measure_quality
  int folded_after = 0;
  int edge_turns = 0;  // accepted edge turns
  int smoothings = 0;  // accepted local smoothings
};

// `fixed` (#V flags, nonzero = boundary) keeps the boundary vertices where they are;
// `corner_vertices` are the panel's corners (for the gate's measures); `project` lifts a point
// onto the panel's surface (may be empty). The mesh's vertex count and boundary never change;
// its faces may. Each round takes the best change over all folded quads and stops when none
// improves (fewer folded quads, then no new sliver, then a better worst corner); at most
// `rounds` rounds.
FoldRepairResult repair_folds(meshing::QuadMesh& mesh, std::span<const char> fixed,
                              std::span<const int> corner_vertices,
                              const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& project,
                              int rounds = 8);

}  // namespace sd::garment
