#include "garment/curve_network.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "garment/body_surface.hpp"
#include "garment/stroke_projection.hpp"
#include "scene/sketch_file.hpp"
#include "tests/garment/test_helpers.hpp"

namespace sd::garment {
// The tests read sketch files through the scene layer.
using scene::parse_sketch;
using scene::Sketch;

namespace {

const BodySurface& sphere() {
  static const BodySurface surface(meshing::icosphere(0.3, 5, {0, 1, 0}));
  return surface;
}

CurveNetwork network_of(const char* json, const std::set<std::string>& mirrored = {}) {
  const Sketch s = parse_sketch(json, "network.json");
  return build_network(s, project_curves(s, sphere()), mirrored);
}

// Three strokes on the front of the sphere whose ends miss each other by 4-8 mm (inside the
// 15 mm tolerance): one triangle of three junctions.
TEST(CurveNetwork, EndsWithinTheToleranceMeetAtOneJunction) {
  const CurveNetwork net = network_of(R"({
    "curves": [
      { "id": "a", "points": [[-0.10, 0.95], [0.10, 0.95]] },
      { "id": "b", "points": [[0.106, 0.954], [0.0, 1.10]] },
      { "id": "c", "points": [[0.004, 1.108], [-0.104, 0.946]] }
    ],
    "panels": [ { "id": "p", "boundary": ["a", "b", "c"] } ] })");
  ASSERT_EQ(net.nodes.size(), 3u);
  ASSERT_EQ(net.edges.size(), 3u);
  ASSERT_EQ(net.curves.size(), 3u);
  // Each junction is shared by exactly two edge ends, and the polylines end exactly on it.
  std::vector<int> ends(3, 0);
  for (const NetworkEdge& e : net.edges) {
    ++ends[static_cast<size_t>(e.from)];
    ++ends[static_cast<size_t>(e.to)];
    EXPECT_LT((e.points.row(0).transpose() - net.nodes[static_cast<size_t>(e.from)]).norm(), 1e-12);
    EXPECT_LT((e.points.bottomRows(1).transpose() - net.nodes[static_cast<size_t>(e.to)]).norm(),
              1e-12);
    EXPECT_NEAR(e.length, polyline_length(e.points), 1e-12);
  }
  for (int n : ends) EXPECT_EQ(n, 2);
}

// A stroke ending on the interior of another splits it there: 4 junctions, 4 pieces, and the
// split curve keeps its pieces in curve order.
TEST(CurveNetwork, AnEndOnAnotherCurvesInteriorSplitsIt) {
  const CurveNetwork net = network_of(R"({
    "curves": [
      { "id": "long", "points": [[-0.12, 1.0], [0.12, 1.0]] },
      { "id": "stem", "points": [[0.0, 1.0], [0.0, 1.12]] }
    ],
    "panels": [ { "id": "p", "boundary": ["long", "stem"] } ] })");
  EXPECT_EQ(net.nodes.size(), 4u);
  EXPECT_EQ(net.edges.size(), 3u);
  const NetworkCurve& lng = net.curves[static_cast<size_t>(net.find_curve("long"))];
  ASSERT_EQ(lng.edges.size(), 2u);
  ASSERT_EQ(lng.nodes.size(), 3u);
  const NetworkCurve& stem = net.curves[static_cast<size_t>(net.find_curve("stem"))];
  ASSERT_EQ(stem.edges.size(), 1u);
  EXPECT_EQ(lng.nodes[1], stem.nodes[0]);  // the T-junction
  // The two pieces together are as long as the unsplit curve would be (about 0.24 m of arc on
  // the sphere, more than the chord).
  const double total = net.edges[static_cast<size_t>(lng.edges[0])].length +
                       net.edges[static_cast<size_t>(lng.edges[1])].length;
  EXPECT_GT(total, 0.24);
  EXPECT_LT(total, 0.30);
}

// Mirrored curves get copies across x = 0; a curve lying on the plane is its own mirror, and
// a curve ending near the plane is snapped onto it so that its copy meets it there.
TEST(CurveNetwork, MirrorCopiesReflectAndMeetOnThePlane) {
  const CurveNetwork net = network_of(R"({
    "curves": [
      { "id": "side",   "points": [[0.006, 0.95], [0.12, 1.0]] },
      { "id": "centre", "points": [[0.0, 0.95], [0.0, 1.10]] }
    ],
    "panels": [ { "id": "p", "boundary": ["side", "centre"] } ] })",
                                      {"side", "centre"});
  const int side = net.find_curve("side");
  const int copy = net.find_curve("side.mirror");
  ASSERT_GE(side, 0);
  ASSERT_GE(copy, 0);
  ASSERT_NE(side, copy);
  EXPECT_TRUE(net.curves[static_cast<size_t>(copy)].mirror_copy);
  EXPECT_EQ(net.find_curve("centre.mirror"), net.find_curve("centre"));
  // Point by point, the copy is the reflection of the original.
  const NetworkEdge& e =
      net.edges[static_cast<size_t>(net.curves[static_cast<size_t>(side)].edges[0])];
  const NetworkEdge& m =
      net.edges[static_cast<size_t>(net.curves[static_cast<size_t>(copy)].edges[0])];
  ASSERT_EQ(e.points.rows(), m.points.rows());
  for (Eigen::Index i = 0; i < e.points.rows(); ++i)
    EXPECT_LT((mirror_point(e.points.row(i).transpose()) - m.points.row(i).transpose()).norm(),
              1e-12);
  EXPECT_EQ(m.orbit, net.curves[static_cast<size_t>(side)].edges[0]);
  // The end 6 mm from the plane was snapped onto it: original and copy share that junction,
  // which is also where the centre curve starts.
  EXPECT_EQ(net.curves[static_cast<size_t>(side)].nodes.front(),
            net.curves[static_cast<size_t>(copy)].nodes.front());
  EXPECT_NEAR(
      net.nodes[static_cast<size_t>(net.curves[static_cast<size_t>(side)].nodes.front())].x(), 0.0,
      1e-12);
}

TEST(CurveNetwork, PolylineLengthAndEndTangents) {
  Eigen::MatrixX3d quarter(91, 3);  // a quarter circle of radius 0.5 in the x-y plane
  for (int i = 0; i <= 90; ++i) {
    const double t = M_PI / 2 * i / 90.0;
    quarter.row(i) << 0.5 * std::cos(t), 0.5 * std::sin(t), 0.0;
  }
  // Inscribed polyline: shorter than the arc by about L·θ²/24 with θ the angle per segment.
  const double arc = M_PI / 4, step = M_PI / 180;
  EXPECT_NEAR(polyline_length(quarter), arc * (1 - step * step / 24), 1e-9);
  // Over 2 cm of arc the tangent leaving (0.5, 0) turns by 0.02 / 0.5 rad at most.
  const Eigen::Vector3d start = polyline_end_tangent(quarter, true, kJunctionTangentArc);
  const Eigen::Vector3d end = polyline_end_tangent(quarter, false, kJunctionTangentArc);
  EXPECT_NEAR(start.norm(), 1.0, 1e-12);
  EXPECT_NEAR(end.norm(), 1.0, 1e-12);
  EXPECT_GT(start.dot(Eigen::Vector3d::UnitY()), std::cos(0.02 / 0.5));
  EXPECT_GT(end.dot(-Eigen::Vector3d::UnitX()), std::cos(0.02 / 0.5));
}

}  // namespace
}  // namespace sd::garment
