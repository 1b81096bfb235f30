#pragma once
// Scenes shared by the adaptive-detail tests and benchmark: a horizontal sheet as a 4-8 mesh of
// quads (Birra & Santos' fig. 5 experiment: hung by 3 of its 4 corners), material points to
// compare runs on different meshes, and the shape figures the comparison uses.

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "meshing/mesh48.hpp"
#include "sim/adaptive_detail.hpp"
#include "sim/fabric.hpp"
#include "sim/sheet.hpp"
#include "sim/simulation.hpp"
#include "sim/surface_sampling.hpp"

namespace sd::sim::testing {

struct AdaptiveSheetSpec {
  double size = 1.0;  // m, square
  int quads = 4;      // level-0 quads per side (4: 32 triangles, as in the paper's fig. 5)
  std::vector<std::string> pins = {"top-left", "top-right", "bottom-left"};
  double duration = 4.0;  // s
  double dt = 1.0 / 60.0;
  LinearSolverKind solver = LinearSolverKind::cholmod;
  meshing::TriMesh body;  // what the sheet drapes on (a table, a sphere); no faces: none
};

// The fabric of the experiment: cotton with a bending rigidity 10x higher (the paper too made
// its cloth stiffer in bending so that differences show) and air drag to let it settle.
inline FabricParameters adaptive_sheet_fabric() {
  FabricParameters fabric = fabric_preset("cotton");
  fabric.bend *= 10.0;
  return fabric;
}

inline SimulationSettings adaptive_sheet_settings(const AdaptiveSheetSpec& spec) {
  SimulationSettings settings;
  settings.solver = spec.solver;
  settings.dt = spec.dt;
  settings.duration = spec.duration;
  settings.stop_at_rest = false;
  settings.forces.air_drag = 0.5;
  return settings;
}

struct AdaptiveSheet {
  meshing::Mesh48 mesh;
  AdaptiveMaterial material;
  std::vector<Pin> pins;
};

// A horizontal square sheet at y = 1 m as a 4-8 mesh of quads (vertex ids = sheet grid ids).
inline AdaptiveSheet build_adaptive_sheet(const AdaptiveSheetSpec& spec) {
  SheetSpec sheet_spec;
  sheet_spec.size = {spec.size, spec.size};
  sheet_spec.columns = sheet_spec.rows = spec.quads;
  sheet_spec.orientation = SheetOrientation::horizontal;
  sheet_spec.pins = spec.pins;
  const SheetScene scene = build_sheet(sheet_spec);
  AdaptiveSheet out{sheet_mesh48(scene), {}, {}};
  out.material.fabric = adaptive_sheet_fabric();
  out.material.source_warp = sheet_quad_warp(scene);  // towards the top: −Z
  out.material.up = scene.input.up;
  for (int v : scene.pinned_vertices) out.pins.push_back({v, {}});
  return out;
}

// An AdaptiveCloth on the sheet: starting at `start_level` (uniformly refined), adapting with
// `adaptive` (enabled = false: a fixed-resolution run).
inline AdaptiveCloth make_adaptive_sheet(const AdaptiveSheetSpec& spec, int start_level,
                                         AdaptiveSettings adaptive) {
  AdaptiveSheet sheet = build_adaptive_sheet(spec);
  AdaptiveCloth cloth(std::move(sheet.mesh), sheet.material, {}, sheet.pins,
                      adaptive_sheet_settings(spec), adaptive);
  if (spec.body.face_count() > 0) cloth.set_body(spec.body);
  if (start_level > 0) cloth.refine_uniformly(start_level);
  return cloth;
}

// n by n material points on the rest sheet, inset by a hair so each lies inside a triangle.
inline Eigen::MatrixX3d sheet_material_points(const AdaptiveSheetSpec& spec, int n) {
  Eigen::MatrixX3d points(n * n, 3);
  const double half = 0.5 * spec.size * (1.0 - 1e-9);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      points.row(i * n + j) << -half + 2 * half * i / (n - 1), 1.0, -half + 2 * half * j / (n - 1);
  return points;
}

inline Eigen::MatrixX3d material_positions(const AdaptiveCloth& cloth,
                                           const Eigen::MatrixX3d& points) {
  return positions_at_material_points(cloth.rest_positions(), cloth.faces(), cloth.positions(),
                                      points);
}

// Shape figures of a drape: lowest point (y) and bounding box extent.
struct ShapeFigures {
  double lowest = 0.0;
  Eigen::Vector3d extent = Eigen::Vector3d::Zero();
};

inline ShapeFigures shape_figures(const Eigen::MatrixX3d& positions) {
  return {positions.col(1).minCoeff(),
          (positions.colwise().maxCoeff() - positions.colwise().minCoeff()).transpose()};
}

}  // namespace sd::sim::testing
