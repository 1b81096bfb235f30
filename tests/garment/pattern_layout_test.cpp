// Tests of garment/pattern_layout: the cutting line with a seam allowance per outline edge (a
// seam's or a hem's own), against exact figures on a square piece, and its refusal when the
// allowances of a tight concave outline would cross.
#include "garment/pattern_layout.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace sd::garment {
namespace {

// One piece: a closed outline of `points` (m, counter-clockwise), each side sampled with `per`
// edges so that runs of edges share an allowance as on a real piece.
FlatPattern one_piece(const std::vector<Eigen::Vector2d>& corners, int per) {
  FlatPanel panel;
  panel.id = "piece";
  panel.panel = 0;
  std::vector<Eigen::Vector2d> points;
  for (size_t c = 0; c < corners.size(); ++c)
    for (int k = 0; k < per; ++k)
      points.push_back(corners[c] + (corners[(c + 1) % corners.size()] - corners[c]) * k / per);
  panel.uv.resize(static_cast<Eigen::Index>(points.size()), 2);
  for (size_t i = 0; i < points.size(); ++i) {
    panel.uv.row(static_cast<Eigen::Index>(i)) = points[i].transpose();
    panel.boundary.push_back(static_cast<int>(i));
    panel.vertices.push_back(static_cast<int>(i));
  }
  FlatPattern pattern;
  pattern.panels.push_back(panel);
  return pattern;
}

double signed_area(const Eigen::MatrixX2d& p) {
  double a = 0;
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    const Eigen::Index j = (i + 1) % p.rows();
    a += p(i, 0) * p(j, 1) - p(j, 0) * p(i, 1);
  }
  return 0.5 * a;
}

// A 0.2 m square, 1 cm allowance on three sides and a 3 cm hem along the bottom: the cutting
// line is the 0.22 × 0.24 m rectangle (the hem's line meets the sides' at square corners),
// exactly; notches at the hem's ends are snipped as deep as the narrower allowance allows.
TEST(PatternLayout, AllowancePerSeamCutsTheExactRectangle) {
  const int per = 8;  // edges per side
  FlatPattern pattern = one_piece({{0, 0}, {0.2, 0}, {0.2, 0.2}, {0, 0.2}}, per);
  pattern.panels[0].notches = {0, per};  // the hem's two ends
  PatternLayoutOptions options;
  options.seam_allowance = 0.01;
  options.edge_allowance = {std::vector<double>(4 * per, -1.0)};
  for (int k = 0; k < per; ++k) options.edge_allowance[0][static_cast<size_t>(k)] = 0.03;
  const PatternLayout layout = lay_out_pattern(pattern, options);
  const PatternPiece& piece = layout.pieces[0];
  EXPECT_NEAR(piece.size.x(), 0.22, 1e-12);
  EXPECT_NEAR(piece.size.y(), 0.24, 1e-12);
  EXPECT_NEAR(piece.cut_area, 0.22 * 0.24, 1e-12);
  EXPECT_NEAR(piece.sewn_area, 0.04, 1e-12);
  EXPECT_EQ(piece.cutting.rows(), 4);
  // The sewing line sits 1 cm from the left and 3 cm from the bottom of the cutting line.
  EXPECT_NEAR(piece.sewing.col(0).minCoeff(), 0.01, 1e-12);
  EXPECT_NEAR(piece.sewing.col(1).minCoeff(), 0.03, 1e-12);
  ASSERT_EQ(piece.allowances.size(), 2u);
  EXPECT_EQ(piece.allowances[0].first, 0);
  EXPECT_EQ(piece.allowances[0].last, per - 1);
  EXPECT_DOUBLE_EQ(piece.allowances[0].allowance, 0.03);
  EXPECT_EQ(piece.allowances[1].first, per);
  EXPECT_EQ(piece.allowances[1].last, 4 * per - 1);
  EXPECT_DOUBLE_EQ(piece.allowances[1].allowance, 0.01);
  ASSERT_EQ(piece.notches.size(), 2u);
  for (const PatternNotch& notch : piece.notches) EXPECT_DOUBLE_EQ(notch.allowance, 0.01);
}

