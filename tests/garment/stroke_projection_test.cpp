#include "garment/stroke_projection.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "garment/sketch_error.hpp"
#include "tests/garment/test_helpers.hpp"

namespace sd::garment {
namespace {

constexpr double kRadius = 0.3;
const Eigen::Vector3d kCentre(0, 1, 0);

// Sag of a level-5 octahedral sphere is below 4e-4 R; 5e-4 m bounds it for R = 0.3 m.
constexpr double kFacetTolerance = 5e-4;

GarmentRequest sketch_with(const CurveSpec& curve) {
  GarmentRequest s;
  s.file = "t.json";
  s.curves.push_back(curve);
  return s;
}

TEST(StrokeProjection, FrontViewLandsOnOffsetSphere) {
  const BodySurface body(meshing::icosphere(kRadius, 5, kCentre));
  CurveSpec c;
  c.id = "c";
  c.json_path = "/curves/0";
  c.points = {{-0.1, 1.0}, {0.0, 1.1}, {0.1, 1.05}};
  c.offset = 0.02;
  const ProjectedCurve p = project_curve(sketch_with(c), c, &body);
  ASSERT_GT(p.points.rows(), 20);
  EXPECT_EQ(p.misses, 0);
  for (Eigen::Index k = 0; k < p.points.rows(); ++k) {
    const Eigen::Vector3d q = p.points.row(k).transpose();
    EXPECT_NEAR((q - kCentre).norm(), kRadius + 0.02, kFacetTolerance);
    EXPECT_GT(q.z(), 0);  // the side facing the camera
  }
  // The ends are exactly where they were drawn in x and y (smoothing keeps the ends).
  EXPECT_NEAR(p.points(0, 0), -0.1 * (kRadius + 0.02) / kRadius, 0.01);
}

TEST(StrokeProjection, EachViewHitsItsOwnSide) {
  const BodySurface body(meshing::icosphere(kRadius, 4, kCentre));
  const std::pair<ViewKind, Eigen::Vector3d> views[] = {{ViewKind::kFront, {0, 0, 1}},
                                                        {ViewKind::kBack, {0, 0, -1}},
                                                        {ViewKind::kLeft, {1, 0, 0}},
                                                        {ViewKind::kRight, {-1, 0, 0}}};
  for (const auto& [kind, side] : views) {
    CurveSpec c;
    c.id = "c";
    c.view.kind = kind;
    c.points = {{0.05, 1.0}, {0.1, 1.0}};
    c.offset = 0;
    const ProjectedCurve p = project_curve(sketch_with(c), c, &body);
    const Eigen::Vector3d q = p.points.row(0).transpose() - kCentre;
    EXPECT_GT(q.dot(side), 0.25) << static_cast<int>(kind);
    // The view's "x to the right" convention: u = +0.05 lands on the viewer's right.
    const ViewFrame f = view_frame(c.view);
    EXPECT_NEAR(q.dot(f.right), 0.05, 1e-3);
  }
}

TEST(StrokeProjection, MissesTakeDepthFromNeighbours) {
  const BodySurface body(meshing::icosphere(kRadius, 5, kCentre));
  CurveSpec c;
  c.id = "c";
  c.smooth = false;
  c.offset = 0;
  // Starts on the sphere and runs out past its silhouette (x > 0.3).
  c.points = {{0.0, 1.0}, {0.5, 1.0}};
  const ProjectedCurve p = project_curve(sketch_with(c), c, &body);
  EXPECT_GT(p.misses, 0);
  const Eigen::Index last = p.points.rows() - 1;
  EXPECT_NEAR(p.points(last, 0), 0.5, 1e-9);
  // The missed end keeps the depth of the last hit, which is near the silhouette (z ≈ 0).
  EXPECT_LT(std::abs(p.points(last, 2)), 0.06);
}

TEST(StrokeProjection, CurveMissingEverythingIsAnError) {
  const BodySurface body(meshing::icosphere(kRadius, 3, kCentre));
  CurveSpec c;
  c.id = "far";
  c.json_path = "/curves/0";
  c.points = {{1.0, 1.0}, {1.2, 1.0}};
  try {
    project_curve(sketch_with(c), c, &body);
    FAIL();
  } catch (const SketchError& e) {
    EXPECT_EQ(e.json_path(), "/curves/0/points");
  }
  c.on_body = false;  // drawn in free space: fine, lies in the view plane
  const ProjectedCurve p = project_curve(sketch_with(c), c, &body);
  EXPECT_NEAR(p.points(0, 2), 0.0, 1e-12);
}

// A curve written over a hole of an open body (a scan) folds once its points are moved onto
// the body, each landing on the hole's rim: the error says the curve runs over a hole there,
// where and how wide (trial 39, P6: only "crosses itself" was said). A sphere of 30 cm with its
// front cap (every triangle within 12 cm of the front pole) cut out.
TEST(StrokeProjection, CurveOverAHoleOfTheBodySaysSo) {
  const meshing::TriMesh sphere = meshing::icosphere(kRadius, 5, kCentre);
  meshing::TriMesh open = sphere;
  std::vector<Eigen::Index> kept;
  for (Eigen::Index f = 0; f < sphere.faces.rows(); ++f) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) c += sphere.vertices.row(sphere.faces(f, k)).transpose() / 3;
    if ((c - (kCentre + Eigen::Vector3d(0, 0, kRadius))).norm() > 0.12) kept.push_back(f);
  }
  open.faces.resize(static_cast<Eigen::Index>(kept.size()), 3);
  for (size_t i = 0; i < kept.size(); ++i)
    open.faces.row(static_cast<Eigen::Index>(i)) = sphere.faces.row(kept[i]);
  const BodySurface body(open);
  CurveSpec c;
  c.id = "cf";
  c.points3d = {{-0.2, 1.0, 0.22}, {0.0, 1.0, 0.2}, {0.2, 1.0, 0.22}};
  try {
    project_curve(sketch_with(c), c, &body);
    ADD_FAILURE() << "accepted";
  } catch (const SketchError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("curve 'cf' crosses itself"), std::string::npos) << what;
    EXPECT_NE(what.find("The curve runs over a hole of the body there: an opening"),
              std::string::npos)
        << what;
  }
}

