#include "garment/garment_crossings.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <iterator>
#include <map>
#include <utility>

namespace sd::garment {

std::vector<PanelCrossing> find_panel_crossings(const Garment& garment) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Mesh = CGAL::Surface_mesh<Kernel::Point_3>;
  const meshing::QuadMesh& quads = garment.mesh;
  Mesh mesh;
  std::vector<Mesh::Vertex_index> vertex(static_cast<std::size_t>(quads.vertex_count()));
  for (Eigen::Index v = 0; v < quads.vertex_count(); ++v)
    vertex[static_cast<std::size_t>(v)] =
        mesh.add_vertex({quads.vertices(v, 0), quads.vertices(v, 1), quads.vertices(v, 2)});
  // Triangle face → its quad. A triangle the surface cannot take (a non-manifold seam, which the
  // garment's fan check refuses before this) is left out of the test.
  std::map<Mesh::Face_index, Eigen::Index> quad_of;
  for (Eigen::Index f = 0; f < quads.face_count(); ++f)
    for (const auto& [i, j, k] : {std::array<int, 3>{0, 1, 2}, std::array<int, 3>{0, 2, 3}}) {
      const auto at = [&](int c) { return vertex[static_cast<std::size_t>(quads.faces(f, c))]; };
      const Mesh::Face_index t = mesh.add_face(at(i), at(j), at(k));
      if (t != Mesh::null_face()) quad_of[t] = f;
    }
  std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> pairs;
  CGAL::Polygon_mesh_processing::self_intersections(mesh, std::back_inserter(pairs));
  std::map<std::pair<int, int>, PanelCrossing> crossings;
  for (const auto& [s, t] : pairs) {
    int a = garment.face_panel(quad_of.at(s)), b = garment.face_panel(quad_of.at(t));
    if (a > b) std::swap(a, b);
    PanelCrossing& c = crossings[{a, b}];
    if (c.pairs++ > 0) continue;
    c.panel_a = a;
    c.panel_b = b;
    for (const Mesh::Face_index face : {s, t})
      for (const Mesh::Vertex_index v : vertices_around_face(mesh.halfedge(face), mesh)) {
        const Kernel::Point_3& p = mesh.point(v);
        c.where += Eigen::Vector3d(p.x(), p.y(), p.z()) / 6.0;
      }
  }
  std::vector<PanelCrossing> result;
  for (const auto& [key, c] : crossings) result.push_back(c);
  return result;
}

}  // namespace sd::garment