// Without edge allowances the piece keeps the straight skeleton's offset at its own allowance,
// and one edge allowance equal to it everywhere changes nothing.
TEST(PatternLayout, UniformEdgeAllowanceIsTheStraightSkeletonOffset) {
  const FlatPattern pattern = one_piece({{0, 0}, {0.3, 0}, {0.15, 0.2}}, 5);
  PatternLayoutOptions options;
  options.seam_allowance = 0.015;
  const PatternLayout plain = lay_out_pattern(pattern, options);
  options.edge_allowance = {std::vector<double>(15, 0.015)};
  const PatternLayout same = lay_out_pattern(pattern, options);
  EXPECT_EQ(plain.pieces[0].cutting, same.pieces[0].cutting);
  ASSERT_EQ(same.pieces[0].allowances.size(), 1u);
  EXPECT_EQ(same.pieces[0].allowances[0].first, 0);
  EXPECT_EQ(same.pieces[0].allowances[0].last, 14);
}

// A triangle with one side's allowance raised: every cutting-line corner lies on the lines of
// its two sides moved out by their own allowances (distance to each side's line = allowance).
TEST(PatternLayout, MitredCornersLieOnBothOffsetLines) {
  const std::vector<Eigen::Vector2d> corners = {{0, 0}, {0.3, 0}, {0.1, 0.25}};
  const int per = 6;
  const FlatPattern pattern = one_piece(corners, per);
  PatternLayoutOptions options;
  options.seam_allowance = 0.01;
  options.edge_allowance = {std::vector<double>(3 * per, -1.0)};
  for (int k = per; k < 2 * per; ++k) options.edge_allowance[0][static_cast<size_t>(k)] = 0.025;
  const PatternPiece piece = lay_out_pattern(pattern, options).pieces[0];
  ASSERT_EQ(piece.cutting.rows(), 3);
  const double allowance[3] = {0.01, 0.025, 0.01};
  // Sides in the piece's frame: the sewing line's corners are rows 0, per and 2·per.
  for (Eigen::Index c = 0; c < 3; ++c) {
    const Eigen::Vector2d p = piece.cutting.row(c);
    int on_lines = 0;
    for (int s = 0; s < 3; ++s) {
      const Eigen::Vector2d a = piece.sewing.row(s * per);
      const Eigen::Vector2d b = piece.sewing.row(((s + 1) % 3) * per);
      const Eigen::Vector2d t = (b - a).normalized();
      const double outside = (p - a).x() * t.y() - (p - a).y() * t.x();  // right of a→b: out
      if (std::abs(outside - allowance[s]) < 1e-12) ++on_lines;
    }
    EXPECT_EQ(on_lines, 2) << "corner " << c;
  }
  EXPECT_GT(signed_area(piece.cutting), signed_area(piece.sewing));
}

// A piece with a slot 1 cm wide cut into it, a 3 cm allowance along the slot's end and 1 cm
// elsewhere: the mitred lines of the slot's two walls, 1 cm out each, cross inside it. Refused
// with the panel named (a uniform allowance goes through the straight skeleton, which merges
// them instead).
TEST(PatternLayout, CrossingAllowancesAreRefused) {
  const FlatPattern pattern = one_piece({{0, 0},
                                         {0.2, 0},
                                         {0.2, 0.2},
                                         {0.105, 0.2},
                                         {0.105, 0.05},
                                         {0.095, 0.05},
                                         {0.095, 0.2},
                                         {0, 0.2}},
                                        2);
  PatternLayoutOptions options;
  options.edge_allowance = {std::vector<double>(16, -1.0)};
  options.edge_allowance[0][8] = options.edge_allowance[0][9] = 0.03;  // the notch's right side
  try {
    lay_out_pattern(pattern, options);
    FAIL() << "crossing allowances were accepted";
  } catch (const PatternError& e) {
    EXPECT_EQ(e.panel(), "piece");
    EXPECT_NE(std::string(e.what()).find("cross"), std::string::npos) << e.what();
  }
}

