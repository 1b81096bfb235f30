#include "src/app/cloth_scene.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>

#include "garment/body_surface.hpp"
#include "garment/material_frames.hpp"
#include "garment/sketch_inputs.hpp"
#include "sim/sheet.hpp"
#include "sim/simulation.hpp"

namespace sd::app {
namespace {

// The fabric at `json_path`: the sketch's inline fabric object (by its name), a preset name,
// or a path to a fabric .json file (relative to the sketch); else a SketchError at the JSON
// path of the bad value ("/fabric/bend" for an inline constant) that lists the known presets.
sim::FabricParameters fabric_at(const garment::Sketch& sketch, const std::string& name,
                                const std::string& json_path) {
  // A panel without its own fabric carries the file's name for it, inline ones included.
  if (!sketch.fabric_inline.empty() && name == sketch.fabric) {
    try {
      return sim::parse_fabric_json(sketch.fabric_inline, "the fabric given inline");
    } catch (const sim::InvalidFabricError& e) {
      sketch.fail("/fabric" + e.pointer(), e.what());
    }
  }
  try {
    return sim::fabric_preset(name);
  } catch (const sim::UnknownFabricError& e) {
    if (name.size() < 5 || name.substr(name.size() - 5) != ".json")
      sketch.fail(json_path, std::string(e.what()) + "; or give a fabric file (.json) or the "
                                                      "fabric's constants as an object");
  }
  try {
    return sim::load_fabric_file(sketch.resolve(name).string());
  } catch (const sim::InvalidFabricError& e) {
    sketch.fail(json_path, e.what());
  }
}

// simulate.pin_above: holds every vertex that starts at or above that height.
void pin_above(const garment::Sketch& sketch, ClothScene& scene) {
  if (!sketch.simulate.pin_above) return;
  const std::size_t before = scene.pinned.size();  // a sheet's named pins come first
  for (Eigen::Index v = 0; v < scene.start.rows(); ++v)
    if (scene.start(v, 1) >= *sketch.simulate.pin_above) scene.pinned.push_back(static_cast<int>(v));
  if (scene.pinned.size() == before)
    sketch.fail("/simulate/pin_above",
                fmt::format("no garment vertex lies at or above {} m (the garment's top is at "
                            "{:.3f} m)",
                            *sketch.simulate.pin_above, scene.start.col(1).maxCoeff()));
}

void build_sheet_scene(const garment::Sketch& sketch, ClothScene& scene) {
  const garment::SheetSpec& spec = *sketch.sheet;
  sim::SheetSpec sheet;
  sheet.size = spec.size;
  sheet.columns = spec.columns;
  sheet.rows = spec.rows;
  sheet.orientation =
      spec.horizontal ? sim::SheetOrientation::horizontal : sim::SheetOrientation::vertical;
  sheet.centre = spec.centre;
  sheet.pins = spec.pins;
  sim::SheetScene built = sim::build_sheet(sheet);
  scene.input = std::move(built.input);
  scene.start = scene.input.rest_positions;
  scene.pinned = std::move(built.pinned_vertices);
  // simulate.pin_above holds a sheet too (a clamp of several rows of a hanging sheet), together
  // with the named pins.
  pin_above(sketch, scene);
  std::sort(scene.pinned.begin(), scene.pinned.end());
  scene.pinned.erase(std::unique(scene.pinned.begin(), scene.pinned.end()), scene.pinned.end());
  scene.triangle_group = Eigen::VectorXi::Zero(scene.input.triangles.rows());
  scene.group_names = {"sheet"};
  scene.fabric_name = sketch.fabric;
  scene.fabric = fabric_at(sketch, sketch.fabric, "/fabric");
}

void build_garment_scene(const garment::Sketch& sketch, ClothScene& scene) {
  scene.body = garment::load_sketch_body(sketch);
  const garment::BodySurface surface(scene.body->mesh);
  const auto start = std::chrono::steady_clock::now();
  garment::Garment g = garment::build_garment(sketch, surface);
  scene.meshing_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();

  // One fabric per simulation for now: the first panel's; others are reported if different.
  const garment::GarmentPanel& first = g.panels.front();
  scene.fabric_name = first.fabric;
  const garment::PanelSpec* first_spec = sketch.find_panel(first.id);
  scene.fabric = fabric_at(sketch, first.fabric,
                           first_spec ? first_spec->json_path + "/fabric" : "/fabric");
  for (const garment::GarmentPanel& p : g.panels)
    if (p.fabric != first.fabric)
      spdlog::warn("panel '{}' asks for fabric '{}'; this version simulates a garment in one fabric "
                   "and uses '{}' (panel '{}') throughout",
                   p.id, p.fabric, first.fabric, first.id);

  meshing::Mesh48 m48 = meshing::Mesh48::from_quads(g.mesh);
  const std::vector<std::string> problems = m48.validate();
  if (!problems.empty()) throw std::runtime_error("4-8 mesh check failed: " + problems.front());
  const meshing::Mesh48Arrays arrays = m48.arrays();
  const garment::MaterialFrames frames = garment::material_frames(g.mesh);

  // Groups: a join's panels share its group.
  std::vector<int> panel_group(g.panels.size());
  for (size_t p = 0; p < g.panels.size(); ++p) {
    auto it = std::find(scene.group_names.begin(), scene.group_names.end(), g.panels[p].group);
    if (it == scene.group_names.end())
      it = scene.group_names.insert(scene.group_names.end(), g.panels[p].group);
    panel_group[p] = static_cast<int>(it - scene.group_names.begin());
  }

  const Eigen::Index triangles = arrays.faces.rows();
  scene.input.rest_positions = arrays.rest_positions;
  scene.input.triangles = arrays.faces;
  scene.input.warp.resize(triangles, 3);
  scene.triangle_group.resize(triangles);
  scene.triangle_ease.resize(triangles);
  for (Eigen::Index t = 0; t < triangles; ++t) {
    const int quad = m48.source_face(arrays.triangle_ids[static_cast<size_t>(t)]);
    scene.input.warp.row(t) = frames.warp.row(quad);
    scene.triangle_group(t) = panel_group[static_cast<size_t>(g.face_panel(quad))];
    scene.triangle_ease(t) = g.panels[static_cast<size_t>(g.face_panel(quad))].ease;
  }
  if ((scene.triangle_ease.array() == 1.0).all()) scene.triangle_ease.resize(0);
  scene.start = arrays.rest_positions;
  pin_above(sketch, scene);
  scene.mesh48_face_group.resize(g.mesh.face_count());
  for (Eigen::Index q = 0; q < g.mesh.face_count(); ++q)
    scene.mesh48_face_group(q) = panel_group[static_cast<size_t>(g.face_panel(q))];
  if (scene.triangle_ease.size() > 0) {
    scene.mesh48_face_ease.resize(g.mesh.face_count());
    for (Eigen::Index q = 0; q < g.mesh.face_count(); ++q)
      scene.mesh48_face_ease(q) = g.panels[static_cast<size_t>(g.face_panel(q))].ease;
  }
  scene.mesh48 = std::move(m48);
  scene.garment = std::move(g);
}

// An imported triangle garment: its 4-8 mesh comes from the sqrt3 conversion; warp is the
// in-plane direction closest to +Y (the simulator's default when no warp is given).
void build_imported_scene(const garment::Sketch& sketch, ClothScene& scene) {
  if (sketch.body.mesh != "none") scene.body = garment::load_sketch_body(sketch);
  const meshing::TriMesh triangles = garment::load_garment_mesh(sketch);
  meshing::Mesh48 m48 = [&] {
    try {
      return meshing::Mesh48::from_triangles_sqrt3(triangles);
    } catch (const meshing::Mesh48InputError& e) {
      sketch.fail("/garment_mesh",
                  fmt::format("the garment mesh cannot become a 4-8 mesh: {}", e.what()));
    }
  }();
  const meshing::Mesh48Arrays arrays = m48.arrays();
  scene.input.rest_positions = arrays.rest_positions;
  scene.input.triangles = arrays.faces;
  scene.start = arrays.rest_positions;
  scene.triangle_group = Eigen::VectorXi::Zero(arrays.faces.rows());
  scene.group_names = {"garment"};
  scene.fabric_name = sketch.fabric;
  scene.fabric = fabric_at(sketch, sketch.fabric, "/fabric");
  pin_above(sketch, scene);
  scene.mesh48_face_group = Eigen::VectorXi::Zero(triangles.face_count());
  scene.mesh48 = std::move(m48);
}

}  // namespace

sim::SimulationSettings simulation_settings(const garment::Sketch& sketch) {
  const garment::SimulateSpec& spec = sketch.simulate;
  sim::SimulationSettings settings;
  settings.integrator =
      spec.integrator == "bdf2" ? sim::Integrator::bdf2 : sim::Integrator::implicit_euler;
  settings.solver = spec.solver == "pcg" ? sim::LinearSolverKind::pcg : sim::LinearSolverKind::cholmod;
  settings.dt = spec.time_step;
  settings.min_dt = std::min(settings.min_dt, spec.time_step / 64);
  settings.duration = spec.duration;
  settings.stop_at_rest = spec.stop_at_rest;
  settings.forces.gravity = spec.gravity;
  settings.contact.check_body_vertices = spec.check_body_vertices;
  try {
    settings.validate();
  } catch (const sim::InvalidSimulationSettingsError& e) {
    sketch.fail("/simulate", e.what());
  }
  return settings;
}

sim::ClothModel build_scene_model(const ClothScene& scene) {
  sim::ClothModel model = sim::build_cloth_model(scene.input, scene.fabric);
  if (scene.triangle_ease.size() > 0) sim::scale_rest_shapes(model, scene.triangle_ease);
  return model;
}

// The motion of the sketch's body: the arms lowering, or the body's own poses at given times
// (its mesh is the pose at time 0).
sim::PoseSequence body_motion(const garment::Sketch& sketch, const garment::Body& body) {
  const garment::BodyMotionSpec& spec = *sketch.body.motion;
  if (spec.type == "poses") {
    std::vector<double> times = {0.0};
    std::vector<Eigen::MatrixX3d> poses = {body.mesh.vertices};
    for (const garment::BodyPoseSpec& pose : spec.poses) {
      try {
        poses.push_back(garment::load_body_pose(sketch.resolve(pose.mesh).string(), body).vertices);
      } catch (const garment::BodyError& e) {
        sketch.fail(pose.json_path + "/mesh",
                    fmt::format("the pose '{}' cannot be used: {}", pose.mesh, e.what()));
      }
      times.push_back(pose.time);
    }
    try {
      return sim::PoseSequence(body.mesh.faces, std::move(times), std::move(poses));
    } catch (const sim::InvalidBodyMotionError& e) {
      sketch.fail("/body/motion/poses", e.what());
    }
  }
  sim::ArmLoweringOptions options;
  options.angle_degrees = spec.degrees;
  options.start = spec.start;
  options.duration = spec.duration;
  return sim::make_arm_lowering(body.mesh, options);
}

ClothScene build_cloth_scene(const garment::Sketch& sketch) {
  ClothScene scene;
  if (sketch.sheet) {
    build_sheet_scene(sketch, scene);
    if (sketch.body.mesh != "none") scene.body = garment::load_sketch_body(sketch);
  } else if (sketch.garment_mesh) {
    build_imported_scene(sketch, scene);
  } else {
    build_garment_scene(sketch, scene);
  }
  if (scene.body && sketch.body.motion) scene.body_motion = body_motion(sketch, *scene.body);
  return scene;
}

meshing::TriMesh body_at(const ClothScene& scene, double t) {
  return scene.body_motion ? scene.body_motion->mesh_at(t) : scene.body->mesh;
}

}  // namespace sd::app
