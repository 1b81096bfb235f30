#include "garment/surface_relaxation.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "meshing/quad_quality.hpp"
#include "tests/garment/quad_grids.hpp"

namespace sd::garment {
namespace {

using test::grid_boundary;
using test::plane_grid;
using test::sphere_grid;

std::vector<int> grid_corners(int n) {
  return {0, n, (n + 1) * (n + 1) - 1, n * (n + 1)};
}

TEST(SurfaceRelaxation, SpreadsACollapsedInteriorBackToTheUniformGrid) {
  // On a plane the fixed point of the sweeps is the discrete harmonic map, which for a square
  // grid with uniformly spaced boundary vertices is the uniform grid itself: an exact answer.
  const int n = 8;
  const meshing::QuadMesh grid = plane_grid(n);
  meshing::QuadMesh mesh = grid;
  const std::vector<char> fixed = grid_boundary(n);
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
    if (!fixed[static_cast<std::size_t>(v)]) mesh.vertices.row(v) << 0.5, 0.5, 0.0;  // one point
  const SurfaceLift plane = [](const Eigen::Vector3d& p) {
    return LiftedPoint{{p.x(), p.y(), 0.0}, Eigen::Vector3d::UnitZ()};
  };
  const SurfaceRelaxationResult result = relax_on_surface(
      mesh, fixed, plane, {.max_sweeps = 2000, .tolerance = 1e-13, .max_step = 1.0});
  EXPECT_LT(result.sweeps, 2000);
  EXPECT_EQ(result.refused, 0);
  EXPECT_LT((mesh.vertices - grid.vertices).cwiseAbs().maxCoeff(), 1e-10);
}

// test::rhombus_tiling(k), the interior (c, the k spoke midpoints, the k rhombus centres) pulled
// towards c and relaxed with the outline fixed. Returns how far the result is from the
// tiling (with the weights of relax_on_surface the tiling is the fixed point of the sweeps).
double distance_from_rhombus_tiling(int k, bool weigh_high_valence = false) {
  auto [mesh, fixed] = test::rhombus_tiling(k);
  EXPECT_EQ(mesh.vertex_count(), 6 * k + 1);
  EXPECT_EQ(std::count(fixed.begin(), fixed.end(), 0), 2 * k + 1);
  const meshing::QuadMesh tiling = mesh;
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
    if (!fixed[static_cast<size_t>(v)]) mesh.vertices.row(v) *= 0.3;
  const SurfaceLift plane = [](const Eigen::Vector3d& p) {
    return LiftedPoint{{p.x(), p.y(), 0.0}, Eigen::Vector3d::UnitZ()};
  };
  const SurfaceRelaxationResult result =
      relax_on_surface(mesh, fixed, plane,
                       {.max_sweeps = 2000,
                        .tolerance = 1e-13,
                        .max_step = 1.0,
                        .weigh_high_valence = weigh_high_valence});
  EXPECT_LT(result.sweeps, 2000);
  return (mesh.vertices - tiling.vertices).cwiseAbs().maxCoeff();
}

// A regular hexagon of side 2 tiled by three rhombi (120° at the centre): plain means of the
// neighbours pull the three spoke midpoints to 0.73 from the centre and the rhombus centres to
// 0.93, shrinking the quads there (the small quads at valence-3 vertices of the corpus).
TEST(SurfaceRelaxation, QuadsAroundAValenceThreeVertexKeepTheSizeOfTheirNeighbours) {
  EXPECT_LT(distance_from_rhombus_tiling(3), 1e-9);
}

// Five rhombi (72° at the centre): plain means push the spoke midpoints out (the large quads at
// valence-5 vertices of the corpus); the weight 1 + 2 cos 72° = 1.618 of the centre, with
// weigh_high_valence, holds them. By default (off, for the arms-lowering t-shirt's drape) the
// plain means stay: the tiling is left by more than a tenth of a quad's side (measured 0.18).
TEST(SurfaceRelaxation, QuadsAroundAValenceFiveVertexKeepTheSizeOfTheirNeighbours) {
  EXPECT_LT(distance_from_rhombus_tiling(5, true), 1e-9);
  EXPECT_GT(distance_from_rhombus_tiling(5), 0.1);
}

TEST(SurfaceRelaxation, ValenceWeightsBalanceRhombiOfOneSize) {
  EXPECT_EQ(valence_weight(3), 0.0);
  EXPECT_EQ(valence_weight(4), 1.0);
  EXPECT_NEAR(valence_weight(5), (1 + std::sqrt(5.0)) / 2, 1e-15);  // the golden ratio
  EXPECT_NEAR(valence_weight(6), 2.0, 1e-15);
}

TEST(SurfaceRelaxation, KeepsTheBoundaryAndStaysOnASphere) {
  // A folded patch on a sphere: the interior dragged and pushed off the surface. Relaxed, every
  // free vertex lies on the sphere, the boundary is untouched (bitwise: panels are stitched by
  // their boundary vertices) and no quad is folded.
  const int n = 8;
  const double r = 0.3;
  meshing::QuadMesh mesh = sphere_grid(n, r, 0.3);
  const std::vector<char> fixed = grid_boundary(n);
  const meshing::QuadMesh start = mesh;
  // Drag one inner vertex across two of its neighbours and lift another 5 cm off the surface.
  mesh.vertices.row(3 * (n + 1) + 3) = mesh.vertices.row(3 * (n + 1) + 6);
  mesh.vertices.row(5 * (n + 1) + 5) *= (r + 0.05) / r;
  ASSERT_GT(meshing::measure_quality(mesh, grid_corners(n)).inverted_quads, 0);
  const SurfaceLift sphere = [r](const Eigen::Vector3d& p) {
    return LiftedPoint{r * p.normalized(), p.normalized()};
  };
  relax_on_surface(mesh, fixed, sphere, {.max_sweeps = 200, .tolerance = 1e-9, .max_step = 0.02});
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v) {
    if (fixed[static_cast<std::size_t>(v)]) {
      EXPECT_EQ(mesh.vertices.row(v), start.vertices.row(v)) << v;
    } else {
      EXPECT_NEAR(mesh.vertices.row(v).norm(), r, 1e-12) << v;
    }
  }
  const meshing::QuadQuality quality = meshing::measure_quality(mesh, grid_corners(n));
  EXPECT_EQ(quality.inverted_quads, 0);
  EXPECT_GT(quality.scaled_jacobian_min, 0.9);  // a fine grid on a sphere: nearly square
}

TEST(SurfaceRelaxation, RefusesLiftsThatJumpAcrossARidge) {
  // A closest-point map with a ridge at x = 4.5: beyond it, points land on a parallel sheet
  // 1 m away (as cloth under the arm lands on the torso or on the arm). Moves of at most 0.4
  // never reach across: every vertex that would land over there stays on its own sheet.
  const int n = 8;
  meshing::QuadMesh mesh = plane_grid(n);
  const std::vector<char> fixed = grid_boundary(n);
  // Interior squeezed to the left half, so that relaxing pulls it across the ridge.
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
    if (!fixed[static_cast<std::size_t>(v)]) mesh.vertices(v, 0) *= 0.5;
  const SurfaceLift ridge = [](const Eigen::Vector3d& p) {
    return LiftedPoint{{p.x(), p.y(), p.x() > 4.5 ? 1.0 : 0.0}, Eigen::Vector3d::UnitZ()};
  };
  const SurfaceRelaxationResult result =
      relax_on_surface(mesh, fixed, ridge, {.max_sweeps = 100, .tolerance = 1e-9, .max_step = 0.4});
  EXPECT_GT(result.refused, 0);
  EXPECT_EQ(mesh.vertices.col(2).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LE(mesh.vertices.col(0).maxCoeff(), n);
}

TEST(SurfaceRelaxation, RejectsAFixedListOfTheWrongLength) {
  meshing::QuadMesh mesh = plane_grid(2);
  const std::vector<char> fixed(3, 0);
  const SurfaceLift plane = [](const Eigen::Vector3d& p) {
    return LiftedPoint{p, Eigen::Vector3d::UnitZ()};
  };
  EXPECT_THROW(relax_on_surface(mesh, fixed, plane), std::invalid_argument);
}

}  // namespace
}  // namespace sd::garment
