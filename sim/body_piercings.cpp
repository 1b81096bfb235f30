#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <tuple>
#include <utility>
#include <vector>

#include "sim/body_collider.hpp"
#include "sim/parallel.hpp"

// The other half of body-cloth contact: body vertices that poke through the cloth's triangles
// (a thin cloth over a sharp body feature), found over a hashed grid of the cloth.
namespace sd::sim {
namespace {

Eigen::Vector3d row(const Eigen::VectorXd& x, Eigen::Index vertex) {
  return x.segment<3>(3 * vertex);
}

// Body vertices per chunk at least: most fall outside the cloth's box and cost a comparison.
constexpr int kBodyVertexGrain = 1024;

// The height of body vertex b over the cloth where the closest point of triangle t to it lies on
// one of t's corners or inner edges: along the cloth's angle-weighted pseudo-normal there
// (Bærentzen & Aanæs 2005, the rule the body's own sign follows), the normals of the triangles
// around the feature turned to the side of t's `normal`. The plane of t alone is not the
// cloth's side there: on the arms-lowering t-shirt an arm vertex in the armpit lay 1.1 mm above
// the plane of one triangle around a cloth vertex, 8 mm beside it, and 3 mm in front of the
// cloth by the pseudo-normal (every other triangle around the vertex had it in front), and it
// was counted as through the cloth.
double feature_height(const Eigen::Vector3d& b, const TriangleClosestPoint& closest,
                      const std::array<int, 3>& triangle, const Eigen::Vector3d& normal,
                      const ClothTriangles& cloth, const Eigen::VectorXd& x) {
  const double plane = (b - closest.point).dot(normal);
  if (closest.feature == TriangleFeature::face || cloth.vertex_offsets.empty()) return plane;
  const auto turned = [&](const std::array<int, 3>& u) {
    Eigen::Vector3d n = triangle_normal(row(x, u[0]), row(x, u[1]), row(x, u[2]));
    return n.dot(normal) < 0.0 ? Eigen::Vector3d(-n) : n;
  };
  const auto around = [&](int v) {
    return std::pair(cloth.vertex_triangles.begin() + cloth.vertex_offsets[v],
                     cloth.vertex_triangles.begin() + cloth.vertex_offsets[v + 1]);
  };
  Eigen::Vector3d pseudo = Eigen::Vector3d::Zero();
  if (closest.feature == TriangleFeature::vertex) {
    const int v = triangle[closest.index];
    const auto [first, last] = around(v);
    for (auto it = first; it != last; ++it) {
      const std::array<int, 3>& u = cloth.triangles[static_cast<std::size_t>(*it)];
      const int k = u[0] == v ? 0 : u[1] == v ? 1 : 2;
      const Eigen::Vector3d e1 = row(x, u[(k + 1) % 3]) - row(x, v);
      const Eigen::Vector3d e2 = row(x, u[(k + 2) % 3]) - row(x, v);
      const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
      pseudo += angle * turned(u);
    }
  } else {  // an edge: the triangles holding both of its ends
    const int a = triangle[closest.index], c = triangle[(closest.index + 1) % 3];
    const auto [first, last] = around(a);
    for (auto it = first; it != last; ++it) {
      const std::array<int, 3>& u = cloth.triangles[static_cast<std::size_t>(*it)];
      if (u[0] == c || u[1] == c || u[2] == c) pseudo += turned(u);
    }
  }
  const double length = pseudo.norm();
  return length > 1e-12 ? (b - closest.point).dot(pseudo / length) : plane;
}

}  // namespace

ClothTriangles::ClothTriangles(std::vector<std::array<int, 3>> list)
    : triangles(std::move(list)), open_edges(triangles.size(), 0) {
  std::vector<std::tuple<int, int, int>> edges;  // (smaller vertex, larger vertex, 3t + k)
  edges.reserve(3 * triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = triangles[t][k], b = triangles[t][(k + 1) % 3];
      edges.emplace_back(std::min(a, b), std::max(a, b), static_cast<int>(3 * t) + k);
    }
  std::sort(edges.begin(), edges.end());
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i + 1;
    while (j < edges.size() && std::get<0>(edges[j]) == std::get<0>(edges[i]) &&
           std::get<1>(edges[j]) == std::get<1>(edges[i]))
      ++j;
    if (j == i + 1) open_edges[std::get<2>(edges[i]) / 3] |= 1 << (std::get<2>(edges[i]) % 3);
    i = j;
  }
  int vertex_count = 0;
  for (const auto& t : triangles)
    for (int v : t) vertex_count = std::max(vertex_count, v + 1);
  vertex_offsets.assign(static_cast<std::size_t>(vertex_count) + 1, 0);
  for (const auto& t : triangles)
    for (int v : t) ++vertex_offsets[static_cast<std::size_t>(v) + 1];
  for (int v = 0; v < vertex_count; ++v) vertex_offsets[v + 1] += vertex_offsets[v];
  vertex_triangles.assign(static_cast<std::size_t>(vertex_offsets.back()), 0);
  std::vector<int> fill(vertex_offsets.begin(), vertex_offsets.end() - 1);
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (int v : triangles[t]) vertex_triangles[fill[v]++] = static_cast<int>(t);
}

