#pragma once
// From a garment request to one stitched garment, in named stages (garment_mesh.cpp):
// 1. resolve_network: strokes projected on the body, the curve network, panel loops, edge counts
//    with the parity fix, panel sizes checked;
// 2. seam_users: each curve piece a seam between at most two panels;
// 3. per panel: boundary vertices placed once per curve piece (BoundaryVertices, shared by the
//    panels on both sides), the panel filled with quads on the body's offset surface or across
//    a hollow (fill_panel, panel_fill.hpp), mirror copies made by reflecting the filled original;
// 4. assemble_mesh: doublets merged, unused vertices dropped, one quad mesh;
// 5. check_fans, check_seam_directions: the panels meet along seams, facing the same way;
// 6. label_panels: join groups, body parts, areas.

#include <Eigen/Core>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "garment/body_surface.hpp"
#include "garment/garment_request.hpp"
#include "meshing/quad_mesh.hpp"
#include "meshing/quad_quality.hpp"

namespace sd::garment {

// Coarse body regions, for collision handling and reports.
enum class BodyPart { kHead, kTorso, kLeftArm, kRightArm, kLeftLeg, kRightLeg };
std::string body_part_name(BodyPart part);

// Region of a point on (or near) an upright, normalised body of height `height` (feet at y = 0,
// facing +Z, left = +x). Bands: head above 0.86 h, legs below the crotch at 0.45 h, arms beyond
// |x| = 0.105 h in between (an A-pose body: torso ±0.09 h at the waist, shoulders ±0.10 h).
BodyPart classify_body_point(const Eigen::Vector3d& p, double height);

struct GarmentPanel {
  std::string id;     // "front", "front.mirror"
  std::string group;  // the join it belongs to, else its id
  std::string fabric;
  std::string body_part;  // nearest body region (majority over its faces)
  bool mirror_copy = false;
  PanelEase ease;                   // warp and weft scale of the rest shape and the pattern piece
  std::vector<std::string> curves;  // boundary curves in loop order (pieces repeat their curve)
  std::vector<int> side_counts;     // edges per side, counter-clockwise from outside
  std::string partition;            // the filler's construction
  int distortion = 0;
  int irregular_vertices = 0;
  meshing::QuadQuality quality;
  int faces = 0;
  double area = 0;           // m²
  double max_body_gap = 0;   // m: largest |distance to body − offset| of on-body vertices
  std::string fit = "body";  // how the interior was shaped: "body" or "free"
  double span_gap = 0;       // m: farthest the spanned surface stands off the offset surface
  // The corners found by turning angle (empty when the panel lists "corners" or a corner lies
  // inside one curve): the curve that begins at each, as "corners" names it, in the order of
  // the panel's boundary list, with the turning angle in degrees. The quality gate suggests
  // the list without the gentlest one.
  std::vector<std::pair<std::string, double>> turning_corners;
  // The corners the panel lists in "corners" (empty when it lists none): the curve that begins at
  // each, as "corners" names it, the junction's place (m) and its turning angle (degrees), in the
  // order of the panel's boundary list. The quality gate says so when a sliver lies at one.
  struct ListedCorner {
    std::string curve;
    Eigen::Vector3d at = Eigen::Vector3d::Zero();
    double turning_deg = 0;
  };
  std::vector<ListedCorner> listed_corners;
  // The grain (GrainSpec, garment_request.hpp): "vertical" or "limb" as chosen, the unit
  // direction whose projection into each quad is the warp there (+Y, or the limb's axis pointing
  // towards the body), and the turn about the outward normal (degrees; a mirror copy's is the
  // original's negated, so that the copy is the reflection).
  std::string grain = "vertical";
  Eigen::Vector3d grain_axis = Eigen::Vector3d::UnitY();
  double grain_turn_deg = 0.0;
};

struct Garment {
  meshing::QuadMesh mesh;      // one conforming mesh, outward orientation
  Eigen::VectorXi face_panel;  // #Q: index into panels
  std::vector<GarmentPanel> panels;
  int seam_edges = 0;      // mesh edges shared by two panels
  int parity_changes = 0;  // curve pieces whose count the parity fix changed
  int curve_pieces = 0;    // network edges used by panels
  // Seam vertices left inside only two quads folded onto each other, merged away (the quality
  // gate warns of each, quality_gate.hpp): a side vertex of one quad on a seam a panel shares
  // with its own mirror copy (the shorts' centre front has one). Each where it was (m), the
  // panels of its two quads (the merged quad keeps the first's) and the curve of its seam ("" if
  // not known).
  struct MergedSeamVertex {
    Eigen::Vector3d where = Eigen::Vector3d::Zero();
    std::string panel, other, curve;
  };
  std::vector<MergedSeamVertex> merged_doublets;
  // The network curve (its id: "hem", "side.mirror") that each mesh edge on a panel's outline
  // lies on, by the edge's (lower, higher) vertex: which seam or edge of the sketch a piece's
  // outline follows (a curve's own seam allowance). Edges made by merging a doublet are absent.
  std::map<std::pair<int, int>, std::string> edge_curve;
};

// The whole meshing pipeline for a sketch with curves and panels. Throws SketchError for
// anything the designer can fix (with the JSON path), std::runtime_error for internal failures.
Garment build_garment(const GarmentRequest& sketch, const BodySurface& body);

}  // namespace sd::garment