// The same slot in a piece cut on the fold along its left side, 1 cm allowance everywhere else
// (the file's uniform allowance; none along the fold). Before, the fold's 0 made two allowances
// and the mitred path refused it as above (trial 43, P1: the jumpsuit's folded back leg at the
// default 1 cm). Now the piece opened out across its fold is offset by the straight skeleton,
// which merges the slot's offsets, and cut back at the fold: exactly the rectangle 0 .. 0.21 by
// -0.01 .. 0.21 m, the fold its left side, half the opened piece's own cutting line.
TEST(PatternLayout, UniformAllowanceOnAFoldPieceMergesLikeTheSkeleton) {
  const std::vector<Eigen::Vector2d> corners = {{0, 0},       {0.2, 0},      {0.2, 0.2},
                                                {0.105, 0.2}, {0.105, 0.05}, {0.095, 0.05},
                                                {0.095, 0.2}, {0, 0.2}};
  const int per = 2;
  const FlatPattern pattern = one_piece(corners, per);
  PatternLayoutOptions options;
  std::vector<bool> fold(8 * per, false);
  for (int k = 7 * per; k < 8 * per; ++k) fold[static_cast<size_t>(k)] = true;  // x = 0
  options.fold_edge = {fold};
  const PatternPiece piece = lay_out_pattern(pattern, options).pieces[0];
  EXPECT_TRUE(piece.on_fold);
  EXPECT_NEAR(piece.size.x(), 0.21, 1e-9);
  EXPECT_NEAR(piece.size.y(), 0.22, 1e-9);
  EXPECT_NEAR(piece.cut_area, 0.21 * 0.22, 1e-9);
  // The fold is the cutting line's left side, the allowance 1 cm beyond its ends.
  EXPECT_NEAR(piece.fold_start.x(), 0.0, 1e-9);
  EXPECT_NEAR(piece.fold_end.x(), 0.0, 1e-9);
  EXPECT_NEAR(piece.fold_end.y() - piece.cutting.col(1).minCoeff(), 0.01, 1e-9);
  // The piece opened out (its mirror image across x = 0 joined on), cut with one allowance.
  std::vector<Eigen::Vector2d> opened;
  for (const Eigen::Vector2d& c : corners) opened.push_back(c + Eigen::Vector2d(0.2, 0));
  for (size_t c = corners.size() - 1; c-- > 1;)
    opened.push_back(Eigen::Vector2d(0.2 - corners[c].x(), corners[c].y()));
  const PatternPiece whole = lay_out_pattern(one_piece(opened, 1)).pieces[0];
  EXPECT_NEAR(piece.cut_area, 0.5 * whole.cut_area, 1e-9);
}

// A trapezoid "front" and its copy "front.mirror" (x → 0.3 − x, reversed to stay
// counter-clockwise), each with notches at its hem's ends: one piece to a cutter, drawn once
// ("cut 2", the copy drawn as it) while the fabric to cut both from one layer is still nested
// with both; a copy with one corner 2 mm off (4 × the 0.5 mm tolerance) is drawn on its own, one
// 0.2 mm off (under it) is still the pair; `pair_mirrors` off draws both.
TEST(PatternLayout, ExactMirrorPairIsDrawnOnceAsCutTwo) {
  const std::vector<Eigen::Vector2d> front = {{0, 0}, {0.3, 0}, {0.22, 0.4}, {0.05, 0.4}};
  const auto mirrored = [&](double moved) {
    std::vector<Eigen::Vector2d> copy;
    for (auto it = front.rbegin(); it != front.rend(); ++it)
      copy.push_back({0.3 - it->x(), it->y()});
    std::rotate(copy.begin(), copy.begin() + 2, copy.end());  // start at the hem's left end
    copy[2].x() += moved;                                     // a top corner
    FlatPattern pattern = one_piece(front, 6);
    FlatPanel panel = one_piece(copy, 6).panels[0];
    panel.id = "front.mirror";
    panel.panel = 1;
    pattern.panels[0].id = "front";
    pattern.panels[0].notches = {0, 6};
    panel.notches = {0, 6};
    pattern.panels.push_back(panel);
    return pattern;
  };
  const PatternLayout pair = lay_out_pattern(mirrored(0.0));
  ASSERT_EQ(pair.pieces.size(), 2u);
  EXPECT_EQ(pair.pairs, 1);
  EXPECT_EQ(pair.pieces[0].quantity, 2);
  EXPECT_EQ(pair.pieces[0].drawn_as, -1);
  EXPECT_EQ(pair.pieces[1].quantity, 0);
  EXPECT_EQ(pair.pieces[1].drawn_as, 0);
  EXPECT_EQ(pair.pieces[1].placement, pair.pieces[0].placement);
  // The sheet holds one piece; cutting both from one layer takes the unpaired layout's fabric.
  const double gap = PatternLayoutOptions{}.gap;
  EXPECT_NEAR(pair.sheet_length, pair.pieces[0].placement.y() + pair.pieces[0].size.y() + gap,
              1e-12);
  EXPECT_NEAR(pair.sheet_efficiency,
              pair.pieces[0].cut_area / (pair.sheet_length * pair.fabric_width), 1e-12);
  PatternLayoutOptions apart;
  apart.pair_mirrors = false;
  const PatternLayout both = lay_out_pattern(mirrored(0.0), apart);
  EXPECT_EQ(both.pairs, 0);
  EXPECT_EQ(both.pieces[0].quantity, 1);
  EXPECT_EQ(both.pieces[1].quantity, 1);
  EXPECT_DOUBLE_EQ(pair.length_used, both.length_used);
  EXPECT_DOUBLE_EQ(pair.efficiency, both.efficiency);
  EXPECT_DOUBLE_EQ(both.sheet_length, both.length_used);

  EXPECT_EQ(lay_out_pattern(mirrored(0.0002)).pairs, 1);
  const PatternLayout off = lay_out_pattern(mirrored(0.002));
  EXPECT_EQ(off.pairs, 0);
  EXPECT_EQ(off.pieces[0].quantity, 1);
  EXPECT_EQ(off.pieces[1].quantity, 1);
}

