#include "src/render/scene.hpp"

#include <gtest/gtest.h>

#include <set>

#include "tests/render/test_scenes.hpp"

namespace sd::render {
namespace {

TEST(Scene, TriangleEdgesAreUniqueAndComplete) {
  const meshing::TriMesh box = test::box_mesh({0, 0, 0}, {1, 1, 1});
  const Eigen::MatrixX2i edges = triangle_edges(box);
  // A closed triangle mesh has E = 3F/2; Euler: V - E + F = 2 for the box (8 - 18 + 12).
  EXPECT_EQ(edges.rows(), 18);
  std::set<std::pair<int, int>> seen;
  for (Eigen::Index e = 0; e < edges.rows(); ++e) {
    EXPECT_LT(edges(e, 0), edges(e, 1));
    EXPECT_TRUE(seen.insert({edges(e, 0), edges(e, 1)}).second);
  }
}

// A 2 by 1 strip of quads: 7 edges, and none of them is a triangulation diagonal.
TEST(Scene, QuadEdgesExcludeDiagonals) {
  Eigen::MatrixX4i quads(2, 4);
  quads << 0, 1, 4, 3, 1, 2, 5, 4;
  const Eigen::MatrixX2i edges = quad_edges(quads);
  EXPECT_EQ(edges.rows(), 7);
  const Eigen::MatrixX3i tris = triangulate_quads(quads);
  ASSERT_EQ(tris.rows(), 4);
  for (Eigen::Index e = 0; e < edges.rows(); ++e) {
    const std::pair<int, int> edge{edges(e, 0), edges(e, 1)};
    EXPECT_NE(edge, std::make_pair(0, 4));  // diagonal of quad 0
    EXPECT_NE(edge, std::make_pair(1, 5));  // diagonal of quad 1
  }
  // The triangles keep the quads' orientation: same winding as (0, 1, 4).
  EXPECT_EQ(tris.row(0), Eigen::RowVector3i(0, 1, 4));
  EXPECT_EQ(tris.row(1), Eigen::RowVector3i(0, 4, 3));
}

TEST(Scene, FaceValuesBecomeTheLargestOnEachEdge) {
  meshing::TriMesh m;
  m.vertices.resize(5, 3);
  m.vertices << 0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 5, 5, 0;
  m.faces.resize(2, 3);
  m.faces << 0, 1, 2, 1, 3, 2;
  Eigen::MatrixX2i edges(3, 2);
  edges << 1, 2,  // shared
      0, 1,       // face 0 only
      3, 4;       // no face
  Eigen::VectorXd values(2);
  values << 4, 7;
  const Eigen::VectorXd e = edge_values_from_faces(m, edges, values);
  EXPECT_EQ(e[0], 7);
  EXPECT_EQ(e[1], 4);
  EXPECT_TRUE(std::isnan(e[2]));
  EXPECT_THROW(edge_values_from_faces(m, edges, Eigen::VectorXd(3)), std::invalid_argument);
}

TEST(Scene, ColourMaps) {
  EXPECT_TRUE(colour_map(ColourMap::kViridis, 0).isApprox(Eigen::Vector3f(0.267f, 0.005f, 0.329f)));
  EXPECT_TRUE(colour_map(ColourMap::kViridis, 1).isApprox(Eigen::Vector3f(0.993f, 0.906f, 0.144f)));
  EXPECT_TRUE(colour_map(ColourMap::kViridis, 2).isApprox(colour_map(ColourMap::kViridis, 1)));
  // Viridis brightens monotonically (sum of channels as a proxy for lightness).
  for (double t = 0; t < 1; t += 0.05)
    EXPECT_LT(colour_map(ColourMap::kViridis, t).sum() - 1e-6,
              colour_map(ColourMap::kViridis, t + 0.05).sum());
  // Ten distinct level colours; levels 4..8 must be told apart.
  for (int a = 0; a < 10; ++a)
    for (int b = a + 1; b < 10; ++b)
      EXPECT_GT((colour_map(ColourMap::kLevels, a) - colour_map(ColourMap::kLevels, b)).norm(),
                0.1);
  EXPECT_TRUE(colour_map(ColourMap::kLevels, 3.4).isApprox(colour_map(ColourMap::kLevels, 3)));
}

TEST(Scene, PanelColoursAreStableAndDistinct) {
  Eigen::VectorXi ids(10);
  ids << 0, 1, 2, 3, 4, 5, 6, 7, 0, 3;
  const Eigen::MatrixX3f c = panel_colours(ids);
  EXPECT_TRUE(c.row(8).isApprox(c.row(0)));
  EXPECT_TRUE(c.row(9).isApprox(c.row(3)));
  for (int a = 0; a < 8; ++a)
    for (int b = a + 1; b < 8; ++b) EXPECT_GT((c.row(a) - c.row(b)).norm(), 0.1);
  EXPECT_THROW(panel_colours(Eigen::VectorXi::Constant(1, -1)), std::invalid_argument);
}

TEST(Scene, ValidationNamesTheProblem) {
  Scene scene;
  SceneMesh& m = scene.meshes.emplace_back();
  m.mesh = test::box_mesh({0, 0, 0}, {1, 1, 1});
  EXPECT_NO_THROW(validate_scene(scene));
  m.face_colours = Eigen::MatrixX3f::Zero(3, 3);
  EXPECT_THROW(validate_scene(scene), std::invalid_argument);
  m.face_colours.resize(0, 3);
  Wireframe w;
  w.edges.resize(1, 2);
  w.edges << 0, 8;  // out of range
  m.wireframe = w;
  EXPECT_THROW(validate_scene(scene), std::invalid_argument);
  m.wireframe->edges << 0, 7;
  m.wireframe->edge_values = Eigen::VectorXd::Zero(2);
  EXPECT_THROW(validate_scene(scene), std::invalid_argument);
  m.wireframe->edge_values = Eigen::VectorXd::Zero(1);
  EXPECT_NO_THROW(validate_scene(scene));
  m.mesh.vertices(0, 0) = std::numeric_limits<double>::infinity();
  EXPECT_THROW(validate_scene(scene), std::invalid_argument);
}

TEST(Scene, BoundsCoverEveryMesh) {
  Scene scene;
  scene.meshes.emplace_back().mesh = test::box_mesh({0, 0, 0}, {1, 1, 1});
  scene.meshes.emplace_back().mesh = test::box_mesh({-2, 0.5, 0}, {-1, 3, 0.5});
  const meshing::BoundingBox b = scene_bounds(scene);
  EXPECT_TRUE(b.min.isApprox(Eigen::Vector3d(-2, 0, 0)));
  EXPECT_TRUE(b.max.isApprox(Eigen::Vector3d(1, 3, 1)));
}

}  // namespace
}  // namespace sd::render
