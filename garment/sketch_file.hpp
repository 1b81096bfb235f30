#pragma once
// The sketch file (format "sketchdrape/1", docs/sketch-format.md): a plain model of what the
// designer wrote, every value validated, with defaults filled in. Units are metres, +Y up, the
// mannequin faces +Z. Parsing checks each field on its own; whether curves meet, panels close
// and strokes land on the body is checked later (curve network, projection), with the same
// SketchError and JSON paths.

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "garment/sketch_error.hpp"

namespace sd::garment {

inline constexpr const char* kSketchFormat = "sketchdrape/1";

enum class ViewKind { kFront, kBack, kLeft, kRight, kCamera };

// A perspective camera; 2D stroke points are metres in the plane through `target` that faces
// the camera (x to the camera's right, y to its up).
struct CameraSpec {
  Eigen::Vector3d eye{0.0, 1.3, 3.0};
  Eigen::Vector3d target{0.0, 1.0, 0.0};
  Eigen::Vector3d up{0.0, 1.0, 0.0};
  double fov_degrees = 35.0;  // vertical field of view (images only)
};

struct ViewSpec {
  ViewKind kind = ViewKind::kFront;
  CameraSpec camera;  // used when kind == kCamera
  std::string name() const;
};

struct CurveSpec {
  std::string id;
  std::string json_path;                  // "/curves/3"
  ViewSpec view;                          // the view `points` were drawn in
  std::vector<Eigen::Vector2d> points;    // view-plane metres; empty when points3d is given
  std::vector<Eigen::Vector3d> points3d;  // world metres; empty when points is given
  double offset = 0.0;                    // metres along the body normal (default: file's)
  bool on_body = true;                    // project/snap onto the body's offset surface
  bool smooth = true;                     // Catmull-Rom through the points (false: polyline)
  bool closed = false;                    // the last point joins the first
  std::optional<double> edge_length;      // metres; overrides panel and global
  std::optional<int> edges;               // fixed edge count (parity may not change it)