// Two pieces cut on the fold along their left side, each a 0.5 × 0.3 m half (1 cm allowance
// except along the fold: 0.51 × 0.32 m cut). Cut, each is opened out to 1.02 m, so on 1.5 m of
// fabric the two go one above the other: 3 gaps + 2 × 0.32 m = 0.67 m of fabric, with both
// halves of each counted in the efficiency. The sheet draws the halves side by side (0.34 m).
// Counting the halves only, as before, said 0.34 m for both.
TEST(PatternLayout, FoldPieceTakesBothHalvesOfTheFabric) {
  const int per = 5;
  FlatPattern pattern = one_piece({{0, 0}, {0.5, 0}, {0.5, 0.3}, {0, 0.3}}, per);
  pattern.panels.push_back(pattern.panels[0]);
  pattern.panels[1].id = "other";
  pattern.panels[1].panel = 1;
  PatternLayoutOptions options;
  std::vector<bool> fold(4 * per, false);
  for (int k = 3 * per; k < 4 * per; ++k) fold[static_cast<size_t>(k)] = true;  // x = 0
  options.fold_edge = {fold, fold};
  const PatternLayout layout = lay_out_pattern(pattern, options);
  const double gap = options.gap;
  for (const PatternPiece& piece : layout.pieces) {
    EXPECT_TRUE(piece.on_fold);
    EXPECT_NEAR(piece.size.x(), 0.51, 1e-9);
    EXPECT_NEAR(piece.size.y(), 0.32, 1e-9);
    EXPECT_NEAR(piece.fold_start.x(), 0.0, 1e-12);  // the fold is the cutting line's left side
    EXPECT_NEAR(piece.fold_end.x(), 0.0, 1e-12);
  }
  EXPECT_NEAR(layout.length_used, 3 * gap + 2 * 0.32, 1e-9);
  EXPECT_NEAR(layout.efficiency,
              2 * 2 * layout.pieces[0].cut_area / (layout.length_used * layout.fabric_width),
              1e-12);
  EXPECT_NEAR(layout.sheet_length, 2 * gap + 0.32, 1e-9);
  EXPECT_NEAR(layout.sheet_efficiency,
              2 * layout.pieces[0].cut_area / (layout.sheet_length * layout.fabric_width), 1e-12);
  // The same pieces sewn along x = 0 instead (1 cm allowance there too): 0.52 m, side by side.
  const PatternLayout seamed = lay_out_pattern(pattern);
  EXPECT_NEAR(seamed.length_used, 2 * gap + 0.32, 1e-9);
}

