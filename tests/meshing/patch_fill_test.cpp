#include "meshing/patch_fill.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <optional>
#include <random>

#include "meshing/region_partition.hpp"
#include "tests/meshing/patch_fill_checks.hpp"

namespace sd::meshing {
namespace {

using test::well_formed;

struct Reference {
  std::vector<int> sides;
  int distortion;
};

// Total valence deviation reported by Takayama, Panozzo & Sorkine-Hornung (2014); we must
// never be worse.
TEST(PatchFill, NeverWorseThanTakayama2014) {
  const std::vector<Reference> references = {
      {{3, 3, 4}, 1},    {{5, 5, 6}, 1},     {{5, 6, 3, 6, 4}, 1},    {{3, 3, 3, 3, 4}, 1},
      {{6, 4, 4, 2}, 2}, {{10, 4, 4, 2}, 2}, {{2, 2, 2, 2, 2, 2}, 2}, {{4, 3, 3, 4, 3, 3}, 2},
      {{2, 8, 4}, 3},    {{4, 4, 4, 4}, 0}};
  for (const auto& [sides, distortion] : references) {
    const PatchTopology topo = fill_region(sides);
    EXPECT_TRUE(well_formed(topo, sides));
    EXPECT_LE(topo.distortion, distortion) << test::describe(sides);
  }
}

TEST(PatchFill, NasriPartitionWhenEveryDistanceIsPositive) {
  // Random fair counts: whenever the closed-form d_i are all >= 1 the fill is the Nasri
  // partition with exactly one irregular vertex, the centre, of valence n.
  std::mt19937 rng(7);
  int checked = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int n = 3 + trial % 8;
    if (n % 4 == 0) continue;
    std::vector<int> counts(static_cast<size_t>(n));
    for (int& c : counts) c = std::uniform_int_distribution(3, 14)(rng);
    if (std::accumulate(counts.begin(), counts.end(), 0) % 2 != 0) ++counts[0];
    const std::vector<int> doubled = detail::nasri_distances_doubled(counts);
    if (std::any_of(doubled.begin(), doubled.end(), [](int d) { return d < 2 || d % 2 != 0; }))
      continue;
    const PatchTopology topo = fill_region(counts);
    ASSERT_TRUE(well_formed(topo, counts));
    EXPECT_EQ(topo.partition, "nasri") << test::describe(counts);
    EXPECT_EQ(topo.distortion, std::abs(n - 4)) << test::describe(counts);
    EXPECT_EQ(topo.irregular_vertices, 1) << test::describe(counts);
    ++checked;
  }
  EXPECT_GT(checked, 60);
}

TEST(PatchFill, ClosedFormDistancesMatchTheDesign) {
  // DESIGN.md: n = 3, d_i = ½ (l_{i+1} + l_{i+2} − l_i); the paper's pentagon (5,6,3,6,4).
  const std::vector<int> tri{2, 8, 4};
  EXPECT_EQ(detail::nasri_distances_doubled(tri), (std::vector<int>{10, -2, 6}));
  const std::vector<int> pentagon{5, 6, 3, 6, 4};
  const std::vector<int> doubled = detail::nasri_distances_doubled(pentagon);
  for (int i = 0; i < 5; ++i)  // l_i = d_{i-1} + d_{i+1}
    EXPECT_EQ(doubled[static_cast<size_t>((i + 4) % 5)] + doubled[static_cast<size_t>((i + 1) % 5)],
              2 * pentagon[static_cast<size_t>(i)]);
}

TEST(PatchFill, GridWhenOppositeSidesMatch) {
  const std::vector<int> counts{7, 3, 7, 3};
  const PatchTopology topo = fill_region(counts);
  EXPECT_TRUE(well_formed(topo, counts));
  EXPECT_EQ(topo.distortion, 0);
  EXPECT_EQ(topo.mesh.faces.rows(), 21);
}

TEST(PatchFill, SmallAndDegenerateCounts) {
  for (const std::vector<int>& counts :
       std::vector<std::vector<int>>{{1, 3},
                                     {2, 2},
                                     {3, 1},
                                     {1, 1, 2},
                                     {1, 1, 1, 1},
                                     {1, 1, 1, 1, 1, 1},
                                     {1, 1, 1, 1, 1, 1, 1, 1},
                                     {59, 1},
                                     {1, 1, 1, 1, 1, 1, 1, 1, 1, 1},
                                     {60, 1, 1, 1, 1},
                                     {1, 60, 1}}) {
    const PatchTopology topo = fill_region(counts);
    EXPECT_TRUE(well_formed(topo, counts));
    EXPECT_TRUE(test::within_bounds(topo, counts));
  }
  // Four boundary edges make one quad.
  EXPECT_EQ(fill_region(std::vector<int>{1, 3}).mesh.faces.rows(), 1);
}

TEST(PatchFill, BadCountsAreFillErrorsWithASentence) {
  auto message = [](const std::vector<int>& counts) {
    try {
      fill_region(counts);
    } catch (const FillError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message({3, 4, 4}).find("even"), std::string::npos);
  EXPECT_NE(message({3, 0, 3}).find("at least 1"), std::string::npos);
  EXPECT_NE(message({-2, 4, 4}).find("at least 1"), std::string::npos);
  EXPECT_NE(message({4}).find("at least 2 sides"), std::string::npos);
  EXPECT_NE(message({1, 1}).find("at least 4 boundary edges"), std::string::npos);
  EXPECT_THROW(fill_region(std::vector<int>{}), std::invalid_argument);
}

// Points of a closed curve split into sides with the given counts; curve(t), t in [0, 1).
template <class Curve>
std::vector<Eigen::MatrixX3d> sides_on(const Curve& curve, std::span<const int> counts) {
  const int total = std::accumulate(counts.begin(), counts.end(), 0);
  std::vector<Eigen::MatrixX3d> sides;
  int start = 0;
  for (const int count : counts) {
    Eigen::MatrixX3d side(count + 1, 3);
    for (int k = 0; k <= count; ++k)
      side.row(k) = curve(static_cast<double>((start + k) % total) / total).transpose();
    sides.push_back(side);
    start += count;
  }
  return sides;
}

Eigen::Vector3d ellipse(double t) {
  const double a = 2 * std::numbers::pi * t;
  return {1.6 * std::cos(a), std::sin(a), 0};
}

// Corners on the unit circle (angles proportional to the counts), each side a parabolic arc
// bowed inwards by `bow` times its chord: concave sides, convex corners for a mild bow.
std::vector<Eigen::MatrixX3d> bowed_sides(std::span<const int> counts, double bow) {
  const int total = std::accumulate(counts.begin(), counts.end(), 0);
  auto corner = [&](int position) {
    const double a = 2 * std::numbers::pi * position / total;
    return Eigen::Vector3d(std::cos(a), std::sin(a), 0);
  };
  std::vector<Eigen::MatrixX3d> sides;
  int start = 0;
  for (const int count : counts) {
    const Eigen::Vector3d a = corner(start), b = corner(start + count);
    const Eigen::Vector3d inward = -(0.5 * (a + b)).normalized();
    Eigen::MatrixX3d side(count + 1, 3);
    for (int k = 0; k <= count; ++k) {
      const double t = static_cast<double>(k) / count;
      side.row(k) =
          ((1 - t) * a + t * b + 4 * bow * (b - a).norm() * t * (1 - t) * inward).transpose();
    }
    side.row(0) = a.transpose();
    side.row(count) = b.transpose();
    sides.push_back(side);
    start += count;
  }
  return sides;
}

TEST(PatchFillGeometry, BoundaryVerticesAreTheGivenPointsBitwise) {
  const std::vector<int> counts{5, 6, 3, 6, 4};
  const auto sides = sides_on(ellipse, counts);
  const FilledPatch patch = fill_region(sides);
  for (size_t i = 0; i < sides.size(); ++i)
    for (Eigen::Index k = 0; k < sides[i].rows(); ++k) {
      const int v = patch.topology.side_vertices[i][static_cast<size_t>(k)];
      for (int c = 0; c < 3; ++c) EXPECT_EQ(patch.mesh.vertices(v, c), sides[i](k, c));
    }
  EXPECT_EQ(patch.mesh.faces, patch.topology.mesh.faces);
  EXPECT_EQ(patch.quality.distortion, patch.topology.distortion);
}

TEST(PatchFillGeometry, NoInvertedQuadsOnConvexBoundaries) {
  for (const std::vector<int>& counts : std::vector<std::vector<int>>{{3, 3, 4},
                                                                      {6, 4, 4, 2},
                                                                      {10, 4, 4, 2},
                                                                      {2, 8, 4},
                                                                      {5, 6, 3, 6, 4},
                                                                      {12, 12, 12, 12},
                                                                      {30, 4, 4, 4, 4},
                                                                      {8, 8, 8, 8, 8, 8, 8, 8},
                                                                      {20, 2, 20, 4},
                                                                      {1, 1, 1, 1, 1, 1}}) {
    const FilledPatch patch = fill_region(sides_on(ellipse, counts));
    EXPECT_TRUE(validate(patch.mesh).ok()) << test::describe(counts);
    EXPECT_EQ(patch.quality.inverted_quads, 0) << test::describe(counts);
    EXPECT_GT(patch.quality.scaled_jacobian_min, -1e-9) << test::describe(counts);
  }
}

TEST(PatchFillGeometry, NoInvertedQuadsOnMildlyConcaveBoundaries) {
  for (const std::vector<int>& counts : std::vector<std::vector<int>>{{8, 8, 8, 8},
                                                                      {6, 6, 6, 6, 6},
                                                                      {10, 6, 10, 6},
                                                                      {7, 9, 8},
                                                                      {6, 6, 6, 6, 6, 6},
                                                                      {5, 6, 3, 6, 4},
                                                                      {12, 10, 9, 11},
                                                                      {9, 7, 8, 6, 9, 7, 8}}) {
    const FilledPatch patch = fill_region(bowed_sides(counts, 0.08));
    EXPECT_TRUE(validate(patch.mesh).ok()) << test::describe(counts);
    EXPECT_EQ(patch.quality.inverted_quads, 0) << test::describe(counts);
  }
}

TEST(PatchFillGeometry, ProjectionPutsInteriorOnTheSurface) {
  // A spherical cap: boundary on the sphere of radius 2, interior projected onto it.
  const double radius = 2;
  auto cap = [&](double t) {
    const double a = 2 * std::numbers::pi * t;
    const Eigen::Vector3d p(std::cos(a), std::sin(a), 0);
    return Eigen::Vector3d(p.x(), p.y(), std::sqrt(radius * radius - 1));
  };
  FillGeometryOptions options;
  options.project = [&](const Eigen::Vector3d& p) -> Eigen::Vector3d {
    return radius * p.normalized();
  };
  const std::vector<int> counts{6, 6, 6, 4, 4};
  const FilledPatch patch = fill_region(sides_on(cap, counts), options);
  for (Eigen::Index v = 0; v < patch.mesh.vertices.rows(); ++v)
    EXPECT_NEAR(patch.mesh.vertices.row(v).norm(), radius, 1e-12);
  EXPECT_EQ(patch.quality.inverted_quads, 0);
  EXPECT_TRUE(validate(patch.mesh).ok());
}

TEST(PatchFillGeometry, PlaceReplacesTheVertexByVertexStart) {
  // The same cap: a `place` that lifts the free vertices (and only those) onto the sphere along
  // +z is the start instead of `project`, called once per filled plan with the boundary fixed;
  // with no relaxation sweep the interior stays exactly where it put it.
  const double radius = 2;
  auto cap = [&](double t) {
    const double a = 2 * std::numbers::pi * t;
    return Eigen::Vector3d(std::cos(a), std::sin(a), std::sqrt(radius * radius - 1));
  };
  int calls = 0, projected = 0;
  FillGeometryOptions options;
  options.relax_iterations = 0;
  options.project = [&](const Eigen::Vector3d& p) -> Eigen::Vector3d {
    ++projected;
    return p;
  };
  options.place = [&](std::vector<Eigen::Vector3d>& positions,
                      std::span<const std::array<int, 4>> quads, std::span<const char> fixed) {
    ++calls;
    ASSERT_EQ(fixed.size(), positions.size());
    ASSERT_FALSE(quads.empty());
    for (size_t v = 0; v < positions.size(); ++v) {
      if (fixed[v]) {
        EXPECT_NEAR(positions[v].norm(), radius, 1e-12);  // the boundary is on the sphere
        continue;
      }
      const Eigen::Vector2d xy = positions[v].head<2>();
      positions[v].z() = std::sqrt(radius * radius - xy.squaredNorm());
    }
  };
  const std::vector<int> counts{6, 6, 6, 4, 4};
  const FilledPatch patch = fill_region(sides_on(cap, counts), options);
  EXPECT_GE(calls, 1);
  EXPECT_EQ(projected, 0);
  for (Eigen::Index v = 0; v < patch.mesh.vertices.rows(); ++v)
    EXPECT_NEAR(patch.mesh.vertices.row(v).norm(), radius, 1e-12);
  EXPECT_EQ(patch.quality.inverted_quads, 0);
}

TEST(PatchFillGeometry, ScaleInvariant) {
  // The same region at 1e-4 and 1e4 gives the same mesh up to scale.
  const std::vector<int> counts{7, 5, 6, 4};
  const FilledPatch unit = fill_region(sides_on(ellipse, counts));
  for (const double scale : {1e-4, 1e4}) {
    auto scaled = sides_on(ellipse, counts);
    for (auto& side : scaled) side *= scale;
    const FilledPatch patch = fill_region(scaled);
    EXPECT_TRUE(validate(patch.mesh).ok());
    EXPECT_LT((patch.mesh.vertices / scale - unit.mesh.vertices).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_NEAR(patch.quality.scaled_jacobian_min, unit.quality.scaled_jacobian_min, 1e-9);
  }
}

TEST(PatchFillGeometry, PolylinesAreResampledByArcLength) {
  // A square with corners at (0,0), (4,0), (4,4), (0,4); side 0 given with an extra point.
  std::vector<Eigen::MatrixX3d> polylines(4);
  polylines[0].resize(3, 3);
  polylines[0] << 0, 0, 0, 1, 0, 0, 4, 0, 0;
  polylines[1].resize(2, 3);
  polylines[1] << 4, 0, 0, 4, 4, 0;
  polylines[2].resize(2, 3);
  polylines[2] << 4, 4, 0, 0, 4, 0;
  polylines[3].resize(2, 3);
  polylines[3] << 0, 4, 0, 0, 0, 0;
  const std::vector<int> counts{4, 2, 4, 2};
  const FilledPatch patch = fill_region(polylines, counts);
  const auto& side0 = patch.topology.side_vertices[0];
  for (int k = 0; k <= 4; ++k)
    EXPECT_NEAR(patch.mesh.vertices(side0[static_cast<size_t>(k)], 0), k, 1e-12);
  EXPECT_EQ(patch.quality.distortion, 0);
  // A plain grid stays a plain grid: every quad a 1 by 2 rectangle.
  EXPECT_NEAR(patch.quality.min_angle_deg, 90, 1e-6);
  EXPECT_NEAR(patch.quality.max_aspect_ratio, 2, 1e-6);
}

TEST(PatchFillGeometry, SidesThatDoNotMeetAreAFillError) {
  std::vector<Eigen::MatrixX3d> sides = sides_on(ellipse, std::vector<int>{4, 4, 4, 4});
  sides[2](0, 0) += 0.1;
  EXPECT_THROW(fill_region(sides), FillError);
  sides = sides_on(ellipse, std::vector<int>{4, 4, 4, 4});
  sides[1](1, 2) = std::nan("");
  EXPECT_THROW(fill_region(sides), FillError);
}

// FillGeometryOptions::good_enough: offered the search's best patch only when a last resort is
// due (the notched quadrilaterals with a 210° corner: every plan of some folds before the last
// resorts and the planar placement clean them). Declined, the fill is the same bits as without
// it; accepted, the offered patch is the result, as offered.
TEST(PatchFill, GoodEnoughIsOfferedTheSearchsBestBeforeTheLastResorts) {
  int offers = 0, fills = 0;
  test::for_each_count_vector(4, [&](const std::vector<int>& small) {
    if (offers >= 3) return;
    std::vector<int> counts = small;
    for (int& c : counts) c += 4;
    const std::vector<Eigen::MatrixX3d> sides = test::notched_sides(counts, 210);
    ++fills;
    const FilledPatch plain = fill_region(sides);
    std::optional<FilledPatch> offered;
    FillGeometryOptions declining;
    declining.good_enough = [&](const FilledPatch& p) {
      offered = p;
      return false;
    };
    const FilledPatch declined = fill_region(sides, declining);
    SCOPED_TRACE(test::describe(counts));
    EXPECT_TRUE(declined.mesh.vertices == plain.mesh.vertices);
    EXPECT_TRUE(declined.mesh.faces == plain.mesh.faces);
    if (!offered) return;
    ++offers;
    // Offered because it folds: the last resorts are for fills that keep inverted quads.
    EXPECT_GT(offered->quality.inverted_quads, 0);
    FillGeometryOptions accepting;
    accepting.good_enough = [](const FilledPatch&) { return true; };
    const FilledPatch accepted = fill_region(sides, accepting);
    EXPECT_TRUE(accepted.mesh.vertices == offered->mesh.vertices);
    EXPECT_EQ(accepted.quality.inverted_quads, offered->quality.inverted_quads);
    EXPECT_EQ(plain.quality.inverted_quads, 0);  // the last resorts clean it
  });
  EXPECT_GE(offers, 1) << "of " << fills << " notched fills";
}

}  // namespace
}  // namespace sd::meshing
