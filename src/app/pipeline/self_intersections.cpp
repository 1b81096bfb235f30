#include "src/app/pipeline/self_intersections.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <spdlog/spdlog.h>

#include <iterator>
#include <utility>
#include <vector>

namespace sd::app {

int count_self_intersections(const Eigen::MatrixX3d& vertices, const Eigen::MatrixX3i& faces) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Mesh = CGAL::Surface_mesh<Kernel::Point_3>;
  Mesh mesh;
  std::vector<Mesh::Vertex_index> index;
  index.reserve(static_cast<std::size_t>(vertices.rows()));
  for (Eigen::Index i = 0; i < vertices.rows(); ++i)
    index.push_back(
        mesh.add_vertex(Kernel::Point_3(vertices(i, 0), vertices(i, 1), vertices(i, 2))));
  int skipped = 0;
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    if (mesh.add_face(index[faces(f, 0)], index[faces(f, 1)], index[faces(f, 2)]) ==
        Mesh::null_face())
      ++skipped;
  }
  if (skipped > 0) spdlog::warn("self-intersection count: {} non-manifold faces left out", skipped);
  std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> pairs;
  CGAL::Polygon_mesh_processing::self_intersections(mesh, std::back_inserter(pairs));
  return static_cast<int>(pairs.size());
}

}  // namespace sd::app