TEST(StrokeProjection, Points3dSnapToOffsetSurface) {
  const BodySurface body(meshing::icosphere(kRadius, 5, kCentre));
  CurveSpec c;
  c.id = "c";
  c.points3d = {{0.5, 1.0, 0.0}, {0.0, 1.0, 0.5}};
  c.offset = 0.01;
  const ProjectedCurve p = project_curve(sketch_with(c), c, &body);
  for (Eigen::Index k = 0; k < p.points.rows(); ++k)
    EXPECT_NEAR((p.points.row(k).transpose() - kCentre).norm(), kRadius + 0.01, 2e-3);
}

// Two spheres of 10 cm side by side with a 6 cm gap between them (an arm hanging beside the
// torso). A curve written from the front of one across the gap to the front of the other (a
// kimono's underarm seam from the underside of the arm to the side seam) used to be snapped
// sample by sample to the nearer sphere: it ran down into the gap on one side and stepped across
// to the other where the nearer sphere changed, a step of about 4 cm between two 5 mm samples
// whose place a 1 cm move of the written middle point shifted. Now the samples in the gap keep
// their written shape (BodySurface::in_gap), so consecutive samples stay about 5 mm apart, and
// the samples near either sphere still lie on its offset surface.
TEST(StrokeProjection, Points3dBridgeAGapBetweenTwoPartsOfTheBody) {
  const meshing::TriMesh left = meshing::icosphere(0.1, 5, Eigen::Vector3d(-0.13, 1.0, 0.0));
  const meshing::TriMesh right = meshing::icosphere(0.1, 5, Eigen::Vector3d(0.13, 1.0, 0.0));
  meshing::TriMesh both = left;
  both.vertices.conservativeResize(2 * left.vertex_count(), 3);
  both.faces.conservativeResize(2 * left.face_count(), 3);
  both.vertices.bottomRows(right.vertex_count()) = right.vertices;
  both.faces.bottomRows(right.face_count()) =
      right.faces.array() + static_cast<int>(left.vertex_count());
  const BodySurface body(both);
  for (const double middle_z : {0.02, 0.03}) {  // the written middle point moved by 1 cm
    CurveSpec c;
    c.id = "underarm";
    c.offset = 0.01;
    c.points3d = {{-0.10, 1.0, 0.105}, {0.0, 1.0, middle_z}, {0.10, 1.0, 0.105}};
    const ProjectedCurve p = project_curve(sketch_with(c), c, &body);
    double longest = 0;
    for (Eigen::Index k = 0; k + 1 < p.points.rows(); ++k)
      longest = std::max(longest, (p.points.row(k + 1) - p.points.row(k)).norm());
    // 5 mm samples, stretched where a run's ends moved apart onto the offset surfaces: 1 cm
    // bounds it, where snapping sample by sample stepped 4 cm across the gap.
    EXPECT_LT(longest, 0.01) << "middle z " << middle_z;
    // Nothing inside either offset surface (the level-5 sphere's facets: 0.4 mm).
    for (Eigen::Index k = 0; k < p.points.rows(); ++k)
      EXPECT_GT(body.signed_distance(p.points.row(k).transpose()), 0.01 - 5e-4);
    // The ends, near a sphere, are on its offset surface.
    EXPECT_NEAR(body.signed_distance(p.points.row(0).transpose()), 0.01, 5e-4);
    EXPECT_NEAR(body.signed_distance(p.points.bottomRows(1).transpose()), 0.01, 5e-4);
  }
}

