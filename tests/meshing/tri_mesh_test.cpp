#include "meshing/tri_mesh.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>

namespace sd::meshing {
namespace {

// A unit cube as 12 outward-facing triangles.
TriMesh cube() {
  TriMesh m;
  m.vertices.resize(8, 3);
  for (int i = 0; i < 8; ++i) m.vertices.row(i) << (i & 1), (i >> 1) & 1, (i >> 2) & 1;
  m.faces.resize(12, 3);
  m.faces << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4,
      6, 1, 3, 5, 3, 7, 5;
  return m;
}

TEST(TriMesh, CubeIsClosedOrientedSingleComponent) {
  const TriMeshTopology topo = analyse_topology(cube());
  EXPECT_TRUE(topo.closed());
  EXPECT_TRUE(topo.oriented());
  EXPECT_EQ(topo.components, 1);
  EXPECT_EQ(topo.degenerate_faces, 0);
  EXPECT_NEAR(face_areas(cube()).sum(), 6.0, 1e-12);
}

// Every level: closed, oriented, on the sphere, faces outward (the enclosed volume, by the
// divergence theorem, is positive and approaches 4/3 π r³), with a vertex at the top.
TEST(TriMesh, IcosphereIsAClosedOutwardSphere) {
  const Eigen::Vector3d centre(0.1, 1.0, -0.2);
  const double radius = 0.25;
  for (int level = 0; level <= 4; ++level) {
    const TriMesh sphere = icosphere(radius, level, centre);
    EXPECT_EQ(sphere.face_count(), 20 << (2 * level));
    const TriMeshTopology topo = analyse_topology(sphere);
    EXPECT_TRUE(topo.closed() && topo.oriented());
    EXPECT_EQ(topo.components, 1);
    double volume = 0.0, top = -1.0;
    for (Eigen::Index v = 0; v < sphere.vertices.rows(); ++v) {
      const Eigen::Vector3d p = sphere.vertices.row(v).transpose() - centre;
      EXPECT_NEAR(p.norm(), radius, 1e-12);
      top = std::max(top, p.y());
    }
    for (Eigen::Index f = 0; f < sphere.face_count(); ++f) {
      const Eigen::Vector3d a = sphere.vertices.row(sphere.faces(f, 0)).transpose() - centre;
      const Eigen::Vector3d b = sphere.vertices.row(sphere.faces(f, 1)).transpose() - centre;
      const Eigen::Vector3d c = sphere.vertices.row(sphere.faces(f, 2)).transpose() - centre;
      volume += a.dot(b.cross(c)) / 6.0;
    }
    const double ball = 4.0 / 3.0 * 3.14159265358979323846 * radius * radius * radius;
    EXPECT_GT(volume, 0.6 * ball);
    EXPECT_LT(volume, ball);
    if (level >= 4) {
      EXPECT_GT(volume, 0.99 * ball);
    }
    if (level >= 1) {
      EXPECT_NEAR(top, radius, 1e-12);
    }
  }
}

TEST(TriMesh, OpenFlippedAndNonManifoldAreCounted) {
  TriMesh m = cube();
  m.faces.conservativeResize(11, 3);  // drop one triangle: 3 boundary edges
  EXPECT_EQ(analyse_topology(m).boundary_edges, 3);

  m = cube();
  m.faces.row(0) = Eigen::RowVector3i(0, 1, 2);  // flip one face: its 3 edges disagree
  EXPECT_EQ(analyse_topology(m).inconsistent_edges, 3);

  m = cube();
  m.faces.conservativeResize(13, 3);
  m.faces.row(12) = Eigen::RowVector3i(0, 2, 7);  // a third face on edge 0-2
  EXPECT_EQ(analyse_topology(m).non_manifold_edges, 1);
}

TEST(TriMesh, ComponentsAndDegenerateFaces) {
  TriMesh two = cube();
  const TriMesh c = cube();
  two.vertices.conservativeResize(16, 3);
  two.vertices.bottomRows(8) = c.vertices.array() + 5.0;
  two.faces.conservativeResize(25, 3);
  two.faces.middleRows(12, 12) = c.faces.array() + 8;
  two.faces.row(24) = Eigen::RowVector3i(0, 0, 1);
  const TriMeshTopology topo = analyse_topology(two);
  EXPECT_EQ(topo.components, 2);
  EXPECT_EQ(topo.degenerate_faces, 1);
}

TEST(TriMesh, OutOfRangeIndexIsAnError) {
  TriMesh m = cube();
  m.faces(3, 1) = 8;
  EXPECT_THROW(analyse_topology(m), std::invalid_argument);
}

TEST(TriMesh, NormalsPointOutOfTheCube) {
  const TriMesh m = cube();
  const Eigen::MatrixX3d n = vertex_normals(m);
  const Eigen::RowVector3d centre(0.5, 0.5, 0.5);
  for (int v = 0; v < 8; ++v) EXPECT_GT(n.row(v).dot(m.vertices.row(v) - centre), 0.5);
}

}  // namespace
}  // namespace sd::meshing