  bool is_3d() const { return !points3d.empty(); }
};

// A point inside an "auto" panel: drawn in a view (`point`, projected onto the body like a
// stroke point) or given in the world (`point3d`, used as written).
struct SeedSpec {
  std::string json_path;                   // "/panels/1/seed"
  ViewSpec view;                           // the view `point` was drawn in
  std::optional<Eigen::Vector2d> point;    // view-plane metres
  std::optional<Eigen::Vector3d> point3d;  // world metres
};

// How a panel's interior takes its shape (docs/garment.md, "Panel surfaces"): spanned by its
// boundary curves and pushed out of the body only where it would be inside ("free"), laid on
// the body's offset surface ("body"), or chosen from how far the spanned surface is from the
// body ("auto").
enum class PanelFit { kAuto, kBody, kFree };

struct PanelSpec {
  std::string id;
  std::string json_path;                 // "/panels/1"
  std::vector<std::string> boundary;     // curve ids in order around the panel
  bool auto_boundary = false;            // "boundary": "auto"
  std::optional<SeedSpec> seed;          // "auto": which region of the curve network
  std::vector<std::string> corners;      // curves whose start (along the loop) is a corner
  std::string fabric;                    // default: the file's fabric
  bool mirror = false;                   // also make the copy across x = 0
  std::optional<double> edge_length;     // metres
  double ease = 1.0;                     // rest shape scale (1 = as designed)
  std::optional<std::string> rest;       // "flat" | "shaped"; default: simulate.rest
  std::optional<double> seam_allowance;  // metres; default: output.pattern.seam_allowance
  PanelFit fit = PanelFit::kAuto;        // "fit"
};

struct JoinSpec {
  std::string id;
  std::string json_path;
  std::vector<std::string> panels;
};

// One keyframe of a "poses" motion: the body file of that pose and when the body is in it.
struct BodyPoseSpec {
  double time = 0.0;  // s of the drape, > 0 (the body's own mesh is the pose at 0)
  std::string mesh;   // path relative to the sketch file
  std::string json_path;
};

// "body": {"motion": {...}}: the body moving during the drape. Two kinds: "arms-lowering", the
// A-pose mannequin's arms turning towards the body about the shoulders
// (sim::make_arm_lowering), and "poses", meshes of the same body in other poses at given
// times, interpolated linearly in between (sim::PoseSequence).
struct BodyMotionSpec {
  std::string type = "arms-lowering";
  double degrees = 10.0;  // arms-lowering: rotation at the end; negative raises the arms
  double start = 0.0;     // arms-lowering: s, the arms start moving at this time of the drape
  double duration = 1.0;  // arms-lowering: s from start to end
  std::vector<BodyPoseSpec> poses;  // poses: strictly increasing times
};

struct BodySpec {
  std::string mesh = "builtin";          // "builtin", "none", or a path relative to the sketch file
  std::optional<double> height;          // metres
  std::optional<double> scale;           // metres per file unit
  std::optional<std::string> up;         // "+z", "y", ...
  std::optional<BodyMotionSpec> motion;  // a still body when absent
};

// "simulate": {"adaptive": {...}}: the adaptive 4-8 detail's settings. Unset values take the
// simulator's defaults (sim::AdaptiveSettings, docs/adaptive.md).
struct AdaptiveSpec {
  std::optional<double> refine_threshold;   // m of sag above which an edge is split
  std::optional<double> coarsen_threshold;  // m of sag below which a block may be merged
  std::optional<double> steady_rate;        // rad/s: hinges turning faster are not merged
  std::optional<double> min_lifetime;       // s a triangle lives before it may be merged
  std::optional<int> min_level;             // coarsest level a merge returns to
  std::optional<int> max_level;             // finest level a split makes
  std::optional<int> max_vertices;          // particle budget, 0: none
  std::optional<double> merge_batch;        // fraction of the particles lone merges wait for
  std::optional<bool> even_levels;          // keep the leaves on even levels
};

// How the drape is simulated (`sketchdrape run`): plain values with defaults.
struct SimulateSpec {
  double duration = 3.0;                      // seconds of simulated time at most
  bool adaptive = true;                       // 4-8 refinement/coarsening
  bool adaptive_given = false;                // the file says "adaptive" (a sheet adapts only then)
  AdaptiveSpec adaptive_settings;             // "adaptive": {...} (with "enabled" for the bool)
  double time_step = 1.0 / 60.0;              // seconds, the largest step
  std::string integrator = "implicit-euler";  // "implicit-euler" | "bdf2"
  std::string solver = "cholmod";             // "pcg" | "cholmod"
  // "hinges" | "quadratic": the discrete bending energy (docs/simulator.md, "Bending on any
  // mesh"). Hinges by default until the quadratic model is as fast and every design rests with
  // it (docs/fabrics.md).
  std::string bending = "hinges";
  // "linear" | "buckling": the membrane's answer to compression (docs/simulator.md,
  // "Compression and buckling"); buckling caps it at each triangle's Euler load.
  std::string compression = "linear";
  bool stop_at_rest = true;
  Eigen::Vector3d gravity{0.0, -9.81, 0.0};
  std::optional<double> pin_above;  // metres: garment vertices designed at y >= this are pinned
  // Also keep the body's vertices from poking through cloth triangles (sharp features: a dress
  // form's edges, shoulder tips, the front of a shoulder under 3 cm triangles). On by default:
  // without it a preview shows the body through the cloth; off saves up to half a drape's
  // time (docs/collision.md).
  bool check_body_vertices = true;
  // The cloth's rest shape: "shaped" (each triangle as drawn on the body) or "flat" (the
  // triangle in the panel's flattened pattern piece, docs/pattern.md). Panels may override it.
  std::string rest = "shaped";
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
  CameraSpec camera;
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

struct Sketch {
  std::string file;                // as given, for messages
  std::filesystem::path base_dir;  // relative paths resolve here
  BodySpec body;
  double edge_length = 0.03;           // metres
  double offset = 0.01;                // default curve offset, metres
  double junction_tolerance = 0.015;   // metres: endpoints closer than this meet
  double corner_angle_degrees = 35.0;  // a junction turning more than this is a corner
  int relax_iterations = 10;           // interior smoothing sweeps of the quad filler
  std::string fabric =
      "jersey";  // a preset of data/fabrics or a fabric .json path (sketchdrape run checks it)
  std::string
      fabric_inline;  // "fabric" given as an object: its JSON text (then `fabric` is its name)
  std::optional<std::string> garment_mesh;  // triangle garment file: skips sketching and meshing
  std::optional<SheetSpec> sheet;  // a sheet scene: no curves, panels or (unless given) body
  std::vector<CurveSpec> curves;
  std::vector<PanelSpec> panels;
  std::vector<JoinSpec> joins;
  SimulateSpec simulate;
  OutputSpec output;

  // Throws SketchError(file, json_path, sentence).
  [[noreturn]] void fail(const std::string& json_path, const std::string& sentence) const;
  const CurveSpec* find_curve(std::string_view id) const;
  const PanelSpec* find_panel(std::string_view id) const;
  std::filesystem::path resolve(const std::string& relative) const;
};

// Parses and validates the text of a sketch file; `file` names it in errors, `base_dir` is where
// relative paths point. Throws SketchError.
Sketch parse_sketch(std::string_view text, const std::string& file,
                    const std::filesystem::path& base_dir = {});

// Reads and parses a sketch file. Throws SketchError (also when the file cannot be read).
Sketch load_sketch(const std::filesystem::path& path);

}  // namespace sd::garment