// Points written inside the body around its centre (a cuff drawn round a guessed arm axis):
// they do not cross, but snapped radially onto the sphere the curve runs 0° → 90°, back to
// 45°, then on to 135° and doubles over itself. The error says so and names the written point
// that moved farthest (the one 2 cm from the centre: 0.29 m).
TEST(StrokeProjection, Points3dFoldedBySnappingNameTheFarthestMove) {
  const BodySurface body(meshing::icosphere(kRadius, 5, kCentre));
  CurveSpec c;
  c.id = "cuff";
  c.json_path = "/curves/0";
  c.smooth = false;
  const auto at = [](double degrees, double r) {
    const double a = degrees * M_PI / 180;
    return Eigen::Vector3d(r * std::cos(a), 1.0, r * std::sin(a));
  };
  c.points3d = {at(0, 0.05), at(90, 0.05), at(45, 0.02), at(135, 0.05)};
  c.offset = 0.0;
  try {
    project_curve(sketch_with(c), c, &body);
    FAIL() << "the folded curve was accepted";
  } catch (const SketchError& e) {
    EXPECT_EQ(e.json_path(), "/curves/0/points3d");
    // 28 cm: farther than points are written by eye, so the move leads (trial 39, P11).
    EXPECT_EQ(e.sentence().rfind("curve 'cuff' is written 28.", 0), 0u) << e.sentence();
    EXPECT_NE(e.sentence().find("cm inside the body: its point 2 (0.014, 1.000, 0.014), the one "
                                "that moved farthest, lies that deep below its surface, and moved "
                                "onto it the curve crosses itself near"),
              std::string::npos)
        << e.sentence();
  }
}