std::optional<BodyPiercing> BodyCollider::piercing_of_pair(const Eigen::VectorXd& x,
                                                           const std::array<int, 3>& triangle,
                                                           int triangle_index, int body_vertex,
                                                           const ClothTriangles* cloth) const {
  const Eigen::Vector3d b = corner(body_vertex, 1.0);
  const Eigen::Vector3d p0 = row(x, triangle[0]), p1 = row(x, triangle[1]),
                        p2 = row(x, triangle[2]);
  Eigen::Vector3d normal = triangle_normal(p0, p1, p2);
  const double facing = normal.dot(vertex_normals_[body_vertex].normalized());
  if (std::abs(facing) < 0.2) return std::nullopt;  // degenerate (zero normal) or edge-on
  if (facing < 0.0) normal = -normal;
  BodyPiercing piercing;
  piercing.body_vertex = body_vertex;
  piercing.cloth_triangle = triangle_index;
  const TriangleClosestPoint closest = closest_point_on_triangle(b, p0, p1, p2);
  piercing.barycentric = closest.barycentric;
  piercing.normal = normal;
  piercing.height = cloth != nullptr ? feature_height(b, closest, triangle, normal, *cloth, x)
                                     : (b - p0).dot(normal);
  piercing.body_velocity = velocities_[body_vertex];
  return piercing;
}

