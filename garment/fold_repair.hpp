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
// in one quad on a saddle of the body (shirt-human's armpit) folds by the stitched garment's
// normals but not by the panel's own: the second pass after stitching (garment_mesh.cpp) runs
// the same repair with the neighbouring panels' share of each seam vertex's normal
// (`extra_normals`), so that it judges the panel as the quality gate does.

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
  // Work done, for the tests that keep it local: candidate changes judged, and quads measured
  // again to judge them (each candidate re-measures only the quads its change reaches, about
  // 10-40, however large the mesh; the rounds measure the whole mesh once each).
  int candidates = 0;
  long quads_measured = 0;
};

// `fixed` (#V flags, nonzero = boundary) keeps the boundary vertices where they are;
// `corner_vertices` are the panel's corners (for the gate's measures); `project` lifts a point
// onto the panel's surface (may be empty). The mesh's vertex count and boundary never change;
// its faces may. Each round takes the best change over all folded quads and stops when none
// improves (fewer folded quads, then no new sliver, then a better worst corner); at most
// `rounds` rounds. `extra_normals` (#V × 3, or empty): what the quads outside this mesh add to
// each vertex's normal (the sum of their corner cross products, m², as the quality gate sums
// them over the stitched garment); with it a quad folds when a corner turns against the summed
// normals of the whole garment (the gate's measure, garment/quality_gate.cpp) and the worst
// corner is taken the same way.
FoldRepairResult repair_folds(meshing::QuadMesh& mesh, std::span<const char> fixed,
                              std::span<const int> corner_vertices,
                              const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& project,
                              int rounds = 8, const Eigen::MatrixX3d& extra_normals = {});

}  // namespace sd::garment
