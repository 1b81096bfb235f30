#include "meshing/quad_mesh.hpp"

#include <gtest/gtest.h>

#include "tests/meshing/quad_grid.hpp"

namespace sd::meshing {
namespace {

using test::quad_grid;

bool mentions(const MeshCheck& check, const std::string& word) {
  for (const auto& p : check.problems)
    if (p.find(word) != std::string::npos) return true;
  return false;
}

TEST(QuadMesh, GridIsValid) {
  const MeshCheck check = validate(quad_grid(3, 2));
  EXPECT_TRUE(check.ok()) << (check.problems.empty() ? "" : check.problems.front());
}

TEST(QuadMesh, ValencesOfAGrid) {
  const Eigen::VectorXi valence = vertex_valences(quad_grid(2, 2));
  // Corners 2, side midpoints 3, centre 4.
  EXPECT_EQ(valence(0), 2);
  EXPECT_EQ(valence(1), 3);
  EXPECT_EQ(valence(4), 4);
  EXPECT_EQ(valence.sum(), 2 * 12);  // 12 edges
}

TEST(QuadMesh, BoundaryLoopFollowsTheFaces) {
  const std::vector<int> loop = boundary_loop(quad_grid(2, 1));
  ASSERT_EQ(loop.size(), 6u);
  // Counter-clockwise: after vertex 0 comes 1 (along the bottom).
  const auto it = std::find(loop.begin(), loop.end(), 0);
  EXPECT_EQ(loop[static_cast<size_t>((it - loop.begin() + 1) % 6)], 1);
}

TEST(QuadMesh, RepeatedVertexIsReported) {
  QuadMesh mesh = quad_grid(1, 1);
  mesh.faces(0, 2) = mesh.faces(0, 0);
  EXPECT_TRUE(mentions(validate(mesh), "repeats"));
}

TEST(QuadMesh, FlippedFaceIsReported) {
  QuadMesh mesh = quad_grid(2, 1);
  mesh.faces.row(1) = mesh.faces.row(1).reverse().eval();
  EXPECT_TRUE(mentions(validate(mesh), "orientation"));
}

TEST(QuadMesh, EdgeWithThreeFacesIsReported) {
  QuadMesh mesh = quad_grid(2, 1);  // vertices 0..5; add a third face on edge 1-4
  mesh.vertices.conservativeResize(8, 3);
  mesh.vertices.row(6) << 1, 0, 1;
  mesh.vertices.row(7) << 1, 1, 1;
  mesh.faces.conservativeResize(3, 4);
  mesh.faces.row(2) << 4, 1, 6, 7;
  EXPECT_TRUE(mentions(validate(mesh), "more than two faces"));
}

TEST(QuadMesh, TwoBoundaryLoopsAreReported) {
  // A 3x3 grid without its middle quad is an annulus.
  QuadMesh full = quad_grid(3, 3);
  QuadMesh ring;
  ring.vertices = full.vertices;
  ring.faces.resize(8, 4);
  for (int f = 0, r = 0; f < 9; ++f)
    if (f != 4) ring.faces.row(r++) = full.faces.row(f);
  EXPECT_FALSE(validate(ring).ok());
  EXPECT_THROW(boundary_loop(ring), std::invalid_argument);
}

TEST(QuadMesh, UnusedVertexAndZeroAreaAreReported) {
  QuadMesh mesh = quad_grid(1, 1);
  mesh.vertices.conservativeResize(5, 3);
  mesh.vertices.row(4) << 9, 9, 0;
  EXPECT_TRUE(mentions(validate(mesh), "used by no face"));
  QuadMesh flat = quad_grid(1, 1);
  flat.vertices.col(1).setZero();  // all four corners on a line
  flat.vertices.conservativeResize(6, 3);
  flat.vertices.row(4) << 0, 5, 0;  // keep the bounding box non-degenerate
  flat.vertices.row(5) << 1, 5, 0;
  flat.faces.conservativeResize(2, 4);
  flat.faces.row(1) << 2, 3, 5, 4;  // a proper quad on top of the flattened one
  EXPECT_TRUE(mentions(validate(flat), "zero area"));
}

TEST(QuadMesh, ObjHasOneLinePerVertexAndFace) {
  const std::string obj = to_obj(quad_grid(2, 1));
  EXPECT_EQ(std::count(obj.begin(), obj.end(), 'v'), 6);
  EXPECT_NE(obj.find("f 1 2 5 4"), std::string::npos);
}

}  // namespace
}  // namespace sd::meshing