// A gathered piece is spread about the apex of its sides along the grain (pattern_layout.cpp,
// eased_outline), not scaled across as a whole: a flared half tier (an annular sector, radii 0.6
// and 0.9 m about the apex at (0, 1), from the centre line straight down to 20° off it) cut with
// "weft" 1.5 keeps its side seam and centre line at their 0.3 m, with the centre line on the grain
// (x constant), and its top and hem arcs come out 1.5 times as long. Scaling x by 1.5 would have
// cut the side seam sqrt(cos² 20° + 1.5² sin² 20°) = 7.1 % long. Bounds: the side's and centre's
// points stay on their rays exactly (1e-12 m); a chord of an arc spread by 1.5 is 2r sin(0.75 δ)
// against 2r sin(δ / 2), 1.5 times as long to (1.25 / 24) δ² = 6e-5 at δ = 2°, bound 1e-4. Two
// sides sewn to pieces cut with a different ease (gathered into them) do not set the apex, and
// parallel sides give the plain scale.
TEST(PatternLayout, GatheredFlaredPieceIsSpreadAboutItsApex) {
  const int steps = 10;
  const double pi = 3.14159265358979323846, spread = 20 * pi / 180;
  const Eigen::Vector2d apex(0, 1);
  const auto at = [&](double r, double angle) {
    return Eigen::Vector2d(apex + r * Eigen::Vector2d(std::sin(angle), -std::cos(angle)));
  };
  // CCW: the hem from the centre out, the side up, the top back in, the centre line down.
  std::vector<Eigen::Vector2d> points;
  for (int k = 0; k < steps; ++k) points.push_back(at(0.9, spread * k / steps));
  for (int k = 0; k < steps; ++k) points.push_back(at(0.9 - 0.3 * k / steps, spread));
  for (int k = 0; k < steps; ++k) points.push_back(at(0.6, spread * (steps - k) / steps));
  for (int k = 0; k < steps; ++k) points.push_back(at(0.6 + 0.3 * k / steps, 0));
  FlatPattern pattern = one_piece(points, 1);
  pattern.panels.push_back(pattern.panels[0]);
  pattern.panels[1].id = "back";
  pattern.panels[1].panel = 1;
  const auto run = [](int first, int count) {
    std::vector<int> v;
    for (int k = 0; k <= count; ++k) v.push_back((first + k) % (4 * steps));
    return v;
  };
  PatternSeam side, centre;
  side.panel_a = 0, side.panel_b = 1, side.vertices_a = side.vertices_b = run(steps, steps);
  centre.panel_a = 0, centre.panel_b = 1, centre.vertices_a = run(3 * steps, steps);
  centre.vertices_b = centre.vertices_a;
  pattern.seams = {side, centre};
  PatternLayoutOptions options;
  options.panel_ease = {PanelEase{1.0, 1.5}, PanelEase{1.0, 1.5}};
  const PatternLayout layout = lay_out_pattern(pattern, options);
  const Eigen::MatrixX2d& cut = layout.pieces[0].sewing;
  const auto length = [&](const Eigen::MatrixX2d& p, int first, int count) {
    double l = 0;
    for (int k = 0; k < count; ++k)
      l += (p.row((first + k + 1) % p.rows()) - p.row((first + k) % p.rows())).norm();
    return l;
  };
  Eigen::MatrixX2d flat(4 * steps, 2);
  for (int k = 0; k < 4 * steps; ++k) flat.row(k) = points[static_cast<size_t>(k)].transpose();
  EXPECT_NEAR(length(cut, steps, steps), 0.3, 1e-12) << "the side seam";
  EXPECT_NEAR(length(cut, 3 * steps, steps), 0.3, 1e-12) << "the centre line";
  for (int k = 3 * steps; k < 4 * steps; ++k) EXPECT_NEAR(cut(k, 0), cut(0, 0), 1e-12);
  EXPECT_NEAR(length(cut, 0, steps) / length(flat, 0, steps), 1.5, 1.5e-4) << "the hem";
  EXPECT_NEAR(length(cut, 2 * steps, steps) / length(flat, 2 * steps, steps), 1.5, 1.5e-4)
      << "the top";
  // The same sides sewn to pieces cut with another ease: scaled across as a whole.
  options.panel_ease[1] = PanelEase{};
  const Eigen::MatrixX2d scaled = lay_out_pattern(pattern, options).pieces[0].sewing;
  const double affine =
      std::sqrt(std::pow(std::cos(spread), 2) + 2.25 * std::pow(std::sin(spread), 2));
  EXPECT_NEAR(length(scaled, steps, steps), 0.3 * affine, 1e-12);
  EXPECT_GT(affine, 1.07);
  // Parallel sides (a rectangle): the plain scale, 1.5 times as wide, as tall as drawn.
  FlatPattern rectangle = one_piece({{0, 0}, {0.4, 0}, {0.4, 0.3}, {0, 0.3}}, 5);
  rectangle.panels.push_back(rectangle.panels[0]);
  rectangle.panels[1].panel = 1;
  PatternSeam left, right;
  left.panel_a = right.panel_a = 0, left.panel_b = right.panel_b = 1;
  left.vertices_a = left.vertices_b = {15, 16, 17, 18, 19, 0};
  right.vertices_a = right.vertices_b = {5, 6, 7, 8, 9, 10};
  rectangle.seams = {left, right};
  options.panel_ease = {PanelEase{1.0, 1.5}, PanelEase{1.0, 1.5}};
  const PatternPiece wide = lay_out_pattern(rectangle, options).pieces[0];
  const Eigen::Vector2d size = wide.sewing.colwise().maxCoeff() - wide.sewing.colwise().minCoeff();
  EXPECT_NEAR(size.x(), 0.6, 1e-12);
  EXPECT_NEAR(size.y(), 0.3, 1e-12);
}

}  // namespace
}  // namespace sd::garment
