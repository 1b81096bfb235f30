#include "garment/piece_grain.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace sd::garment {
namespace {

// A flat rectangle piece `length` × `width` (m), its length turned `degrees` counter-clockwise
// from the grain line (+y), split into `cells` squares-ish along its length (two triangles each).
FlatPanel strip(double length, double width, double degrees, int cells = 20) {
  FlatPanel piece;
  piece.id = "strap";
  const double a = degrees * std::numbers::pi / 180.0;
  const Eigen::Vector2d along(-std::sin(a), std::cos(a)), across(std::cos(a), std::sin(a));
  piece.uv.resize(2 * (cells + 1), 2);
  for (int k = 0; k <= cells; ++k)
    for (int s = 0; s < 2; ++s)
      piece.uv.row(2 * k + s) = (length * k / cells * along + width * s * across).transpose();
  piece.triangles.resize(2 * cells, 3);
  for (int k = 0; k < cells; ++k) {
    piece.triangles.row(2 * k) << 2 * k, 2 * k + 2, 2 * k + 1;
    piece.triangles.row(2 * k + 1) << 2 * k + 1, 2 * k + 2, 2 * k + 3;
  }
  return piece;
}

GarmentPanel strap_panel(double turn = 0.0) {
  GarmentPanel panel;
  panel.id = "strap";
  panel.grain = "vertical";
  panel.grain_turn_deg = turn;
  return panel;
}

TEST(PieceGrain, TheShapeOfAStripIsItsLengthWidthAndAngle) {
  for (const double degrees : {0.0, 30.0, -60.0, 89.0}) {
    const PieceShape shape = piece_shape(strip(0.3, 0.03, degrees));
    // Exact for a rectangle: its principal axes are its sides (to rounding).
    EXPECT_NEAR(shape.length, 0.3, 1e-9) << degrees;
    EXPECT_NEAR(shape.width, 0.03, 1e-9) << degrees;
    EXPECT_NEAR(shape.angle_deg, degrees, 1e-6) << degrees;
  }
  // An axis has no direction: 120° is −60°.
  EXPECT_NEAR(piece_shape(strip(0.3, 0.03, 120.0)).angle_deg, -60.0, 1e-6);
}

TEST(PieceGrain, AStrapAcrossTheGrainIsWarnedWithTheTurnThatLaysItAlong) {
  const std::string said = cross_grain_warning(strip(0.3, 0.03, 80.0), strap_panel());
  EXPECT_NE(said.find("panel 'strap': a long narrow piece (300 × 30 mm"), std::string::npos)
      << said;
  EXPECT_NE(said.find("80° off the grain line"), std::string::npos) << said;
  EXPECT_NE(said.find("\"grain\": 80 (or {\"along\": \"vertical\", \"turn\": 80})"),
            std::string::npos)
      << said;
  EXPECT_NE(cross_grain_warning(strip(0.3, 0.03, -45.0), strap_panel()).find("\"grain\": -45"),
            std::string::npos);
}

TEST(PieceGrain, AlongTheGrainShortOrTurnedOnPurposeIsNotWarned) {
  EXPECT_EQ(cross_grain_warning(strip(0.3, 0.03, 0.0), strap_panel()), "");
  EXPECT_EQ(cross_grain_warning(strip(0.3, 0.03, 25.0), strap_panel()), "");  // within 30°
  // 3.5 times as long as wide: a sleeve or a trouser leg can be, not a strap.
  EXPECT_EQ(cross_grain_warning(strip(0.35, 0.1, 90.0), strap_panel()), "");
  // A panel whose grain is turned (a bias cut) is the designer's own choice.
  EXPECT_EQ(cross_grain_warning(strip(0.3, 0.03, 90.0), strap_panel(45.0)), "");
}

}  // namespace
}  // namespace sd::garment
