#include "garment/surface_relaxation.hpp"

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace sd::garment {

SurfaceRelaxationResult relax_on_surface(meshing::QuadMesh& mesh, std::span<const char> fixed,
                                         const SurfaceLift& lift,
                                         const SurfaceRelaxationOptions& options) {
  const Eigen::Index vertex_count = mesh.vertex_count();
  if (static_cast<Eigen::Index>(fixed.size()) != vertex_count)
    throw std::invalid_argument("relax_on_surface: one fixed flag per vertex is needed");
  std::vector<std::vector<int>> neighbours(static_cast<std::size_t>(vertex_count));
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f)
    for (int k = 0; k < 4; ++k) {
      const int a = mesh.faces(f, k), b = mesh.faces(f, (k + 1) % 4);
      neighbours[static_cast<std::size_t>(a)].push_back(b);
      neighbours[static_cast<std::size_t>(b)].push_back(a);
    }
  // Each vertex's surface normal, from its last lift (the filler left the vertices on the
  // surface, so lifting them where they are only measures the normal).
  std::vector<Eigen::Vector3d> normals(static_cast<std::size_t>(vertex_count),
                                       Eigen::Vector3d::Zero());
  for (Eigen::Index v = 0; v < vertex_count; ++v) {
    auto& around = neighbours[static_cast<std::size_t>(v)];
    std::sort(around.begin(), around.end());
    around.erase(std::unique(around.begin(), around.end()), around.end());
    if (fixed[static_cast<std::size_t>(v)] || around.empty()) continue;
    const LiftedPoint here = lift(mesh.vertices.row(v).transpose());
    mesh.vertices.row(v) = here.position.transpose();
    normals[static_cast<std::size_t>(v)] = here.normal;
  }

  SurfaceRelaxationResult result;
  for (; result.sweeps < options.max_sweeps; ++result.sweeps) {
    if (result.sweeps > 0 && result.last_move <= options.tolerance) break;
    result.last_move = 0.0;
    for (Eigen::Index v = 0; v < vertex_count; ++v) {
      const auto& around = neighbours[static_cast<std::size_t>(v)];
      if (fixed[static_cast<std::size_t>(v)] || around.empty()) continue;
      const Eigen::Vector3d here = mesh.vertices.row(v).transpose();
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (int w : around) mean += mesh.vertices.row(w).transpose();
      mean /= static_cast<double>(around.size());
      Eigen::Vector3d& normal = normals[static_cast<std::size_t>(v)];
      Eigen::Vector3d step = mean - here;
      step -= step.dot(normal) * normal;  // a zero normal (off the surface) leaves it whole
      const double length = step.norm();
      if (length <= options.tolerance) continue;  // settled: no lift needed
      if (length > options.max_step) step *= options.max_step / length;
      const LiftedPoint moved = lift(here + step);
      if ((moved.position - (here + step)).norm() > options.max_step) {
        ++result.refused;
        continue;
      }
      mesh.vertices.row(v) = moved.position.transpose();
      normal = moved.normal;
      result.last_move = std::max(result.last_move, (moved.position - here).norm());
    }
  }
  return result;
}

}  // namespace sd::garment
