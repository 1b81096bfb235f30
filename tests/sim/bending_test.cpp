// The quadratic bending model (ClothModelOptions::bend_model = BendModel::quadratic, the
// default; sim/cloth_model VertexBendElement, sim/forces): derivatives against finite
// differences, the continuum energy of smooth bends on every triangulation, rest shapes, and the
// cantilever strips of the bending study (docs/simulator.md, "Bending on any mesh") against the
// elastica.
// GCC 12 reports a false "may be used uninitialized" inside Eigen's eigensolver products.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include "sim/fabric.hpp"
#include "sim/forces.hpp"
#include "sim/sheet.hpp"
#include "sim/static_equilibrium.hpp"
#include "tests/sim/cantilever_elastica.hpp"
#include "tests/sim/force_differences.hpp"
#include "tests/sim/strip_meshes.hpp"
#include "tests/sim/test_scenes.hpp"

namespace sd::sim {
namespace {

// Ghost points at the clamp and the diamond membrane (docs/simulator.md, "The diamond membrane").
ClothModelOptions diamond_options() {
  ClothModelOptions options;
  options.clamp_ghost_points = true;
  options.diamond_membrane = true;
  return options;
}

struct StripMeasure {
  bool converged = false;
  double drop = 0.0;   // tip drop / L
  double chord = 0.0;  // degrees
};

StripMeasure measure_strip(test::StripMesh mesh, const FabricParameters& fabric, double alpha,
                           int cells, int across, const ClothModelOptions& options = {}) {
  const double length = std::cbrt(alpha * fabric.bend / (fabric.area_density * 9.81));
  const test::Strip strip = test::make_strip(mesh, length, 0.25 * length, cells, across);
  const ClothModel model = build_cloth_model(strip.input, fabric, options);
  Eigen::VectorXd x = flatten_positions(strip.input.rest_positions);
  const StaticResult result = solve_static(model, x, strip.clamped);
  StripMeasure m;
  m.converged = result.converged;
  Eigen::Vector3d clamp = Eigen::Vector3d::Zero(), tip = Eigen::Vector3d::Zero();
  for (int v : strip.clamp_line) clamp += x.segment<3>(3 * v) / strip.clamp_line.size();
  for (int v : strip.tip) tip += x.segment<3>(3 * v) / strip.tip.size();
  m.drop = (clamp.y() - tip.y()) / length;
  m.chord = std::atan2(clamp.y() - tip.y(), tip.z() - clamp.z()) * 180.0 / std::numbers::pi;
  return m;
}

// A horizontal 4-8 sheet (XZ plane at y = 0) of `cells` × `cells` squares of side `size`.
ClothInput flat_sheet(int cells, double size) {
  SheetSpec spec;
  spec.orientation = SheetOrientation::horizontal;
  spec.size = {size, size};
  spec.columns = cells;
  spec.rows = cells;
  spec.centre = Eigen::Vector3d::Zero();
  return build_sheet(spec).input;
}

// The same sheet wrapped onto a sphere of radius R (a shaped, doubly curved panel).
ClothInput sphere_cap(int cells, double size, double radius) {
  ClothInput input = flat_sheet(cells, size);
  for (Eigen::Index i = 0; i < input.rest_positions.rows(); ++i) {
    const double x = input.rest_positions(i, 0), z = input.rest_positions(i, 2);
    input.rest_positions(i, 1) = std::sqrt(radius * radius - x * x - z * z) - radius;
  }
  return input;
}

Eigen::Matrix3d random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  return Eigen::Quaterniond(normal(rng), normal(rng), normal(rng), normal(rng))
      .normalized()
      .toRotationMatrix();
}

// The flat-rest bends summed into one operator (FlatBendOperator) against the same bends element
// by element (the model with its operator removed): force, energy, the Jacobian's product and its
// matrix, with damping, on a flat sheet (every bend flat), a clamped one (clamp_bending doubles
// some bends and rebuilds the operator) and a sphere cap (every bend curved: nothing summed).
TEST(QuadraticBending, FlatBendOperatorMatchesTheElements) {
  FabricParameters fabric;
  fabric.bend = 2e-3;
  fabric.bend_damping = 0.05;
  std::mt19937 rng(11);
  ForceSettings settings;
  settings.terms = {false, false, true, true, false, false};
  for (int scene = 0; scene < 3; ++scene) {
    const ClothInput input = scene == 2 ? sphere_cap(6, 0.3, 0.4) : flat_sheet(8, 0.3);
    ClothModel summed = build_cloth_model(input, fabric);
    if (scene == 1) clamp_bending(summed, {0, 1, 2, 9, 10, 11});
    ASSERT_EQ(summed.flat_bends.elements, summed.vertex_bends.size());
    ASSERT_EQ(summed.flat_bends.k_start.size(), static_cast<std::size_t>(summed.vertex_count) + 1);
    EXPECT_EQ(summed.flat_bends.curved.size(), scene == 2 ? summed.vertex_bends.size() : 0u);
    ClothModel elements = summed;
    elements.flat_bends = FlatBendOperator();
    for (int trial = 0; trial < 2; ++trial) {
      const Eigen::VectorXd x = testing::random_configuration(input.rest_positions, rng);
      const Eigen::VectorXd v = Eigen::VectorXd::Random(x.size());
      const Eigen::VectorXd u = Eigen::VectorXd::Random(x.size());
      struct Result {
        Eigen::VectorXd force, product;
        EnergyBreakdown energy;
        Eigen::MatrixXd matrix;
      };
      const auto evaluate = [&](const ClothModel& model) {
        Result r;
        SparseMatrixR matrix = model.pattern.zero_matrix;
        JacobianTarget target;
        target.matrix = &matrix;
        target.dfdx_scale = -0.01;
        target.dfdv_scale = -0.1;
        target.product_input = &u;
        target.product_output = &r.product;
        r.product = Eigen::VectorXd::Zero(u.size());
        evaluate_forces(model, settings, x, v, r.force, &r.energy, &target);
        r.matrix = Eigen::MatrixXd(matrix);
        return r;
      };
      const Result a = evaluate(summed), b = evaluate(elements);
      EXPECT_GT(b.energy.bend, 0.0);
      EXPECT_NEAR(a.energy.bend, b.energy.bend, 1e-10 * b.energy.bend) << scene;
      EXPECT_LE((a.force - b.force).norm(), 1e-12 * b.force.norm()) << scene;
      EXPECT_LE((a.product - b.product).norm(), 1e-12 * b.product.norm()) << scene;
      EXPECT_LE((a.matrix - b.matrix).norm(), 1e-12 * b.matrix.norm()) << scene;
    }
  }
}

// Force against the energy's gradient, the exact ∂f/∂x and ∂f/∂v against central differences,
// and the solve Jacobian symmetric negative semi-definite, for a flat rest (quadratic energy) and
// a curved rest (the area-vector target), with damping.
TEST(QuadraticBending, ForcesAndJacobiansMatchFiniteDifferences) {
  FabricParameters fabric;
  fabric.bend = 2e-3;
  fabric.bend_damping = 0.05;
  std::mt19937 rng(5);
  for (const bool curved : {false, true}) {
    const ClothInput input = curved ? sphere_cap(4, 0.3, 0.4) : flat_sheet(4, 0.3);
    const ClothModel model = build_cloth_model(input, fabric);
    ASSERT_EQ(model.vertex_bends.size(), 25u);
    bool any_curved = false;
    for (const VertexBendElement& b : model.vertex_bends) any_curved |= !b.fan.empty();
    EXPECT_EQ(any_curved, curved);
    ForceSettings settings;
    settings.terms = {false, false, true, true, false, false};
    for (int trial = 0; trial < 3; ++trial) {
      const Eigen::VectorXd x = testing::random_configuration(input.rest_positions, rng);
      const Eigen::VectorXd v = Eigen::VectorXd::Random(x.size());
      const Eigen::MatrixXd dfdx =
          testing::dense_jacobian(model, settings, x, v, 1, 0, JacobianKind::exact);
      const Eigen::MatrixXd dfdv =
          testing::dense_jacobian(model, settings, x, v, 0, 1, JacobianKind::exact);
      const testing::ForceDifferences d = testing::force_differences(model, settings, x, v);
      const Eigen::MatrixXd& fd_x = d.dfdx;
      const Eigen::MatrixXd& fd_v = d.dfdv;
      const Eigen::VectorXd& grad = d.bend_gradient;
      const Eigen::VectorXd& force = d.conservative_force;
      EXPECT_LE((force + grad).norm(), 1e-6 * force.norm()) << curved << " trial " << trial;
      EXPECT_LE((fd_x - dfdx).norm(), 1e-6 * dfdx.norm()) << curved << " trial " << trial;
      EXPECT_LE((fd_v - dfdv).norm(), 1e-6 * dfdv.norm()) << curved << " trial " << trial;
      const Eigen::MatrixXd j =
          testing::dense_jacobian(model, settings, x, v, 1, 0, JacobianKind::solve);
      EXPECT_LE((j - j.transpose()).norm(), 1e-12 * j.norm());
      EXPECT_LE(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(j).eigenvalues().maxCoeff(),
                1e-9 * j.norm());
      if (!curved) {  // quadratic energy: the exact Jacobian is the solve Jacobian, constant
        EXPECT_LE((j - dfdx).norm(), 1e-12 * j.norm());
      }
    }
  }
}

// Affine maps of a flat rest (stretch, shear, compression, rotation) cost no bending: the
// membrane's strain never turns into bending forces. A designed (curved) panel is at rest in its
// rest shape and in any rigid motion of it: zero energy and force.
TEST(QuadraticBending, RestShapesAndRigidMotionsCostNothing) {
  FabricParameters fabric;
  fabric.bend = 1e-5;
  ForceSettings settings;
  settings.terms = {false, false, true, false, false, false};
  std::mt19937 rng(11);
  for (const bool curved : {false, true}) {
    const ClothInput input = curved ? sphere_cap(6, 0.3, 0.25) : flat_sheet(6, 0.3);
    const ClothModel model = build_cloth_model(input, fabric);
    // A reference scale: the force of a 1 mm bump at one vertex.
    Eigen::VectorXd bumped = flatten_positions(input.rest_positions), force;
    bumped(3 * 24 + 1) += 1e-3;
    evaluate_forces(model, settings, bumped, Eigen::VectorXd::Zero(bumped.size()), force);
    const double scale = force.norm();
    ASSERT_GT(scale, 0.0);
    for (int trial = 0; trial < 4; ++trial) {
      Eigen::Matrix3d map = random_rotation(rng);
      if (!curved) map *= Eigen::Matrix3d::Identity() + 0.3 * Eigen::Matrix3d::Random();
      const Eigen::Vector3d shift = Eigen::Vector3d::Random();
      Eigen::VectorXd x(3 * input.rest_positions.rows());
      for (Eigen::Index i = 0; i < input.rest_positions.rows(); ++i)
        x.segment<3>(3 * i) = map * input.rest_positions.row(i).transpose() + shift;
      EnergyBreakdown energy;
      evaluate_forces(model, settings, x, Eigen::VectorXd::Zero(x.size()), force, &energy);
      EXPECT_LT(force.norm(), 1e-9 * scale) << curved << " trial " << trial;
      EXPECT_LT(energy.bend, 1e-18) << curved << " trial " << trial;
    }
  }
}

// A smooth bend costs the continuum energy ½·B·κ²·area on every triangulation and in every
// direction, free edges included (their flux completes the boundary vertices' Laplacian): a strip
// rolled onto a cylinder of radius R (isometric) with its axis at 0..165° to the strip. The
// discrete energy differs from the continuum one by O(h²/R²) and by the boundary's O(h/R) chord
// errors; R = 4 widths here. On the irregular mesh the quadrature of the energy (Σ A_v·density
// with mixed areas) errs by up to 2 %.
TEST(QuadraticBending, CylindersCostTheContinuumEnergyOnEveryMesh) {
  FabricParameters fabric;
  fabric.bend = 1e-5;
  ForceSettings settings;
  settings.terms = {false, false, true, false, false, false};
  for (const test::StripMesh mesh :
       {test::StripMesh::four_eight, test::StripMesh::four_eight_45,
        test::StripMesh::equilateral_across, test::StripMesh::irregular}) {
    const test::Strip strip = test::make_strip(mesh, 0.1, 0.05, 16, 8);
    const ClothModel model = build_cloth_model(strip.input, fabric);
    const double area = model.vertex_area.sum();
    const double radius = 0.2;
    for (int step = 0; step < 12; ++step) {
      const double angle = step * std::numbers::pi / 12.0;
      const Eigen::Vector3d d(std::cos(angle), 0.0, std::sin(angle));
      Eigen::VectorXd x(3 * strip.input.rest_positions.rows());
      for (Eigen::Index i = 0; i < strip.input.rest_positions.rows(); ++i) {
        const Eigen::Vector3d p = strip.input.rest_positions.row(i).transpose();
        const double s = p.dot(d) - 0.05;
        x.segment<3>(3 * i) = p - p.dot(d) * d + (0.05 + radius * std::sin(s / radius)) * d +
                              Eigen::Vector3d(0.0, radius * (1.0 - std::cos(s / radius)), 0.0);
      }
      Eigen::VectorXd force;
      EnergyBreakdown energy;
      evaluate_forces(model, settings, x, Eigen::VectorXd::Zero(x.size()), force, &energy);
      const double continuum = 0.5 * fabric.bend / (radius * radius) * area;
      // Measured: within 3e-4 on the regular meshes, 1.9 % on the irregular one.
      const double tolerance = mesh == test::StripMesh::irregular ? 0.025 : 1e-3;
      EXPECT_NEAR(energy.bend / continuum, 1.0, tolerance)
          << test::strip_mesh_name(mesh) << " at " << 15 * step << " deg";
    }
  }
}

// Peirce's cantilever (overhang 2c, alpha = 8: chord 41.49 degrees in the continuum) at 16
// cells along the overhang, clamped by three lines of vertices: every preset on the 4-8 mesh
// along the strip, and cotton on the 4-8 mesh at 45 degrees, an equilateral mesh with edges
// across and an irregular (jittered, randomly split) grid. Measured (cotton): 41.90, 41.97,
// 41.70, 41.70 degrees with ghost points and the diamond membrane (42.16, 41.39 on the 4-8 meshes
// without); the tolerance is issue 21's ±1.5 degrees.
TEST(QuadraticBending, PeirceChordIsWithinOneAndAHalfDegreesAtSixteenCells) {
  const double peirce = test::cantilever_elastica(8.0).chord_angle_deg();
  for (const std::string& name : fabric_preset_names()) {
    const FabricParameters fabric = fabric_preset(name);
    for (const test::StripMesh mesh :
         {test::StripMesh::four_eight, test::StripMesh::four_eight_45,
          test::StripMesh::equilateral_across, test::StripMesh::irregular}) {
      if (name != "cotton" && mesh != test::StripMesh::four_eight) continue;
      const StripMeasure m = measure_strip(mesh, fabric, 8.0, 16, 4, diamond_options());
      std::printf("Peirce %-9s %-26s 16 cells: chord %.2f deg\n", name.c_str(),
                  test::strip_mesh_name(mesh).c_str(), m.chord);
      ASSERT_TRUE(m.converged) << name << ", " << test::strip_mesh_name(mesh);
      EXPECT_NEAR(m.chord, peirce, 1.5) << name << ", " << test::strip_mesh_name(mesh);
    }
  }
}

// The effective rigidity from the small-deflection drop (alpha = 1; B_eff = B·alpha/alpha' with
// alpha' the elastica's for the measured drop) is within issue 21's ±3 % of B at 16 cells along on
// every mesh, with ghost points at the clamp and the diamond membrane (not yet the defaults).
// Measured 0.964, 0.990, 0.984, 0.966 at 8 cells and 0.984, 0.981, 0.994, 0.993 at 16 for the
// meshes in the order below (docs/simulator.md, "The diamond membrane"). The 4-8 mesh at 45° is not
// monotone (0.990, 0.981, 0.990 at 8, 16, 32 cells: the ghost points' clamp correction and the
// interior's own error have opposite signs), so the bound at 8 cells is the measured spread's
// 4 % rather than a decrease; without ghost points the 45° strip read 0.946 and 0.962.
TEST(QuadraticBending, EffectiveRigidityConvergesToB) {
  const FabricParameters fabric = fabric_preset("cotton");
  for (const test::StripMesh mesh :
       {test::StripMesh::four_eight, test::StripMesh::four_eight_45,
        test::StripMesh::equilateral_across, test::StripMesh::irregular}) {
    for (const int cells : {8, 16}) {
      const StripMeasure m =
          measure_strip(mesh, fabric, 1.0, cells, std::max(2, cells / 4), diamond_options());
      ASSERT_TRUE(m.converged);
      const double rigidity = 1.0 / test::elastica_alpha_for_drop(m.drop);
      std::printf("rigidity %-26s %2d cells: B_eff/B %.3f\n", test::strip_mesh_name(mesh).c_str(),
                  cells, rigidity);
      EXPECT_NEAR(rigidity, 1.0, cells == 16 ? 0.03 : 0.04)
          << test::strip_mesh_name(mesh) << ", " << cells << " cells";
    }
  }
}

// Ghost points at a clamp (ClothModelOptions::clamp_ghost_points, off by default): a free
// vertex's rows read the pinned points behind the clamp's edge as the even extension of the free
// side, so the curvature next to the clamp is not averaged with the clamp's zero. The rows stay
// exact for affine maps: a stretched, sheared and rotated copy of the clamped flat strip costs no
// bending. On the 4-8 mesh at 45° the centres next to the clamp read their twist across it (the
// 0.962 B of EffectiveRigidityConvergesToB), so some of their rows must change.
TEST(QuadraticBending, ClampGhostPointsKeepAffineMapsFree) {
  FabricParameters fabric;
  fabric.bend = 1e-5;
  ClothModelOptions options;
  options.clamp_ghost_points = true;
  for (const test::StripMesh mesh : {test::StripMesh::four_eight, test::StripMesh::four_eight_45}) {
    const test::Strip strip = test::make_strip(mesh, 0.1, 0.05, 8, 4);
    ClothModel model = build_cloth_model(strip.input, fabric, options);
    const Eigen::VectorXd rest = flatten_positions(strip.input.rest_positions);
    clamp_bending(model, strip.clamped, &rest);
    int ghosted = 0;
    for (const VertexBendElement& b : model.vertex_bends) ghosted += b.ghosted ? 1 : 0;
    EXPECT_GT(ghosted, 0) << test::strip_mesh_name(mesh);
    ForceSettings settings;
    settings.terms = {false, false, true, false, false, false};
    std::mt19937 rng(3);
    Eigen::Matrix3d map =
        random_rotation(rng) * (Eigen::Matrix3d::Identity() + 0.3 * Eigen::Matrix3d::Random());
    Eigen::VectorXd x(rest.size()), force;
    for (Eigen::Index i = 0; i < rest.size() / 3; ++i)
      x.segment<3>(3 * i) = map * rest.segment<3>(3 * i) + Eigen::Vector3d(0.1, -0.2, 0.3);
    EnergyBreakdown energy;
    evaluate_forces(model, settings, x, Eigen::VectorXd::Zero(x.size()), force, &energy);
    // The scale: the bending energy of the strip rolled to a curvature of 1/m is 2.5e-8 J.
    EXPECT_LT(energy.bend, 1e-20) << test::strip_mesh_name(mesh);
  }
}

// With ghost points at the clamp every mesh meets issue 21's rigidity targets at small
// deflection (α = 1, cotton): within 3 % at 16 cells on the narrow strips (measured 0.981 on the
// 4-8 mesh at 45°, 0.962 without) and within 8 % at 4 square cells (measured 0.932 on the 4-8 mesh
// along the strip, 0.914 without). Measured alone; with the diamond membrane, which removes the 4-8
// mesh's membrane locking, with which silk's Peirce chord at 45° fell to 39.7° (docs/simulator.md,
// "Ghost points at a clamp", "The diamond membrane").
TEST(QuadraticBending, ClampGhostPointsMeetTheRigidityTargets) {
  const FabricParameters fabric = fabric_preset("cotton");
  ClothModelOptions options;
  options.clamp_ghost_points = true;
  for (const test::StripMesh mesh :
       {test::StripMesh::four_eight, test::StripMesh::four_eight_45,
        test::StripMesh::equilateral_across, test::StripMesh::irregular}) {
    const StripMeasure m = measure_strip(mesh, fabric, 1.0, 16, 4, options);
    ASSERT_TRUE(m.converged) << test::strip_mesh_name(mesh);
    const double rigidity = 1.0 / test::elastica_alpha_for_drop(m.drop);
    std::printf("ghost points: rigidity %-26s 16 cells: B_eff/B %.3f\n",
                test::strip_mesh_name(mesh).c_str(), rigidity);
    EXPECT_NEAR(rigidity, 1.0, 0.03) << test::strip_mesh_name(mesh);
    // Square cells, 4 along and 4 across, a strip as wide as long.
    const double length = std::cbrt(fabric.bend / (fabric.area_density * 9.81));
    const test::Strip strip = test::make_strip(mesh, length, length, 4, 4);
    const ClothModel model = build_cloth_model(strip.input, fabric, options);
    Eigen::VectorXd x = flatten_positions(strip.input.rest_positions);
    ASSERT_TRUE(solve_static(model, x, strip.clamped).converged);
    double clamp = 0.0, tip = 0.0;
    for (int v : strip.clamp_line) clamp += x(3 * v + 1) / strip.clamp_line.size();
    for (int v : strip.tip) tip += x(3 * v + 1) / strip.tip.size();
    const double coarse = 1.0 / test::elastica_alpha_for_drop((clamp - tip) / length);
    std::printf("ghost points: rigidity %-26s 4 square cells: B_eff/B %.3f\n",
                test::strip_mesh_name(mesh).c_str(), coarse);
    EXPECT_NEAR(coarse, 1.0, 0.08) << test::strip_mesh_name(mesh);
  }
}

// On the 4-8 mesh with w × h cells (w ≠ h) a smooth bend must not couple to the sublattice mode
// (the degree-4 and degree-8 vertices moving against each other, a checkerboard of heights): a
// coupling lets a bent strip lower its energy by zigzagging, a rigidity below B at every
// resolution. The degree-4 vertices read the mode with their 5-point differences, so the
// degree-8 vertices must read it the same way: the curvatures their nearest opposite pairs
// determine come from those pairs, not from a least-squares fit over the whole 3 × 3 block
// (which reads the mode at a third, a cross term 16/3·g·κ·(1/w² − 1/h²) per cell pair: 26 % and
// 13 % of the geometric mean of the two energies here before). The
// energy's cross term between a cylinder y = ½κz² and the checkerboard, summed over the
// interior vertices of whole periods, is zero to rounding on 1 × 2 and 4 × 3 cells, in both
// orientations of the tangent frame (the frame follows each vertex's first neighbour).
TEST(QuadraticBending, SmoothBendsDoNotCoupleToTheSublatticeModeOnElongatedCells) {
  FabricParameters fabric;
  fabric.bend = 1e-5;
  for (const int across : {16, 6}) {  // cells 0.5 h and 1.33 h wide
    const int cells = 8;
    const test::Strip strip =
        test::make_strip(test::StripMesh::four_eight, 1.0, 1.0, cells, across);
    const ClothModel model = build_cloth_model(strip.input, fabric);
    const Eigen::MatrixX3d& rest = strip.input.rest_positions;
    const double h = 1.0 / cells, w = 1.0 / across;
    Eigen::VectorXd bend(rest.rows()), zigzag(rest.rows());
    for (Eigen::Index i = 0; i < rest.rows(); ++i) {
      const double z = rest(i, 2);
      bend(i) = 0.5 * z * z;  // κ = 1 along the strip
      zigzag(i) = (std::lround(z / h) + std::lround(rest(i, 0) / w)) % 2 == 0 ? 1.0 : -1.0;
    }
    double cross = 0.0, bend_energy = 0.0, zigzag_energy = 0.0;
    int counted = 0;
    for (const VertexBendElement& b : model.vertex_bends) {
      const int v = b.vertices[static_cast<std::size_t>(b.centre)];
      const long r = std::lround(rest(v, 2) / h), c = std::lround(rest(v, 0) / w);
      // Vertices of whole periods whose neighbours are all interior: rows 2..7, columns
      // 2..across-3 (even counts; next to a free edge the rows stay least-squares fits).
      if (r < 2 || r > 7 || c < 2 || c > across - 3) continue;
      Eigen::Vector3d a = Eigen::Vector3d::Zero(), g = Eigen::Vector3d::Zero();
      for (std::size_t j = 0; j < b.vertices.size(); ++j) {
        a += b.rows.col(static_cast<Eigen::Index>(j)) * bend(b.vertices[j]);
        g += b.rows.col(static_cast<Eigen::Index>(j)) * zigzag(b.vertices[j]);
      }
      const Eigen::Vector3d weight(0.5, 0.5, 2.0);
      cross += b.inverse_area * (weight.array() * a.array() * g.array()).sum();
      bend_energy += b.inverse_area * (weight.array() * a.array().square()).sum();
      zigzag_energy += b.inverse_area * (weight.array() * g.array().square()).sum();
      ++counted;
    }
    ASSERT_EQ(counted, 6 * (across - 4));
    EXPECT_LE(std::abs(cross), 1e-9 * std::sqrt(bend_energy * zigzag_energy)) << across;
  }
}

// Elongated cells, the case the sublattice coupling above made soft at every resolution: a cotton
// strip as wide as its free length c (α = 1) on the 4-8 mesh with cells twice as long as wide
// (2·cells across). Measured: MEASURED (the whole-one-ring least-squares rows: 0.901, 0.930, 0.934,
// and 0.934 at 32 cells in a linear analysis). Issue 21 asks ±8 % at 4 cells and ±3 % at 16.
TEST(QuadraticBending, RigidityConvergesOnElongatedCellsOfThe48Mesh) {
  const FabricParameters fabric = fabric_preset("cotton");
  const double length = std::cbrt(fabric.bend / (fabric.area_density * 9.81));
  const auto rigidity = [&](int cells, double width, int across) {
    const test::Strip strip =
        test::make_strip(test::StripMesh::four_eight, length, width, cells, across);
    const ClothModel model = build_cloth_model(strip.input, fabric);
    Eigen::VectorXd x = flatten_positions(strip.input.rest_positions);
    EXPECT_TRUE(solve_static(model, x, strip.clamped).converged) << cells << " x " << across;
    double clamp = 0.0, tip = 0.0;
    for (int v : strip.clamp_line) clamp += x(3 * v + 1) / strip.clamp_line.size();
    for (int v : strip.tip) tip += x(3 * v + 1) / strip.tip.size();
    return 1.0 / test::elastica_alpha_for_drop((clamp - tip) / length);
  };
  double previous_error = 1.0;
  for (const int cells : {4, 8, 16}) {
    const double r = rigidity(cells, length, 2 * cells);
    std::printf("rigidity 4-8, %2d cells along, %2d across (2:1): B_eff/B %.3f\n", cells, 2 * cells,
                r);
    EXPECT_NEAR(r, 1.0, cells == 4 ? 0.08 : cells == 8 ? 0.05 : 0.03) << cells;
    EXPECT_LT(std::abs(r - 1.0), previous_error) << cells;
    previous_error = std::abs(r - 1.0);
  }
}

}  // namespace
}  // namespace sd::sim
