#include "garment/body_clefts.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "garment/body.hpp"
#include "garment/body_surface.hpp"
#include "garment/garment_mesh.hpp"
#include "garment/quality_gate.hpp"
#include "garment/sketch_inputs.hpp"
#include "meshing/tri_mesh.hpp"
#include "scene/sketch_file.hpp"

namespace sd::garment {
namespace {

// Two balls of radius 0.1 m whose centres are 0.18 m apart along x, overlapping: a concave crease
// round the circle where they meet (x = 0, radius 4.36 cm), like the seat's two cheeks.
meshing::TriMesh two_cheeks() {
  meshing::TriMesh left = meshing::icosphere(0.1, 5, {-0.09, 1.0, 0.0});
  const meshing::TriMesh right = meshing::icosphere(0.1, 5, {0.09, 1.0, 0.0});
  const Eigen::Index offset = left.vertices.rows();
  left.vertices.conservativeResize(offset + right.vertices.rows(), 3);
  left.vertices.bottomRows(right.vertices.rows()) = right.vertices;
  const Eigen::Index faces = left.faces.rows();
  left.faces.conservativeResize(faces + right.faces.rows(), 3);
  left.faces.bottomRows(right.faces.rows()) = right.faces.array() + static_cast<int>(offset);
  return left;
}

TEST(BodyClefts, ACreaseBetweenTwoBallsOpeningBackwardsIsACleft) {
  const BodySurface body(two_cheeks());
  // 1 cm behind the crease (the crease at z = −0.0436): each ball's closest point lies on its own
  // side, the normals (∓0.85, 0, −0.52) are 117° apart and face each other.
  const std::optional<BodyCleft> behind = cleft_at(body, {0.0, 1.0, -0.0536});
  ASSERT_TRUE(behind.has_value());
  // Backwards within 25° (measured −0.935: the narrowest pair of the probe circle's points lies a
  // little off the plane between the balls); one opening downwards would read near 0.
  EXPECT_LT(behind->opening.z(), -0.9) << "the crease opens backwards";
  EXPECT_GT(behind->width, 0.005);
  EXPECT_LT(behind->width, 0.05);
  EXPECT_LT(behind->wall_a.x() * behind->wall_b.x(), 0.0) << "one wall on each ball";
  // Under the crease it opens downwards: cloth hanging there falls out of it (an armpit's apex,
  // the crotch), not a cleft the gate warns about.
  EXPECT_FALSE(cleft_at(body, {0.0, 0.9464, 0.0}).has_value());
  // On the outside of one ball, away from the crease: no facing wall.
  EXPECT_FALSE(cleft_at(body, {0.2, 1.0, 0.0}).has_value());
  EXPECT_FALSE(cleft_at(body, {0.09, 1.11, 0.0}).has_value());
}

// The clearance from each wall is measured from the wall's tangent plane: at the crease's
// mouth between the two balls a point lies in front of both, behind the mouth it would not.
TEST(BodyClefts, AJunctionBetweenBothWallsIsNearerThanTheOffsetToEach) {
  const BodySurface body(two_cheeks());
  const Eigen::Vector3d p(0.0, 1.0, -0.0536);
  const std::optional<BodyCleft> cleft = cleft_at(body, p);
  ASSERT_TRUE(cleft.has_value());
  // On the plane between the balls the two clearances agree (the probe's pair is not exactly
  // symmetric: within 2 mm) and are below the 1 cm offset: the point is held by both balls.
  EXPECT_GT(cleft->clearance_a(p), 0.0);
  EXPECT_GT(cleft->clearance_b(p), 0.0);
  EXPECT_LT(cleft->clearance_a(p), 0.01);
  EXPECT_LT(cleft->clearance_b(p), 0.01);
  EXPECT_NEAR(cleft->clearance_a(p), cleft->clearance_b(p), 0.002);
  EXPECT_NEAR(cleft->normal_a.norm(), 1.0, 1e-9);
  EXPECT_LT(cleft->normal_a.dot(cleft->normal_b), 0.0) << "the walls face each other";
}

struct CleftWarnings {
  std::vector<JunctionInCleft> junctions;
  std::vector<QualityWarning> warnings;
  Garment garment;
  std::optional<BodySurface> surface;
  double offset = 0.0;
};

CleftWarnings cleft_warnings_of(const std::filesystem::path& file) {
  const scene::Sketch sketch = scene::load_sketch(file);
  const Body body = load_sketch_body(sketch);
  CleftWarnings out;
  out.offset = sketch.offset;
  out.surface.emplace(body.mesh);
  out.garment = build_garment(sketch, *out.surface);
  const BodyLandmarks landmarks = find_landmarks(body.mesh);
  CleftProbe probe;
  probe.offset = sketch.offset;
  out.junctions = find_junctions_in_clefts(out.garment, *out.surface, probe);
  out.warnings = check_quality_tried(out.garment, sketch, body.mesh, &landmarks);
  return out;
}

// The cropped jacket's underarm: its four panels meet in the crease between arm and torso, which
// is a cleft by its width (2.6 cm against twice the 1.2 cm offset plus 5 mm), but each panel lies
// on its own wall there (garment/crease_wall.hpp: front and back on the torso, the sleeves on the
// arm): the junction is 1.13 cm from the torso and 1.53 cm from the arm, not nearer than the
// offset to both, and is not warned (it was, falsely, until 27 November).
TEST(BodyClefts, TheCroppedJacketsUnderarmFollowsTheCreaseAndIsNotWarned) {
  const auto jacket =
      cleft_warnings_of(std::filesystem::path(SD_SOURCE_DIR) / "data/designs/cropped-jacket.json");
  EXPECT_TRUE(jacket.junctions.empty());
  for (const QualityWarning& w : jacket.warnings) EXPECT_NE(w.kind, "junction_in_cleft");
  // The junction is still in a cleft by cleft_at's own test: what spares it is its clearance.
  const meshing::QuadMesh& mesh = jacket.garment.mesh;
  int in_cleft = 0;
  for (int v = 0; v < mesh.vertex_count(); ++v) {
    const Eigen::Vector3d p = mesh.vertices.row(v).transpose();
    if ((p - Eigen::Vector3d(0.178, 1.225, 0.0)).norm() > 0.005) continue;
    CleftProbe probe;
    probe.offset = jacket.offset;
    const std::optional<BodyCleft> cleft = cleft_at(*jacket.surface, p, probe);
    if (!cleft) continue;
    ++in_cleft;
    // One wall at the offset (1.2 cm) or farther, with 1.5 mm to spare (measured 1.13 and
    // 1.53 cm: 3.3 mm), so that the test fails before a small change of the mesh flips it.
    EXPECT_GE(std::max(cleft->clearance_a(p), cleft->clearance_b(p)), jacket.offset + 0.0015);
  }
  EXPECT_EQ(in_cleft, 1) << "the underarm junction lies in the crease";
}

// The Collada human's strapless dress of trial 35: its back bodice and back skirt (and their
// mirror copies) meet at one junction in the seat's cleft, where the 20 s drape blew up. Its twin
// with the seam 12 cm higher, above the cleft, rested at 3.4 s and is not warned.
TEST(BodyClefts, TheStraplessDressJunctionInTheSeatIsWarnedAboveItNot) {
  const std::filesystem::path human = "/usr/share/assimp/models/Collada/human.zae";
  if (!std::filesystem::exists(human))
    GTEST_SKIP() << "assimp-testmodels' human.zae is not installed";
  const std::filesystem::path dir = std::filesystem::path(SD_SOURCE_DIR) / "tests/cli/sketches";
  const auto warnings_of = [](const std::filesystem::path& file) {
    const scene::Sketch sketch = scene::load_sketch(file);
    const Body body = load_sketch_body(sketch);
    const BodySurface surface(body.mesh);
    const Garment garment = build_garment(sketch, surface);
    const BodyLandmarks landmarks = find_landmarks(body.mesh);
    return std::make_pair(find_junctions_in_clefts(garment, surface),
                          check_quality_tried(garment, sketch, body.mesh, &landmarks));
  };
  const auto [junctions, warnings] = warnings_of(dir / "strapless-dress-human.json");
  ASSERT_EQ(junctions.size(), 1u);
  EXPECT_EQ(junctions[0].panels.size(), 4u);
  EXPECT_NEAR(junctions[0].where.x(), 0.0, 1e-6);
  EXPECT_NEAR(junctions[0].where.y(), 0.824, 0.01);
  EXPECT_LT(junctions[0].cleft.opening.z(), -0.7) << "the seat opens backwards";
  // Bridged: nearer than the 1 cm offset to both cheeks (measured 0.1 and 0.2 cm).
  EXPECT_LT(std::max(junctions[0].clearance_a, junctions[0].clearance_b), 0.005);
  int said = 0;
  for (const QualityWarning& w : warnings)
    if (w.kind == "junction_in_cleft") {
      ++said;
      EXPECT_NE(w.message.find("'bodice_back', 'bodice_back.mirror', 'skirt_back', "
                               "'skirt_back.mirror'"),
                std::string::npos)
          << w.message;
      EXPECT_NE(w.message.find("opening towards the back"), std::string::npos) << w.message;
      EXPECT_NE(w.message.find("move the seam above or below the cleft"), std::string::npos);
      EXPECT_NE(w.message.find("and bridges it"), std::string::npos) << w.message;
    }
  EXPECT_EQ(said, 1);
  const auto [above, above_warnings] = warnings_of(dir / "strapless-dress-human-seam-above.json");
  EXPECT_TRUE(above.empty());
  for (const QualityWarning& w : above_warnings) EXPECT_NE(w.kind, "junction_in_cleft");
}

// A design written for this test while the criterion was chosen, and not changed for it
// (tests/cli/sketches/ yoke-skirt-human.json): a hip yoke whose seam crosses the seat at 0.81 m,
// the skirt below it seamed at the centre back. Its centre-back junction lies in the seat's cleft
// like the dress's and is warned; the yoke's junctions at the front and the side are not in a
// cleft.
TEST(BodyClefts, AYokeSeamAcrossTheSeatIsWarnedAtTheCentreBack) {
  if (!std::filesystem::exists("/usr/share/assimp/models/Collada/human.zae"))
    GTEST_SKIP() << "assimp-testmodels' human.zae is not installed";
  const auto skirt = cleft_warnings_of(std::filesystem::path(SD_SOURCE_DIR) /
                                       "tests/cli/sketches/yoke-skirt-human.json");
  ASSERT_EQ(skirt.junctions.size(), 1u);
  EXPECT_NEAR(skirt.junctions[0].where.x(), 0.0, 1e-6);
  EXPECT_LT(skirt.junctions[0].where.z(), -0.15) << "at the back";
  EXPECT_NEAR(skirt.junctions[0].where.y(), 0.81, 0.01);
  int said = 0;
  for (const QualityWarning& w : skirt.warnings)
    if (w.kind == "junction_in_cleft") {
      ++said;
      EXPECT_NE(w.message.find("'yoke_back', 'yoke_back.mirror', 'skirt_back', "
                               "'skirt_back.mirror'"),
                std::string::npos)
          << w.message;
    }
  EXPECT_EQ(said, 1);
}

}  // namespace
}  // namespace sd::garment
