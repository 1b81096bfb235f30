// Finite-difference checks of the element conditions: gradient against central differences of
// the value, Hessian against central differences of the gradient.
#include "sim/element_forces.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

namespace sd::sim {
namespace {

template <int N, typename F>
void check_derivatives(const Eigen::Matrix<double, N, 1>& x, F&& condition, double step,
                       double tolerance) {
  const Condition<N> c = condition(x, true);
  Eigen::Matrix<double, N, 1> fd_gradient;
  Eigen::Matrix<double, N, N> fd_hessian;
  for (int j = 0; j < N; ++j) {
    Eigen::Matrix<double, N, 1> plus = x, minus = x;
    plus[j] += step;
    minus[j] -= step;
    const Condition<N> cp = condition(plus, true);
    const Condition<N> cm = condition(minus, true);
    fd_gradient[j] = (cp.value - cm.value) / (2 * step);
    fd_hessian.col(j) = (cp.gradient - cm.gradient) / (2 * step);
  }
  EXPECT_LE((fd_gradient - c.gradient).norm(), tolerance * std::max(1.0, c.gradient.norm()));
  EXPECT_LE((fd_hessian - c.hessian).norm(), tolerance * std::max(1.0, c.hessian.norm()));
  EXPECT_LE((c.hessian - c.hessian.transpose()).norm(), 1e-12 * std::max(1.0, c.hessian.norm()));
}

TEST(ElementForces, TriangleConditionsMatchFiniteDifferences) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    TriangleElement t;
    // Rest coefficients of a random triangle (they sum to zero like real ones).
    const Eigen::Vector2d u1(0.05 + 0.05 * uniform(rng), 0.02 * uniform(rng));
    const Eigen::Vector2d u2(0.02 * uniform(rng), 0.05 + 0.05 * uniform(rng));
    Eigen::Matrix2d d;
    d << u1.x(), u2.x(), u1.y(), u2.y();
    const Eigen::Matrix2d inverse = d.inverse();
    t.du = Eigen::Vector3d(-inverse(0, 0) - inverse(1, 0), inverse(0, 0), inverse(1, 0));
    t.dv = Eigen::Vector3d(-inverse(0, 1) - inverse(1, 1), inverse(0, 1), inverse(1, 1));
    Eigen::Matrix<double, 9, 1> x;
    for (int k = 0; k < 9; ++k) x[k] = 0.08 * uniform(rng);
    for (int which = 0; which < 3; ++which) {
      check_derivatives<9>(
          x,
          [&](const Eigen::Matrix<double, 9, 1>& y, bool hessian) {
            const TriangleConditions c =
                triangle_conditions(t, y.segment<3>(0), y.segment<3>(3), y.segment<3>(6), hessian);
            return which == 0 ? c.warp : which == 1 ? c.weft : c.shear;
          },
          1e-7, 1e-5);
    }
  }
}

TEST(ElementForces, DihedralAngleMatchesFiniteDifferencesAndGeometry) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  int checked = 0;
  for (int trial = 0; trial < 300; ++trial) {
    Eigen::Matrix<double, 12, 1> x;
    x.segment<3>(0) = Eigen::Vector3d(0, 0, 0);
    x.segment<3>(3) = Eigen::Vector3d(1, 0, 0);
    // Opposite vertices on either side of the edge, at any fold angle.
    const double fold = 3.0 * uniform(rng);
    x.segment<3>(6) = Eigen::Vector3d(0.5 + 0.4 * uniform(rng), 0.8, 0.0);
    x.segment<3>(9) =
        Eigen::Vector3d(0.5 + 0.4 * uniform(rng), -0.8 * std::cos(fold), 0.8 * std::sin(fold));
    for (int k = 0; k < 12; ++k) x[k] += 0.1 * uniform(rng);
    const auto condition = [](const Eigen::Matrix<double, 12, 1>& y, bool hessian) {
      return dihedral_angle_condition(y.segment<3>(0), y.segment<3>(3), y.segment<3>(6),
                                      y.segment<3>(9), hessian);
    };
    if (std::abs(condition(x, false).value) > 3.0) continue;  // too close to the ±π seam
    check_derivatives<12>(x, condition, 1e-6, 1e-5);
    ++checked;
  }
  EXPECT_GT(checked, 250);
  // |θ| is the angle between the normals: a 90° fold.
  const double theta = dihedral_angle({0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, 0, 1});
  EXPECT_NEAR(std::abs(theta), M_PI / 2, 1e-12);
  EXPECT_NEAR(dihedral_angle({0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, -1, 0}), 0.0, 1e-12);
  // Rigid motions do not change it.
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const double rotated =
      dihedral_angle(rotation * Eigen::Vector3d(0, 0, 0), rotation * Eigen::Vector3d(1, 0, 0),
                     rotation * Eigen::Vector3d(0.5, 1, 0), rotation * Eigen::Vector3d(0.5, 0, 1));
  EXPECT_NEAR(rotated, theta, 1e-12);
}

TEST(ElementForces, DegenerateElementsGiveFiniteZeroDerivatives) {
  const Condition<12> c =
      dihedral_angle_condition({0, 0, 0}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, true);
  EXPECT_EQ(c.value, 0.0);
  EXPECT_TRUE(c.gradient.allFinite());
  EXPECT_TRUE(c.hessian.allFinite());
  TriangleElement t;
  t.du = Eigen::Vector3d(-1, 1, 0);
  t.dv = Eigen::Vector3d(-1, 0, 1);
  const TriangleConditions tc = triangle_conditions(t, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}, true);
  EXPECT_TRUE(tc.warp.gradient.allFinite() && tc.warp.hessian.allFinite());
}

}  // namespace
}  // namespace sd::sim