std::vector<BodyPiercing> BodyCollider::find_piercings(
    const Eigen::VectorXd& x, const ClothTriangles& cloth, double min_height, double max_height,
    double unchecked_height, PiercingQueryStats* stats_out, bool every_triangle,
    bool pseudo_normal_sides) const {
  const std::vector<std::array<int, 3>>& triangles = cloth.triangles;
  PiercingQueryStats stats;
  std::vector<BodyPiercing> result;
  if (x.size() % 3 != 0)
    throw std::invalid_argument("cloth positions must hold 3 coordinates per vertex");
  if (!x.allFinite()) throw std::invalid_argument("cloth positions must be finite");
  for (const auto& t : triangles)
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || 3 * static_cast<Eigen::Index>(t[k]) >= x.size())
        throw std::invalid_argument("a cloth triangle's vertex index is out of range");
  if (triangles.empty() || !(max_height > min_height)) return result;
  // Cells as large as the longest cloth edge or the reach, whichever is larger (see below).
  Eigen::Vector3d low = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d high = -low;
  double longest = 0.0;
  for (const auto& t : triangles)
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d a = row(x, t[k]);
      low = low.cwiseMin(a);
      high = high.cwiseMax(a);
      longest = std::max(longest, (row(x, t[(k + 1) % 3]) - a).norm());
    }
  if (!(longest > 0.0)) return result;
  // The grid covers the cloth's box, expanded by the largest height reported.
  const double reach = std::max({std::abs(min_height), std::abs(max_height), 1e-9});
  low.array() -= reach;
  high.array() += reach;
  // Cells at least as large as the reach too: with cells of the longest edge alone, a fine
  // cloth (0.15 mm edges) and a reach of centimetres put each triangle in (2·reach/edge)³ cells,
  // millions each (the 17 GB of a sketched strip's piercing count). With cell ≥ max(edge, reach)
  // a grown box spans at most 4 cells per axis.
  const double cell = std::max(longest, reach);
  const Eigen::Vector3d extent = high - low;
  constexpr std::int64_t kMaxCells = 1 << 20;  // per axis, so that a key packs in 63 bits
  if ((extent / cell).maxCoeff() >= static_cast<double>(kMaxCells)) return result;
  const auto cell_of = [&](const Eigen::Vector3d& p) {
    return Eigen::Vector3i(static_cast<int>((p.x() - low.x()) / cell),
                           static_cast<int>((p.y() - low.y()) / cell),
                           static_cast<int>((p.z() - low.z()) / cell));
  };
  // Every cell a triangle's box, grown by the reach (where the body vertices it can cover lie),
  // overlaps: the triangles of each cell in increasing order. Cells are counted and filled in
  // triangle order (a counting sort over the grid's cells, row-major i, j, k), the order the
  // sorted (cell, triangle) pairs of the first version had, so each vertex meets its triangles
  // in the same order and the result is the same bits. A sparse grid (more cells than 4 per
  // entry) keeps the sorted pairs: the count array would cost more than the sort.
  const Eigen::Vector3i dims = cell_of(high) + Eigen::Vector3i::Ones();
  std::vector<std::array<Eigen::Vector3i, 2>> boxes(triangles.size());
  std::int64_t entries = 0;
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    Eigen::Vector3d a = row(x, triangles[t][0]), b = a;
    for (int k = 1; k < 3; ++k) {
      a = a.cwiseMin(row(x, triangles[t][k]));
      b = b.cwiseMax(row(x, triangles[t][k]));
    }
    boxes[t] = {cell_of(a.array() - reach), cell_of(b.array() + reach)};
    entries += (boxes[t][1] - boxes[t][0] + Eigen::Vector3i::Ones()).cast<std::int64_t>().prod();
  }
  const std::int64_t grid_cells = dims.cast<std::int64_t>().prod();
  const bool dense = grid_cells <= std::max<std::int64_t>(4 * entries, 1 << 16);
  const auto key_of = [&](const Eigen::Vector3i& c) {
    return dense ? (static_cast<std::int64_t>(c.x()) * dims.y() + c.y()) * dims.z() + c.z()
                 : (static_cast<std::int64_t>(c.x()) * kMaxCells + c.y()) * kMaxCells + c.z();
  };
  const auto each_cell = [&](std::size_t t, const auto& visit) {
    const auto& [c0, c1] = boxes[t];
    for (int i = c0.x(); i <= c1.x(); ++i)
      for (int j = c0.y(); j <= c1.y(); ++j)
        for (int k = c0.z(); k <= c1.z(); ++k) visit(key_of({i, j, k}));
  };
  std::vector<std::int64_t> cell_start;  // per cell (dense) or listed key (sparse): first entry
  std::vector<int> cell_triangles;       // the entries, cell by cell
  std::vector<std::int64_t> keys;        // sparse: the cells holding entries, increasing
  if (dense) {
    cell_start.assign(static_cast<std::size_t>(grid_cells) + 1, 0);
    for (std::size_t t = 0; t < triangles.size(); ++t)
      each_cell(t, [&](std::int64_t key) { ++cell_start[static_cast<std::size_t>(key) + 1]; });
    for (std::size_t c = 1; c < cell_start.size(); ++c) cell_start[c] += cell_start[c - 1];
    cell_triangles.resize(static_cast<std::size_t>(entries));
    std::vector<std::int64_t> fill(cell_start.begin(), cell_start.end() - 1);
    for (std::size_t t = 0; t < triangles.size(); ++t)
      each_cell(t, [&](std::int64_t key) {
        cell_triangles[static_cast<std::size_t>(fill[static_cast<std::size_t>(key)]++)] =
            static_cast<int>(t);
      });
  } else {
    std::vector<std::pair<std::int64_t, int>> cells;
    cells.reserve(static_cast<std::size_t>(entries));
    for (std::size_t t = 0; t < triangles.size(); ++t)
      each_cell(t, [&](std::int64_t key) { cells.emplace_back(key, static_cast<int>(t)); });
    std::sort(cells.begin(), cells.end());
    cell_triangles.reserve(cells.size());
    for (std::size_t e = 0; e < cells.size(); ++e) {
      if (e == 0 || cells[e].first != cells[e - 1].first) {
        keys.push_back(cells[e].first);
        cell_start.push_back(static_cast<std::int64_t>(e));
      }
      cell_triangles.push_back(cells[e].second);
    }
    cell_start.push_back(static_cast<std::int64_t>(cells.size()));
  }
  // The triangles in the cell of point b (inside the grid), in increasing order.
  const auto triangles_at = [&](const Eigen::Vector3d& b) -> std::pair<const int*, const int*> {
    std::int64_t key = key_of(cell_of(b));
    if (!dense) {
      const auto it = std::lower_bound(keys.begin(), keys.end(), key);
      if (it == keys.end() || *it != key) return {nullptr, nullptr};
      key = it - keys.begin();
    }
    const int* first = cell_triangles.data();
    return {first + cell_start[static_cast<std::size_t>(key)],
            first + cell_start[static_cast<std::size_t>(key) + 1]};
  };
  stats.grid_entries = entries;
  // Unit normals once per triangle (zero when degenerate), not once per pair.
  std::vector<Eigen::Vector3d> normals(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t)
    normals[t] =
        triangle_normal(row(x, triangles[t][0]), row(x, triangles[t][1]), row(x, triangles[t][2]));

  // Body vertices in chunks on the simulator's threads, joined in vertex order (the same result
  // on any thread count, sim/parallel.hpp).
  const int chunks = chunk_count(vertex_count(), kBodyVertexGrain);
  std::vector<std::vector<BodyPiercing>> chunk_result(static_cast<std::size_t>(chunks));
  std::vector<PiercingQueryStats> chunk_stats(static_cast<std::size_t>(chunks));
  parallel_chunks(vertex_count(), kBodyVertexGrain, [&](int chunk, int first, int last) {
    std::vector<BodyPiercing>& found = chunk_result[static_cast<std::size_t>(chunk)];
    PiercingQueryStats& local = chunk_stats[static_cast<std::size_t>(chunk)];
    for (int v = first; v < last; ++v) {
      const Eigen::Vector3d b = corner(v, 1.0);
      if ((b - low).minCoeff() < 0.0 || (high - b).minCoeff() < 0.0) continue;
      ++local.body_vertices;
      const auto [cell_first, cell_last] = triangles_at(b);
      const Eigen::Vector3d body_normal = vertex_normals_[v].normalized();
      std::optional<BodyPiercing> best;
      for (const int* it = cell_first; it != cell_last; ++it) {
        const int t = *it;
        ++local.pairs;
        Eigen::Vector3d normal = normals[static_cast<std::size_t>(t)];
        const double facing = normal.dot(body_normal);
        // Cloth edge-on to the body surface there (or degenerate): not covering the vertex.
        if (std::abs(facing) < 0.2) continue;
        if (facing < 0.0) normal = -normal;
        // The height over the triangle's closest point is the height over its plane (the closest
        // point lies in it): the band test needs no closest point.
        const Eigen::Vector3d p0 = row(x, triangles[t][0]);
        const double plane_height = (b - p0).dot(normal);
        if (plane_height <= min_height || plane_height >= max_height) continue;
        if (!every_triangle && best && plane_height <= best->height) continue;
        // The closest point of the triangle, not only the projection: a body vertex pushed
        // through a ridge of the cloth (the shared edge of two triangles folded over it) projects
        // outside both triangles, but it is above both planes and its closest points lie on
        // the edge.
        const TriangleClosestPoint closest =
            closest_point_on_triangle(b, p0, row(x, triangles[t][1]), row(x, triangles[t][2]));
        if (closest.squared_distance >= max_height * max_height) continue;
        // At a corner or an edge the cloth's side is its pseudo-normal's, not t's plane.
        const double height = pseudo_normal_sides
                                  ? feature_height(b, closest, triangles[t], normal, cloth, x)
                                  : plane_height;
        if (height <= min_height || (!every_triangle && best && height <= best->height)) continue;
        // Not through (within the asked band below the cloth): only where the cloth covers the
        // vertex, its projection inside the triangle.
        if (height <= 0.0 && closest.feature != TriangleFeature::face) continue;
        // Closest to the cloth's open edge (or a corner on it): the vertex is beside the cloth,
        // not under it: a neck beside a neckline, a wrist beside a cuff. Over an inner edge it is
        // a ridge of the cloth folded over it, which counts.
        const std::uint8_t open = cloth.open_edges[static_cast<std::size_t>(t)];
        if (closest.feature == TriangleFeature::edge && (open >> closest.index & 1)) continue;
        if (closest.feature == TriangleFeature::vertex &&
            ((open >> closest.index & 1) || (open >> (closest.index + 2) % 3 & 1)))
          continue;
        // The triangle must dip into the body under the vertex (for a height above zero): a
        // cloth triangle lying beyond a body part, or beside it, is not pierced by it.
        if (height > unchecked_height) {
          ++local.inside_checks;
          const std::optional<BodyProximity> under =
              nearest(closest.point, 1.0, std::sqrt(closest.squared_distance) + 1e-9);
          if (!under || under->distance > 0.0) continue;
        }
        const Eigen::Vector3d w = closest.barycentric;
        BodyPiercing piercing;
        piercing.body_vertex = v;
        piercing.cloth_triangle = t;
        piercing.barycentric = w;
        piercing.normal = normal;
        piercing.height = height;
        piercing.body_velocity = velocities_[v];
        if (every_triangle)
          found.push_back(piercing);
        else
          best = piercing;
      }
      if (best) found.push_back(*best);
    }
  });
  for (std::size_t c = 0; c < chunk_result.size(); ++c) {
    result.insert(result.end(), chunk_result[c].begin(), chunk_result[c].end());
    stats.body_vertices += chunk_stats[c].body_vertices;
    stats.pairs += chunk_stats[c].pairs;
    stats.inside_checks += chunk_stats[c].inside_checks;
  }
  stats.piercings = static_cast<int>(result.size());
  if (stats_out != nullptr) *stats_out = stats;
  return result;
}

}  // namespace sd::sim
