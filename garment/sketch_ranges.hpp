#pragma once
// The ranges a sketch file's coordinates, lengths and counts may take (docs/sketch-format.md,
// "Ranges"), so that no number, however large, makes a command slow or huge. Two layers: fixed
// limits checked while the file is read (parse_sketch), and limits relative to the body, checked
// once the body is loaded (check_against_body) and once the edge counts are known
// (check_panel_sizes). Every failure is a SketchError at the value's JSON path.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "garment/garment_request.hpp"
#include "meshing/tri_mesh.hpp"

namespace sd::garment {

// Fixed limits (parse time).
inline constexpr double kMaxCoordinate = 100.0;       // m: any point, camera or sheet centre
inline constexpr double kMaxSheetSide = 100.0;        // m: a sheet's width or height
inline constexpr double kMinBodyHeight = 0.1;         // m: body.height, and a body after scaling
inline constexpr double kMaxBodyHeight = 5.0;         // m
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
// The garment's quads, estimated from the panels' boundary edge counts before filling.
inline constexpr double kMaxGarmentQuads = 400000;

// "130 m is outside ...": the sentence for a coordinate or length `value` (metres) that is out of
// range, with a hint when it reads as centimetres or millimetres typed for metres (its hundredth
// or thousandth would be within [low, high]).
std::string out_of_range_sentence(double value, double low, double high, const std::string& what);

// Every point, seed and camera of the sketch against the body's bounding box (metres, after
// normalisation): within kBodyMarginHeights body heights of it; every curve's control polygon
// at most kMaxCurveLengthHeights body heights long. Throws SketchError.
void check_against_body(const GarmentRequest& sketch, const meshing::BoundingBox& body_box);

// The quads a panel whose boundary has `boundary_edges` edges can hold at most (a square region
// of that perimeter): (B/4)².
double estimated_quads(double boundary_edges);

// Before filling: the garment's estimated quads (sum over panels) must stay below
// kMaxGarmentQuads. `boundary_edges[p]` and `panel_paths[p]` per panel. Throws SketchError at the
// largest panel's path, with the edge length that would fit.
void check_panel_sizes(const GarmentRequest& sketch, const std::vector<double>& boundary_edges,
                       const std::vector<std::string>& panel_paths,
                       const std::vector<std::string>& panel_ids);

}  // namespace sd::garment
