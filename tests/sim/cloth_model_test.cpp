#include "sim/cloth_model.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "sim/element_forces.hpp"
#include "sim/forces.hpp"
#include "sim/sheet.hpp"
#include "tests/sim/strip_meshes.hpp"

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

// clamp_bending doubles the energy of the vertex bends on a clamp's edge once, however often it
// is applied (an adaptive update keeps the elements of the previous, clamped model), and a vertex
// that leaves the clamp gets its own energy back exactly.
TEST(ClothModel, ClampBendingDoublesOnceAndUndoesExactly) {
  SheetSpec spec;
  spec.size = {0.6, 0.4};
  spec.columns = 6;
  spec.rows = 4;
  spec.pins = {"top:2"};  // two lines of vertices: the triangles between them are all pinned
  const SheetScene scene = build_sheet(spec);
  const ClothModel plain = build_cloth_model(scene.input, fabric_preset("cotton"));
  ClothModel model = plain;
  clamp_bending(model, scene.pinned_vertices);
  int doubled = 0;
  for (std::size_t b = 0; b < model.vertex_bends.size(); ++b)
    if (model.vertex_bends[b].clamped) {
      ++doubled;
      EXPECT_EQ(model.vertex_bends[b].inverse_area, 2.0 * plain.vertex_bends[b].inverse_area);
    } else {
      EXPECT_EQ(model.vertex_bends[b].inverse_area, plain.vertex_bends[b].inverse_area);
    }
  EXPECT_EQ(doubled, spec.columns + 1);  // the second line of pinned vertices
  const ClothModel once = model;
  clamp_bending(model, scene.pinned_vertices);
  for (std::size_t b = 0; b < model.vertex_bends.size(); ++b)
    EXPECT_EQ(model.vertex_bends[b].inverse_area, once.vertex_bends[b].inverse_area);
  clamp_bending(model, {});
  for (std::size_t b = 0; b < model.vertex_bends.size(); ++b) {
    EXPECT_FALSE(model.vertex_bends[b].clamped);
    EXPECT_EQ(model.vertex_bends[b].inverse_area, plain.vertex_bends[b].inverse_area);
  }
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

// A gathered panel's ease (scale_rest_shapes with a warp and a weft column) is the rest shape
// whose coordinates along the warp are a times and along the weft b times the designed ones:
// the same elements as build_cloth_model of those coordinates, unstrained in the sheet
// stretched by a along its warp (+y) and b along its weft (−x). One column is the isotropic ease,
// the same as two equal ones bit for bit.
TEST(ClothModel, EaseScalesTheRestShapeByWarpAndWeftFactors) {
  const SheetScene scene = small_sheet();
  const double a = 1.25, b = 1.5;  // binary fractions: the scaled coordinates are exact
  ClothModel model = build_cloth_model(scene.input, FabricParameters{});
  const double mass = model.total_mass();
  const Eigen::Index triangles = static_cast<Eigen::Index>(model.triangles.size());
  Eigen::MatrixXd scale(triangles, 2);
  scale.col(0).setConstant(a);
  scale.col(1).setConstant(b);
  scale_rest_shapes(model, scale);

  // The same rest shape given as coordinates: the vertical sheet's warp is +y, its weft −x.
  ClothInput given = scene.input;
  given.rest_uv.resize(given.triangles.rows(), 6);
  for (Eigen::Index f = 0; f < given.triangles.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d p = given.rest_positions.row(given.triangles(f, k)) -
                                given.rest_positions.row(given.triangles(f, 0));
      given.rest_uv(f, 2 * k) = a * p.y();
      given.rest_uv(f, 2 * k + 1) = -b * p.x();
    }
  const ClothModel reference = build_cloth_model(given, FabricParameters{});
  for (size_t t = 0; t < model.triangles.size(); ++t) {
    // Areas: a product of exact factors; du, dv: one division each way (a few ulps of 1/m).
    EXPECT_NEAR(model.triangles[t].rest_area, reference.triangles[t].rest_area, 1e-15);
    EXPECT_NEAR((model.triangles[t].du - reference.triangles[t].du).norm(), 0.0, 1e-9);
    EXPECT_NEAR((model.triangles[t].dv - reference.triangles[t].dv).norm(), 0.0, 1e-9);
  }
  EXPECT_NEAR(model.total_mass(), a * b * mass, 1e-15);

  // Lengths: the sheet stretched by a along the warp and b along the weft is at rest (with a
  // and b swapped it would be strained by b/a − 1 = 0.2); stretched twice that along one
  // direction, it is strained by 1 along it (max_stretch_strain sees stretch only).
  const auto strain = [&](double along_warp, double along_weft) {
    Eigen::MatrixX3d x = scene.input.rest_positions;
    x.col(1) *= along_warp;
    x.col(0) *= along_weft;
    return max_stretch_strain(model, flatten_positions(x));
  };
  EXPECT_NEAR(strain(a, b), 0.0, 1e-12);
  EXPECT_NEAR(strain(2 * a, b), 1.0, 1e-12);
  EXPECT_NEAR(strain(a, 2 * b), 1.0, 1e-12);
  EXPECT_NEAR(strain(b, a), b / a - 1.0, 1e-12);

  // The isotropic ease: one column or two equal ones give the same elements bit for bit.
  ClothModel one = build_cloth_model(scene.input, FabricParameters{});
  ClothModel two = one;
  scale_rest_shapes(one, Eigen::VectorXd::Constant(triangles, 1.1));
  scale_rest_shapes(two, Eigen::MatrixXd::Constant(triangles, 2, 1.1));
  for (size_t t = 0; t < one.triangles.size(); ++t) {
    EXPECT_EQ(one.triangles[t].rest_area, two.triangles[t].rest_area);
    EXPECT_EQ(one.triangles[t].du, two.triangles[t].du);
    EXPECT_EQ(one.triangles[t].dv, two.triangles[t].dv);
  }
  EXPECT_THROW(scale_rest_shapes(one, Eigen::MatrixXd::Constant(triangles, 3, 1.0)),
               InvalidClothError);
  EXPECT_THROW(scale_rest_shapes(one, Eigen::MatrixXd::Constant(triangles, 2, -1.0)),
               InvalidClothError);
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

namespace sd::sim {
namespace {

// Bending energy of the hinges whose edge midpoint lies in [lo, hi)² (x, z) of a flat mesh in
// the XZ plane bent into the height field y = ½·κ·(u·(p − c))², u = (cos φ, sin φ), c the
// region's centre, relative to the
// continuum ½·B·κ² times their share (A1+A2)/3 of the area.
double cylinder_energy_ratio(const ClothModel& model, const Eigen::MatrixX3d& rest, double phi,
                             double kappa, double lo, double hi) {
  Eigen::MatrixX3d bent = rest;
  const Eigen::Vector2d u(std::cos(phi), std::sin(phi));
  const double centre = 0.5 * (lo + hi);  // slopes stay small: the height field is a cylinder
  for (Eigen::Index i = 0; i < rest.rows(); ++i) {
    const double s = u.dot(Eigen::Vector2d(rest(i, 0) - centre, rest(i, 2) - centre));
    bent(i, 1) = 0.5 * kappa * s * s;
  }
  double energy = 0.0, continuum = 0.0;
  for (const HingeElement& h : model.hinges) {
    const Eigen::Vector3d mid = 0.5 * (rest.row(h.vertices[0]) + rest.row(h.vertices[1]));
    if (mid.x() < lo || mid.x() >= hi || mid.z() < lo || mid.z() >= hi) continue;
    const auto p = [&](int k) { return Eigen::Vector3d(bent.row(h.vertices[k])); };
    const double theta = dihedral_angle(p(0), p(1), p(2), p(3)) - h.rest_angle;
    energy += 0.5 * h.weight * theta * theta;
    const auto q = [&](int k) { return Eigen::Vector3d(rest.row(h.vertices[k])); };
    const double areas = 0.5 * (q(1) - q(0)).cross(q(2) - q(0)).norm() +
                         0.5 * (q(1) - q(0)).cross(q(3) - q(0)).norm();
    continuum += 0.5 * kappa * kappa * areas / 3.0;
  }
  return energy / continuum;
}

// The calibrated weights give every smooth cylinder its continuum energy, in any direction, on
// the 4-8 mesh in both orientations and on the equilateral mesh (regions of whole periods of
// the pattern, away from the boundary). The edge weights |e|²/(A1+A2) are exact only for
// bends across grid lines: on the 4-8 mesh a bend at 45° to them costs 1.5 times as much (the
// hypotenuse hinges bend under a bend along them as much as across).
TEST(ClothModel, CalibratedHingeWeightsHoldTheCylinderEnergyInEveryDirection) {
  struct Case {
    test::StripMesh mesh;
    double period;  // in cells
  };
  for (const Case c :
       {Case{test::StripMesh::four_eight, 2.0}, Case{test::StripMesh::four_eight_45, 1.0}}) {
    const int cells = 30;
    const double h = 0.01;
    const test::Strip patch = test::make_strip(c.mesh, cells * h, 32 * h, cells, 32);
    ClothModelOptions options;
    options.bend_weights = BendWeights::calibrated;
    const ClothModel calibrated = build_cloth_model(patch.input, FabricParameters{}, options);
    options.bend_weights = BendWeights::edge;
    const ClothModel edge = build_cloth_model(patch.input, FabricParameters{}, options);
    const double lo = 8 * h, hi = lo + 8 * c.period * h;
    for (int k = 0; k < 12; ++k) {
      const double phi = k * std::numbers::pi / 12;
      EXPECT_NEAR(
          cylinder_energy_ratio(calibrated, patch.input.rest_positions, phi, 0.001 / h, lo, hi),
          1.0, 2e-3)
          << test::strip_mesh_name(c.mesh) << ", bend direction " << phi;
    }
    const double diagonal = c.mesh == test::StripMesh::four_eight ? std::numbers::pi / 4 : 0.0;
    EXPECT_NEAR(
        cylinder_energy_ratio(edge, patch.input.rest_positions, diagonal, 0.001 / h, lo, hi), 1.5,
        3e-3)
        << test::strip_mesh_name(c.mesh);
  }
}

// A bend stencil measures only what is not smooth: zero for every rigid motion and quadratic
// bend of a flat sheet, and at the rest shape of a curved one; not zero for the 4-8 mesh's
// zigzag (degree-8 vertices moving against the degree-4 ones).
TEST(ClothModel, BendStencilsVanishOnSmoothShapes) {
  const test::Strip patch = test::make_strip(test::StripMesh::four_eight, 0.1, 0.1, 10, 10);
  ClothModelOptions options;
  options.bend_stencil_stiffness = 1.0;
  const ClothModel model = build_cloth_model(patch.input, FabricParameters{}, options);
  ASSERT_FALSE(model.stencils.empty());
  const auto stencil_energy = [&](const ClothModel& m, const Eigen::MatrixX3d& shape) {
    double energy = 0.0;
    for (const BendStencil& b : m.stencils)
      for (std::size_t j = 0; j < b.vertices.size(); ++j)
        for (std::size_t l = 0; l < b.vertices.size(); ++l)
          energy += 0.5 * b.coupling(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(l)) *
                    shape.row(b.vertices[j]).dot(shape.row(b.vertices[l]));
    return energy;
  };
  const Eigen::MatrixX3d& rest = patch.input.rest_positions;
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, 2.0, 3.0).normalized()).toRotationMatrix();
  Eigen::MatrixX3d smooth = rest, zigzag = rest;
  for (Eigen::Index i = 0; i < rest.rows(); ++i) {
    const double x = rest(i, 0), z = rest(i, 2);
    smooth(i, 1) = 3.0 * x * x - 2.0 * x * z + 5.0 * z * z + 0.1 * x;
    const long r = std::lround(z / 0.01), c = std::lround(x / 0.01);
    zigzag(i, 1) = (r + c) % 2 == 0 ? 1e-2 : -1e-2;
  }
  smooth = (smooth * rotation.transpose()).rowwise() + Eigen::RowVector3d(0.3, -0.2, 1.0);
  const double scale = stencil_energy(model, zigzag);
  EXPECT_GT(scale, 0.0);
  EXPECT_LE(stencil_energy(model, smooth), 1e-9 * scale);  // round-off of positions ~1 m
  // A curved rest shape (a cylinder of radius 5 cm) is its own zero.
  Eigen::MatrixX3d curved = rest;
  for (Eigen::Index i = 0; i < rest.rows(); ++i) {
    curved(i, 0) = 0.05 * std::sin(rest(i, 0) / 0.05);
    curved(i, 1) = 0.05 * (1.0 - std::cos(rest(i, 0) / 0.05));
  }
  ClothInput input = patch.input;
  input.rest_positions = curved;
  const ClothModel bent = build_cloth_model(input, FabricParameters{}, options);
  EXPECT_LE(stencil_energy(bent, curved), 1e-9 * scale);
}

}  // namespace
}  // namespace sd::sim
