// The foldover-free placement (detail::untangle_in_plane): its energy's gradient against finite
// differences, and folded grids coming out with every quad corner positive.

#include "meshing/patch_relaxation.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "tests/meshing/quad_grid.hpp"

namespace sd::meshing {
namespace {

std::vector<std::array<int, 4>> quads_of(const QuadMesh& mesh) {
  std::vector<std::array<int, 4>> quads(static_cast<size_t>(mesh.faces.rows()));
  for (size_t f = 0; f < quads.size(); ++f)
    for (int k = 0; k < 4; ++k)
      quads[f][static_cast<size_t>(k)] = mesh.faces(static_cast<Eigen::Index>(f), k);
  return quads;
}

// Smallest cross product of a quad corner's two edges in the z = 0 plane (> 0: not folded).
double smallest_corner(const std::vector<Eigen::Vector3d>& x,
                       const std::vector<std::array<int, 4>>& quads) {
  double smallest = 1e300;
  for (const auto& q : quads)
    for (size_t k = 0; k < 4; ++k) {
      const Eigen::Vector3d a =
          x[static_cast<size_t>(q[(k + 1) % 4])] - x[static_cast<size_t>(q[k])];
      const Eigen::Vector3d b =
          x[static_cast<size_t>(q[(k + 3) % 4])] - x[static_cast<size_t>(q[k])];
      smallest = std::min(smallest, a.x() * b.y() - a.y() * b.x());
    }
  return smallest;
}

TEST(PlanarUntangling, GradientMatchesFiniteDifferences) {
  const QuadMesh grid = test::quad_grid(3, 2);
  const auto quads = quads_of(grid);
  std::mt19937 random(7);
  std::uniform_real_distribution<double> jitter(-0.45, 0.45);
  for (const double epsilon : {1e-3, 0.1, 1.0}) {
    for (int trial = 0; trial < 20; ++trial) {
      std::vector<Eigen::Vector2d> x(static_cast<size_t>(grid.vertices.rows()));
      for (size_t v = 0; v < x.size(); ++v)  // some corners folded, some not
        x[v] = grid.vertices.row(static_cast<Eigen::Index>(v)).head<2>().transpose() +
               Eigen::Vector2d(jitter(random), jitter(random));
      std::vector<Eigen::Vector2d> gradient;
      const double h = 1.3;
      const double energy = detail::untangling_energy(x, quads, h, epsilon, &gradient);
      for (size_t v = 0; v < x.size(); ++v)
        for (int c = 0; c < 2; ++c) {
          auto central = [&](double step) {
            std::vector<Eigen::Vector2d> plus = x, minus = x;
            plus[v][c] += step;
            minus[v][c] -= step;
            return (detail::untangling_energy(plus, quads, h, epsilon) -
                    detail::untangling_energy(minus, quads, h, epsilon)) /
                   (2 * step);
          };
          // Richardson's extrapolation of two central differences: truncation O(step⁴).
          const double numeric = (4 * central(5e-7) - central(1e-6)) / 3;
          // Rounding O(1e-16 energy / step),
          // which matters for folded corners at small ε (χ ~ ε² / 4|det|: energies ~1e6).
          EXPECT_NEAR(gradient[v][c], numeric, 1e-5 * (1 + std::abs(numeric)) + 1e-9 * energy)
              << "epsilon " << epsilon << ", vertex " << v << ", coordinate " << c;
        }
    }
  }
}

TEST(PlanarUntangling, UnfoldsAGridWithItsInteriorScrambled) {
  QuadMesh grid = test::quad_grid(6, 5);
  const auto quads = quads_of(grid);
  std::vector<Eigen::Vector3d> x(static_cast<size_t>(grid.vertices.rows()));
  std::vector<char> fixed(x.size(), 0);
  std::mt19937 random(3);
  std::uniform_real_distribution<double> jitter(-1.5, 1.5);
  for (size_t v = 0; v < x.size(); ++v) {
    x[v] = grid.vertices.row(static_cast<Eigen::Index>(v)).transpose();
    const int i = static_cast<int>(v) % 7, j = static_cast<int>(v) / 7;
    fixed[v] = i == 0 || i == 6 || j == 0 || j == 5;
    if (!fixed[v]) x[v] += Eigen::Vector3d(jitter(random), jitter(random), 0);
  }
  ASSERT_LT(smallest_corner(x, quads), 0);  // folded to start with
  const std::vector<Eigen::Vector3d> start = x;
  ASSERT_TRUE(detail::untangle_in_plane(x, quads, fixed, Eigen::Vector3d::UnitZ()));
  EXPECT_GT(smallest_corner(x, quads), 0);
  for (size_t v = 0; v < x.size(); ++v) {
    EXPECT_EQ(x[v].z(), 0);
    if (fixed[v]) {
      EXPECT_EQ(x[v], start[v]);  // the boundary stays, bitwise
    }
  }
}

TEST(PlanarUntangling, UnfoldsAnLShapeWithItsReflexCornerInverted) {
  // A 4 by 4 grid with its top-right 2 by 2 block removed: the reflex corner at (2, 2) is an
  // interior-side vertex; pulling the free vertices next to it across folds the quads there.
  QuadMesh grid = test::quad_grid(4, 4);
  std::vector<std::array<int, 4>> quads;
  for (const auto& q : quads_of(grid)) {
    const Eigen::Vector3d centre = 0.25 * (grid.vertices.row(q[0]) + grid.vertices.row(q[1]) +
                                           grid.vertices.row(q[2]) + grid.vertices.row(q[3]))
                                              .transpose();
    if (!(centre.x() > 2 && centre.y() > 2)) quads.push_back(q);
  }
  std::vector<Eigen::Vector3d> x(static_cast<size_t>(grid.vertices.rows()));
  std::vector<char> fixed(x.size(), 1);
  for (size_t v = 0; v < x.size(); ++v)
    x[v] = grid.vertices.row(static_cast<Eigen::Index>(v)).transpose();
  // Vertex j·5 + i is at (i, j); the interior ones are (1,1), (2,1), (3,1), (1,2), (1,3).
  for (const int v : {6, 7, 8, 11, 16}) fixed[static_cast<size_t>(v)] = 0;
  x[7] = {2.6, 2.7, 0};  // across the reflex corner (2, 2), into the missing block
  x[8] = {3.2, 2.4, 0};
  x[11] = {2.5, 3.5, 0};
  ASSERT_LT(smallest_corner(x, quads), 0);
  ASSERT_TRUE(detail::untangle_in_plane(x, quads, fixed, Eigen::Vector3d::UnitZ()));
  EXPECT_GT(smallest_corner(x, quads), 0);
}

// The relaxation's probe (detail::RelaxProbe): a grid whose right side is pushed in past the
// middle as a narrow tongue folds quads in the unguarded sweeps. A probe that stops there
// leaves those sweeps' positions and counts the folded quads; one that does not stop, and a
// grid that does not fold, relax to the same bits as without a probe.
TEST(RelaxationProbe, StopsAFoldingLayoutAfterTheUnguardedSweepsAndChangesNothingElse) {
  const auto relaxed = [](double push, detail::RelaxProbe* probe) {
    const QuadMesh grid = test::quad_grid(10, 10);
    std::vector<Eigen::Vector3d> x(static_cast<size_t>(grid.vertices.rows()));
    std::vector<char> fixed(x.size(), 0);
    for (size_t v = 0; v < x.size(); ++v) {
      x[v] = grid.vertices.row(static_cast<Eigen::Index>(v)).transpose();
      const int i = static_cast<int>(v) % 11, j = static_cast<int>(v) / 11;
      fixed[v] = i == 0 || i == 10 || j == 0 || j == 10;
      if (i == 10 && j > 1 && j < 9) x[v].x() -= push;  // the right side's tongue
    }
    detail::relax_interior(x, quads_of(grid), fixed, 10, {}, detail::ReferenceNormals::kStart,
                           probe);
    return x;
  };
  for (const double push : {9.5, 0.5}) {
    SCOPED_TRACE(push);
    const std::vector<Eigen::Vector3d> plain = relaxed(push, nullptr);
    detail::RelaxProbe watching;  // never stops
    EXPECT_EQ(relaxed(push, &watching), plain);
    EXPECT_FALSE(watching.stopped);
    detail::RelaxProbe stopping{1};
    const std::vector<Eigen::Vector3d> probed = relaxed(push, &stopping);
    EXPECT_EQ(stopping.folds, watching.folds);
    if (push > 1) {  // the tongue reaches past the middle: folds, stopped
      EXPECT_TRUE(stopping.stopped);
      EXPECT_GT(stopping.folds, 0);
      EXPECT_LT(smallest_corner(probed, quads_of(test::quad_grid(10, 10))), 0);
      EXPECT_NE(probed, plain);  // the guarded sweeps and untangling did not run
    } else {
      EXPECT_EQ(stopping.folds, 0);
      EXPECT_FALSE(stopping.stopped);
      EXPECT_EQ(probed, plain);
    }
  }
}

}  // namespace
}  // namespace sd::meshing
