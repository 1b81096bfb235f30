#include "garment/surface_untangle.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <limits>
#include <set>
#include <vector>

namespace sd::garment {
namespace {

// Quads count as folded below this worst corner (sin of the corner angle, against the normal);
// vertices are moved until their quads clear a small margin above it.
constexpr double kFolded = 0.0;
constexpr double kMargin = 0.05;

using Face = std::array<int, 4>;

// Smallest scaled corner value of quad f: ((e1 × e2) · n) / (|e1| |e2|) over its four corners.
double worst_corner(const meshing::QuadMesh& mesh, const Face& f, const Eigen::Vector3d& n) {
  double worst = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d p = mesh.vertices.row(f[static_cast<size_t>(k)]).transpose();
    const Eigen::Vector3d e1 =
        mesh.vertices.row(f[static_cast<size_t>((k + 1) % 4)]).transpose() - p;
    const Eigen::Vector3d e2 =
        mesh.vertices.row(f[static_cast<size_t>((k + 3) % 4)]).transpose() - p;
    const double scale = e1.norm() * e2.norm();
    worst = std::min(worst, scale > 0 ? e1.cross(e2).dot(n) / scale : -1.0);
  }
  return worst;
}

}  // namespace

UntangleResult untangle_on_surface(
    meshing::QuadMesh& mesh, std::span<const char> fixed,
    const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& project,
    const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& normal, int sweeps) {
  const size_t vertex_count = static_cast<size_t>(mesh.vertex_count());
  std::vector<Face> faces(static_cast<size_t>(mesh.face_count()));
  std::vector<std::vector<int>> incident(vertex_count);
  for (size_t f = 0; f < faces.size(); ++f)
    for (int k = 0; k < 4; ++k) {
      faces[f][static_cast<size_t>(k)] = mesh.faces(static_cast<Eigen::Index>(f), k);
      incident[static_cast<size_t>(faces[f][static_cast<size_t>(k)])].push_back(
          static_cast<int>(f));
    }
  auto centre = [&](const Face& f) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int v : f) c += mesh.vertices.row(v).transpose();
    return Eigen::Vector3d(c / 4);
  };
  // Surface normals per quad, taken once: the moves are small, and each query costs a closest
  // point search on the body.
  std::vector<Eigen::Vector3d> normals(faces.size());
  for (size_t f = 0; f < faces.size(); ++f) normals[f] = normal(centre(faces[f]));
  auto count_folded = [&] {
    int folded = 0;
    for (size_t f = 0; f < faces.size(); ++f)
      folded += worst_corner(mesh, faces[f], normals[f]) < kFolded ? 1 : 0;
    return folded;
  };

  UntangleResult result;
  result.folded_before = result.folded_after = count_folded();
  for (int sweep = 0; sweep < sweeps && result.folded_after > 0; ++sweep) {
    // Free vertices of the quads below the margin.
    std::set<int> movable;
    for (size_t f = 0; f < faces.size(); ++f)
      if (worst_corner(mesh, faces[f], normals[f]) < kMargin)
        for (int v : faces[f])
          if (!fixed[static_cast<size_t>(v)]) movable.insert(v);
    int moved = 0;
    for (int v : movable) {
      const auto& around = incident[static_cast<size_t>(v)];
      auto local = [&] {
        double worst = std::numeric_limits<double>::infinity();
        for (int f : around)
          worst = std::min(worst, worst_corner(mesh, faces[static_cast<size_t>(f)],
                                               normals[static_cast<size_t>(f)]));
        return worst;
      };
      // Candidates: the parallelogram completion a + c − b of each quad (a, c its neighbours
      // there, b opposite), averaged; the mean of the edge neighbours; halfway to each.
      Eigen::Vector3d parallelogram = Eigen::Vector3d::Zero(), neighbours = Eigen::Vector3d::Zero();
      for (int f : around) {
        const Face& q = faces[static_cast<size_t>(f)];
        const int k = static_cast<int>(std::find(q.begin(), q.end(), v) - q.begin());
        const Eigen::Vector3d a =
            mesh.vertices.row(q[static_cast<size_t>((k + 1) % 4)]).transpose();
        const Eigen::Vector3d b =
            mesh.vertices.row(q[static_cast<size_t>((k + 2) % 4)]).transpose();
        const Eigen::Vector3d c =
            mesh.vertices.row(q[static_cast<size_t>((k + 3) % 4)]).transpose();
        parallelogram += a + c - b;
        neighbours += 0.5 * (a + c);
      }
      parallelogram /= static_cast<double>(around.size());
      neighbours /= static_cast<double>(around.size());
      const Eigen::Vector3d here = mesh.vertices.row(v).transpose();
      const std::array<Eigen::Vector3d, 4> candidates = {
          parallelogram, neighbours, 0.5 * (here + parallelogram), 0.5 * (here + neighbours)};
      double best = local();
      Eigen::Vector3d best_place = here;
      for (const Eigen::Vector3d& candidate : candidates) {
        const Eigen::Vector3d place = project ? project(candidate) : candidate;
        mesh.vertices.row(v) = place.transpose();
        const double value = local();
        if (value > best + 1e-9) best = value, best_place = place;
      }
      mesh.vertices.row(v) = best_place.transpose();
      if (best_place != here) ++moved;
    }
    result.moves += moved;
    result.folded_after = count_folded();
    if (moved == 0) break;
  }
  return result;
}

}  // namespace sd::garment
