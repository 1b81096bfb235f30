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
    }
  EXPECT_EQ(said, 1);
  const auto [above, above_warnings] = warnings_of(dir / "strapless-dress-human-seam-above.json");
  EXPECT_TRUE(above.empty());
  for (const QualityWarning& w : above_warnings) EXPECT_NE(w.kind, "junction_in_cleft");
}

}  // namespace
}  // namespace sd::garment
