#include "garment/surface_untangle.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

namespace sd::garment {
namespace {

// An n × n grid of quads on the sphere of radius r around the origin, centred on +z, facing out.
meshing::QuadMesh sphere_grid(int n, double r, double span) {
  meshing::QuadMesh mesh;
  mesh.vertices.resize((n + 1) * (n + 1), 3);
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) {
      const Eigen::Vector3d p(span * (j - n / 2.0) / n, span * (i - n / 2.0) / n, r);
      mesh.vertices.row(i * (n + 1) + j) = (r * p.normalized()).transpose();
    }
  mesh.faces.resize(n * n, 4);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const int a = i * (n + 1) + j;
      mesh.faces.row(i * n + j) << a, a + 1, a + n + 2, a + n + 1;  // counter-clockwise from +z
    }
  return mesh;
}

TEST(SurfaceUntangle, UnfoldsDraggedVerticesOnASphere) {
  const int n = 8;
  const double r = 0.3;
  meshing::QuadMesh mesh = sphere_grid(n, r, 0.3);
  std::vector<char> fixed(static_cast<size_t>(mesh.vertex_count()), 0);
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j)
      if (i == 0 || j == 0 || i == n || j == n) fixed[static_cast<size_t>(i * (n + 1) + j)] = 1;
  const auto project = [r](const Eigen::Vector3d& p) -> Eigen::Vector3d { return r * p.normalized(); };
  const auto normal = [](const Eigen::Vector3d& p) -> Eigen::Vector3d { return p.normalized(); };
  // Drag two inner vertices across their neighbours (on the sphere), folding their quads.
  for (const auto& [v, to] : {std::pair{3 * (n + 1) + 3, 3 * (n + 1) + 6}, std::pair{5 * (n + 1) + 5, 2 * (n + 1) + 5}}) {
    const Eigen::Vector3d target = mesh.vertices.row(to).transpose() + Eigen::Vector3d(0.004, 0.003, 0);
    mesh.vertices.row(v) = project(target).transpose();
  }
  const UntangleResult result = untangle_on_surface(mesh, fixed, project, normal);
  EXPECT_GT(result.folded_before, 3);
  EXPECT_EQ(result.folded_after, 0);
  EXPECT_GT(result.moves, 0);
  // Every quad now turns the right way round against the sphere's normal, and the vertices are
  // still on the sphere (moved only through `project`).
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f)
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d p = mesh.vertices.row(mesh.faces(f, k)).transpose();
      const Eigen::Vector3d e1 = mesh.vertices.row(mesh.faces(f, (k + 1) % 4)).transpose() - p;
      const Eigen::Vector3d e2 = mesh.vertices.row(mesh.faces(f, (k + 3) % 4)).transpose() - p;
      EXPECT_GT(e1.cross(e2).dot(p.normalized()), 0) << "quad " << f << " corner " << k;
    }
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v) EXPECT_NEAR(mesh.vertices.row(v).norm(), r, 1e-12);
}

TEST(SurfaceUntangle, LeavesAGoodMeshAlone) {
  meshing::QuadMesh mesh = sphere_grid(6, 0.3, 0.2);
  const meshing::QuadMesh before = mesh;
  std::vector<char> fixed(static_cast<size_t>(mesh.vertex_count()), 0);
  const auto normal = [](const Eigen::Vector3d& p) -> Eigen::Vector3d { return p.normalized(); };
  const UntangleResult result = untangle_on_surface(mesh, fixed, {}, normal);
  EXPECT_EQ(result.folded_before, 0);
  EXPECT_EQ(result.moves, 0);
  EXPECT_EQ(mesh.vertices, before.vertices);
}

}  // namespace
}  // namespace sd::garment
