#include "sim/surface_sampling.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "sim/collision_geometry.hpp"

namespace sd::sim {

std::vector<MaterialLocation> locate_material_points(const Eigen::MatrixX3d& rest,
                                                     const Eigen::MatrixX3i& faces,
                                                     const Eigen::MatrixX3d& material_points) {
  if (faces.rows() == 0)
    throw std::invalid_argument("locate_material_points: the mesh has no faces");
  std::vector<MaterialLocation> located(static_cast<std::size_t>(material_points.rows()));
  for (Eigen::Index p = 0; p < material_points.rows(); ++p) {
    const Eigen::Vector3d point = material_points.row(p).transpose();
    double best = std::numeric_limits<double>::infinity();
    for (Eigen::Index f = 0; f < faces.rows(); ++f) {
      const TriangleClosestPoint closest = closest_point_on_triangle(
          point, rest.row(faces(f, 0)), rest.row(faces(f, 1)), rest.row(faces(f, 2)));
      if (closest.squared_distance < best) {
        best = closest.squared_distance;
        located[static_cast<std::size_t>(p)] = {static_cast<int>(f), closest.barycentric};
      }
    }
  }
  return located;
}

Eigen::MatrixX3d positions_at(const std::vector<MaterialLocation>& located,
                              const Eigen::MatrixX3i& faces, const Eigen::MatrixX3d& positions) {
  Eigen::MatrixX3d out(static_cast<Eigen::Index>(located.size()), 3);
  for (std::size_t p = 0; p < located.size(); ++p) {
    const MaterialLocation& l = located[p];
    out.row(static_cast<Eigen::Index>(p)) = l.weights(0) * positions.row(faces(l.face, 0)) +
                                            l.weights(1) * positions.row(faces(l.face, 1)) +
                                            l.weights(2) * positions.row(faces(l.face, 2));
  }
  return out;
}

Eigen::MatrixX3d positions_at_material_points(const Eigen::MatrixX3d& rest,
                                              const Eigen::MatrixX3i& faces,
                                              const Eigen::MatrixX3d& positions,
                                              const Eigen::MatrixX3d& material_points) {
  if (positions.rows() != rest.rows() || faces.rows() == 0)
    throw std::invalid_argument(
        "positions_at_material_points: need one current position per rest vertex and faces");
  return positions_at(locate_material_points(rest, faces, material_points), faces, positions);
}

double rms_distance(const Eigen::MatrixX3d& a, const Eigen::MatrixX3d& b) {
  if (a.rows() != b.rows() || a.rows() == 0)
    throw std::invalid_argument("rms_distance: the point sets must have the same, non-zero size");
  return std::sqrt((a - b).rowwise().squaredNorm().mean());
}

}  // namespace sd::sim
