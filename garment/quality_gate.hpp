#pragma once
// The quality gate of a meshed garment: per panel, the quads the simulator would struggle with
// (folded quads, slivers with a tiny corner, long thin quads, vertices almost on top of each
// other, quads far from the asked size), each reported once per panel and kind with the worst
// place (a 3D point and the nearest body landmark) and what to change in the sketch.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "garment/body_landmarks.hpp"
#include "garment/garment_mesh.hpp"
#include "garment/garment_request.hpp"

namespace sd::garment {

struct QualityLimits {
  double min_angle_deg = 10.0;     // a quad corner below this is a sliver
  double max_aspect_ratio = 10.0;  // longest over shortest edge of a quad
  double near_fraction = 0.1;      // vertices closer than this × edge_length are near-coincident
  double size_low = 0.25;          // a quad's mean side outside [low, high] × edge_length (low:
                                   // a tapering panel needs small quads near its apex)
  double size_high = 2.0;
  // m: cloth deeper than this inside the body is reported: twice the simulator's penetration
  // tolerance (1 mm), so that the sag of a quad's middle below its corners on the offset surface
  // over a bent arm (an armpit or an elbow, 1-2 mm on the corpus) is not reported, a hem written
  // through a knee (15 mm) or a thigh bulging through a wide leg (6 mm) is.
  double inside_tolerance = 0.002;
  // Quads above which check_quality_tried does not try its advice: each trial meshes the whole
  // garment again (the shirt at edge_length 0.006: 23,426 quads, 18 warnings, validate 120 s
  // of CPU with its trials; at 0.01, 8,482 quads, 5 s), so a fine preview would run for minutes
  // before it said anything. Above this the advice that needs a trial is left out and an info
  // line says so.
  int max_trial_quads = 15000;
};

struct QualityWarning {
  std::string panel;
  std::string kind;    // "inverted_quads", "min_angle", "aspect_ratio", "near_vertices",
                       // "quad_size", "self_intersection" (count: crossing triangle pairs),
                       // "inside_body" (check_quality_tried only; count: quads, worst: m deep),
                       // "junction_in_cleft" (check_quality_tried only; a seam junction in a
                       // cleft of the body, body_clefts.hpp; panel: the first of the junction's,
                       // count: its panels, worst: the cleft's width in m),
                       // "merged_seam_vertex" (merged_seam_vertex_warnings only; count 1)
  int count = 0;       // quads (or vertex pairs) of that kind in the panel
  double worst = 0.0;  // the worst value (degrees, ratio, metres, or size / edge_length)
  Eigen::Vector3d where = Eigen::Vector3d::Zero();  // m, the worst place
  std::string landmark;  // the nearest body landmark ("" when the body has none)
  std::string message;   // one sentence for the designer, with what to change
  // The "corners" list the message offers (a folding panel's turning corners without the
  // gentlest) and the words that offer it, as they appear in `message`; empty when none.
  std::vector<std::string> corners;
  std::string corners_hint;
  // A min_angle warning's sliver at a corner the panel lists in "corners": the curve that begins
  // there (its message says the corner is listed); else empty.
  std::string listed_corner;
  // check_quality_tried's other offer for such a panel: the garment has fewer warnings without
  // its "corners" list (the corners then where its outline turns most); `corners` is then empty.
  bool corners_unlisted = false;
  // A curve the message offers its own edge_length for (m; check_quality_tried), else empty.
  std::string curve;
  double curve_edge_length = 0.0;
  // The panel's own edge_length the message offers with it (m; a fifth below the panel's, when
  // no curve alone helps; for "inside_body", 0.7 of it when that was tried and clears the
  // panel), else 0.
  double panel_edge_length = 0.0;
};

// Checks every panel of `garment` except mirror copies (the same quads reflected: a warning on
// the original holds for its copy). `landmarks` may be null (a body that is not a standing
// figure).
std::vector<QualityWarning> check_quality(const Garment& garment, const GarmentRequest& sketch,
                                          const BodyLandmarks* landmarks,
                                          const QualityLimits& limits = {});

// check_quality, with the advice that rewrites the sketch tried before it is given: a panel
// offered a "corners" list is meshed again with it (the rest of the sketch unchanged), and the
// offer stays only when the garment then has fewer warnings, else it is taken out of the
// message; quads larger than the band are offered an edge_length of their own for the panel's
// curve nearest them (with the panel's own a fifth lower when no curve alone helps), only one
// that was tried and gave fewer warnings (dropping the underarm corner cleaned the tank top's
// back on the Collada human, but dropping the shell top's turned its 2 warnings into 3). Costs
// one more garment build per panel with an offer (and the body's search tree, built then; up to
// 13 for quads too large: trial 40's poncho validated in 0.80 s of CPU instead of 0.55 s); none
// above `limits.max_trial_quads` quads, where those offers are left out.
std::vector<QualityWarning> check_quality_tried(const Garment& garment,
                                                const GarmentRequest& sketch,
                                                const meshing::TriMesh& body,
                                                const BodyLandmarks* landmarks,
                                                const QualityLimits& limits = {});

// The seam vertices the garment merged away (Garment::merged_doublets), one warning each with
// its place, the curve of its seam and the panel it is shared with (mirror copies' own left out:
// the original's holds). Not the gate's: the filler's layout causes them, no sketch change
// measured so far removes them (trial 39's shortalls, curve 'cf' at 1.6-2.0 cm edges), so
// validate --strict and mesh --strict do not count them. Trial 39, P5: before, one line without
// file or place, printed by every build of the garment (4 times by validate).
std::vector<QualityWarning> merged_seam_vertex_warnings(const Garment& garment,
                                                        const BodyLandmarks* landmarks);

}  // namespace sd::garment