// Written points far off the body (written for another body) are named: the one that moved
// farthest, by its JSON path and how far, and how many moved more than the limit; a point given
// relative to a landmark is not counted (it follows its landmark), nor one a few centimetres off.
TEST(StrokeProjection, WrittenPointsMovedFarOntoTheBodyAreNamed) {
  const BodySurface body(meshing::icosphere(kRadius, 5, kCentre));
  GarmentRequest sketch;
  sketch.file = "t.json";
  const auto curve = [&](const std::string& id, std::vector<Eigen::Vector3d> points,
                         std::vector<bool> at_landmark) {
    CurveSpec c;
    c.id = id;
    c.json_path = "/curves/" + std::to_string(sketch.curves.size());
    c.points3d = std::move(points);
    c.at_landmark = std::move(at_landmark);
    c.offset = 0.01;
    sketch.curves.push_back(c);
  };
  // On the sphere's offset surface (r = 0.31) at 2 and 3 cm out: near enough.
  curve("near", {{0.0, 1.0, 0.33}, {0.0, 1.1, std::sqrt(0.34 * 0.34 - 0.01)}}, {false, false});
  std::vector<ProjectedCurve> projected = project_curves(sketch, body);
  ASSERT_EQ(projected[0].written_moves.size(), 2u);
  EXPECT_NEAR(projected[0].written_moves[0], 0.02, 1e-3);  // the facets: within 1 mm
  EXPECT_NEAR(projected[0].written_moves[1], 0.03, 1e-3);
  EXPECT_EQ(moved_points_warning(sketch, projected, body), "");
  // 9 cm out, and a landmark-relative point 15 cm out (the sphere has no landmarks: the flag is
  // what the sketch reader sets).
  curve("far", {{0.4, 1.0, 0.0}, {0.0, 1.0, -0.46}, {-0.31, 1.0, 0.0}}, {false, true, false});
  projected = project_curves(sketch, body);
  EXPECT_LT(projected[1].written_moves[1], 0.0) << "not counted";
  const std::string said = moved_points_warning(sketch, projected, body);
  EXPECT_NE(said.find("t.json: /curves/1/points3d/0: point 0 of curve 'far', written at (0.400, "
                      "1.000, 0.000) m, moved 9.0 cm onto the body"),
            std::string::npos)
      << said;
  EXPECT_NE(said.find("1 of the file's 4 written [x, y, z] points moved more than 6 cm"),
            std::string::npos)
      << said;
  EXPECT_NE(said.find("\"at\""), std::string::npos) << said;
  EXPECT_NE(said.find("Points relative to a landmark"), std::string::npos) << said;
  // The curves off the body and view strokes are not snapped: not counted.
  for (CurveSpec& c : sketch.curves) c.on_body = false;
  projected = project_curves(sketch, body);
  EXPECT_TRUE(projected[1].written_moves.empty());
  EXPECT_EQ(moved_points_warning(sketch, projected, body), "");
}

// Trial 39, P12: a curve's own "offset": 0.5 lifted its points, written on the skin, 50 cm out,
// and that was counted as a move "likely written for another body". The offset the curve asks
// for is no move: points written on the skin or on the offset surface are both where they were
// meant to be.
TEST(StrokeProjection, ACurvesOwnOffsetIsNoMove) {
  const BodySurface body(meshing::icosphere(kRadius, 5, kCentre));
  GarmentRequest sketch;
  sketch.file = "t.json";
  CurveSpec c;
  c.id = "lifted";
  c.json_path = "/curves/0";
  c.offset = 0.2;
  // On the skin (r = 0.3), then on the offset surface (r = 0.5), then 10 cm beyond it.
  c.points3d = {{0.0, 1.0, 0.3}, {0.5, 1.0, 0.0}, {0.0, 1.0, -0.6}};
  c.at_landmark = {false, false, false};
  sketch.curves.push_back(c);
  const std::vector<ProjectedCurve> projected = project_curves(sketch, body);
  ASSERT_EQ(projected[0].written_moves.size(), 3u);
  EXPECT_LT(projected[0].written_moves[0], 2e-3);  // the facets: within 2 mm
  EXPECT_LT(projected[0].written_moves[1], 2e-3);
  EXPECT_NEAR(projected[0].written_moves[2], 0.1, 2e-3);
  const std::string said = moved_points_warning(sketch, projected, body);
  EXPECT_NE(said.find("/curves/0/points3d/2: point 2 of curve 'lifted'"), std::string::npos)
      << said;
  EXPECT_NE(said.find("1 of the file's 3 written"), std::string::npos) << said;
}

