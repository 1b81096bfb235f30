#pragma once
// Flat patterns: every panel of a stitched garment mapped to the plane with as little distortion
// as its surface allows (LSCM as the start, then as-rigid-as-possible iterations that also hold
// every boundary edge at its 3D length, so the two sides of each seam sew), turned so that the
// warp of the panel's material frame runs along the piece's +y (the grain line), with per-panel
// distortion figures, seams as pairs of 2D polylines and the seam junctions as notches.

#include <Eigen/Core>
#include <stdexcept>
#include <string>
#include <vector>

#include "garment/garment_mesh.hpp"

namespace sd::garment {

// A panel that cannot become a flat pattern piece without folding, or that is not a disk (a tube
// closed on itself). `panel()` names it; the message says why and what would help.
class PatternError : public std::runtime_error {
 public:
  PatternError(std::string panel, const std::string& message)
      : std::runtime_error(message), panel_(std::move(panel)) {}
  // A refusal at one place: `where` (m) is written in the message as point_text(where), after
  // which the caller may name the body's nearest landmark.
  PatternError(std::string panel, const std::string& message, const Eigen::Vector3d& where)
      : std::runtime_error(message), panel_(std::move(panel)), where_(where), placed_(true) {}
  const std::string& panel() const { return panel_; }
  bool placed() const { return placed_; }
  const Eigen::Vector3d& where() const { return where_; }

