#pragma once
// Exact point-triangle geometry for body collision: the closest point on a triangle together
// with the feature (face interior, edge or vertex) it lies on, which decides which
// pseudo-normal gives the inside/outside sign (Bærentzen & Aanæs 2005).

#include <Eigen/Core>
#include <array>
#include <vector>

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

// Closest points of segments p0p1 and q0q1: p0 + s (p1 − p0) and q0 + t (q1 − q0) with s, t in
// [0, 1] (Ericson §5.1.9). Parallel segments get s = 0 (any pair of closest points is right);
// a segment of zero length is a point.
struct SegmentClosestPoints {
  double s = 0.0;
  double t = 0.0;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Vector3d q = Eigen::Vector3d::Zero();
  double squared_distance = 0.0;
};
SegmentClosestPoints closest_points_on_segments(const Eigen::Vector3d& p0,
                                                const Eigen::Vector3d& p1,
                                                const Eigen::Vector3d& q0,
                                                const Eigen::Vector3d& q1);

// When four points moving linearly from x0[k] to x1[k] over t in [0, 1] are coplanar: the roots
// in [0, 1] of the cubic f(t) = ((x1 − x0) × (x2 − x0)) · (x3 − x0) of the moving points (the
// orientation of point 0 against the plane of points 1, 2, 3, negative when it lies on the side
// their counter-clockwise normal points to), the
// candidate times of a vertex-face or edge-edge collision (Provot 1997; Bridson et al. 2002).
// A root where f only touches zero counts (a vertex reaching the face at t = 1 exactly).
struct CoplanarTime {
  double t = 0.0;
  int sign_before = 0;  // sign of f just before t (0 when f is zero there, e.g. at t = 0)
};
struct CoplanarTimes {
  // f vanishes (to rounding) for every t: the points stay coplanar (parallel edges, a vertex
  // moving in its face's plane); the times then say nothing and the caller must look otherwise.
  bool degenerate = false;
  std::vector<CoplanarTime> roots;  // ascending
  int sign_at_start = 0;            // sign of f(0), 0 when it is zero to rounding
};
CoplanarTimes coplanar_times(const std::array<Eigen::Vector3d, 4>& x0,
                             const std::array<Eigen::Vector3d, 4>& x1);

}  // namespace sd::sim
