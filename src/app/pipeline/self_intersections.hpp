#pragma once
// An independent count of a cloth's self-intersections for the run report: CGAL's
// Polygon_mesh_processing::self_intersections with exact predicates (a check of the simulator's
// own self-collision, sim/self_collision.hpp, by code that shares nothing with it). CGAL stays
// in this one translation unit (it is slow to compile).

#include <Eigen/Core>

namespace sd::app {

// Pairs of triangles of the mesh (V: #V by 3 metres, F: #F by 3) that intersect other than
// along the edge or vertex they share. Faces CGAL cannot add to a manifold mesh (a non-manifold
// edge) are left out of the count.
int count_self_intersections(const Eigen::MatrixX3d& vertices, const Eigen::MatrixX3i& faces);

}  // namespace sd::app