TEST(StrokeProjection, SelfIntersectionFound) {
  const std::vector<Eigen::Vector2d> figure8 = {{0, 0}, {1, 1}, {1, 0}, {0, 1}};
  EXPECT_GE(find_self_intersection(figure8, false).first, 0);
  const std::vector<Eigen::Vector2d> zigzag = {{0, 0}, {1, 1}, {2, 0}, {3, 1}};
  EXPECT_EQ(find_self_intersection(zigzag, false).first, -1);
  const std::vector<Eigen::Vector2d> square = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  EXPECT_EQ(find_self_intersection(square, true).first, -1);
}

// A loop in front of the body (outward +z): the strands of a figure of eight 2 cm apart in
// depth do not touch in 3D, but seen from outside they cross. The same polyline with its halves
// on opposite sides of a limb (outward +z and -z) does not fold a panel; a hairpin whose strands
// do not cross in projection is not a crossing either.
TEST(StrokeProjection, CrossingSeenFromOutsideFound) {
  Eigen::MatrixX3d loop(7, 3);  // segment 0 along y = 0 at z = 0.02, segment 3 across it at z ≈ 0
  loop << 0, 0, 0.02, 0.1, 0, 0.02, 0.11, 0.03, 0.015, 0.08, 0.04, 0.01, 0.06, -0.03, 0.0, 0.08,
      -0.04, 0.0, 0.2, 0, 0.0;
  const std::vector<Eigen::Vector3d> front(7, Eigen::Vector3d::UnitZ());
  EXPECT_EQ(find_self_intersection(loop, false, 1e-3).first, -1);  // 3D: 1 cm apart at least
  const auto [i, j] = find_crossing_seen_from_outside(loop, false, front, 0.1);
  EXPECT_EQ(i, 0);
  EXPECT_EQ(j, 3);
  std::vector<Eigen::Vector3d> opposite = front;
  for (size_t k = 4; k < opposite.size(); ++k) opposite[k] = -Eigen::Vector3d::UnitZ();
  EXPECT_EQ(find_crossing_seen_from_outside(loop, false, opposite, 0.1).first, -1);
  EXPECT_EQ(find_crossing_seen_from_outside(loop, false, front, 0.005).first, -1);  // too far
  Eigen::MatrixX3d hairpin(7, 3);
  hairpin << 0, 0, 0, 0.1, 0, 0, 0.2, 0, 0, 0.21, 0.005, 0.005, 0.2, 0.01, 0.01, 0.1, 0.01, 0.01, 0,
      0.01, 0.01;
  EXPECT_EQ(find_crossing_seen_from_outside(hairpin, false, front, 0.1).first, -1);
}

TEST(StrokeProjection, SamplingKeepsControlPointsAndSpacing) {
  const std::vector<Eigen::Vector2d> pts = {{0, 0}, {0.1, 0.05}, {0.2, 0}};
  const auto dense = sample_stroke<2>(pts, false, true, 0.005);
  EXPECT_EQ(dense.front(), pts.front());
  EXPECT_EQ(dense.back(), pts.back());
  bool passes_middle = false;
  for (const auto& q : dense) passes_middle = passes_middle || (q - pts[1]).norm() < 1e-12;
  EXPECT_TRUE(passes_middle);  // Catmull-Rom interpolates its control points
  for (size_t k = 1; k < dense.size(); ++k) EXPECT_LT((dense[k] - dense[k - 1]).norm(), 0.0075);
}

}  // namespace
}  // namespace sd::garment
