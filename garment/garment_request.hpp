#pragma once
// What garment/ builds a garment from (docs/garment.md): the curves, panels and joins a designer
// drew, the body they were drawn on and the meshing settings, as plain values. The scene layer
// (scene/sketch_file) reads them from the sketch file and checks each field on its own; garment/
// never sees the file format. Units are metres, +Y up, the mannequin faces +Z.
//
// Errors found while building (curves that do not meet, panels that do not close, strokes off
// the body) are the designer's to fix, so they go through `fail` with a JSON path: every curve,
// panel, seed and join carries the path the scene layer read it from, and find_curve/find_panel
// map an id back to it.

#include <Eigen/Core>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "garment/sketch_error.hpp"

namespace sd::garment {

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
  // Per points3d point: given relative to a landmark ({"at": ...}) rather than as [x, y, z]
  // (empty: none is).
  std::vector<bool> at_landmark;
  // Per points3d point given relative to a landmark: its name, where that landmark is on this
  // body and the offset as written (m; with "drawn_on" the point is not their sum: the offset is
  // scaled for this body). For a point far off the body, which is then told its landmark and the
  // offset's readings in other units (trial 43, P4, P15). At a limb's landmark (an elbow, a wrist,
  // a knee, an ankle) also the torso landmark nearest the point where it was drawn and the offset
  // from it there. Empty names for [x, y, z] points.
  std::vector<std::string> landmark_name;
  std::vector<Eigen::Vector3d> landmark_at;
  std::vector<Eigen::Vector3d> landmark_offset;
  std::vector<std::string> torso_name;
  std::vector<Eigen::Vector3d> torso_offset;
  double offset = 0.0;                   // metres along the body normal (default: file's)
  bool on_body = true;                   // project/snap onto the body's offset surface
  bool smooth = true;                    // Catmull-Rom through the points (false: polyline)
  bool closed = false;                   // the last point joins the first
  std::optional<double> edge_length;     // metres; overrides panel and global
  std::optional<int> edges;              // fixed edge count (parity may not change it)
  std::optional<double> seam_allowance;  // metres, along this curve in the pattern (a seam's
                                         // two sides, or an edge's); default: the panel's

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

// Which way the warp (the grain line of the cut piece) runs on a panel (docs/garment.md,
// "Grain"): along the limb the panel wraps (a sleeve, a trouser leg), along the body's vertical,
// or chosen from the panel ("auto": along the limb for a panel on an arm or round one leg, else
// vertical). `turn_deg` then turns it about the panel's outward normal (45: on the bias).
enum class GrainRule { kAuto, kVertical, kLimb };
struct GrainSpec {
  GrainRule rule = GrainRule::kAuto;
  double turn_deg = 0.0;  // degrees, -90 .. 90, counter-clockwise seen from outside
};

// A panel's ease: the scale of its rest shape, and of its pattern piece, along the warp and
// along the weft of its material frame (1 = as designed). `"ease": e` is e both ways; a larger
// factor one way makes the piece longer that way than the seams it is sewn to, so the cloth
// gathers along them (a skirt tier with weft 1.5 gathers round the body).
struct PanelEase {
  double warp = 1.0;
  double weft = 1.0;
  bool isotropic() const { return warp == weft; }
  bool operator==(const PanelEase&) const = default;
};

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
  PanelEase ease;                        // rest shape scale (1 = as designed)
  std::optional<std::string> rest;       // "flat" | "shaped"; default: simulate.rest
  std::optional<double> seam_allowance;  // metres; default: output.pattern.seam_allowance
  PanelFit fit = PanelFit::kAuto;        // "fit"
  GrainSpec grain;                       // "grain"
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
  std::optional<std::string> facing;     // the way the figure faces in the file; by convention
  std::optional<BodyMotionSpec> motion;  // a still body when absent
  // "drawn_on": the body the offsets of landmark points were written for; on another body they
  // scale by its size at each landmark (docs/sketch-format.md, "Points relative to a
  // landmark"). Fixed metres when empty.
  std::shared_ptr<const BodySpec> drawn_on;
};

// The garment to build: what every garment algorithm takes.
struct GarmentRequest {
  std::string file;                // as given, for messages
  std::filesystem::path base_dir;  // relative paths resolve here
  BodySpec body;
  double edge_length = 0.03;                // metres
  double offset = 0.01;                     // default curve offset, metres
  double junction_tolerance = 0.015;        // metres: endpoints closer than this meet
  double corner_angle_degrees = 35.0;       // a junction turning more than this is a corner
  int relax_iterations = 10;                // interior smoothing sweeps of the quad filler
  std::optional<std::string> garment_mesh;  // triangle garment file: skips sketching and meshing
  std::vector<CurveSpec> curves;
  std::vector<PanelSpec> panels;
  std::vector<JoinSpec> joins;

  // The error sink: throws SketchError(file, json_path, sentence).
  [[noreturn]] void fail(const std::string& json_path, const std::string& sentence) const;
  const CurveSpec* find_curve(std::string_view id) const;
  const PanelSpec* find_panel(std::string_view id) const;
  std::filesystem::path resolve(const std::string& relative) const;
};

}  // namespace sd::garment
