#pragma once
// The flat pattern laid out for cutting: each flattened panel scaled by its ease (what is cut),
// its sewing line offset outwards by the seam allowance into the cutting line (CGAL straight
// skeleton), notches where seams meet, a grain line along the warp, and the pieces nested on a
// length of fabric of a given width (bottom-left on column skylines, grain along the bolt).

#include <Eigen/Core>
#include <vector>

#include "garment/garment_request.hpp"
#include "garment/panel_flattening.hpp"
#include "garment/pattern_outline.hpp"

namespace sd::garment {

struct PatternLayoutOptions {
  double fabric_width = 1.5;     // m, across the bolt (selvedge to selvedge)
  double seam_allowance = 0.01;  // m, for pieces without their own
  // Per FlatPattern panel (empty: none); a negative entry takes seam_allowance.
  std::vector<double> panel_allowance;
  // Per FlatPattern panel, per outline edge k (boundary[k] → boundary[k + 1]): that edge's own
  // allowance (a seam's or a hem's, m), or negative for the piece's; an empty list (or none for
  // the panel) gives the piece's everywhere.
  std::vector<std::vector<double>> edge_allowance;
  std::vector<PanelEase> panel_ease;  // per panel rest-shape scale (empty: 1)
  double gap = 0.01;                  // m between pieces, and from the selvedges and the cut end
  // Per FlatPattern panel, per outline point k (boundary[k]): where the outline passes from one
  // sketch curve to the next, a corner the smooth sewing line keeps (empty: none given). Seam
  // junctions (FlatPanel::notches) and turns sharper than kCornerTurn are corners too.
  std::vector<std::vector<bool>> corners;
  // Per FlatPattern panel, per outline edge k: the edge lies on the garment's mirror plane and
  // the piece is cut on the fold there (no seam allowance; empty: no fold).
  std::vector<std::vector<bool>> fold_edge;
  // Per FlatPattern panel: the panel whose fold piece this one is the other half of (a mirror
  // copy sewn to its original along the centre line only), or −1. Such a piece is not laid out.
  std::vector<int> folded_into;
  // A panel "X" and its mirror copy "X.mirror" whose pieces are each other's reflection to
  // kMirrorPairTolerance (cutting and sewing lines, notches) are drawn once on the sheet, as
  // "cut 2 (mirror pair)" (PatternPiece::quantity); false draws every piece.
  bool pair_mirrors = true;
};

// A turn of the outline sharper than this (radians) at a point is a corner the smooth sewing
// line keeps: 40°, above the mesh's turns along a drawn curve (an armhole of 6 cm radius at
// 3 cm edges turns 29° a point) and below a seam corner (60-120°).
constexpr double kCornerTurn = 40.0 * 3.14159265358979323846 / 180.0;
// m: the densified sewing curve lies within this of its Béziers (a pencil line is 0.5 mm wide).
constexpr double kCurveTolerance = 1e-4;

// m: two pieces closer than this to each other's reflection, every point of each outline within
// it of the other's, are one piece to a cutter (a pencil line is about 0.5 mm wide, and shears
// follow a line to about a millimetre).
constexpr double kMirrorPairTolerance = 5e-4;

// A notch on the sewing line, `normal` pointing out of the piece (unit).
struct PatternNotch {
  Eigen::Vector2d point = Eigen::Vector2d::Zero();
  Eigen::Vector2d normal = Eigen::Vector2d::UnitY();
  double allowance = 0;  // m: the narrower of the allowances of the two outline edges there
  // A balance notch along a seam (FlatPanel::balance_notches), not a seam junction.
  bool balance = false;
};

// A run of the sewing line with one seam allowance: edges first .. last (edge i joins sewing
// point i to i + 1, cyclically), `allowance` m.
struct AllowanceRun {
  int first = 0, last = 0;
  double allowance = 0;
};

// One piece in its own frame: piece = scale() · FlatPanel::uv + origin (m), warp along +y, the
// cutting line's bounding box starting at (0, 0): x scaled by the weft ease, y by the warp
// ease. A gathered piece (different factors) is cut longer than the seams it gathers into:
// spread about the apex of its sides along the grain (docs/pattern.md, "Gathered seams"), so
// that those sides keep the smaller factor; scale() · uv is then its limit for parallel sides.
// On the fabric it sits at `placement`.
struct PatternPiece {
  int panel = -1;  // index into FlatPattern::panels
  PanelEase ease;
  double allowance = 0;                  // the piece's (m), where no seam has its own
  std::vector<AllowanceRun> allowances;  // along the sewing line, covering every edge once
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();
  // The outline's points (the panel's boundary vertices), closed (first point not repeated),
  // CCW; point k is FlatPanel::boundary[k].
  Eigen::MatrixX2d sewing;
  // The sewing line: the smooth curve through `sewing` (pattern_outline.hpp), densified to
  // kCurveTolerance; curve.at[k] is point k's row.
  SmoothOutline curve;
  // The smooth sewing line offset out by its allowances, CCW: by the straight skeleton when they
  // are all equal; else each simplified edge's line moved out by its own and neighbouring lines met
  // at their intersection (a mitred corner; where two different allowances meet nearly in line, a
  // step across).
  Eigen::MatrixX2d cutting;
  std::vector<PatternNotch> notches;
  Eigen::Vector2d grain_start = Eigen::Vector2d::Zero(), grain_end = Eigen::Vector2d::Zero();
  Eigen::Vector2d size = Eigen::Vector2d::Zero();       // of the cutting line's bounding box
  Eigen::Vector2d placement = Eigen::Vector2d::Zero();  // on the sheet: x across, y along
  // How many times the drawn piece is cut: 1; 2 for a panel whose mirror copy it stands for
  // (cut 2, the second with the piece turned over); 0 for that copy, which is not drawn: its
  // piece is `drawn_as`'s (index into PatternLayout::pieces; −1 for a drawn piece), reflected,
  // and its placement is that piece's.
  int quantity = 1;
  int drawn_as = -1;
  // The ease as the piece frame's (x, y) scale: (weft, warp).
  Eigen::Vector2d scale() const { return {ease.weft, ease.warp}; }
  double sewn_area = 0, cut_area = 0;  // m²
  // Cut on the fold: the fold line (piece frame, from fold_start to fold_end along the outline)
  // is the piece's straight edge on the garment's mirror plane, cut with no allowance; the piece
  // stands for itself and its mirror copy. `folded_into` ≥ 0: this piece is that copy, not laid
  // out (index into PatternLayout::pieces of the fold piece).
  bool on_fold = false;
  Eigen::Vector2d fold_start = Eigen::Vector2d::Zero(), fold_end = Eigen::Vector2d::Zero();
  int folded_into = -1;
};

struct PatternLayout {
  std::vector<PatternPiece> pieces;  // in FlatPattern order
  double fabric_width = 0;           // m
  // The fabric to cut every piece as many times as it is cut, from one layer (a mirror pair's
  // piece twice, the second turned over; a piece cut on the fold opened out, both its halves,
  // the fabric it takes however the fold is made): m from the cut end to the last piece
  // (+ gap), and Σ cut area (a fold piece's twice) / (length_used · fabric_width).
  double length_used = 0;
  double efficiency = 0;
  // The sheet: the drawn pieces (quantity ≥ 1, a fold piece as its half) at their placements,
  // the same as the above when no piece stands for a mirror pair or is cut on the fold. m, and
  // Σ drawn cut area / (sheet_length · width).
  double sheet_length = 0;
  double sheet_efficiency = 0;
  int pairs = 0;  // pieces drawn once for a mirror pair
};

// Every point of FlatPattern piece p (FlatPanel::uv's rows, m, before `origin`) as cut with its
// ease (`eases` per FlatPattern panel; empty or short: 1): the piece frame scaled by diag(weft,
// warp), or, for a gathered piece whose sides along the grain meet at an apex, spread about it
// (docs/pattern.md, "Gathered seams"); `spread` says which. The sewing line is this map's image
// of the outline, and the flat rest drapes this map's image of every triangle, so that the
// cloth draped is the cloth cut.
struct EasedPiece {
  Eigen::MatrixX2d uv;  // #L by 2
  bool spread = false;
};
EasedPiece eased_piece(const FlatPattern& pattern, size_t p, const std::vector<PanelEase>& eases);

// Lays out every piece (a mirror pair's once on the sheet: PatternLayoutOptions::pair_mirrors).
// Throws PatternError for a piece whose outline crosses itself in 2D, whose
// cutting line with different seam allowances crosses itself (a concave curve tighter than its
// allowance) or that is wider than the fabric.
PatternLayout lay_out_pattern(const FlatPattern& pattern, const PatternLayoutOptions& options = {});

}  // namespace sd::garment
