// The preconditioner's membrane pattern: A without the flat bends' c·I couplings, their c on the
// diagonal.
#include "sim/membrane_pattern.hpp"

#include <gtest/gtest.h>

#include <random>

#include "sim/cloth_model.hpp"
#include "sim/fabric.hpp"
#include "sim/forces.hpp"
#include "sim/sheet.hpp"
#include "test_scenes.hpp"

namespace sd::sim {
namespace {

// The Jacobian system of a 12x12 cotton sheet (flat-rest quadratic bending) at a perturbed
// state, as one implicit step assembles it.
SparseMatrixR sheet_matrix(const ClothModel& model, const Eigen::MatrixX3d& rest) {
  std::mt19937 rng(5);
  const Eigen::VectorXd x = testing::random_configuration(rest, rng, 0.002);
  const Eigen::VectorXd v = Eigen::VectorXd::Random(x.size());
  SparseMatrixR a = model.pattern.zero_matrix;
  for (int i = 0; i < model.vertex_count; ++i)
    for (int k = 0; k < 3; ++k)
      a.valuePtr()[block_value_index(a, i, model.pattern.diagonal_offsets[i], k, k)] =
          model.mass[i];
  JacobianTarget target;
  target.matrix = &a;
  target.dfdx_scale = -1.0 / (24.0 * 24.0);
  target.dfdv_scale = -1.0 / 24.0;
  Eigen::VectorXd force;
  evaluate_forces(model, ForceSettings{}, x, v, force, nullptr, &target);
  return a;
}

TEST(MembranePattern, DropsTheBendsCouplingsAndKeepsTheRowSums) {
  SheetSpec spec;
  spec.size = {0.5, 0.5};
  spec.columns = 12;
  spec.rows = 12;
  const SheetScene scene = build_sheet(spec);
  const ClothModel model = build_cloth_model(scene.input, fabric_preset("cotton"));
  const SparseMatrixR a = sheet_matrix(model, scene.input.rest_positions);
  MembranePattern membrane;
  ASSERT_TRUE(membrane.build(a, model.pattern.diagonal_offsets));
  const SparseMatrixR& m = membrane.matrix();
  const Eigen::MatrixXd full = Eigen::MatrixXd(a);
  const Eigen::MatrixXd reduced = Eigen::MatrixXd(m);
  // The second ring's couplings are most of the off-diagonal blocks (a 13x13-vertex grid's
  // interior vertex has 6 first-ring neighbours and up to 12 more through the bends).
  const int off_diagonal = static_cast<int>(a.nonZeros() / 9) - model.vertex_count;
  EXPECT_GT(membrane.dropped_blocks(), off_diagonal / 2);
  EXPECT_EQ(m.nonZeros() / 9, a.nonZeros() / 9 - membrane.dropped_blocks());
  // Every kept off-diagonal entry is A's; the pattern keeps the diagonal blocks where the
  // offsets say.
  for (int i = 0; i < model.vertex_count; ++i) {
    EXPECT_EQ(m.innerIndexPtr()[m.outerIndexPtr()[3 * i] + membrane.diagonal_offsets()[i]], 3 * i);
    for (int j = 0; j < model.vertex_count; ++j) {
      if (i == j) continue;
      const Eigen::Matrix3d kept = reduced.block<3, 3>(3 * i, 3 * j);
      if (!kept.isZero(0.0)) {
        EXPECT_TRUE(kept == (full.block<3, 3>(3 * i, 3 * j))) << i << ", " << j;
      }
    }
  }
  // As symmetric as A (only diagonal entries change), and the same product as A on a uniform
  // translation (the row sums), to rounding (entries of order the mass, 1e-3 kg, sums of about
  // 20 of them).
  EXPECT_LE((reduced - reduced.transpose()).cwiseAbs().maxCoeff(),
            (full - full.transpose()).cwiseAbs().maxCoeff());
  for (int axis = 0; axis < 3; ++axis) {
    Eigen::VectorXd t = Eigen::VectorXd::Zero(a.rows());
    for (int i = 0; i < model.vertex_count; ++i) t[3 * i + axis] = 1.0;
    EXPECT_LE((reduced * t - full * t).cwiseAbs().maxCoeff(), 1e-12 * full.cwiseAbs().maxCoeff());
  }
  // A matrix not made of vertex blocks is refused.
  SparseMatrixR odd(5, 5);
  odd.setIdentity();
  EXPECT_FALSE(membrane.build(odd, std::vector<int>(1, 0)));
}

}  // namespace
}  // namespace sd::sim
