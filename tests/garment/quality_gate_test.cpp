#include "garment/quality_gate.hpp"

#include <gtest/gtest.h>

#include "tests/garment/quad_grids.hpp"

namespace sd::garment {
namespace {

// A one-panel garment on an n × n grid of quads with sides of `edge` metres.
Garment grid_garment(int n, double edge) {
  Garment g;
  g.mesh = test::plane_grid(n);
  g.mesh.vertices *= edge;
  g.face_panel = Eigen::VectorXi::Zero(g.mesh.face_count());
  GarmentPanel panel;
  panel.id = "patch";
  g.panels.push_back(panel);
  return g;
}

GarmentRequest sketch_with_edge(double edge) {
  GarmentRequest sketch;
  sketch.edge_length = edge;
  return sketch;
}

const QualityWarning* find_kind(const std::vector<QualityWarning>& warnings,
                                const std::string& kind) {
  for (const QualityWarning& w : warnings)
    if (w.kind == kind) return &w;
  return nullptr;
}

TEST(QualityGate, ARegularGridIsClean) {
  EXPECT_TRUE(check_quality(grid_garment(6, 0.03), sketch_with_edge(0.03), nullptr).empty());
}

TEST(QualityGate, FoldedQuadIsFoundWhereItIs) {
  // Vertex (2, 2) pushed across its neighbours: the quads around it fold over.
  Garment g = grid_garment(6, 0.03);
  const int v = 2 * 7 + 2;
  g.mesh.vertices.row(v) += Eigen::RowVector3d(0.045, 0.045, 0.0);
  const std::vector<QualityWarning> warnings = check_quality(g, sketch_with_edge(0.03), nullptr);
  const QualityWarning* inverted = find_kind(warnings, "inverted_quads");
  ASSERT_NE(inverted, nullptr);
  EXPECT_GE(inverted->count, 1);
  EXPECT_LT(inverted->worst, 0.0);
  EXPECT_EQ(inverted->panel, "patch");
  // The worst fold is one of the quads around the moved vertex (within 1.5 quads of it).
  EXPECT_LT((inverted->where - Eigen::Vector3d(0.06, 0.06, 0.0)).norm(), 0.05);
  EXPECT_NE(inverted->message.find("panel 'patch'"), std::string::npos);
}

TEST(QualityGate, SliversLongQuadsAndNearVerticesAreNamed) {
  // Squash the last column of quads to 1/20 of their width: aspect 20, and the vertices of
  // the squashed column 1.5 mm apart (below 0.1 × 3 cm).
  Garment g = grid_garment(6, 0.03);
  for (Eigen::Index v = 0; v < g.mesh.vertex_count(); ++v)
    if (g.mesh.vertices(v, 0) > 0.179) g.mesh.vertices(v, 0) = 0.15 + 0.0015;
  const std::vector<QualityWarning> warnings = check_quality(g, sketch_with_edge(0.03), nullptr);
  const QualityWarning* aspect = find_kind(warnings, "aspect_ratio");
  ASSERT_NE(aspect, nullptr);
  EXPECT_NEAR(aspect->worst, 20.0, 1e-9);
  EXPECT_EQ(aspect->count, 6);
  const QualityWarning* near = find_kind(warnings, "near_vertices");
  ASSERT_NE(near, nullptr);
  EXPECT_NEAR(near->worst, 0.0015, 1e-12);
  EXPECT_EQ(near->count, 7);  // one pair per row of the squashed column
  EXPECT_EQ(find_kind(warnings, "inverted_quads"), nullptr);
}

// Panels that pass through each other or themselves at the start stay so in the drape (the
// simulator's untangling is bounded by the strain it may add; docs/collision.md): the gate names
// the panel, the other panel and the place.
TEST(QualityGate, PanelsCrossingEachOtherAreNamedWhereTheyCross) {
  // Panel 'a': a 6 × 6 grid of 3 cm quads at z = 0; panel 'b': the same grid standing in the
  // plane x = 7.5 cm, its middle row at z = 0, so it cuts through 'a' along x = 7.5 cm.
  Garment g = grid_garment(6, 0.03);
  meshing::QuadMesh b = test::plane_grid(6);
  const Eigen::Index offset = g.mesh.vertex_count();
  b.vertices *= 0.03;
  for (Eigen::Index v = 0; v < b.vertex_count(); ++v)
    b.vertices.row(v) = Eigen::RowVector3d(0.075, b.vertices(v, 1), b.vertices(v, 0) - 0.09);
  g.mesh.vertices.conservativeResize(offset + b.vertex_count(), 3);
  g.mesh.vertices.bottomRows(b.vertex_count()) = b.vertices;
  const Eigen::Index quads = g.mesh.face_count();
  g.mesh.faces.conservativeResize(quads + b.face_count(), 4);
  g.mesh.faces.bottomRows(b.face_count()) = b.faces.array() + static_cast<int>(offset);
  g.face_panel.conservativeResize(quads + b.face_count());
  g.face_panel.tail(b.face_count()).setOnes();
  GarmentPanel second;
  second.id = "b";
  g.panels.push_back(second);
  g.panels[0].id = "a";
  const std::vector<QualityWarning> warnings = check_quality(g, sketch_with_edge(0.03), nullptr);
  const QualityWarning* crossing = find_kind(warnings, "self_intersection");
  ASSERT_NE(crossing, nullptr);
  EXPECT_EQ(crossing->panel, "a");
  EXPECT_GT(crossing->count, 0);
  EXPECT_NEAR(crossing->where.x(), 0.075, 0.03);  // a pair's centre, within a quad of the cut
  EXPECT_NE(crossing->message.find("passes through panel 'b'"), std::string::npos);
  // Each panel alone is clean.
  EXPECT_EQ(find_kind(check_quality(grid_garment(6, 0.03), sketch_with_edge(0.03), nullptr),
                      "self_intersection"),
            nullptr);
}

TEST(QualityGate, APanelFoldedThroughItselfIsNamed) {
  // The two last columns of vertices (x = 15 and 18 cm) folded back over the grid to x = 6 cm
  // (1 cm above) and x = 3 cm (1 cm below): the folded strip passes down through the sheet.
  Garment g = grid_garment(6, 0.03);
  for (Eigen::Index v = 0; v < g.mesh.vertex_count(); ++v) {
    if (g.mesh.vertices(v, 0) > 0.179)
      g.mesh.vertices.row(v) << 0.03, g.mesh.vertices(v, 1), -0.01;
    else if (g.mesh.vertices(v, 0) > 0.149)
      g.mesh.vertices.row(v) << 0.06, g.mesh.vertices(v, 1), 0.01;
  }
  const std::vector<QualityWarning> warnings = check_quality(g, sketch_with_edge(0.03), nullptr);
  const QualityWarning* crossing = find_kind(warnings, "self_intersection");
  ASSERT_NE(crossing, nullptr);
  EXPECT_EQ(crossing->panel, "patch");
  EXPECT_NE(crossing->message.find("passes through itself"), std::string::npos);
  EXPECT_LT(crossing->where.x(), 0.1);  // on the folded-back part
}

TEST(QualityGate, QuadsMuchLargerThanAskedAreFound) {
  // 3 cm quads where 1 cm is asked: three times the edge length.
  const std::vector<QualityWarning> warnings =
      check_quality(grid_garment(4, 0.03), sketch_with_edge(0.01), nullptr);
  const QualityWarning* size = find_kind(warnings, "quad_size");
  ASSERT_NE(size, nullptr);
  EXPECT_EQ(size->count, 16);
  EXPECT_NEAR(size->worst, 3.0, 1e-9);
}

// A strip of 2 × `length` quads of 3 cm: its outline as four curves, the end 'strap_end' (2 edges
// along y = 0), 'outer' (up x = 2), 'top' (2) and 'inner' (down x = 0).
Garment strip_garment(int length) {
  Garment g;
  g.mesh = test::quad_grid(2, length);
  g.mesh.vertices *= 0.03;
  g.face_panel = Eigen::VectorXi::Zero(g.mesh.face_count());
  GarmentPanel panel;
  panel.id = "front";
  panel.curves = {"strap_end", "outer", "top", "inner"};
  panel.side_counts = {2, length, 2, length};
  g.panels.push_back(panel);
  const auto id = [](int i, int j) { return j * 3 + i; };
  for (int i = 0; i < 2; ++i) {
    g.edge_curve[{id(i, 0), id(i + 1, 0)}] = "strap_end";
    g.edge_curve[{id(i, length), id(i + 1, length)}] = "top";
  }
  for (int j = 0; j < length; ++j) {
    g.edge_curve[{id(2, j), id(2, j + 1)}] = "outer";
    g.edge_curve[{id(0, j), id(0, j + 1)}] = "inner";
  }
  return g;
}

TEST(QualityGate, APanelWithALongThinArmIsToldWhatToChange) {
  // Like the one-piece halter's strap (data/designs/repro/halter-one-piece.json: its end 2 edges
  // across between sides of 27 and 20): an end of 2 edges between sides of 12, which leave it
  // parallel. The quads are 3 cm where 1 cm is asked, so the panel has a quad_size warning to
  // advise on.
  // Each check's warnings are kept alive while `size` points into them.
  const Garment g = strip_garment(12);
  const std::vector<QualityWarning> strip = check_quality(g, sketch_with_edge(0.01), nullptr);
  const QualityWarning* size = find_kind(strip, "quad_size");
  ASSERT_NE(size, nullptr);
  EXPECT_NE(size->message.find("long thin arm ('strap_end' with 2 edge(s) across its end, between "
                               "'inner' with 12 and 'outer' with 12 edges)"),
            std::string::npos)
      << size->message;
  EXPECT_NE(size->message.find("seam across it where it meets the body"), std::string::npos);
  // The advice sits before the place, where the gate's offers go (at the first ';').
  EXPECT_LT(size->message.find("long thin arm"), size->message.find(';'));

  // The same outline narrowing to its end (a raglan sleeve at the neck): its sides leave the end
  // 2 × 26.6° apart (x spread by 1 + y / 2 about the middle), more than kArmSpread. No advice.
  Garment wedge = strip_garment(12);
  for (Eigen::Index v = 0; v < wedge.mesh.vertex_count(); ++v) {
    const double y = wedge.mesh.vertices(v, 1) / 0.03;
    wedge.mesh.vertices(v, 0) = 0.03 + (wedge.mesh.vertices(v, 0) - 0.03) * (1 + y / 2);
  }
  const std::vector<QualityWarning> wedged = check_quality(wedge, sketch_with_edge(0.01), nullptr);
  size = find_kind(wedged, "quad_size");
  ASSERT_NE(size, nullptr);
  EXPECT_EQ(size->message.find("long thin arm"), std::string::npos) << size->message;

  // An end of 2 edges between sides of 11, less than kArmLength = 6 times as long: no arm.
  const std::vector<QualityWarning> shorter =
      check_quality(strip_garment(11), sketch_with_edge(0.01), nullptr);
  size = find_kind(shorter, "quad_size");
  ASSERT_NE(size, nullptr);
  EXPECT_EQ(size->message.find("long thin arm"), std::string::npos) << size->message;
}

TEST(QualityGate, ClothInsideTheBodyIsNamedWithItsDepth) {
  // A 6 × 6 grid of 3 cm quads at z = 0 over a ball of radius 0.1 m whose top pokes 5 mm
  // through the middle of quad (2, 2): the cloth there lies 5 mm inside the body (less the
  // icosphere's facets: at 5 subdivisions its faces sit within 0.1 mm of the sphere), so the
  // gate reports that panel with the depth and the place, the deepest sample right over the
  // ball's top. A ball 1.5 mm through (below the 2 mm tolerance) is not reported.
  const Garment g = grid_garment(6, 0.03);
  BodyLandmarks landmarks;
  landmarks.points = {{"left_knee", {0.08, 0.07, -0.02}}, {"crotch", {1.0, 1.0, 1.0}}};
  const meshing::TriMesh deep = meshing::icosphere(0.1, 5, {0.075, 0.075, -0.095});
  const std::vector<QualityWarning> warnings =
      check_quality_tried(g, sketch_with_edge(0.03), deep, &landmarks);
  const QualityWarning* inside = find_kind(warnings, "inside_body");
  ASSERT_NE(inside, nullptr);
  EXPECT_EQ(inside->panel, "patch");
  EXPECT_NEAR(inside->worst, 0.005, 2e-4);
  EXPECT_NEAR(inside->where.x(), 0.075, 0.005);
  EXPECT_NEAR(inside->where.y(), 0.075, 0.005);
  EXPECT_EQ(inside->landmark, "left_knee");
  EXPECT_NE(inside->message.find("inside the body"), std::string::npos);
  EXPECT_NE(inside->message.find("pushes them out at its start"), std::string::npos);
  // Trial 43, P3: a smaller edge_length was offered whether or not it helped (there it made 5
  // warnings of 1), with no number, and the sentence ended in ';'. Now it is offered, with its
  // number (0.7 of 3 cm), only after the sketch meshed at it had no quad inside the ball.
  EXPECT_NE(inside->message.find("\"edge_length\": 0.021, whose quads follow the body"),
            std::string::npos)
      << inside->message;
  EXPECT_DOUBLE_EQ(inside->panel_edge_length, 0.021);
  EXPECT_NE(inside->message.back(), ';') << inside->message;
  // 50 mm through: deeper than the drape's start is known to recover from (45 mm), said so.
  const meshing::TriMesh deeper = meshing::icosphere(0.1, 5, {0.075, 0.075, -0.05});
  const std::vector<QualityWarning> deeper_warnings =
      check_quality_tried(g, sketch_with_edge(0.03), deeper, &landmarks);
  const QualityWarning* caught = find_kind(deeper_warnings, "inside_body");
  ASSERT_NE(caught, nullptr);
  EXPECT_NEAR(caught->worst, 0.05, 1e-3);
  EXPECT_NE(caught->message.find("deeper than the drape's start is known to push cloth out"),
            std::string::npos)
      << caught->message;
  const meshing::TriMesh shallow = meshing::icosphere(0.1, 5, {0.075, 0.075, -0.0985});
  EXPECT_EQ(
      find_kind(check_quality_tried(g, sketch_with_edge(0.03), shallow, &landmarks), "inside_body"),
      nullptr);
}

TEST(QualityGate, NamesTheNearestLandmark) {
  Garment g = grid_garment(6, 0.03);
  g.mesh.vertices.row(2 * 7 + 2) += Eigen::RowVector3d(0.045, 0.045, 0.0);
  BodyLandmarks landmarks;
  landmarks.points = {{"waist", {0.06, 0.06, 0.1}}, {"crotch", {1.0, 1.0, 1.0}}};
  const std::vector<QualityWarning> warnings = check_quality(g, sketch_with_edge(0.03), &landmarks);
  ASSERT_FALSE(warnings.empty());
  EXPECT_EQ(warnings.front().landmark, "waist");
  EXPECT_NE(warnings.front().message.find("near the waist"), std::string::npos);
}

}  // namespace
}  // namespace sd::garment