 private:
  std::string panel_;
  Eigen::Vector3d where_ = Eigen::Vector3d::Zero();
  bool placed_ = false;
};

// "(0.151, 1.232, -0.012) m": a place as the pattern's messages write it.
std::string point_text(const Eigen::Vector3d& p);

// Where a surface turns back on itself: the two neighbouring faces (sharing an edge) whose
// normals are farthest apart. A panel drawn into a crease of the body (a kimono's underarm taken
// deep into the armpit) folds there: its faces on the two walls of the crease face each other.
struct SurfaceFold {
  double angle_deg = 0;  // between the two faces' normals (0: flat, 180: folded flat)
  Eigen::Vector3d where = Eigen::Vector3d::Zero();  // the middle of their shared edge (m)
  int edges = 0;  // shared edges whose faces turn more than the threshold asked
};
// Faces: #F rows of 3 (triangles) or 4 (quads, split into two triangles along the diagonal
// the pattern splits them on) vertex indices into `vertices` (#V by 3); only faces with the same
// `group` (when given, #F) are neighbours.
SurfaceFold sharpest_fold(const Eigen::MatrixX3d& vertices, const Eigen::MatrixXi& faces,
                          double threshold_deg, const Eigen::VectorXi* group = nullptr);
// Neighbouring faces of one panel whose normals are more than this far apart: the surface turns
// back on itself. Over the 49 examples and designs the largest angle between neighbouring
// triangles of a panel is 108° (the raglan top's front sleeve), then 87°; trial 41's kimono drawn
// into the armpit turns 140° and 177° (docs/sketch-format.md, `folded_surface`).
inline constexpr double kTurnedBackDeg = 120.0;

struct FlatteningOptions {
  // Length distortion (|σ − 1| of the 3D → 2D map, 95th percentile) above which a panel gets a
  // warning.
  double warn_stretch = 0.05;
  // Above this the panel is refused (PatternError): such a piece is no longer cloth cut flat.
  double refuse_stretch = 0.35;
  int max_iterations = 200;  // as-rigid-as-possible local/global sweeps at most
  // Weight of the boundary-length terms against the triangles' rigidity (per edge, relative to
  // a triangle of area l²/2 next to an edge of length l).
  double boundary_weight = 200.0;
  // Balance notches: a seam longer than balance_from (3D, m) gets notches at equal fractions of
  // each side's length, at most balance_spacing apart (one in the middle of a 30 cm seam, two at
  // its thirds for 53 cm), so the two sides are matched along the way as well as at the ends.
  double balance_from = 0.25;
  double balance_spacing = 0.20;
  // A panel's outline run on the garment's mirror plane, sewn to its own mirror copy (a centre
  // front or back), is flattened a second time with that run held on one straight line (ARAP
  // with the run's points on a line, free to slide along it), so the piece can be cut on the
  // fold; that flattening is kept when its 95th-percentile length distortion is at most this
  // much above the free one's (a negative value never holds a centre line straight). 2.5
  // points: on the examples and designs a bodice or skirt centre held straight costs 0-2.1
  // points, a back over a deep hollow of the spine 3.2-3.8, a crotch curve 3.2-16, a hood 37-40
  // (docs/pattern.md, "Cut on the fold").
  double straight_centre_cost = 0.025;
  // Cut on the fold, a piece's grain is where the fold puts it: its centre line lies on a
  // thread of the folded fabric. A panel whose grain is turned more than this (degrees) off the
  // threads of its centre line (a bias cut, "grain": 45) is not held straight nor cut on the
  // fold: the piece keeps its centre seam and its grain as drawn, cut 2. 2°: fabric is itself
  // woven up to 1-2° askew (docs/pattern.md, "Folds on the grain").
  double fold_off_grain_deg = 2.0;
  // Nor when the warp beside the centre line crosses it anywhere by more than this (degrees;
  // FlatPanel::centre_across_warp_deg): a crotch curve turns forward under the seat, away from
  // the leg's warp, and held straight as a fold it would turn the whole leg off the grain (trial
  // 43, P2: 26°). 45°: beyond it the line runs nearer the weft than the warp there, no thread;
  // on the examples and designs the bodices, skirts, capes and collars reach 0.3-24°, the
  // crotch curves 59-90° (docs/pattern.md, "Folds on the grain").
  double fold_across_warp_deg = 45.0;
  // Cut on the fold, every thread of a piece is parallel to its fold, where the warp on the body
  // runs along the centre line only there and turns away from it across the piece: the fold
  // turns the piece's threads by the angle between the fold and the mean 2D image of its warp,
  // as the piece held straight has it (FlatPanel::fold_turn_deg), and at the side seam by about
  // twice that. A fitted piece (ease under 1 either way: cut smaller than the body, a band under
  // tension round it) shears where its threads run off that tension, so above this turn
  // (degrees) it is not held straight nor cut on the fold but cut as a mirrored pair with a
  // centre seam, each half on its own mean warp (as jeans cut their back yoke). 2°: the
  // fold_off_grain_deg a turned panel is allowed, fabric's own skew; on the examples and designs
  // the fitted front yokes turn 0.66-1.81°, the fitted back yokes 6.44-10.41°, and cut on the fold
  // the back yokes pull the tiered skirt 3.7 mm down and keep the circle skirt from resting
  // (docs/pattern.md, "Round 44"). A piece at ease 1 or more is not held to it: no hoop tension
  // (the back yokes of three skirts at ease 1, turned 6.2-8.9°, rest on the fold).
  double fitted_fold_turn_deg = 2.0;
  // A thread has no sense: cloth stretches alike either way along its warp. A piece's grain is the
  // mean of its warp's 2D images as arrows, unless the line that fits them best as threads (the
  // least-squares axis: the mean of their doubled angles, halved) fits them better by more than
  // this, in the area-weighted mean of sin² of each warp's angle to the grain. That is a piece
  // whose warps run both ways along it: a strap over the shoulder, its warp up the strap on the
  // front and up it again, the other way, on the back, whose arrows cancel along the strap and
  // leave a residue across it (trial 39, P18). Measured with `pattern` on the examples, the
  // designs and the CLI tests' sketches: every piece but the straps gains at most 0.0025 (the
  // one-shoulder top's back strap, arrows 4.5° off the axis); the straps 0.23 (overalls), 0.24
  // (camisole) and 0.65 (trial 36's slip dress) (docs/pattern.md, "Straps over the shoulder").
  double axis_grain_gain = 0.05;
};

// A point on a piece's outline: on edge `edge` (FlatPanel::boundary[edge] → boundary[edge + 1],
// cyclically), at fraction `t` of the edge from its first point.
struct OutlinePoint {
  int edge = 0;
  double t = 0;
};

// Distortion of a flattening: σ₁ ≥ σ₂ are the singular values of each triangle's 3D → 2D map.
struct FlatDistortion {
  double length_max = 0;   // max over triangles of max(σ₁ − 1, 1 − σ₂)
  double length_mean = 0;  // the same, 3D-area-weighted mean
  // Area-weighted 95th percentile: what the worst twentieth of the piece suffers. Warnings and
  // refusals use it, not the max, which one sliver triangle of the quad mesh can set.
  double length_p95 = 0;
  double area_max = 0;   // max |σ₁σ₂ − 1|
  double area_mean = 0;  // 3D-area-weighted mean of |σ₁σ₂ − 1|
  // Area-weighted centroid (3D, and in the piece's 2D frame) of that worst twentieth.
  Eigen::Vector3d worst_point = Eigen::Vector3d::Zero();
  Eigen::Vector2d worst_point_2d = Eigen::Vector2d::Zero();
  // What the surface on the body demands: the angle defect 2π − Σθ (rad) of the triangles round
  // each interior vertex (its Gaussian curvature integrated over its share), summed separately
  // where it is positive (domed: less angle than flat, as over the seat; cut flat, the cloth
  // is short there: a dart) and negative (saddle-shaped: more angle than flat, as a membrane
  // spanned between a hip line and a hem drawn wider than a cone; cut flat, the cloth is short
  // across it: a seam or a godet). Both zero for a developable surface (a cylinder, a cone).
  double dome = 0;    // rad, ≥ 0
  double saddle = 0;  // rad, ≤ 0
};

struct FlatPanel {
  std::string id;
  int panel = -1;             // index into Garment::panels
  std::vector<int> vertices;  // #L: garment vertex of each local vertex
  // #L by 2, metres, as seen from the outside (right side of the fabric up); +y is the warp
  // (grain line), the piece's bounding box starts at (0, 0). Not scaled by the panel's ease.
  Eigen::MatrixX2d uv;
  Eigen::MatrixX3i triangles;     // #T local indices, counter-clockwise in 2D and seen from outside
  Eigen::VectorXi triangle_quad;  // #T garment quad of each triangle (two per quad)
  std::vector<int> boundary;      // local vertex loop, counter-clockwise in 2D
  std::vector<int> notches;       // local boundary vertices where seams meet (loop order)
  std::vector<OutlinePoint> balance_notches;  // along long seams (PatternSeam::balance)
  FlatDistortion distortion;
  double area_3d = 0;  // m²
  double area_2d = 0;  // m², before ease
  int iterations = 0;  // ARAP sweeps made
  // The centre line held straight (local vertices along the outline, on the garment's mirror
  // plane and sewn to the panel's mirror copy; FlatteningOptions::straight_centre_cost): it lies
  // on one line along +y. Empty when the piece was flattened freely. Then also what the free
  // flattening gave: how far the run bowed from its chord (m) and the free distortion.
  std::vector<int> centre_run;
  // For a panel with a centre line (a run on the mirror plane sewn to its mirror copy): the
  // angle between that line and the nearest thread, warp or weft (degrees, 0 .. 45), as the cut
  // piece has it. A line on a thread (the panel's turn within fold_off_grain_deg of the threads,
  // the warp beside it within fold_across_warp_deg) is held straight on the grain line: its
  // grain's turn (GarmentPanel::grain_turn_deg) folded onto the threads. Any other line keeps
  // its seam: the angle of its chord in the piece to the grain line or the cross grain (a bias
  // panel's about 45°, a crotch curve's 30-40°). −1 when the panel has no centre line.
  double centre_off_grain_deg = -1;
  // For a panel with a centre line: the largest angle between it and the warp beside it (before
  // the panel's turn, degrees, 0 .. 90); above fold_across_warp_deg the line is not held
  // straight. −1 when the panel has no centre line.
  double centre_across_warp_deg = -1;
  // For a panel whose centre line was flattened held straight (kept or not): the angle between
  // that line (the fold) and the mean 2D image of the warp over the held piece (degrees, 0 ..
  // 45, to the nearer thread): how far the fold turns the piece's threads off the warp's. −1 when
  // no held flattening was made. `fold_turn_refused`: the held flattening was not kept for that
  // turn (a fitted piece, FlatteningOptions::fitted_fold_turn_deg): the piece keeps its centre
  // seam.
  double fold_turn_deg = -1;
  bool fold_turn_refused = false;
  double free_centre_bow = 0;
  FlatDistortion free_distortion;
  // A mirror copy whose 3D triangles are exactly its original's reflected: the index (into
  // FlatPattern::panels) of that original, whose piece this one is, reflected (x → width − x).
  // −1 for a piece flattened on its own.
  int reflection_of = -1;
  std::string warning;  // empty unless the piece stretches more than warn_stretch
};

// One seam: the same run of garment edges seen from both panels, as local vertex lists in the
// same order (vertices_a[i] and vertices_b[i] are the same garment vertex).
struct PatternSeam {
  int panel_a = -1, panel_b = -1;  // indices into FlatPattern::panels
  std::vector<int> vertices_a, vertices_b;
  double length_3d = 0;               // m along the garment
  double length_a = 0, length_b = 0;  // m in the two pieces (before ease)
  // Fractions (0..1, increasing from vertices_a[0]) of each side's own length where both sides
  // have a balance notch: eased or not, the two sides are sewn matching these points.
  std::vector<double> balance;
  // |length_a − length_b| / max(length_a, length_b): how well the flattening lets it sew.
  double mismatch() const;
};

struct FlatPattern {
  std::vector<FlatPanel> panels;  // one per garment panel, in the garment's order
  std::vector<PatternSeam> seams;
  std::vector<std::string> warnings;
};

// Flattens every panel of `garment`. Throws PatternError for a panel that is not a disk or that
// cannot be flattened without folding or beyond refuse_stretch; never returns an inverted 2D
// triangle.
FlatPattern flatten_garment(const Garment& garment, const FlatteningOptions& options = {});

// Flattens one disk-shaped triangle mesh (vertices #V by 3, triangles #T by 3, counter-clockwise
// from the side that should face up in 2D). `warp` (3D, may be zero: then the mesh's longest
// axis) sets the +y direction. Fills uv, boundary, distortion, areas, iterations; `name` is
// used in messages. The building block of flatten_garment, public for tests.
FlatPanel flatten_disk(const std::string& name, const Eigen::MatrixX3d& vertices,
                       const Eigen::MatrixX3i& triangles, const Eigen::Vector3d& warp,
                       const FlatteningOptions& options = {});

}  // namespace sd::garment
