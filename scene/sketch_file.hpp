#pragma once
// The scene layer's sketch file (format "sketchdrape/1", docs/sketch-format.md): it reads and
// validates the file once and hands each module its own plain inputs: the garment request
// (garment::GarmentRequest, the base of Sketch), the simulator's settings (SimulateSpec, whose
// adaptive settings are sim's own type) and the render specs (OutputSpec's images). Units are
// metres, +Y up, the mannequin faces +Z. Parsing checks each field on its own; whether curves
// meet, panels close and strokes land on the body is checked later (curve network, projection),
// with the same SketchError and JSON paths.
//
// Where a new field goes: a garment field (curve, panel, join, meshing setting) in
// garment/garment_request.hpp and its parser in scene/sketch_garment.cpp; a "simulate" field in
// SimulateSpec below (an adaptive one in sim::AdaptiveSettings) and its parser in
// scene/sketch_settings.cpp; an "output" or "sheet" field below, parsed in
// scene/sketch_settings.cpp.

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "garment/garment_request.hpp"
#include "garment/sketch_error.hpp"
#include "sim/adaptive_settings.hpp"

namespace sd::scene {

inline constexpr const char* kSketchFormat = "sketchdrape/1";

// How the drape is simulated (`sketchdrape run`): plain values with defaults.
struct SimulateSpec {
  double duration = 3.0;        // seconds of simulated time at most
  bool duration_given = false;  // the file says "duration"
  bool adaptive = true;         // 4-8 refinement/coarsening
  bool adaptive_given = false;  // the file says "adaptive" (a sheet adapts only then)
  // "adaptive": {...} (with "enabled" for the bool): the simulator's own settings, its defaults
  // where the file says nothing (docs/adaptive.md); checked together by run (validate()).
  sim::AdaptiveSettings adaptive_settings;
  double time_step = 1.0 / 60.0;              // seconds, the largest step
  std::string integrator = "implicit-euler";  // "implicit-euler" | "bdf2"
  std::string solver = "auto";                // "auto" (the default) | "pcg" | "cholmod"
  // "time_step": "auto" (the default): the step, like an "auto" solver, is chosen from the scene
  // (sim/automatic_settings.hpp); time_step is then what estimates assume before it is built.
  bool time_step_auto = true;
  // "quadratic" | "hinges": the discrete bending energy (docs/simulator.md, "Bending on any
  // mesh"); empty: the scene's default, quadratic for sheets and imported meshes (the hinges
  // are too soft on the 4-8 mesh: the cantilever droops to 47.8–48.6° instead of 41.5°,
  // docs/fabrics.md), hinges for sketched garments (two designs of the corpus do not come to
  // rest with the quadratic model yet).
  std::string bending;
  // "linear" | "buckling": the membrane's answer to compression (docs/simulator.md,
  // "Compression and buckling"); buckling caps it at each triangle's Euler load.
  std::string compression = "linear";
  bool compression_given = false;  // the file says "compression" (a gathered flat drape's default)
  bool stop_at_rest = true;
  Eigen::Vector3d gravity{0.0, -9.81, 0.0};
  std::optional<double> pin_above;  // metres: garment vertices designed at y >= this are pinned
  // Also keep the body's vertices from poking through cloth triangles (sharp features: a dress
  // form's edges, shoulder tips, the front of a shoulder under 3 cm triangles). On by default:
  // without it a preview shows the body through the cloth; off saves up to half a drape's
  // time (docs/collision.md).
  bool check_body_vertices = true;
  // The body-vertex springs' carried push fades across their hold margin, so a spring is
  // released at no load (ContactSettings::fade_carried_push, docs/collision.md). Unset: on when
  // any panel rests flat, off for shaped rest (docs/pattern.md, "Drapes that do not rest").
  std::optional<bool> fade_carried_push;
  // A gathered panel starts folded into flutes as long as it is cut (docs/pattern.md, "Gathers
  // that start gathered"); false: as drawn, squeezed along the gather.
  bool gather_start = true;
  // The cloth's rest shape: "shaped" (each triangle as drawn on the body) or "flat" (the
  // triangle in the panel's flattened pattern piece, docs/pattern.md). Panels may override it.
  std::string rest = "shaped";
  // s: with flat rest, the cloth's rest shape moves from the drawn triangles to the pattern's
  // over this time (sewing the cut pieces up gently; 0, the default: released at once).
  // Measured on the corpus it lets two drapes rest that did not and keeps two from resting
  // that did (docs/pattern.md), so it is an option, not the default.
  double rest_ramp = 0.0;
  bool rest_ramp_given = false;  // the file says "rest_ramp" (a gathered flat panel's default)
  // Cloth-cloth contact (sim/self_contact.hpp): folds and layers do not pass through each
  // other. Unset: on for garments, off for sheets.
  std::optional<bool> self_collision;
};

// A rectangular sheet of cloth instead of a garment: scenes for tests and benchmarks.
struct SheetSpec {
  Eigen::Vector2d size{1.0, 1.0};         // metres: width (x) and height (y, or z when horizontal)
  int columns = 16;                       // quads along the width
  int rows = 16;                          // quads along the height
  bool horizontal = false;                // in the XZ plane instead of the XY plane
  Eigen::Vector3d centre{0.0, 1.0, 0.0};  // metres
  std::vector<std::string> pins;          // "top-left", ..., or whole edges "top", "left", ...
  // "shape": "disc": a disc of diameter size[0] (the Cusick drape test's specimen), cells about
  // size[0] / resolution[0] wide; pins "centre:R" hold every vertex within R metres of the
  // centre (a clamp between two discs, with a ring of vertices at R).
  bool disc = false;
  // Copies of the sheet stacked one over the other (two sheets falling onto each other): layer
  // k is the first moved by k·layer_offset and turned k·layer_turn degrees about the vertical
  // through the centre. Pins hold the first layer only.
  int layers = 1;
  Eigen::Vector3d layer_offset{0.0, 0.05, 0.0};  // metres
  double layer_turn = 0.0;                       // degrees
};

struct ImageSpec {
  // "front", "back", "left", "right", "three-quarter", or "camera" (then `camera` is used).
  std::string view = "front";
  garment::CameraSpec camera;
  int width = 800;
  int height = 1200;
  std::optional<bool> wireframe;  // default: output.wireframe
};

// "output": {"pattern": true | {...}}: the flat sewing pattern (pattern.svg, .dxf, .json).
struct PatternSpec {
  double fabric_width = 1.5;     // metres across the bolt
  double seam_allowance = 0.01;  // metres, every piece without its own
  double max_stretch = 0.05;     // flattening stretch (95th percentile) that flags a panel
};

struct OutputSpec {
  std::vector<ImageSpec> images;
  bool images_listed = false;        // "images" was given (an empty list means none)
  std::string mesh = "garment.obj";  // file name of the stitched garment (.obj or .glb)
  bool report = true;
  bool wireframe = false;
  std::optional<PatternSpec> pattern;  // absent: no pattern files
};

// The whole file. The garment request is its base rather than a member: garment/ takes it as
// `const garment::GarmentRequest&`, and the app and the tests keep reading `sketch.curves`,
// `sketch.body`, ... where they always did (fields other branches add keep their place).
struct Sketch : garment::GarmentRequest {
  std::string fabric =
      "jersey";  // a preset of data/fabrics or a fabric .json path (sketchdrape run checks it)
  std::string
      fabric_inline;  // "fabric" given as an object: its JSON text (then `fabric` is its name)
  std::optional<SheetSpec> sheet;  // a sheet scene: no curves, panels or (unless given) body
  SimulateSpec simulate;
  OutputSpec output;
};

// Parses and validates the text of a sketch file; `file` names it in errors, `base_dir` is where
// relative paths point. Throws SketchError.
Sketch parse_sketch(std::string_view text, const std::string& file,
                    const std::filesystem::path& base_dir = {});

// Reads and parses a sketch file. Throws SketchError (also when the file cannot be read).
Sketch load_sketch(const std::filesystem::path& path);

}  // namespace sd::scene
