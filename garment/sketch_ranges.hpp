#pragma once
// The ranges a sketch file's coordinates, lengths and counts may take (docs/sketch-format.md,
// "Ranges"), so that no number, however large, makes a command slow or huge. Two layers: fixed
// limits checked while the file is read (parse_sketch), and limits relative to the body, checked
// once the body is loaded (check_against_body) and once the edge counts are known
// (check_panel_sizes). Every failure is a SketchError at the value's JSON path.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "garment/garment_request.hpp"
#include "meshing/tri_mesh.hpp"

namespace sd::garment {

// Fixed limits (parse time).
inline constexpr double kMaxCoordinate = 100.0;  // m: any point, camera or sheet centre
inline constexpr size_t kMaxIdLength = 64;  // characters of a panel's, a curve's or a group's id
inline constexpr double kMaxSheetSide = 100.0;  // m: a sheet's width or height
inline constexpr double kMinBodyHeight = 0.1;   // m: body.height, and a body after scaling
inline constexpr double kMaxBodyHeight = 5.0;   // m
inline constexpr double kTallestPerson = 2.5;   // m: a body taller than this is warned of
inline constexpr double kShortestPerson = 1.0;  // m: errors ask whether a body this short is meant
inline constexpr double kMaxJunctionTolerance = 0.2;  // m
inline constexpr int kMaxCurves = 1000;
inline constexpr int kMaxPanels = 1000;
inline constexpr int kMaxPointsPerCurve = 10000;
inline constexpr int kMaxCurveEdges = 20000;  // "edges" of one curve
inline constexpr int kMaxRelaxIterations = 1000;
inline constexpr int kMaxImages = 64;       // output.images entries
inline constexpr int kMaxImageSide = 4096;  // px; render::kMaxImageSide (checked in src/app)
inline constexpr double kMaxGravity =
    10000.0;                                  // m/s² per component (1000 g, as far as stress goes)
inline constexpr double kMinTimeStep = 1e-5;  // s
inline constexpr double kMaxTimeStep = 0.1;   // s
inline constexpr double kMaxDuration = 3600.0;                     // s of simulated time
inline constexpr std::uintmax_t kMaxSketchFileBytes = 16'000'000;  // a sketch file
inline constexpr std::uintmax_t kMaxMeshFileBytes = 512'000'000;   // a body or garment mesh
// A body's triangles (the built-in body has 8,560; scans come with 50k-500k). A 2M-triangle
// body took 20 s and 790 MB only to be described by `info` (loaded machine); over this it is
// refused with the count and how to reduce it instead of loading for minutes.
inline constexpr std::size_t kMaxBodyTriangles = 1'000'000;

// output.pattern.fabric_width and `pattern --fabric-width`: a strip of trim to a wide sheeting.
inline constexpr double kMinFabricWidth = 0.1;   // m
inline constexpr double kMaxFabricWidth = 10.0;  // m
// A seam allowance (a curve's, a panel's or the pattern's), metres: 10 cm is a deep hem.
inline constexpr double kMaxSeamAllowance = 0.1;

// Relative to the body (once it is loaded).
// Points may lie this many body heights outside the body's bounding box (a flared hem, a cape).
inline constexpr double kBodyMarginHeights = 1.0;
// A curve's control polygon may be at most this many body heights long.
inline constexpr double kMaxCurveLengthHeights = 5.0;
// All curves' control polygons together, in body heights (bounds the samples projected).
inline constexpr double kMaxTotalCurveLengthHeights = 200.0;
// The garment's quads, estimated before filling (estimated_quads below): above this the file is
// refused before any panel is filled, with what it would cost and the edge length that fits.
// The long-sleeved tee at 0.4 cm (51,000 quads) takes 35 s of CPU and 155 MB to validate; at
// 150,000 quads meshing alone would take about two and a half minutes and 450 MB (docs/garment.md,
// "Meshing time and memory at fine edge lengths").
inline constexpr double kMaxGarmentQuads = 150000;
// `fill --sides`: one flat region, no body to lift onto.
inline constexpr double kMaxFillQuads = 400000;
// What meshing a garment costs per quad (CPU seconds, peak resident bytes), for the message:
// 0.70 ms and 3.0 kB per quad measured on the long-sleeved tee at 0.4 cm; the time per quad grows
// with the fineness (folds, docs/garment.md), hence 1 ms.
inline constexpr double kMeshingSecondsPerQuad = 1e-3;
inline constexpr double kMeshingBytesPerQuad = 3000;

// The values a quantity usually takes (metres), inside its allowed range: which reading of a
// number typed in another unit is the likely one. The whole line by default (no preference).
struct UsualRange {
  double low = -1e300;
  double high = 1e300;
};
// Usual values of the sketch's lengths: a point on or round a standing body (its height is at
// most 2.5 m but for a giant), an edge of a garment's mesh (the examples use 1.5-4 cm), a seam
// allowance (3 mm on a fine seam to a 5 cm hem; 1 cm and 15 mm are the standard), a bolt's
// width (0.9-3.2 m), a body's height, a sheet's side (a 10 cm swatch to a 3 m sheet), a junction
// tolerance (2 mm to 5 cm).
inline constexpr UsualRange kUsualCoordinate{-2.5, 2.5};
inline constexpr UsualRange kUsualEdgeLength{0.005, 0.05};
inline constexpr UsualRange kUsualSeamAllowance{0.003, 0.05};
inline constexpr UsualRange kUsualFabricWidth{0.9, 3.2};
inline constexpr UsualRange kUsualBodyHeight{0.5, 2.5};
inline constexpr UsualRange kUsualSheetSide{0.1, 3.0};
inline constexpr UsualRange kUsualJunctionTolerance{0.002, 0.05};
// The shortest "edge_length" a file may give (m; scene/sketch_reader.hpp refuses less).
inline constexpr double kMinEdgeLength = 0.002;

// "130 m is outside ...": the sentence for a coordinate or length `value` (metres) that is out of
// range, with a hint when it reads as centimetres or millimetres typed for metres (its hundredth
// or thousandth would be within [low, high]); a reading within `usual` is named first (a seam
// allowance of 10 is 10 mm, not 10 cm; a hem at 520 is 520 mm, not 5.2 m), both when both fit.
std::string out_of_range_sentence(double value, double low, double high, const std::string& what,
                                  UsualRange usual = {});

// "1.75 m tall" for a body `height` metres tall; outside kShortestPerson .. kTallestPerson
// "0.65 m tall: is that meant? A body's "height" is in metres, …": in an error about a point
// out of reach or a curve that misses the body, the body's size is the likelier slip (trial 40:
// "height": 0.1; trial 42, P10: an inch file read as centimetres).
std::string body_height_clause(double height);

// Every point, seed and camera of the sketch against the body's bounding box (metres, after
// normalisation): within kBodyMarginHeights body heights of it; every curve's control polygon
// at most kMaxCurveLengthHeights body heights long. Throws SketchError.
void check_against_body(const GarmentRequest& sketch, const meshing::BoundingBox& body_box);

// The quads a region whose boundary has `boundary_edges` edges can hold at most (a square region
// of that perimeter): (B/4)².
double estimated_quads(double boundary_edges);

// A panel's size as the edge counts and its curves give it, before it is filled.
struct PanelSize {
  std::string id;    // "front", "front.mirror"
  std::string path;  // the panel's JSON path
  bool mirror_copy = false;
  double boundary_edges = 0;
  double boundary_length = 0;  // m
  double area = 0;  // m²: the fan of triangles from its outline's centroid to its outline
  // The outline's pieces of curves with a fixed "edges" count (CurveSpec::edges): the curve
  // (index into GarmentRequest::curves) and the edges and length (m) it gives this outline.
  struct FixedEdges {
    int curve = -1;
    double edges = 0;
    double length = 0;
  };
  std::vector<FixedEdges> fixed;
};

// A panel's quads, estimated: its area over its mean boundary edge squared (the filler keeps
// quads of about that edge, docs/garment.md "Fill consistency"), the area being 1.1 times the fan
// of its outline (over the corpus the meshes had 0.93-1.38 times the fan's count), at most (B/4)².
double estimated_quads(const PanelSize& panel);

// The area of the fan of triangles from the centroid of a closed outline (#P points, the last
// not repeating the first) to each of its segments: the area of a flat star-shaped outline, and
// a little less than that of a curved panel spanning it (a half-tube's: 0.8 of it).
double fan_area(const std::vector<Eigen::Vector3d>& outline);

// Before filling: the garment's estimated quads (sum over panels) must stay below
// kMaxGarmentQuads. Throws SketchError saying how many quads the garment would have, what
// meshing them would cost (kMeshingSecondsPerQuad, kMeshingBytesPerQuad) and what would fit: at
// a curve's "edges" when fixed counts cut edges far shorter than the rest of their panels' and
// counts that give them their panels' edge would fit (the count to give), else at the largest
// panel's path with the edge length that would fit.
void check_panel_sizes(const GarmentRequest& sketch, const std::vector<PanelSize>& panels);

// Below this mean edge along its outline (m) a panel is warned about before it is filled, with the
// quads its edge implies: where the quad filler was measured to stay clean (trial 41, P3, on the
// built-in body's front: a 30 × 45 cm panel clean at 4 mm, 9,348 quads; 2 quality warnings at
// 3.5 mm; 6-7 at 2-3 mm, 16,871-37,395 quads, with slivers, vertices on one spot and quads
// inside the body; a 20 × 20 cm patch clean at 3 mm). Not a quad count: the patch broke at 6,885
// quads where the large panel was clean at 9,348 (docs/sketch-format.md, "Limits").
inline constexpr double kCleanEdgeLength = 0.004;
// The counts round each curve's length over its edge, so a panel asked for 4 mm has a mean edge
// within a few per cent of it: 3 % below is still "at 4 mm".
inline constexpr double kCleanEdgeSlack = 0.03;

// Before filling: a sentence for every panel (not a mirror copy) whose mean boundary edge is
// below kCleanEdgeLength, with the quads it implies (estimated_quads), what meshing them costs and
// what was measured; empty when none is. A warning, not a refusal: a smaller panel can be clean
// finer (the patch above), and the quality gate judges the mesh made.
std::vector<std::string> fine_edge_warnings(const GarmentRequest& sketch,
                                            const std::vector<PanelSize>& panels);

}  // namespace sd::garment
