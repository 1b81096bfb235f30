// The Cusick test's measures (sim/drape_coefficient) on shapes whose shadow is known: the flat
// disc (DC 1 up to its inscribed polygon, no nodes) and discs pulled in to an outline
// r(θ) = a + b·cos(nθ) (DC from the area π(a² + b²/2), n nodes).
#include "sim/drape_coefficient.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "sim/sheet.hpp"
#include "tests/sim/test_scenes.hpp"

namespace sd::sim {
namespace {

TEST(DrapeCoefficient, FlatDiscCoversItsSpecimen) {
  const SheetScene scene = testing::cusick_disc(30);
  const DrapeShadow shadow = measure_drape_shadow(scene.input.rest_positions, scene.input.triangles,
                                                  {0.0, 1.0, 0.0}, Eigen::Vector3d::UnitY());
  // The rim is a polygon of 76 sides: 0.11 % less area than the circle, DC 0.998.
  EXPECT_NEAR(shadow.drape_coefficient, 0.998, 0.002);
  EXPECT_EQ(shadow.nodes, 0);
  for (const double r : shadow.outline) EXPECT_NEAR(r, 0.15, 0.0025);
}

TEST(DrapeCoefficient, PetalOutlineGivesItsAreaAndNodes) {
  const SheetScene scene = testing::cusick_disc(40);
  const double r0 = 0.09, big = 0.15, pi = std::numbers::pi;
  for (const int n : {4, 6, 9}) {
    const double a = 0.12, b = 0.015;  // outline a + b cos(nθ) between 10.5 and 13.5 cm
    Eigen::MatrixX3d x = scene.input.rest_positions;
    for (Eigen::Index v = 0; v < x.rows(); ++v) {
      const double px = x(v, 0), pz = x(v, 2), rho = std::hypot(px, pz);
      if (rho <= r0) continue;
      const double theta = std::atan2(pz, px);
      const double outline = a + b * std::cos(n * theta);
      const double scaled = r0 + (rho - r0) * (outline - r0) / (big - r0);
      x(v, 0) = scaled * std::cos(theta);
      x(v, 2) = scaled * std::sin(theta);
      x(v, 1) = 1.0 - (rho - r0);  // hanging: the shadow ignores the height
    }
    const DrapeShadow shadow =
        measure_drape_shadow(x, scene.input.triangles, {0.0, 1.0, 0.0}, Eigen::Vector3d::UnitY());
    const double area = pi * (a * a + 0.5 * b * b);
    const double dc = (area - pi * r0 * r0) / (pi * big * big - pi * r0 * r0);
    EXPECT_NEAR(shadow.shadow_area, area, 0.005 * area) << n;
    EXPECT_NEAR(shadow.drape_coefficient, dc, 0.01) << n;
    EXPECT_EQ(shadow.nodes, n);
  }
}

TEST(DrapeCoefficient, NodesIgnoreRipplesAndCountFolds) {
  std::vector<double> outline(360);
  for (int i = 0; i < 360; ++i) {
    const double theta = i * std::numbers::pi / 180;
    // Seven folds of ±2 cm and a ripple of ±0.5 mm every 2°: seven nodes.
    outline[static_cast<size_t>(i)] = 0.12 + 0.02 * std::cos(7 * theta) + 5e-4 * (i % 2);
  }
  EXPECT_EQ(count_nodes(outline), 7);
  std::vector<double> flat(360, 0.15);
  EXPECT_EQ(count_nodes(flat), 0);
}

}  // namespace
}  // namespace sd::sim
