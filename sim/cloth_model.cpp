#include "sim/cloth_model.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <sstream>
#include <string>
#include <utility>

#include <Eigen/Geometry>
#include <spdlog/spdlog.h>

#include "sim/element_forces.hpp"

namespace sd::sim {
namespace {

using Eigen::Vector3d;

std::string triangle_name(Eigen::Index f) { return "triangle " + std::to_string(f); }

// Warp direction of one triangle in its plane, unit length.
Vector3d triangle_warp(const ClothInput& input, Eigen::Index f, const Vector3d& normal) {
  const auto in_plane = [&](const Vector3d& d) { return Vector3d(d - d.dot(normal) * normal); };
  if (input.warp.rows() > 0) {
    const Vector3d warp = in_plane(input.warp.row(f).transpose());
    if (!(warp.norm() > 1e-6))
      throw InvalidClothError(triangle_name(f) +
                              ": the warp direction is (nearly) perpendicular to the triangle");
    return warp.normalized();
  }
  // The in-plane direction closest to `up`; a triangle facing up (horizontal cloth) has none,
  // then the projection of −Z (away from the viewer of a front view) is used, then +X.
  for (const Vector3d& candidate : {input.up, Vector3d(-Vector3d::UnitZ()), Vector3d(Vector3d::UnitX())}) {
    const Vector3d warp = in_plane(candidate);
    if (warp.norm() > 1e-3 * candidate.norm()) return warp.normalized();
  }
  return in_plane(Vector3d::UnitY()).normalized();
}

void check_input(const ClothInput& input) {
  const Eigen::Index n = input.rest_positions.rows();
  if (n == 0 || input.triangles.rows() == 0)
    throw InvalidClothError("the cloth mesh has no vertices or no triangles");
  if (!input.rest_positions.allFinite())
    throw InvalidClothError("the cloth rest positions contain a non-finite coordinate");
  if (input.warp.rows() != 0 && input.warp.rows() != input.triangles.rows())
    throw InvalidClothError("the warp directions must be given for every triangle (" +
                            std::to_string(input.triangles.rows()) + "), got " +
                            std::to_string(input.warp.rows()));
  for (Eigen::Index f = 0; f < input.triangles.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int v = input.triangles(f, k);
      if (v < 0 || v >= n)
        throw InvalidClothError(triangle_name(f) + " uses vertex " + std::to_string(v) +
                                " but the mesh has " + std::to_string(n) + " vertices");
    }
}

}  // namespace

void scale_rest_shapes(ClothModel& model, const Eigen::VectorXd& scale) {
  if (scale.size() != static_cast<Eigen::Index>(model.triangles.size()))
    throw InvalidClothError("a rest-shape scale is needed for every triangle (" +
                            std::to_string(scale.size()) + " given, " +
                            std::to_string(model.triangles.size()) + " triangles)");
  model.mass.setZero();
  model.vertex_area.setZero();
  for (std::size_t t = 0; t < model.triangles.size(); ++t) {
    const double e = scale(static_cast<Eigen::Index>(t));
    if (!(e > 0.0) || !std::isfinite(e))
      throw InvalidClothError("rest-shape scale " + std::to_string(e) + " of triangle " +
                              std::to_string(t) + " is not positive");
    TriangleElement& element = model.triangles[t];
    element.du /= e;
    element.dv /= e;
    element.rest_area *= e * e;
    for (int v : element.vertices) {
      model.vertex_area[v] += element.rest_area / 3.0;
      model.mass[v] += model.fabric.area_density * element.rest_area / 3.0;
    }
  }
}

Eigen::VectorXd flatten_positions(const Eigen::MatrixX3d& positions) {
  Eigen::VectorXd flat(3 * positions.rows());
  for (Eigen::Index i = 0; i < positions.rows(); ++i) flat.segment<3>(3 * i) = positions.row(i);
  return flat;
}

Eigen::MatrixX3d unflatten_positions(const Eigen::VectorXd& flat) {
  Eigen::MatrixX3d positions(flat.size() / 3, 3);
  for (Eigen::Index i = 0; i < positions.rows(); ++i) positions.row(i) = flat.segment<3>(3 * i);
  return positions;
}

ClothModel build_cloth_model(const ClothInput& input, const FabricParameters& fabric,
                             const ClothModelOptions& options) {
  fabric.validate();
  check_input(input);
  ClothModel model;
  model.fabric = fabric;
  const int n = static_cast<int>(input.rest_positions.rows());
  model.vertex_count = n;
  model.mass = Eigen::VectorXd::Zero(n);
  model.vertex_area = Eigen::VectorXd::Zero(n);
  const Eigen::MatrixX3d& rest = input.rest_positions;
  double extent = (rest.colwise().maxCoeff() - rest.colwise().minCoeff()).norm();
  if (extent <= 0.0) extent = 1.0;

  // Triangles: flatten each rest triangle in its own (warp, weft) frame.
  model.triangles.resize(input.triangles.rows());
  for (Eigen::Index f = 0; f < input.triangles.rows(); ++f) {
    TriangleElement& t = model.triangles[f];
    for (int k = 0; k < 3; ++k) t.vertices[k] = input.triangles(f, k);
    const Vector3d p0 = rest.row(t.vertices[0]);
    const Vector3d p1 = rest.row(t.vertices[1]);
    const Vector3d p2 = rest.row(t.vertices[2]);
    const Vector3d cross = (p1 - p0).cross(p2 - p0);
    t.rest_area = 0.5 * cross.norm();
    if (!(t.rest_area > 1e-14 * extent * extent) || t.vertices[0] == t.vertices[1] ||
        t.vertices[1] == t.vertices[2] || t.vertices[0] == t.vertices[2])
      throw InvalidClothError(triangle_name(f) + " has (nearly) zero rest area");
    const Vector3d normal = cross.normalized();
    const Vector3d warp = triangle_warp(input, f, normal);
    const Vector3d weft = normal.cross(warp);
    // [w_u w_v] = [x1−x0, x2−x0]·D⁻¹, D = [[Δu1, Δu2], [Δv1, Δv2]] (rest coordinates).
    Eigen::Matrix2d d;
    d << (p1 - p0).dot(warp), (p2 - p0).dot(warp), (p1 - p0).dot(weft), (p2 - p0).dot(weft);
    const Eigen::Matrix2d inverse = d.inverse();
    t.du = Vector3d(-inverse(0, 0) - inverse(1, 0), inverse(0, 0), inverse(1, 0));
    t.dv = Vector3d(-inverse(0, 1) - inverse(1, 1), inverse(0, 1), inverse(1, 1));
    for (int k = 0; k < 3; ++k) {
      model.vertex_area[t.vertices[k]] += t.rest_area / 3.0;
      model.mass[t.vertices[k]] += fabric.area_density * t.rest_area / 3.0;
    }
  }

  // Hinges: each edge with exactly two triangles. The face edges sorted by (min, max) vertex,
  // then face and corner: runs of equal edges are the faces around an edge, in the order the
  // faces come (a flat sort instead of a map: this runs after every adaptive topology change).
  struct FaceEdge {
    int low, high, face, corner;  // corner: of the edge's first vertex in traversal order
  };
  std::vector<FaceEdge> face_edges;
  face_edges.reserve(3 * model.triangles.size());
  for (int f = 0; f < static_cast<int>(model.triangles.size()); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = model.triangles[f].vertices[k];
      const int b = model.triangles[f].vertices[(k + 1) % 3];
      face_edges.push_back({std::min(a, b), std::max(a, b), f, k});
    }
  std::sort(face_edges.begin(), face_edges.end(), [](const FaceEdge& p, const FaceEdge& q) {
    return std::tie(p.low, p.high, p.face, p.corner) < std::tie(q.low, q.high, q.face, q.corner);
  });
  int non_manifold = 0;
  for (std::size_t begin = 0; begin < face_edges.size();) {
    std::size_t end = begin + 1;
    while (end < face_edges.size() && face_edges[end].low == face_edges[begin].low &&
           face_edges[end].high == face_edges[begin].high)
      ++end;
    const std::size_t count = end - begin;
    const FaceEdge& e0 = face_edges[begin];
    const FaceEdge& e1 = face_edges[begin + (count > 1 ? 1 : 0)];
    begin = end;
    if (count == 1) continue;
    if (count > 2) {
      ++non_manifold;
      continue;
    }
    const auto& first = model.triangles[e0.face];
    const auto& second = model.triangles[e1.face];
    HingeElement h;
    h.vertices[0] = first.vertices[e0.corner];
    h.vertices[1] = first.vertices[(e0.corner + 1) % 3];
    h.vertices[2] = first.vertices[(e0.corner + 2) % 3];
    h.vertices[3] = second.vertices[(e1.corner + 2) % 3];
    const Vector3d p0 = rest.row(h.vertices[0]);
    const Vector3d p1 = rest.row(h.vertices[1]);
    h.weight = (p1 - p0).squaredNorm() / (first.rest_area + second.rest_area);
    if (options.bend_rest == BendRestShape::designed)
      h.rest_angle = dihedral_angle(p0, p1, rest.row(h.vertices[2]).transpose(),
                                    rest.row(h.vertices[3]).transpose());
    model.hinges.push_back(h);
  }
  if (non_manifold > 0)
    spdlog::warn("cloth mesh: {} non-manifold edges get no bending stiffness", non_manifold);

  // Block sparsity pattern: vertex adjacency through triangles and hinges, as one flat array
  // (CSR by vertex: room for every element's entries, then each vertex's run sorted and
  // deduplicated in place).
  std::vector<int> start(n + 1, 0);
  for (int i = 0; i < n; ++i) start[i + 1] = 1;  // itself
  for (const TriangleElement& t : model.triangles)
    for (int v : t.vertices) start[v + 1] += 2;
  for (const HingeElement& h : model.hinges)
    for (int v : h.vertices) start[v + 1] += 3;
  for (int i = 0; i < n; ++i) start[i + 1] += start[i];
  std::vector<int> fill(start.begin(), start.end() - 1);
  std::vector<int> neighbours(static_cast<std::size_t>(start[n]));
  for (int i = 0; i < n; ++i) neighbours[fill[i]++] = i;
  const auto connect = [&](const int* vertices, int count) {
    for (int k = 0; k < count; ++k)
      for (int l = 0; l < count; ++l)
        if (k != l) neighbours[fill[vertices[k]]++] = vertices[l];
  };
  for (const TriangleElement& t : model.triangles) connect(t.vertices.data(), 3);
  for (const HingeElement& h : model.hinges) connect(h.vertices.data(), 4);
  std::vector<int> size(n);  // distinct neighbours of each vertex, at the start of its run
  for (int i = 0; i < n; ++i) {
    const auto first = neighbours.begin() + start[i];
    std::sort(first, neighbours.begin() + start[i + 1]);
    size[i] = static_cast<int>(std::unique(first, neighbours.begin() + start[i + 1]) - first);
  }
  std::vector<int> outer(3 * n + 1, 0);
  std::vector<int> inner;
  inner.reserve(static_cast<std::size_t>(9 * start[n]));
  for (int i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) {
      for (int m = 0; m < size[i]; ++m)
        for (int b = 0; b < 3; ++b) inner.push_back(3 * neighbours[start[i] + m] + b);
      outer[3 * i + a + 1] = static_cast<int>(inner.size());
    }
  }
  const std::vector<double> zeros(inner.size(), 0.0);
  model.pattern.zero_matrix = Eigen::Map<const SparseMatrixR>(
      3 * n, 3 * n, static_cast<int>(inner.size()), outer.data(), inner.data(), zeros.data());
  const auto offset = [&](int i, int j) {
    const auto first = neighbours.begin() + start[i];
    return 3 * static_cast<int>(std::lower_bound(first, first + size[i], j) - first);
  };
  model.pattern.diagonal_offsets.resize(n);
  for (int i = 0; i < n; ++i) model.pattern.diagonal_offsets[i] = offset(i, i);
  for (TriangleElement& t : model.triangles)
    for (int k = 0; k < 3; ++k)
      for (int l = 0; l < 3; ++l) t.blocks[3 * k + l] = offset(t.vertices[k], t.vertices[l]);
  for (HingeElement& h : model.hinges)
    for (int k = 0; k < 4; ++k)
      for (int l = 0; l < 4; ++l) h.blocks[4 * k + l] = offset(h.vertices[k], h.vertices[l]);
  return model;
}

}  // namespace sd::sim
