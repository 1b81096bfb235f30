// Tests of sim/cloth_driver: the fixed 4-8 mesh (adaptivity off) drapes exactly as the plain
// simulator on its model, the observer sees every step and can cap and stop it, a model given
// as is keeps its triangles, and a sheet's quads make its 4-8 mesh.
#include "sim/cloth_driver.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <vector>

#include "sim/sheet.hpp"
#include "tests/sim/adaptive_scenes.hpp"

namespace sd::sim {
namespace {

using namespace sd::sim::testing;

AdaptiveSheetSpec short_sheet() {
  AdaptiveSheetSpec spec;
  spec.duration = 0.5;
  return spec;
}

AdaptiveSettings off() {
  AdaptiveSettings settings;
  settings.enabled = false;
  return settings;
}

// The bench study's and `run`'s fixed mesh: the 4-8 driver with adaptivity off, refined to
// level 2. Stepped through the one run loop it must give, to the last bit, what the plain
// simulator gives on the same model: nothing is added or lost by driving it as a 4-8 mesh.
TEST(ClothDriver, FixedFourEightMeshDrapesExactlyAsTheSimulatorOnItsModel) {
  const AdaptiveSheetSpec spec = short_sheet();
  AdaptiveSheet sheet = build_adaptive_sheet(spec);
  const SimulationSettings settings = adaptive_sheet_settings(spec);
  ClothDriver driver(sheet.mesh, sheet.material, {}, sheet.pins, settings, off());
  driver.adaptive()->refine_uniformly(2);
  ASSERT_EQ(driver.faces().rows(), 4 * 32);

  std::vector<Pin> pins;
  for (int v : driver.adaptive()->pinned_vertices()) pins.push_back({v, {}});
  Simulation plain(driver.simulation().model(), flatten_positions(driver.positions()), pins,
                   settings);
  const int splits_before = driver.adaptive_report()->splits;
  const SimulationReport expected = plain.run();
  const SimulationReport report = driver.run();

  EXPECT_EQ(report.steps, expected.steps);
  EXPECT_EQ(report.sim_time, expected.sim_time);
  EXPECT_EQ(report.energy.size(), expected.energy.size());
  EXPECT_EQ((driver.positions() - unflatten_positions(plain.positions())).cwiseAbs().maxCoeff(),
            0.0);
  EXPECT_EQ(driver.adaptive_report()->splits, splits_before)
      << "adaptivity off: the run itself splits nothing";
  EXPECT_EQ(driver.adaptive_report()->simulation.steps, report.steps);
}

TEST(ClothDriver, ObserverSeesEveryStepCapsItAndStopsTheRun) {
  const AdaptiveSheetSpec spec = short_sheet();
  AdaptiveSheet sheet = build_adaptive_sheet(spec);
  AdaptiveSettings adaptive;  // on: the mesh may change between steps
  ClothDriver driver(sheet.mesh, sheet.material, {}, sheet.pins, adaptive_sheet_settings(spec),
                     adaptive);
  int before = 0, after = 0;
  std::vector<double> times;
  const double every = 0.025;  // not a multiple of dt = 1/60 s: steps must be cut to land on it
  double next = every;
  ClothObserver observer;
  observer.before_step = [&](ClothDriver&) { ++before; };
  observer.max_step = [&](const ClothDriver& d) { return next - d.time(); };
  observer.after_step = [&](const ClothDriver& d, const StepOutcome& outcome) {
    EXPECT_TRUE(outcome.accepted);
    ++after;
    times.push_back(d.time());
    if (d.time() >= next - 1e-12) next += every;
    return d.time() < 0.2 - 1e-9;  // stop at 0.2 s
  };
  const SimulationReport report = driver.run(observer);
  EXPECT_EQ(before, report.steps);
  EXPECT_EQ(after, report.steps);
  EXPECT_NEAR(driver.time(), 0.2, 1e-12);
  EXPECT_FALSE(report.at_rest);
  EXPECT_FALSE(report.failed);
  for (int k = 1; k <= 8; ++k) {
    bool landed = false;
    for (double t : times) landed = landed || std::abs(t - k * every) < 1e-12;
    EXPECT_TRUE(landed) << "no step ended at " << k * every << " s";
  }
  EXPECT_EQ(static_cast<int>(driver.adaptive_report()->steps.size()), report.steps);
}

// Pattern rest coordinates (a flat rest) belong to the mesh as given: the driver drapes them on
// the fixed 4-8 mesh exactly as the simulator on the same input, and refuses adaptivity and
// every split (children would have no pattern coordinates).
TEST(ClothDriver, PatternRestShapesNeedTheFixedMesh) {
  const AdaptiveSheetSpec spec = short_sheet();
  AdaptiveSheet sheet = build_adaptive_sheet(spec);
  const meshing::Mesh48Arrays arrays = sheet.mesh.arrays();
  // Each triangle's rest coordinates: its (x, −z) in the horizontal sheet, stretched 10 % along
  // x, so that the rest shape is not the drawn one.
  sheet.material.rest_uv.resize(arrays.faces.rows(), 6);
  for (Eigen::Index t = 0; t < arrays.faces.rows(); ++t)
    for (int k = 0; k < 3; ++k) {
      const Eigen::RowVector3d p = arrays.rest_positions.row(arrays.faces(t, k));
      sheet.material.rest_uv(t, 2 * k) = 1.1 * p.x();
      sheet.material.rest_uv(t, 2 * k + 1) = -p.z();
    }
  const SimulationSettings settings = adaptive_sheet_settings(spec);
  EXPECT_THROW(
      ClothDriver(sheet.mesh, sheet.material, {}, sheet.pins, settings, AdaptiveSettings{}),
      InvalidAdaptiveSettingsError);
  ClothDriver driver(sheet.mesh, sheet.material, {}, sheet.pins, settings, off());
  EXPECT_THROW(driver.adaptive()->refine_uniformly(1), std::logic_error);

  ClothInput input;
  input.rest_positions = arrays.rest_positions;
  input.triangles = arrays.faces;
  input.up = sheet.material.up;
  input.warp = Eigen::MatrixX3d(arrays.faces.rows(), 3);
  for (Eigen::Index t = 0; t < arrays.faces.rows(); ++t)
    input.warp.row(t) = sheet.material.source_warp.row(
        sheet.mesh.source_face(arrays.triangle_ids[static_cast<std::size_t>(t)]));
  input.rest_uv = sheet.material.rest_uv;
  const ClothModel model = build_cloth_model(input, sheet.material.fabric);
  EXPECT_EQ(driver.simulation().model().mass, model.mass);
  Simulation plain(model, flatten_positions(arrays.rest_positions), sheet.pins, settings);
  plain.run();
  driver.run();
  EXPECT_EQ((driver.positions() - unflatten_positions(plain.positions())).cwiseAbs().maxCoeff(),
            0.0);
}

TEST(ClothDriver, ModelGivenAsIsKeepsItsTriangles) {
  SheetSpec spec;
  spec.columns = spec.rows = 3;
  spec.pins = {"top"};
  const SheetScene sheet = build_sheet(spec);
  SimulationSettings settings;
  settings.duration = 0.1;
  std::vector<Pin> pins;
  for (int v : sheet.pinned_vertices) pins.push_back({v, {}});
  ClothDriver driver(build_cloth_model(sheet.input, fabric_preset("cotton")),
                     flatten_positions(sheet.input.rest_positions), pins, settings);
  EXPECT_EQ(driver.adaptive(), nullptr);
  EXPECT_EQ(driver.adaptive_report(), nullptr);
  EXPECT_EQ(driver.faces(), sheet.input.triangles);
  const Eigen::VectorXi source = driver.source_faces();
  ASSERT_EQ(source.size(), sheet.input.triangles.rows());
  for (Eigen::Index t = 0; t < source.size(); ++t) EXPECT_EQ(source(t), t);
  EXPECT_EQ(driver.face_levels().size(), 0);
  const SimulationReport report = driver.run();
  EXPECT_NEAR(report.sim_time, 0.1, 1e-12);
  EXPECT_LT(driver.positions().col(1).minCoeff(), sheet.input.rest_positions.col(1).minCoeff())
      << "the free edge falls";
}

// The sheet's quads cover it once: its 4-8 mesh keeps its vertices and area, each triangle
// lies in the quad it comes from, and the warp is the sheet's.
TEST(ClothDriver, SheetQuadsMakeItsFourEightMesh) {
  SheetSpec spec;
  spec.size = {0.6, 0.4};
  spec.columns = 3;
  spec.rows = 2;
  const SheetScene sheet = build_sheet(spec);
  ASSERT_EQ(sheet.quads.rows(), 6);
  const meshing::Mesh48 mesh = sheet_mesh48(sheet);
  const meshing::Mesh48Arrays arrays = mesh.arrays();
  EXPECT_EQ(arrays.rest_positions, sheet.input.rest_positions);
  ASSERT_EQ(arrays.faces.rows(), 12);
  double area = 0.0;
  for (Eigen::Index t = 0; t < arrays.faces.rows(); ++t) {
    const Eigen::Vector3d a = arrays.rest_positions.row(arrays.faces(t, 0));
    const Eigen::Vector3d b = arrays.rest_positions.row(arrays.faces(t, 1));
    const Eigen::Vector3d c = arrays.rest_positions.row(arrays.faces(t, 2));
    const Eigen::Vector3d normal = (b - a).cross(c - a);
    area += 0.5 * normal.norm();
    EXPECT_GT(normal.z(), 0.0) << "counter-clockwise seen from +Z (a vertical sheet)";
    const int quad = mesh.source_face(arrays.triangle_ids[static_cast<std::size_t>(t)]);
    std::set<int> corners;
    for (int k = 0; k < 4; ++k) corners.insert(sheet.quads(quad, k));
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(corners.count(arrays.faces(t, k))) << "triangle " << t;
  }
  EXPECT_NEAR(area, 0.6 * 0.4, 1e-12);
  const Eigen::MatrixX3d warp = sheet_quad_warp(sheet);
  ASSERT_EQ(warp.rows(), 6);
  for (Eigen::Index q = 0; q < warp.rows(); ++q)
    EXPECT_EQ(Eigen::Vector3d(warp.row(q)), Eigen::Vector3d::UnitY());
}

}  // namespace
}  // namespace sd::sim
