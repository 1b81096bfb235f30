#include "garment/surface_untangle.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "tests/garment/quad_grids.hpp"

namespace sd::garment {
namespace {

using test::grid_boundary;
using test::sphere_grid;

TEST(SurfaceUntangle, UnfoldsDraggedVerticesOnASphere) {
  const int n = 8;
  const double r = 0.3;
  meshing::QuadMesh mesh = sphere_grid(n, r, 0.3);
  const std::vector<char> fixed = grid_boundary(n);
  const auto project = [r](const Eigen::Vector3d& p) -> Eigen::Vector3d {
    return r * p.normalized();
  };
  const auto normal = [](const Eigen::Vector3d& p) -> Eigen::Vector3d { return p.normalized(); };
  // Drag two inner vertices across their neighbours (on the sphere), folding their quads.
  for (const auto& [v, to] :
       {std::pair{3 * (n + 1) + 3, 3 * (n + 1) + 6}, std::pair{5 * (n + 1) + 5, 2 * (n + 1) + 5}}) {
    const Eigen::Vector3d target =
        mesh.vertices.row(to).transpose() + Eigen::Vector3d(0.004, 0.003, 0);
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
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
    EXPECT_NEAR(mesh.vertices.row(v).norm(), r, 1e-12);
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
