#pragma once
// What `sketchdrape run` simulates, built from a sketch file: the cloth as plain simulator input
// (a stitched garment's 4-8 triangles, or a sheet), its pins, its fabric, and the body it drapes
// over. Only what the scene needs is built: a sheet scene loads no body and meshes no panels.

#include <optional>
#include <string>
#include <vector>

#include "garment/body.hpp"
#include "garment/garment_mesh.hpp"
#include "garment/panel_flattening.hpp"
#include "meshing/mesh48.hpp"
#include "scene/sketch_file.hpp"
#include "sim/automatic_settings.hpp"
#include "sim/body_motion.hpp"
#include "sim/cloth_driver.hpp"
#include "sim/cloth_model.hpp"
#include "sim/fabric.hpp"
#include "sim/simulation.hpp"

namespace sd::app {

// The cloth is a 4-8 mesh plus attributes of its input faces (a garment's quads, an imported
// garment's sqrt3 triangles, a sheet's quads): every triangle, at any level, takes its group,
// ease and warp from the input face it descends from.
struct ClothScene {
  // Rest positions in metres; vertex ids = rows of `start`. Always set by build_cloth_scene
  // (optional only because a Mesh48 is made by its factories).
  std::optional<meshing::Mesh48> mesh48;
  // Per input face of mesh48:
  Eigen::VectorXi face_group;  // group (panel or join; a sheet's layer), into group_names
  // The panel's `ease` (rest shape scale): one column when every panel's is isotropic, else
  // two (warp, weft); empty: all 1.
  Eigen::MatrixXd face_ease;
  Eigen::MatrixX3d face_warp;  // warp direction; empty: the in-plane one closest to +Y
  // The fixed mesh as simulator input (rest shape, triangles, per-triangle warp and, with
  // "rest": "flat", rest_uv): mesh48's level-0 triangles, except for a sheet, whose own
  // triangles alternate their diagonals (mesh48 splits every square quad along the same one;
  // see scene_driver).
  sim::ClothInput input;
  Eigen::VectorXi triangle_face;  // #F of input: the input face each triangle lies in
  bool sheet = false;
  Eigen::MatrixX3d start;   // #V by 3 start positions, metres
  std::vector<int> pinned;  // vertex indices held in place
  std::string fabric_name;
  sim::FabricParameters fabric;
  std::optional<garment::Body> body;  // absent for a sheet without a body
  // The body's poses over the drape ("body": {"motion": ...}); absent for a still body.
  std::optional<sim::PoseSequence> body_motion;
  std::optional<garment::Garment> garment;
  // An imported garment ("garment_mesh"): the file's own counts, for the messages and the
  // report. The cloth simulated (input, mesh48) is its √3 4-8 conversion, which has a vertex
  // more per triangle and a triangle pair per edge (trial 41, P10: validate called those the
  // file's).
  struct ImportedCounts {
    Eigen::Index vertices = 0;
    Eigen::Index triangles = 0;  // polygons fanned into triangles
    long faces = 0;              // as the file writes them (a quad is one)
  };
  std::optional<ImportedCounts> imported;
  std::vector<std::string> group_names;
  double body_ms = 0;     // time spent loading the garment's body
  double meshing_ms = 0;  // time spent building the garment
  // The garment's flattened panels when a panel drapes from flat cloth ("rest": "flat"); then
  // input.rest_uv holds every triangle's rest coordinates (the pattern piece's triangle for flat
  // panels, the drawn triangle for shaped ones) and the hinges rest flat when all panels are flat.
  std::optional<garment::FlatPattern> flat_pattern;
  // With flat rest: the sentence saying that the pieces draped (and written by output.pattern)
  // are the free flattening, which differs from `pattern`'s for pieces `pattern` cuts on the
  // fold; empty when no piece has a centre line on the grain (trial 39, P2). Logged once, and in
  // report.json's warnings.
  std::string flat_rest_differs;
  bool bend_rest_flat = false;
  // With flat rest: every triangle's drawn coordinates (rows and frames of input.rest_uv), where
  // the rest ramp starts, and the ramp's time (simulate.rest_ramp, s; 0: none).
  Eigen::MatrixXd start_rest_uv;
  double rest_ramp = 0.0;
  // Panels that start gathered (cloth_scene.cpp, gather_start): their cloth folded out along its
  // normal into flutes as long as it is cut.
  int gathered_panels = 0;
  sim::BendModel bend_model = sim::BendModel::hinges;  // simulate.bending
  // simulate.compression
  sim::Compression compression = sim::Compression::linear;
  double flattening_ms = 0;
};

// Builds the scene. Throws garment::SketchError (with the JSON path) for anything the designer
// can fix: an unknown fabric, a body that will not load, panels that do not close, ...
ClothScene build_cloth_scene(const scene::Sketch& sketch);

// build_cloth_scene with the size checks `run` makes under the default limits: a sheet refused
// before it is built, any cloth once it is (sketch_checks.hpp). What `validate` and `mesh` build,
// so that they refuse the same files as `run` (trial 35: a file meshed with exit 0 that validate
// refused).
ClothScene build_cloth_scene_within_limits(const scene::Sketch& sketch);

// The body as it stands at time t of the drape (its pose when it moves). The scene must have a
// body.
meshing::TriMesh body_at(const ClothScene& scene, double t);

// The bending model of the sketch's cloth: simulate.bending, else its kind's default (the
// quadratic bending for a sheet and an imported garment_mesh, the hinges for sketched panels).
sim::BendModel scene_bend_model(const scene::Sketch& sketch);

// The options the scene's cloth model is built with (build_scene_model, scene_material): the
// simulator's defaults with the scene's bending, compression and bending rest. The memory check
// predicts the solver's factor from them (sketch_checks.hpp, estimate_run).
sim::ClothModelOptions scene_model_options(const ClothScene& scene);

// The simulator's model of the scene's cloth on its fixed mesh: build_cloth_model on the input,
// then each triangle's rest shape scaled by its panel's ease (lengths along the warp by a and
// along the weft by b, so rest area and mass by a·b; see sim::scale_rest_shapes). A waistband with
// ease below 1 is cut smaller than the body it was drawn on and holds the garment up. Hinges rest
// flat when bend_rest_flat.
sim::ClothModel build_scene_model(const ClothScene& scene);

// What the cloth is made of for the 4-8 driver: fabric, bending rest shape, and the warp, ease
// and (flat rest) pattern coordinates of the scene's input faces.
sim::AdaptiveMaterial scene_material(const ClothScene& scene);

// The driver of the scene's cloth (pins held where they start): its 4-8 mesh adapting when
// `adaptive` is given, else the fixed mesh: the 4-8 mesh with adaptivity off (a garment: its
// level-0 triangles are `input`'s), or a sheet's own triangles as a model. Throws
// sim::InvalidFabricError and the simulator's setting errors.
sim::ClothDriver scene_driver(const ClothScene& scene, const sim::SimulationSettings& settings,
                              const std::optional<sim::AdaptiveSettings>& adaptive);

// #F: the group of each triangle, given the input face each descends from.
Eigen::VectorXi triangle_groups(const ClothScene& scene, const Eigen::VectorXi& source_faces);

// The fabric `name` of the sketch (the file's or a panel's): its inline object (by its name), a
// preset, or a fabric .json file relative to the sketch. Throws garment::SketchError at
// `json_path` (at /fabric/KEY for an inline constant) with the known presets, or saying that
// the name is a folder.
sim::FabricParameters scene_fabric(const scene::Sketch& sketch, const std::string& name,
                                   const std::string& json_path);

// Whether scene_fabric reads the fabric `name` as a path relative to the sketch's folder (a
// fabric file, "fabrics/linen.json", or a folder, "fabrics/") rather than as a preset: a name
// that is not a preset and ends in .json or holds a '/'. `batch` makes such names absolute
// before a job's copy of the sketch moves to the job's folder, as it does the body's path.
bool fabric_name_is_path(const std::string& name);

// Whether a panel draped from flat cloth is cut more than kGatherEase times its drawn size along
// its warp or weft (a gather: `"ease": {"weft": 1.5}`). Drawn at its sewn size, such a panel
// starts compressed by 1 − 1/ease; with the linear compression model (stress K·ε on both sides)
// it was released at once as a spring: at about that strain times the fabric's wave speed
// √(K/ρ) (cotton's weft 217 m/s: 72 m/s for a 1.5 gather, past the step's 50 m/s limit), and,
// ramped in, it still held the tier out at K·ε (2,000 N/m) and crumpled the tier above it. Real
// cloth gathers by buckling under almost no load, so such a drape gets, unless its file says
// otherwise, the buckling compression (sim::Compression::buckling, Choi & Ko) and a rest ramp
// of kGatherRamp that brings the ease in with the pattern, as a gathering thread is drawn up
// (docs/pattern.md, "Gathered pieces").
constexpr double kGatherEase = 1.1;  // released at once: 9 % compression, 20 m/s in cotton
constexpr double kGatherRamp = 1.0;  // s
bool gathered_flat(const scene::Sketch& sketch);
// How many times longer a panel is cut along one direction of its cloth than along the other:
// max/min of its warp and weft ease ({"weft": 1.6}: 1.6; a number, 1). Above kGatherEase the
// panel is gathered into the seams that run that way, whatever its rest shape.
double gather_ratio(const garment::PanelEase& ease);
// Whether any panel, shaped or flat, has a gather_ratio above kGatherEase. Shaped, such a panel
// starts 1 − 1/ratio short of its rest along the gather as well, and with the linear compression
// trial 37's flounce (weft 1.6) failed at t = 0.0004 s (50.7 m/s) and at weft 1.5 held the
// flounce out at K·ε against the yoke above it (45 % stretch at the seam, still moving at
// 1.2 m/s after 4 s): such a drape gets the buckling compression unless its file says otherwise.
bool gathered(const scene::Sketch& sketch);
// s: the rest ramp of a drape (ClothScene::rest_ramp): the file's `simulate.rest_ramp`, else
// kGatherRamp for a gathered flat drape (gathered_flat), else 0.
double rest_ramp_of(const scene::Sketch& sketch);

// The simulator settings of the file's "simulate" section (integrator, solver, step, duration,
// gravity). Throws garment::SketchError at /simulate when they cannot work together.
sim::SimulationSettings simulation_settings(const scene::Sketch& sketch);

// The file's "solver": "auto" and "time_step": "auto" (the defaults) resolved for the built
// scene (sim/automatic_settings.hpp: its size, garment or sheet, self-contact); settings the
// file gives are kept; a garment without a duration of its own gets its settle time (at most
// kMaxSettleDuration; kGatheredSettleDuration with a gathered panel, settle_time.hpp). Returns the
// rule's choice (its `reason` for the report). `motion`: the run writes the motion (`run --frames
// N`), not only the drape.
sim::AutomaticChoice apply_automatic_settings(const scene::Sketch& sketch, const ClothScene& scene,
                                              sim::SimulationSettings& settings,
                                              bool motion = false);

}  // namespace sd::app
