#include "meshing/arm_widening.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "meshing/patch_fill.hpp"
#include "tests/meshing/patch_fill_checks.hpp"

namespace sd::meshing {
namespace {

// A bodice with a strap, flat, edges of about 1 (docs/meshing.md, "Round 42: an arm that
// widens"): hem and side of a 10 × 8 body; the strap rises from the body's top between x = 0 and
// x = `base`, 20 high, to an end of 2 edges between x = 1 and x = 1 + `end`. Sides
// counter-clockwise: hem, side, the armhole and the strap's outer edge, the end, the strap's
// inner edge and the centre front.
struct Strap {
  std::vector<Eigen::MatrixX3d> polylines;
  std::vector<int> counts;
};

Strap strap_region(double end, double base) {
  const auto points = [](std::initializer_list<Eigen::RowVector3d> rows) {
    Eigen::MatrixX3d m(static_cast<Eigen::Index>(rows.size()), 3);
    Eigen::Index r = 0;
    for (const auto& row : rows) m.row(r++) = row;
    return m;
  };
  Strap s;
  s.polylines = {points({{0, 0, 0}, {10, 0, 0}}), points({{10, 0, 0}, {10, 8, 0}}),
                 points({{10, 8, 0}, {base, 8, 0}, {1 + end, 28, 0}}),
                 points({{1 + end, 28, 0}, {1, 28, 0}}),
                 points({{1, 28, 0}, {0, 8, 0}, {0, 0, 0}})};
  s.counts = {10, 8, static_cast<int>(std::lround(10 - base)) + 20, 2, 28};
  if ((s.counts[2] + 48) % 2 != 0) ++s.counts[2];
  return s;
}

std::vector<Eigen::MatrixX3d> resampled(const Strap& s) {
  std::vector<Eigen::MatrixX3d> sides;
  for (size_t i = 0; i < s.counts.size(); ++i)
    sides.push_back(resample_by_arc_length(s.polylines[i], s.counts[i]));
  for (size_t i = 0; i < sides.size(); ++i)
    sides[i].bottomRows<1>() = sides[(i + 1) % sides.size()].topRows<1>();
  return sides;
}

double mean_edge(const std::vector<Eigen::MatrixX3d>& sides) {
  double length = 0;
  Eigen::Index edges = 0;
  for (const auto& side : sides) {
    for (Eigen::Index r = 0; r + 1 < side.rows(); ++r)
      length += (side.row(r + 1) - side.row(r)).norm();
    edges += side.rows() - 1;
  }
  return length / static_cast<double>(edges);
}

TEST(ArmWidening, FindsTheCutWhereAWideningStrapJoinsTheBody) {
  const std::vector<Eigen::MatrixX3d> sides = resampled(strap_region(3, 6));
  const std::optional<ArmCut> cut = find_arm_cut(sides);
  ASSERT_TRUE(cut.has_value());
  EXPECT_EQ(cut->end_side, 3);
  EXPECT_NEAR(cut->end_width, 3.0, 1e-9);
  // The strap is 6 wide where it meets the body (y = 8), which is 4 edges of the armhole from
  // the side's start: the cut is at most a few edges up the strap from there, and needs more
  // quads across than the end's 2.
  const Eigen::RowVector3d from = sides[2].row(cut->from_vertex);
  const Eigen::RowVector3d to = sides[4].row(cut->to_vertex);
  EXPECT_LT(from.y(), 12.0);
  EXPECT_LT(to.y(), 12.0);
  EXPECT_GT(from.y(), 7.9);
  EXPECT_GT(to.y(), 7.9);
  EXPECT_GT(cut->cut_width, 1.5 * cut->end_width);
  EXPECT_GE(cut->across, 4);
  const ArmParts parts = split_at_arm_cut(sides, *cut);
  ASSERT_EQ(parts.arm.size(), 4U);
  ASSERT_EQ(parts.rest.size(), 5U);
  Eigen::Index arm_edges = 0, rest_edges = 0;
  for (const auto& side : parts.arm) arm_edges += side.rows() - 1;
  for (const auto& side : parts.rest) rest_edges += side.rows() - 1;
  EXPECT_EQ(arm_edges % 2, 0);
  EXPECT_EQ(rest_edges % 2, 0);
  EXPECT_EQ(arm_edges + rest_edges, 72 + 2 * cut->across);
}

TEST(ArmWidening, NoCutWithoutAnArmThatWidens) {
  // A strap as wide at the body as at its end (2 edges of 1 across), and a plain rectangle.
  EXPECT_FALSE(find_arm_cut(resampled(strap_region(2, 2))).has_value());
  const std::vector<int> counts{10, 8, 10, 8};
  const std::vector<Eigen::Vector3d> corners{{0, 0, 0}, {10, 0, 0}, {10, 8, 0}, {0, 8, 0}};
  EXPECT_FALSE(find_arm_cut(test::straight_sides(counts, [&](int i) {
                 return corners[static_cast<size_t>(i)];
               })).has_value());
}

// Issue 18, round 42: a strap widening 2× along its length (3 to 6, 2 edges across its end) kept
// two quads across all the way to the body, their mean side growing past twice the edge; cut
// across where it joins, every quad's mean side is within 0.5-2 × the boundary's mean edge.
TEST(ArmWidening, AStrapWideningTwofoldFillsWithQuadsOfTheEdgeLength) {
  const Strap strap = strap_region(3, 6);
  const std::vector<Eigen::MatrixX3d> sides = resampled(strap);
  const double edge = mean_edge(sides);
  FillGeometryOptions without;
  without.widen_arms = false;
  const FilledPatch before = fill_region(sides, without);
  EXPECT_GT(worst_quad_size(before.mesh, edge), 2.0);  // what the filler did before
  const FilledPatch patch = fill_region(sides);
  EXPECT_TRUE(test::well_formed(patch.topology, strap.counts));
  EXPECT_TRUE(validate(patch.mesh).ok());
  EXPECT_EQ(patch.topology.partition, "arm-cut");
  EXPECT_LE(worst_quad_size(patch.mesh, edge), 2.0);
  EXPECT_EQ(patch.quality.inverted_quads, 0);
  EXPECT_LT(patch.quality.max_aspect_ratio, 10.0);
  // The boundary is the sides' points, bit for bit.
  for (size_t i = 0; i < sides.size(); ++i)
    for (Eigen::Index r = 0; r < sides[i].rows(); ++r)
      EXPECT_EQ(patch.mesh.vertices.row(patch.topology.side_vertices[i][static_cast<size_t>(r)]),
                sides[i].row(r));
}

}  // namespace
}  // namespace sd::meshing
