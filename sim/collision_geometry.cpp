#include "sim/collision_geometry.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace sd::sim {

namespace {

TriangleClosestPoint make_result(const Eigen::Vector3d& p, const Eigen::Vector3d& point,
                                 const Eigen::Vector3d& barycentric, TriangleFeature feature,
                                 int index) {
  TriangleClosestPoint result;
  result.point = point;
  result.barycentric = barycentric;
  result.feature = feature;
  result.index = index;
  result.squared_distance = (p - point).squaredNorm();
  return result;
}

}  // namespace

TriangleClosestPoint closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                               const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a;
  const Eigen::Vector3d ac = c - a;
  const Eigen::Vector3d ap = p - a;
  const double d1 = ab.dot(ap);
  const double d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0)
    return make_result(p, a, Eigen::Vector3d(1, 0, 0), TriangleFeature::vertex, 0);

  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp);
  const double d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3)
    return make_result(p, b, Eigen::Vector3d(0, 1, 0), TriangleFeature::vertex, 1);

  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    return make_result(p, a + v * ab, Eigen::Vector3d(1 - v, v, 0), TriangleFeature::edge, 0);
  }

  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp);
  const double d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6)
    return make_result(p, c, Eigen::Vector3d(0, 0, 1), TriangleFeature::vertex, 2);

  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    return make_result(p, a + w * ac, Eigen::Vector3d(1 - w, 0, w), TriangleFeature::edge, 2);
  }

  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return make_result(p, b + w * (c - b), Eigen::Vector3d(0, 1 - w, w), TriangleFeature::edge, 1);
  }

  const double sum = va + vb + vc;
  if (!(sum > 0.0)) {
    // Degenerate (zero-area) triangle that slipped through the region tests: use the closest
    // of its three edges.
    TriangleClosestPoint best;
    best.squared_distance = std::numeric_limits<double>::infinity();
    const Eigen::Vector3d corners[3] = {a, b, c};
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& s = corners[k];
      const Eigen::Vector3d e = corners[(k + 1) % 3] - s;
      const double length2 = e.squaredNorm();
      const double t = length2 > 0.0 ? std::clamp((p - s).dot(e) / length2, 0.0, 1.0) : 0.0;
      Eigen::Vector3d weights = Eigen::Vector3d::Zero();
      weights[k] = 1 - t;
      weights[(k + 1) % 3] += t;
      TriangleClosestPoint candidate = make_result(p, s + t * e, weights, TriangleFeature::edge, k);
      if (candidate.squared_distance < best.squared_distance) best = candidate;
    }
    return best;
  }
  const double v = vb / sum;
  const double w = vc / sum;
  return make_result(p, a + ab * v + ac * w, Eigen::Vector3d(1 - v - w, v, w),
                     TriangleFeature::face, 0);
}

Eigen::Vector3d triangle_normal(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                const Eigen::Vector3d& c) {
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const double length = n.norm();
  return length > 0.0 ? Eigen::Vector3d(n / length) : Eigen::Vector3d::Zero();
}

double corner_angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d u = b - a;
  const Eigen::Vector3d v = c - a;
  // atan2 of |u×v| and u·v is accurate for angles near 0 and π, unlike acos.
  return std::atan2(u.cross(v).norm(), u.dot(v));
}

}  // namespace sd::sim
