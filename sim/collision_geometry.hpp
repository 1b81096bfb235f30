#pragma once
// Exact point-triangle geometry for body collision: the closest point on a triangle together
// with the feature (face interior, edge or vertex) it lies on, which decides which
// pseudo-normal gives the inside/outside sign (Bærentzen & Aanæs 2005).

#include <Eigen/Core>

namespace sd::sim {

// Which part of a triangle holds the closest point.
enum class TriangleFeature : unsigned char {
  face,    // interior of the triangle
  edge,    // interior of edge (index, index+1 mod 3)
  vertex,  // corner `index`
};

struct TriangleClosestPoint {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  // Weights of the three corners (sum 1, all ≥ 0): point = Σ barycentric[k]·corner_k.
  Eigen::Vector3d barycentric = Eigen::Vector3d::Zero();
  TriangleFeature feature = TriangleFeature::face;
  int index = 0;  // edge index (edge k joins corners k and k+1 mod 3) or corner index
  double squared_distance = 0.0;
};

// Closest point on triangle (a, b, c) to p by Voronoi regions (Ericson, Real-Time Collision
// Detection §5.1.5), classifying the region. Degenerate triangles fall into an edge or corner.
TriangleClosestPoint closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                               const Eigen::Vector3d& b, const Eigen::Vector3d& c);

// Unit normal of triangle (a, b, c) by the right-hand rule; zero for a degenerate triangle.
Eigen::Vector3d triangle_normal(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                const Eigen::Vector3d& c);

// Interior angle of triangle (a, b, c) at corner a, radians in [0, π].
double corner_angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);

}  // namespace sd::sim
