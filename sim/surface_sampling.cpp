#include "sim/surface_sampling.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace sd::sim {
namespace {

// Barycentric coordinates of the point of triangle (a, b, c) closest to p (Ericson, Real-Time
// Collision Detection §5.1.5, region by region).
Eigen::Vector3d closest_barycentric(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                    const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double t = d1 / (d1 - d3);
    return {1 - t, t, 0};
  }
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double t = d2 / (d2 - d6);
    return {1 - t, 0, t};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - t, t};
  }
  const double denominator = 1.0 / (va + vb + vc);
  const double v = vb * denominator, w = vc * denominator;
  return {1 - v - w, v, w};
}

}  // namespace

Eigen::MatrixX3d positions_at_material_points(const Eigen::MatrixX3d& rest,
                                              const Eigen::MatrixX3i& faces,
                                              const Eigen::MatrixX3d& positions,
                                              const Eigen::MatrixX3d& material_points) {
  if (positions.rows() != rest.rows() || faces.rows() == 0)
    throw std::invalid_argument(
        "positions_at_material_points: need one current position per rest vertex and faces");
  Eigen::MatrixX3d out(material_points.rows(), 3);
  for (Eigen::Index p = 0; p < material_points.rows(); ++p) {
    const Eigen::Vector3d point = material_points.row(p);
    double best = std::numeric_limits<double>::infinity();
    for (Eigen::Index f = 0; f < faces.rows(); ++f) {
      const Eigen::Vector3d a = rest.row(faces(f, 0)), b = rest.row(faces(f, 1)),
                            c = rest.row(faces(f, 2));
      const Eigen::Vector3d w = closest_barycentric(point, a, b, c);
      const double distance = (w(0) * a + w(1) * b + w(2) * c - point).squaredNorm();
      if (distance < best) {
        best = distance;
        out.row(p) = w(0) * positions.row(faces(f, 0)) + w(1) * positions.row(faces(f, 1)) +
                     w(2) * positions.row(faces(f, 2));
      }
    }
  }
  return out;
}

double rms_distance(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b) {
  if (a.rows() != b.rows() || a.rows() == 0)
    throw std::invalid_argument("rms_distance: the point sets must have the same, non-zero size");
  return std::sqrt((a - b).rowwise().squaredNorm().mean());
}

}  // namespace sd::sim
