#include "meshing/quad_quality.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

namespace sd::meshing {
namespace {

// Regular valence of each vertex: 4 inside, 3 on the boundary, 2 at a corner.
Eigen::VectorXi regular_valences(const QuadMesh& mesh, std::span<const int> corner_vertices) {
  Eigen::VectorXi regular = Eigen::VectorXi::Constant(mesh.vertices.rows(), 4);
  for (const int v : boundary_loop(mesh)) regular(v) = 3;
  for (const int c : corner_vertices) regular(c) = 2;
  return regular;
}

}  // namespace

QuadQuality measure_valence(const QuadMesh& mesh, std::span<const int> corner_vertices) {
  QuadQuality quality;
  const Eigen::VectorXi valence = vertex_valences(mesh);
  const Eigen::VectorXi regular = regular_valences(mesh, corner_vertices);
  for (Eigen::Index v = 0; v < valence.size(); ++v) {
    const int deviation = std::abs(valence(v) - regular(v));
    quality.distortion += deviation;
    quality.irregular_vertices += deviation != 0 ? 1 : 0;
  }
  return quality;
}

QuadQuality measure_quality(const QuadMesh& mesh, std::span<const int> corner_vertices) {
  QuadQuality quality = measure_valence(mesh, corner_vertices);
  // Column per vertex / per face: the rows of the #V by 3 matrices are strided in memory.
  const Eigen::Matrix3Xd x = mesh.vertices.transpose();
  const Eigen::Matrix4Xi q = mesh.faces.transpose();
  // Edge k of quad f runs from its corner k to corner k+1; corner k is spanned by edge k and
  // the reverse of edge k−1 (x_{k−1} − x_k = −(x_k − x_{k−1}) exactly, so each edge vector and
  // length is computed once per quad instead of once per corner).
  std::array<Eigen::Vector3d, 4> edge;
  std::array<double, 4> length;
  auto quad_edges = [&](Eigen::Index f) {
    for (Eigen::Index k = 0; k < 4; ++k)
      edge[static_cast<size_t>(k)] = x.col(q((k + 1) % 4, f)) - x.col(q(k, f));
  };
  // Vertex normals: sums of the corner cross products of the incident quads.
  Eigen::Matrix3Xd normals = Eigen::Matrix3Xd::Zero(3, x.cols());
  for (Eigen::Index f = 0; f < q.cols(); ++f) {
    quad_edges(f);
    for (size_t k = 0; k < 4; ++k) {
      const Eigen::Vector3d e2 = -edge[(k + 3) % 4];
      normals.col(q(static_cast<Eigen::Index>(k), f)) += edge[k].cross(e2);
    }
  }
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double convex_cos_min = kInf, convex_cos_max = -kInf, reflex_cos_min = kInf,
         reflex_cos_max = -kInf;
  double max_aspect = 0, jac_min = std::numeric_limits<double>::infinity(), jac_sum = 0;
  for (Eigen::Index f = 0; f < q.cols(); ++f) {
    double quad_jac = std::numeric_limits<double>::infinity();
    double shortest = std::numeric_limits<double>::infinity(), longest = 0;
    // The quad's reference normal: the sum of its vertices' normals, so that a folded corner
    // (or a whole flipped quad among good neighbours) shows a negative Jacobian.
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) n += normals.col(q(k, f));
    const double nn = n.norm();
    const Eigen::Vector3d unit_normal = nn > 0 ? Eigen::Vector3d(n / nn) : n;
    quad_edges(f);
    for (size_t k = 0; k < 4; ++k) length[k] = edge[k].norm();
    for (size_t k = 0; k < 4; ++k) {
      const Eigen::Vector3d& e1 = edge[k];
      const Eigen::Vector3d e2 = -edge[(k + 3) % 4];
      const double l1 = length[k], l2 = length[(k + 3) % 4];
      shortest = std::min(shortest, l1);
      longest = std::max(longest, l1);
      const double cosine =
          (l1 > 0 && l2 > 0) ? std::clamp(e1.dot(e2) / (l1 * l2), -1.0, 1.0) : 1.0;
      const double jac =
          (l1 > 0 && l2 > 0 && nn > 0) ? e1.cross(e2).dot(unit_normal) / (l1 * l2) : 0.0;
      // A corner whose scaled Jacobian is negative is reflex or folded: its angle is
      // 360° − acos(cosine) > 180°. The angle is monotonic in the cosine on either side, so
      // only the extreme cosines are kept and acos is taken four times per mesh.
      if (jac < 0) {
        reflex_cos_min = std::min(reflex_cos_min, cosine);
        reflex_cos_max = std::max(reflex_cos_max, cosine);
      } else {
        convex_cos_min = std::min(convex_cos_min, cosine);
        convex_cos_max = std::max(convex_cos_max, cosine);
      }
      quad_jac = std::min(quad_jac, jac);
    }
    max_aspect = std::max(
        max_aspect, shortest > 0 ? longest / shortest : std::numeric_limits<double>::infinity());
    jac_min = std::min(jac_min, quad_jac);
    jac_sum += quad_jac;
    // A corner of exactly 180° (a quad at a side vertex of valence 2) is flat, not folded.
    if (quad_jac < -1e-9) ++quality.inverted_quads;
  }
  if (q.cols() > 0) {
    constexpr double kDegrees = 180 / std::numbers::pi;
    double min_angle = kInf, max_angle = 0;
    if (convex_cos_max > -kInf) {
      min_angle = std::acos(convex_cos_max) * kDegrees;
      max_angle = std::acos(convex_cos_min) * kDegrees;
    }
    if (reflex_cos_max > -kInf) {
      min_angle =
          std::min(min_angle, (2 * std::numbers::pi - std::acos(reflex_cos_min)) * kDegrees);
      max_angle =
          std::max(max_angle, (2 * std::numbers::pi - std::acos(reflex_cos_max)) * kDegrees);
    }
    quality.min_angle_deg = min_angle;
    quality.max_angle_deg = max_angle;
    quality.max_aspect_ratio = max_aspect;
    quality.scaled_jacobian_min = jac_min;
    quality.scaled_jacobian_mean = jac_sum / static_cast<double>(q.cols());
  }
  return quality;
}

double mean_side(const QuadMesh& mesh, Eigen::Index face) {
  double perimeter = 0;
  for (int k = 0; k < 4; ++k)
    perimeter +=
        (mesh.vertices.row(mesh.faces(face, (k + 1) % 4)) - mesh.vertices.row(mesh.faces(face, k)))
            .norm();
  return perimeter / 4;
}

}  // namespace sd::meshing
