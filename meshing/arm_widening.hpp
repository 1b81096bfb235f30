#pragma once
// A long thin arm of a region that widens towards the rest (a strap that runs out of a bodice):
// where to cut across it so that the arm can be filled as a 4-sided part of its own, with more
// quads across at the cut than at its end (docs/meshing.md, "Round 42: an arm that widens").
//
// Every layout of the whole region whose irregular vertices lie outside the arm keeps the arm as
// many quads wide as its end all the way to where it joins; cut off, the arm (end l, sides a and
// b, cut c > l) is a 4-sided region with unequal opposite sides, which the filler fills with a
// valence-3/valence-5 pair (or a padded equivalent) inside it, and the cut's vertices become
// interior vertices of the joined mesh.

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <vector>

#include "meshing/patch_fill.hpp"

namespace sd::meshing {

struct ArmCut {
  int end_side = -1;     // the arm's end, a short side; its neighbours run along the arm
  int from_vertex = 0;   // the cut starts at this vertex of side end_side − 1 (0 = its first)
  int to_vertex = 0;     // ... and ends at this vertex of side end_side + 1
  int across = 0;        // edges along the cut (more than the end has)
  double end_width = 0;  // distance between the end's two corners
  double cut_width = 0;  // distance between the cut's two ends
};

// The arm that most needs widening, if any: a side of at most kArmEndEdges (4) edges between two
// sides each at least kArmSideRatio (4) times as long (a long thin arm), walked from its end
// along both sides, pairing each vertex of the side before it with the nearest vertex of the side
// after it, up to where the sides diverge (the width grows by more than kJoinSlope (0.5) of the
// step along the side) or the width reaches kMostWidening (3) times the end's. The cut is the last
// such pair, at least kLeastArmEdges (3) edges from the end on both sides and no nearer the end
// than kLeastArmLength (2) times its width, and kLeastWidening (1.25) times as wide as the end;
// `across` is its width over the region's mean boundary
// edge length rounded to the parity the parts need. nullopt when no arm needs more quads across at
// the cut than at its end. side_points as for fill_region.
std::optional<ArmCut> find_arm_cut(const std::vector<Eigen::MatrixX3d>& side_points);

// The two parts of a region cut at `cut`: the arm (4 sides: the arm's side before the end from
// the cut on, the end, the side after it up to the cut, the cut back) and the rest (the side
// before the end up to the cut, the cut, the side after the end from the cut on, then the other
// sides in order). The cut's vertices are on the straight line between its ends, moved by
// `project` when given.
struct ArmParts {
  std::vector<Eigen::MatrixX3d> arm, rest;
};
ArmParts split_at_arm_cut(
    const std::vector<Eigen::MatrixX3d>& side_points, const ArmCut& cut,
    const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& project = {});

// The region filled in two parts: `fill_part` fills the arm and the rest (split_at_arm_cut), the
// two meshes are joined along the cut (whose vertices become interior) and the joined interior is
// relaxed (options.relax_iterations sweeps, options.project). The result's side_vertices are the
// region's sides; its topology's mesh is the joined mesh (3D), partition "arm-cut"; distortion and
// quality measured. Throws FillError when a part cannot be filled.
FilledPatch fill_with_arm_cut(
    const std::vector<Eigen::MatrixX3d>& side_points, const ArmCut& cut,
    const std::function<FilledPatch(const std::vector<Eigen::MatrixX3d>&)>& fill_part,
    const FillGeometryOptions& options = {});

// The largest ratio of a quad's mean side to `edge`, or of `edge` to it, over the mesh's quads
// (1 when every quad's mean side is exactly `edge`): the quality gate warns above 2
// (docs/garment.md).
double worst_quad_size(const QuadMesh& mesh, double edge);

}  // namespace sd::meshing
