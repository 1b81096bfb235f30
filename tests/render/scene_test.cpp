#include "src/render/scene.hpp"

#include <gtest/gtest.h>

#include <array>
#include <map>
#include <set>
#include <vector>

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

// A dress-like garment of 12 panels, each 2 × 2 quads: a top row of 6 (bodice pieces) sewn to a
// bottom row of 6 (skirt pieces) and each row's neighbours to each other. The skirt's ids are
// those of trial 39's dress: ids 8-11 under 0-3, so that colouring by id alone (id modulo the 8
// colours) gives 0 and 8, 1 and 9, ... one colour across the waist seam.
struct PanelGrid {
  Eigen::MatrixX3i triangles;
  Eigen::VectorXi triangle_panel;
};

PanelGrid twelve_panel_garment() {
  constexpr int kColumns = 12, kRows = 4;  // quads; each panel 2 × 2
  const std::array<std::array<int, 6>, 2> panel_of{{{0, 1, 2, 3, 4, 5}, {8, 9, 10, 11, 6, 7}}};
  Eigen::MatrixX4i quads(kColumns * kRows, 4);
  Eigen::VectorXi quad_panel(kColumns * kRows);
  const auto vertex = [](int i, int j) { return j * (kColumns + 1) + i; };
  for (int j = 0; j < kRows; ++j)
    for (int i = 0; i < kColumns; ++i) {
      const int q = j * kColumns + i;
      quads.row(q) << vertex(i, j), vertex(i + 1, j), vertex(i + 1, j + 1), vertex(i, j + 1);
      quad_panel(q) = panel_of[static_cast<size_t>(j / 2)][static_cast<size_t>(i / 2)];
    }
  PanelGrid grid;
  grid.triangles = triangulate_quads(quads);
  grid.triangle_panel.resize(grid.triangles.rows());
  for (Eigen::Index q = 0; q < quads.rows(); ++q)
    grid.triangle_panel(2 * q) = grid.triangle_panel(2 * q + 1) = quad_panel(q);
  return grid;
}

// Pairs of faces across an edge that belong to different panels, and how many of them show one
// colour.
int sewn_edges_of_one_colour(const PanelGrid& grid, const Eigen::MatrixX3f& colours,
                             int* sewn_edges) {
  std::map<std::pair<int, int>, std::vector<int>> faces_of;
  for (Eigen::Index f = 0; f < grid.triangles.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      faces_of[std::minmax(grid.triangles(f, k), grid.triangles(f, (k + 1) % 3))].push_back(
          static_cast<int>(f));
  int same = 0;
  *sewn_edges = 0;
  for (const auto& [edge, faces] : faces_of) {
    if (faces.size() != 2 || grid.triangle_panel(faces[0]) == grid.triangle_panel(faces[1]))
      continue;
    ++*sewn_edges;
    if (colours.row(faces[0]).isApprox(colours.row(faces[1]))) ++same;
  }
  return same;
}

TEST(Scene, PanelsSewnTogetherNeverShareAColour) {
  const PanelGrid grid = twelve_panel_garment();
  int sewn = 0;
  // By id alone the waist seam under panels 0-3 is one colour on both sides: the test's premise.
  EXPECT_EQ(sewn_edges_of_one_colour(grid, panel_colours(grid.triangle_panel), &sewn), 8);
  EXPECT_EQ(sewn, (5 + 5) * 2 + 6 * 2);  // 5 + 5 row seams and 6 waist seams, 2 quad edges each
  const Eigen::MatrixX3f colours = panel_colours(grid.triangle_panel, grid.triangles);
  EXPECT_EQ(sewn_edges_of_one_colour(grid, colours, &sewn), 0);
  // Every panel is one colour from the palette, and the colouring does not vary between calls.
  const std::vector<int> slots = panel_palette_slots(grid.triangle_panel, grid.triangles);
  ASSERT_EQ(slots.size(), 12u);
  for (Eigen::Index f = 0; f < grid.triangles.rows(); ++f)
    EXPECT_TRUE(colours.row(f).transpose().isApprox(
        panel_palette_colour(slots[static_cast<size_t>(grid.triangle_panel(f))])));
  EXPECT_EQ(panel_palette_slots(grid.triangle_panel, grid.triangles), slots);
  // The first 8 panels keep their colours by id (no neighbour coloured before them has it).
  for (int p = 0; p < 8; ++p) EXPECT_EQ(slots[static_cast<size_t>(p)], p);
}

TEST(Scene, PanelColoursByIdWhenFewPanelsOrNoneSewn) {
  // Eight panels sewn in a row keep the colours of panel_colours(ids).
  PanelGrid grid = twelve_panel_garment();
  for (Eigen::Index f = 0; f < grid.triangle_panel.size(); ++f)
    grid.triangle_panel(f) = grid.triangle_panel(f) % 8;
  EXPECT_TRUE(panel_colours(grid.triangle_panel, grid.triangles)
                  .isApprox(panel_colours(grid.triangle_panel)));
  EXPECT_THROW(panel_palette_slots(Eigen::VectorXi::Zero(3), grid.triangles),
               std::invalid_argument);
  EXPECT_THROW(panel_palette_colour(-1), std::invalid_argument);
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
