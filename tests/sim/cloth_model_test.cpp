#include "sim/cloth_model.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "sim/forces.hpp"
#include "sim/sheet.hpp"

namespace sd::sim {
namespace {

SheetScene small_sheet(SheetOrientation orientation = SheetOrientation::vertical) {
  SheetSpec spec;
  spec.size = {0.6, 0.4};
  spec.columns = 6;
  spec.rows = 4;
  spec.orientation = orientation;
  return build_sheet(spec);
}

TEST(ClothModel, MassesAddUpToDensityTimesArea) {
  const SheetScene scene = small_sheet();
  FabricParameters fabric;
  fabric.area_density = 0.2;
  const ClothModel model = build_cloth_model(scene.input, fabric);
  EXPECT_NEAR(model.total_mass(), 0.2 * 0.6 * 0.4, 1e-12);
  EXPECT_NEAR(model.vertex_area.sum(), 0.24, 1e-12);
  EXPECT_EQ(model.triangles.size(), 48u);
  // Interior edges of a 6x4 grid with diagonals: 3·6·4 + 6 + 4 − 2·(6 + 4) = 62.
  EXPECT_EQ(model.hinges.size(), 62u);
}

TEST(ClothModel, RestShapeHasNoStrainNoElasticForceAndUnitWarp) {
  for (auto orientation : {SheetOrientation::vertical, SheetOrientation::horizontal}) {
    const SheetScene scene = small_sheet(orientation);
    const ClothModel model = build_cloth_model(scene.input, FabricParameters{});
    const Eigen::VectorXd x = flatten_positions(scene.input.rest_positions);
    EXPECT_NEAR(max_stretch_strain(model, x), 0.0, 1e-12);
    ForceSettings settings;
    settings.terms.gravity = false;
    Eigen::VectorXd force;
    EnergyBreakdown energy;
    evaluate_forces(model, settings, x, Eigen::VectorXd::Zero(x.size()), force, &energy);
    EXPECT_LT(force.lpNorm<Eigen::Infinity>(), 1e-9);
    EXPECT_LT(energy.elastic(), 1e-15);
    // w_u of every triangle is the warp direction: here the sheet's "up".
    const Eigen::Vector3d up = orientation == SheetOrientation::vertical
                                   ? Eigen::Vector3d::UnitY()
                                   : Eigen::Vector3d(-Eigen::Vector3d::UnitZ());
    for (const TriangleElement& t : model.triangles) {
      Eigen::Vector3d wu = Eigen::Vector3d::Zero();
      for (int k = 0; k < 3; ++k) wu += t.du[k] * x.segment<3>(3 * t.vertices[k]);
      EXPECT_NEAR((wu - up).norm(), 0.0, 1e-12);
    }
  }
}

TEST(ClothModel, WarpDefaultsToTheInPlaneDirectionClosestToUp) {
  // A sloped triangle: its warp must be the projection of +Y into its plane.
  ClothInput input;
  input.rest_positions.resize(3, 3);
  input.rest_positions << 0, 0, 0, 1, 0, 0, 0, 1, 1;
  input.triangles.resize(1, 3);
  input.triangles << 0, 1, 2;
  const ClothModel model = build_cloth_model(input, FabricParameters{});
  const TriangleElement& t = model.triangles[0];
  Eigen::Vector3d wu = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) wu += t.du[k] * input.rest_positions.row(k).transpose();
  EXPECT_NEAR((wu - Eigen::Vector3d(0, 1, 1).normalized()).norm(), 0.0, 1e-12);
}

TEST(ClothModel, DesignedRestAnglesOrFlat) {
  SheetScene scene = small_sheet();
  // Roll the sheet onto a cylinder of radius 0.3 m around the Y axis.
  for (Eigen::Index i = 0; i < scene.input.rest_positions.rows(); ++i) {
    const double s = scene.input.rest_positions(i, 0);
    scene.input.rest_positions(i, 0) = 0.3 * std::sin(s / 0.3);
    scene.input.rest_positions(i, 2) = 0.3 * std::cos(s / 0.3);
  }
  scene.input.warp.resize(0, 3);
  const ClothModel designed = build_cloth_model(scene.input, FabricParameters{});
  ClothModelOptions flat_options;
  flat_options.bend_rest = BendRestShape::flat;
  const ClothModel flat = build_cloth_model(scene.input, FabricParameters{}, flat_options);
  double largest = 0.0;
  for (const HingeElement& h : designed.hinges) largest = std::max(largest, std::abs(h.rest_angle));
  EXPECT_NEAR(largest, 0.1 / 0.3, 0.02);  // a 0.1 m column of quads spans 1/3 rad
  for (const HingeElement& h : flat.hinges) EXPECT_EQ(h.rest_angle, 0.0);
  // The designed shape is at rest, the flat rest shape is not.
  ForceSettings settings;
  settings.terms.gravity = false;
  Eigen::VectorXd force;
  const Eigen::VectorXd x = flatten_positions(scene.input.rest_positions);
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(x.size());
  evaluate_forces(designed, settings, x, v, force);
  EXPECT_LT(force.lpNorm<Eigen::Infinity>(), 1e-9);
  evaluate_forces(flat, settings, x, v, force);
  EXPECT_GT(force.lpNorm<Eigen::Infinity>(), 1e-7);
}

// Rest coordinates given per triangle (a flat pattern piece): the same numbers as the rest
// positions would give build the same model, and a pair of triangles folded in 3D whose rest
// coordinates are their unfolded shape is unstrained when laid flat, strained as folded.
TEST(ClothModel, RestCoordinatesPerTriangle) {
  const SheetScene scene = small_sheet();
  const ClothModel reference = build_cloth_model(scene.input, FabricParameters{});
  ClothInput given = scene.input;
  given.rest_uv.resize(given.triangles.rows(), 6);
  for (Eigen::Index f = 0; f < given.triangles.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      // The vertical sheet's warp is +y and weft = normal × warp = (+z) × (+y) = −x.
      const Eigen::Vector3d p = given.rest_positions.row(given.triangles(f, k)) -
                                given.rest_positions.row(given.triangles(f, 0));
      given.rest_uv(f, 2 * k) = p.y();
      given.rest_uv(f, 2 * k + 1) = -p.x();
    }
  const ClothModel model = build_cloth_model(given, FabricParameters{});
  ASSERT_EQ(model.triangles.size(), reference.triangles.size());
  for (size_t t = 0; t < model.triangles.size(); ++t) {
    EXPECT_NEAR(model.triangles[t].rest_area, reference.triangles[t].rest_area, 1e-15);
    EXPECT_NEAR((model.triangles[t].du - reference.triangles[t].du).norm(), 0.0, 1e-9);
    EXPECT_NEAR((model.triangles[t].dv - reference.triangles[t].dv).norm(), 0.0, 1e-9);
  }

  // Two unit right triangles sharing the edge 0-1, the second folded up by 90°.
  ClothInput folded;
  folded.rest_positions.resize(4, 3);
  folded.rest_positions << 0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 0, 1;
  folded.triangles.resize(2, 3);
  folded.triangles << 0, 1, 2, 1, 0, 3;
  folded.rest_uv.resize(2, 6);
  folded.rest_uv << 0, 0, 1, 0, 0, 1,  //
      0, 0, -1, 0, 0, -1;  // (1,0,0) → (0,0), (0,0,0) → (−1,0), (1,0,1) → (0,−1)
  const ClothModel flat = build_cloth_model(folded, FabricParameters{});
  EXPECT_NEAR(flat.total_mass(), FabricParameters{}.area_density * 1.0, 1e-12);
  Eigen::MatrixX3d laid(4, 3);
  laid << 0, 0, 0, 1, 0, 0, 0, 1, 0, 1, -1, 0;  // the pair unfolded onto the plane z = 0
  EXPECT_NEAR(max_stretch_strain(flat, flatten_positions(laid)), 0.0, 1e-12);
  EXPECT_NEAR(max_stretch_strain(flat, flatten_positions(folded.rest_positions)), 0.0, 1e-12);
  folded.rest_uv(1, 5) = -0.5;  // the second triangle cut half as long across: now strained
  EXPECT_GT(max_stretch_strain(build_cloth_model(folded, FabricParameters{}),
                               flatten_positions(folded.rest_positions)),
            0.5);
  folded.rest_uv(1, 5) = 1;  // inverted in the pattern
  EXPECT_THROW(build_cloth_model(folded, FabricParameters{}), InvalidClothError);
}

TEST(ClothModel, BadMeshesAreRejected) {
  ClothInput input;
  input.rest_positions.resize(3, 3);
  input.rest_positions << 0, 0, 0, 1, 0, 0, 2, 0, 0;  // collinear
  input.triangles.resize(1, 3);
  input.triangles << 0, 1, 2;
  EXPECT_THROW(build_cloth_model(input, FabricParameters{}), InvalidClothError);
  input.rest_positions << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  input.triangles << 0, 1, 3;
  EXPECT_THROW(build_cloth_model(input, FabricParameters{}), InvalidClothError);
  input.triangles << 0, 1, 2;
  input.warp.resize(1, 3);
  input.warp << 0, 0, 1;  // perpendicular to the triangle
  EXPECT_THROW(build_cloth_model(input, FabricParameters{}), InvalidClothError);
  input.warp.resize(0, 3);
  FabricParameters fabric;
  fabric.area_density = 0.0;
  EXPECT_THROW(build_cloth_model(input, fabric), InvalidFabricError);
}

}  // namespace
}  // namespace sd::sim
