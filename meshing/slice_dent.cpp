#include "meshing/slice_dent.hpp"

#include <algorithm>
#include <limits>
#include <vector>

namespace sd::meshing {
namespace {

double cross(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
}

// Andrew's monotone chain: the hull counter-clockwise, without collinear points.
std::vector<Eigen::Vector2d> convex_hull(std::vector<Eigen::Vector2d> p) {
  std::sort(p.begin(), p.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  if (p.size() < 3) return p;
  std::vector<Eigen::Vector2d> hull(2 * p.size());
  size_t k = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], p[i]) <= 0) --k;
    hull[k++] = p[i];
  }
  for (size_t i = p.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(hull[k - 2], hull[k - 1], p[i]) <= 0) --k;
    hull[k++] = p[i];
  }
  hull.resize(k - 1);
  return hull;
}

double segment_distance(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                        const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

}  // namespace

double hull_dent(const Eigen::MatrixX2d& points, Eigen::Index* deepest) {
  if (points.rows() < 3) return 0.0;
  std::vector<Eigen::Vector2d> p(static_cast<size_t>(points.rows()));
  for (Eigen::Index i = 0; i < points.rows(); ++i)
    p[static_cast<size_t>(i)] = points.row(i).transpose();
  const std::vector<Eigen::Vector2d> hull = convex_hull(p);
  if (hull.size() < 3) return 0.0;
  double depth = 0.0;
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    double d = std::numeric_limits<double>::infinity();
    for (size_t h = 0; h < hull.size(); ++h)
      d = std::min(
          d, segment_distance(p[static_cast<size_t>(i)], hull[h], hull[(h + 1) % hull.size()]));
    if (d > depth) {
      depth = d;
      if (deepest != nullptr) *deepest = i;
    }
  }
  return depth;
}

SliceDent slice_dent(const TriMesh& mesh, double from, double to, int count) {
  SliceDent result;
  if (mesh.vertex_count() == 0 || count < 1) return result;
  const double low = mesh.vertices.col(1).minCoeff(), high = mesh.vertices.col(1).maxCoeff();
  for (int s = 0; s < count; ++s) {
    const double t = count == 1 ? from : from + (to - from) * s / (count - 1);
    const double y = low + t * (high - low);
    std::vector<Eigen::Vector3d> cut;
    for (Eigen::Index f = 0; f < mesh.face_count(); ++f)
      for (int k = 0; k < 3; ++k) {
        const int a = mesh.faces(f, k), b = mesh.faces(f, (k + 1) % 3);
        if (a > b) continue;  // each edge from one side only (both sides give the same point)
        const Eigen::Vector3d pa = mesh.vertices.row(a), pb = mesh.vertices.row(b);
        if ((pa.y() - y) * (pb.y() - y) > 0 || pa.y() == pb.y()) continue;
        cut.push_back(pa + (y - pa.y()) / (pb.y() - pa.y()) * (pb - pa));
      }
    if (cut.empty()) continue;
    ++result.slices;
    Eigen::MatrixX2d xz(static_cast<Eigen::Index>(cut.size()), 2);
    for (size_t i = 0; i < cut.size(); ++i)
      xz.row(static_cast<Eigen::Index>(i)) << cut[i].x(), cut[i].z();
    Eigen::Index deepest = 0;
    const double depth = hull_dent(xz, &deepest);
    if (depth > result.depth) {
      result.depth = depth;
      result.height = y;
      result.where = cut[static_cast<size_t>(deepest)];
    }
  }
  return result;
}

}  // namespace sd::meshing
