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
#include "garment/sketch_file.hpp"
#include "meshing/mesh48.hpp"
#include "sim/cloth_model.hpp"
#include "sim/fabric.hpp"
#include "sim/body_motion.hpp"
#include "sim/simulation.hpp"

namespace sd::app {

struct ClothScene {
  sim::ClothInput input;               // rest shape (the designed garment), triangles, warp
  Eigen::MatrixX3d start;              // #V by 3 start positions, metres
  std::vector<int> pinned;             // vertex indices held in place
  std::string fabric_name;
  sim::FabricParameters fabric;
  std::optional<garment::Body> body;   // absent for a sheet without a body
  // The body's poses over the drape ("body": {"motion": ...}); absent for a still body.
  std::optional<sim::PoseSequence> body_motion;
  std::optional<meshing::Mesh48> mesh48;  // the garment's 4-8 hierarchy (absent for sheets)
  std::optional<garment::Garment> garment;
  Eigen::VectorXi triangle_group;      // #F: group (panel or join) of each triangle
  // #F: the `ease` of each triangle's panel (rest shape scale, 1 = as designed); empty when
  // every triangle is as designed (sheets, imported garments).
  Eigen::VectorXd triangle_ease;
  Eigen::VectorXi mesh48_face_group;   // group of each input face of mesh48 (quad or triangle)
  // The ease of each input face of mesh48 (what adaptive detail needs at every level); empty
  // exactly when triangle_ease is.
  Eigen::VectorXd mesh48_face_ease;
  std::vector<std::string> group_names;
  double meshing_ms = 0;               // time spent building the garment
  // The garment's flattened panels when a panel drapes from flat cloth ("rest": "flat"); then
  // input.rest_uv holds every triangle's rest coordinates (the pattern piece's triangle for flat
  // panels, the drawn triangle for shaped ones) and the hinges rest flat when all panels are flat.
  std::optional<garment::FlatPattern> flat_pattern;
  bool bend_rest_flat = false;
  double flattening_ms = 0;
};

// Builds the scene. Throws garment::SketchError (with the JSON path) for anything the designer
// can fix: an unknown fabric, a body that will not load, panels that do not close, ...
ClothScene build_cloth_scene(const garment::Sketch& sketch);

// The body as it stands at time t of the drape (its pose when it moves). The scene must have a
// body.
meshing::TriMesh body_at(const ClothScene& scene, double t);

// The simulator's model of the scene's cloth on its fixed mesh: build_cloth_model on the input,
// then each triangle's rest shape scaled by its panel's ease (lengths by e, so rest area and
// mass by e²; rest angles do not change under a uniform scale). A waistband with ease below 1
// is cut smaller than the body it was drawn on and holds the garment up. Hinges rest flat when
// bend_rest_flat.
sim::ClothModel build_scene_model(const ClothScene& scene);

// The simulator settings of the file's "simulate" section (integrator, solver, step, duration,
// gravity). Throws garment::SketchError at /simulate when they cannot work together.
sim::SimulationSettings simulation_settings(const garment::Sketch& sketch);

}  // namespace sd::app
