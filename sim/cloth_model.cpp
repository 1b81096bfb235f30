// The cloth model: its triangles, the sparsity pattern of its system, and the update after an
// adaptive change (update_cloth_model). The bend elements (hinges, stencils, vertex bends) are
// made in sim/bend_elements.cpp.
#include "sim/cloth_model.hpp"

#include <spdlog/spdlog.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>

#include "sim/bend_elements.hpp"

namespace sd::sim {

std::string_view bend_model_name(BendModel model) {
  return model == BendModel::hinges ? "hinges" : "quadratic";
}

std::string_view compression_name(Compression compression) {
  return compression == Compression::buckling ? "buckling" : "linear";
}

std::optional<Compression> parse_compression(std::string_view name) {
  if (name == "linear") return Compression::linear;
  if (name == "buckling") return Compression::buckling;
  return std::nullopt;
}

std::optional<BendModel> parse_bend_model(std::string_view name) {
  if (name == "quadratic") return BendModel::quadratic;
  if (name == "hinges") return BendModel::hinges;
  return std::nullopt;
}
namespace {

using detail::calibrate_hinge_weights;
using detail::make_bend_stencils;
using detail::make_hinge;
using detail::make_vertex_bends;
using Eigen::Vector3d;

std::string triangle_name(Eigen::Index f) {
  return "triangle " + std::to_string(f);
}

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
  for (const Vector3d& candidate :
       {input.up, Vector3d(-Vector3d::UnitZ()), Vector3d(Vector3d::UnitX())}) {
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
  if (input.rest_uv.rows() != 0 &&
      (input.rest_uv.rows() != input.triangles.rows() || input.rest_uv.cols() != 6))
    throw InvalidClothError("the rest coordinates must be 6 numbers for every triangle (" +
                            std::to_string(input.triangles.rows()) + "), got " +
                            std::to_string(input.rest_uv.rows()) + " by " +
                            std::to_string(input.rest_uv.cols()));
  if (input.rest_uv.rows() != 0 && !input.rest_uv.allFinite())
    throw InvalidClothError("the rest coordinates contain a non-finite number");
  if (input.buckling_width.rows() != 0 &&
      (input.buckling_width.rows() != input.triangles.rows() ||
       !(input.buckling_width.array() > 0.0).all() || !input.buckling_width.allFinite()))
    throw InvalidClothError("the buckling widths must be 2 positive lengths for every triangle (" +
                            std::to_string(input.triangles.rows()) + "), got " +
                            std::to_string(input.buckling_width.rows()) + " rows");
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

double rest_extent(const Eigen::MatrixX3d& rest) {
  const double extent = (rest.colwise().maxCoeff() - rest.colwise().minCoeff()).norm();
  return extent > 0.0 ? extent : 1.0;
}

// The rest area of triangle (v0, v1, v2) before any scale, as make_triangle computes it.
double unscaled_rest_area(const Eigen::MatrixX3d& rest, const std::array<int, 3>& v) {
  const Vector3d p0 = rest.row(v[0]);
  return 0.5 * (Vector3d(rest.row(v[1])) - p0).cross(Vector3d(rest.row(v[2])) - p0).norm();
}

// Triangle f flattened in its own (warp, weft) frame; blocks are left for the pattern. Its
// buckling widths are input.buckling_width's, or its own extent when none are given or
// `own_widths`.
TriangleElement make_triangle(const ClothInput& input, Eigen::Index f, double extent,
                              bool own_widths = false) {
  const Eigen::MatrixX3d& rest = input.rest_positions;
  TriangleElement t;
  for (int k = 0; k < 3; ++k) t.vertices[k] = input.triangles(f, k);
  const Vector3d p0 = rest.row(t.vertices[0]);
  const Vector3d p1 = rest.row(t.vertices[1]);
  const Vector3d p2 = rest.row(t.vertices[2]);
  const Vector3d cross = (p1 - p0).cross(p2 - p0);
  t.rest_area = 0.5 * cross.norm();
  if (!(t.rest_area > 1e-14 * extent * extent) || t.vertices[0] == t.vertices[1] ||
      t.vertices[1] == t.vertices[2] || t.vertices[0] == t.vertices[2])
    throw InvalidClothError(triangle_name(f) + " has (nearly) zero rest area");
  // [w_u w_v] = [x1−x0, x2−x0]·D⁻¹, D = [[Δu1, Δu2], [Δv1, Δv2]] (rest coordinates).
  Eigen::Matrix2d d;
  if (input.rest_uv.rows() > 0) {
    const auto uv = input.rest_uv.row(f);
    d << uv(2) - uv(0), uv(4) - uv(0), uv(3) - uv(1), uv(5) - uv(1);
    t.rest_area = 0.5 * d.determinant();
    if (!(t.rest_area > 1e-14 * extent * extent))
      throw InvalidClothError(triangle_name(f) +
                              " has a (nearly) zero or inverted rest triangle "
                              "in its rest coordinates");
  } else {
    const Vector3d normal = cross.normalized();
    const Vector3d warp = triangle_warp(input, f, normal);
    const Vector3d weft = normal.cross(warp);
    d << (p1 - p0).dot(warp), (p2 - p0).dot(warp), (p1 - p0).dot(weft), (p2 - p0).dot(weft);
  }
  if (input.buckling_width.rows() > 0 && !own_widths) {
    t.width_u = input.buckling_width(f, 0);
    t.width_v = input.buckling_width(f, 1);
  } else {
    t.width_u = std::max({0.0, d(0, 0), d(0, 1)}) - std::min({0.0, d(0, 0), d(0, 1)});
    t.width_v = std::max({0.0, d(1, 0), d(1, 1)}) - std::min({0.0, d(1, 0), d(1, 1)});
  }
  const Eigen::Matrix2d inverse = d.inverse();
  t.du = Vector3d(-inverse(0, 0) - inverse(1, 0), inverse(0, 0), inverse(1, 0));
  t.dv = Vector3d(-inverse(0, 1) - inverse(1, 1), inverse(0, 1), inverse(1, 1));
  return t;
}

// Row t of a #T by 1 (isotropic) or #T by 2 (warp, weft) scale: rest coordinates (u, v) become
// (a·u, b·v), so [w_u w_v] = [x1−x0, x2−x0]·D⁻¹·diag(1/a, 1/b).
void scale_triangle(TriangleElement& element, const Eigen::MatrixXd& scale, std::size_t t) {
  const auto row = static_cast<Eigen::Index>(t);
  const double a = scale(row, 0), b = scale.cols() > 1 ? scale(row, 1) : a;
  if (!(a > 0.0) || !(b > 0.0) || !std::isfinite(a) || !std::isfinite(b))
    throw InvalidClothError("rest-shape scale (" + std::to_string(a) + ", " + std::to_string(b) +
                            ") of triangle " + std::to_string(t) + " is not positive");
  element.du /= a;
  element.dv /= b;
  element.rest_area *= a * b;
}

// The vertices adjacent to each vertex (itself included) through triangles and hinges, as one
// flat array: vertex i's run starts at start[i], its first size[i] entries are the distinct
// neighbours in increasing order (the rest is room left by duplicates).
struct Neighbours {
  std::vector<int> start, list, size;

  // offset(i,j) of BlockPattern: where block (i,j) starts in row i's columns.
  int offset(int i, int j) const {
    const auto first = list.begin() + start[static_cast<std::size_t>(i)];
    return 3 * static_cast<int>(
                   std::lower_bound(first, first + size[static_cast<std::size_t>(i)], j) - first);
  }
};

// Room in vertex runs for every element's entries: 1 for itself, 2 per triangle, 3 per hinge.
std::vector<int> run_starts(int n, const std::vector<TriangleElement>& triangles,
                            const std::vector<HingeElement>& hinges,
                            const std::vector<BendStencil>& stencils,
                            const std::vector<VertexBendElement>& vertex_bends,
                            const std::vector<DiamondElement>& diamonds) {
  std::vector<int> start(n + 1, 0);
  for (int i = 0; i < n; ++i) start[i + 1] = 1;  // itself
  for (const TriangleElement& t : triangles)
    for (int v : t.vertices) start[v + 1] += 2;
  for (const HingeElement& h : hinges)
    for (int v : h.vertices) start[v + 1] += 3;
  for (const BendStencil& b : stencils)
    for (int v : b.vertices) start[v + 1] += static_cast<int>(b.vertices.size()) - 1;
  for (const VertexBendElement& b : vertex_bends)
    for (int v : b.vertices) start[v + 1] += static_cast<int>(b.vertices.size()) - 1;
  for (const DiamondElement& d : diamonds)
    for (int v : d.vertices) start[v + 1] += DiamondElement::kVertices - 1;
  for (int i = 0; i < n; ++i) start[i + 1] += start[i];
  return start;
}

// Fills the runs of the vertices with wanted[i] (every vertex when empty) from the elements and
// sorts them. The vertex bends, which overlap most (a vertex lies in the bends of its whole
// two-ring, each over a two-ring), are added row by row through their incidence with a mark per
// neighbour, so a run is sorted without their duplicates.
void collect_neighbours(Neighbours& neighbours, const std::vector<TriangleElement>& triangles,
                        const std::vector<HingeElement>& hinges,
                        const std::vector<BendStencil>& stencils,
                        const std::vector<VertexBendElement>& vertex_bends,
                        const std::vector<DiamondElement>& diamonds,
                        const std::vector<char>& wanted) {
  const int n = static_cast<int>(neighbours.size.size());
  const auto want = [&](int v) { return wanted.empty() || wanted[static_cast<std::size_t>(v)]; };
  std::vector<int> fill(neighbours.start.begin(), neighbours.start.end() - 1);
  for (int i = 0; i < n; ++i)
    if (want(i)) neighbours.list[static_cast<std::size_t>(fill[i]++)] = i;
  const auto connect = [&](const int* vertices, int count) {
    for (int k = 0; k < count; ++k) {
      if (!want(vertices[k])) continue;
      for (int l = 0; l < count; ++l)
        if (k != l) neighbours.list[static_cast<std::size_t>(fill[vertices[k]]++)] = vertices[l];
    }
  };
  for (const TriangleElement& t : triangles) connect(t.vertices.data(), 3);
  for (const HingeElement& h : hinges) connect(h.vertices.data(), 4);
  for (const BendStencil& b : stencils)
    connect(b.vertices.data(), static_cast<int>(b.vertices.size()));
  for (const DiamondElement& d : diamonds) connect(d.vertices.data(), DiamondElement::kVertices);
  // The vertex bends over each wanted vertex (CSR by vertex).
  std::vector<int> bend_start(static_cast<std::size_t>(n) + 1, 0);
  for (const VertexBendElement& b : vertex_bends)
    for (int v : b.vertices)
      if (want(v)) ++bend_start[static_cast<std::size_t>(v) + 1];
  for (int i = 0; i < n; ++i) bend_start[i + 1] += bend_start[i];
  std::vector<int> bends(static_cast<std::size_t>(bend_start[n]));
  {
    std::vector<int> next(bend_start.begin(), bend_start.end() - 1);
    for (std::size_t e = 0; e < vertex_bends.size(); ++e)
      for (int v : vertex_bends[e].vertices)
        if (want(v)) bends[static_cast<std::size_t>(next[v]++)] = static_cast<int>(e);
  }
  std::vector<int> mark(static_cast<std::size_t>(n), -1);  // the row that last took a vertex
  for (int i = 0; i < n; ++i) {
    if (!want(i)) continue;
    const auto first = neighbours.list.begin() + neighbours.start[static_cast<std::size_t>(i)];
    // The run so far (itself, triangles, hinges, stencils) without its repeats.
    auto end = first;
    for (auto it = first; it != neighbours.list.begin() + fill[i]; ++it)
      if (mark[static_cast<std::size_t>(*it)] != i) {
        mark[static_cast<std::size_t>(*it)] = i;
        *end++ = *it;
      }
    for (int m = bend_start[i]; m < bend_start[i + 1]; ++m)
      for (int j :
           vertex_bends[static_cast<std::size_t>(bends[static_cast<std::size_t>(m)])].vertices)
        if (mark[static_cast<std::size_t>(j)] != i) {
          mark[static_cast<std::size_t>(j)] = i;
          *end++ = j;
        }
    std::sort(first, end);
    neighbours.size[static_cast<std::size_t>(i)] = static_cast<int>(end - first);
  }
}

// The pattern's matrix: rows 3i..3i+2 hold the 3×3 blocks of vertex i's neighbours. Made in
// place (no index arrays copied into it).
SparseMatrixR zero_pattern_matrix(const Neighbours& neighbours) {
  const int n = static_cast<int>(neighbours.size.size());
  SparseMatrixR matrix(3 * n, 3 * n);
  std::size_t entries = 0;
  for (int i = 0; i < n; ++i)
    entries += 9 * static_cast<std::size_t>(neighbours.size[static_cast<std::size_t>(i)]);
  matrix.resizeNonZeros(static_cast<Eigen::Index>(entries));
  int* outer = matrix.outerIndexPtr();
  int* inner = matrix.innerIndexPtr();
  outer[0] = 0;
  int position = 0;
  for (int i = 0; i < n; ++i) {
    const int* run = neighbours.list.data() + neighbours.start[static_cast<std::size_t>(i)];
    for (int a = 0; a < 3; ++a) {
      for (int m = 0; m < neighbours.size[static_cast<std::size_t>(i)]; ++m)
        for (int b = 0; b < 3; ++b) inner[position++] = 3 * run[m] + b;
      outer[3 * i + a + 1] = position;
    }
  }
  std::fill(matrix.valuePtr(), matrix.valuePtr() + entries, 0.0);
  return matrix;
}

// The elements' block offsets and the diagonal offsets of the rows with wanted[i] (every row
// when empty); vertex bends with fresh_bends[b] (every one when empty) get all their rows.
void set_block_offsets(ClothModel& model, const Neighbours& neighbours,
                       const std::vector<char>& wanted, const std::vector<char>& fresh_bends = {}) {
  const auto want = [&](int v) { return wanted.empty() || wanted[static_cast<std::size_t>(v)]; };
  model.pattern.diagonal_offsets.resize(static_cast<std::size_t>(model.vertex_count));
  for (int i = 0; i < model.vertex_count; ++i)
    if (want(i))
      model.pattern.diagonal_offsets[static_cast<std::size_t>(i)] = neighbours.offset(i, i);
  for (TriangleElement& t : model.triangles)
    for (int k = 0; k < 3; ++k)
      if (want(t.vertices[k]))
        for (int l = 0; l < 3; ++l)
          t.blocks[3 * k + l] = neighbours.offset(t.vertices[k], t.vertices[l]);
  for (HingeElement& h : model.hinges)
    for (int k = 0; k < 4; ++k)
      if (want(h.vertices[k]))
        for (int l = 0; l < 4; ++l)
          h.blocks[4 * k + l] = neighbours.offset(h.vertices[k], h.vertices[l]);
  // Stencils are rebuilt with every model, so all their offsets are set; vertex bends kept
  // from the previous model hold theirs in the rows that did not change.
  // Row by row: the (element, local row) pairs to set in each vertex's row, then the row's
  // offsets by column through a position map (every column an element reads is in the row).
  const int n = model.vertex_count;
  const auto rows_to_set = [&](std::size_t e, int k) {
    return fresh_bends.empty() || fresh_bends[e] ||
           want(model.vertex_bends[e].vertices[static_cast<std::size_t>(k)]);
  };
  std::vector<int> row_start(static_cast<std::size_t>(n) + 1, 0);
  for (std::size_t e = 0; e < model.vertex_bends.size(); ++e)
    for (std::size_t k = 0; k < model.vertex_bends[e].vertices.size(); ++k)
      if (rows_to_set(e, static_cast<int>(k)))
        ++row_start[static_cast<std::size_t>(model.vertex_bends[e].vertices[k]) + 1];
  for (int i = 0; i < n; ++i) row_start[i + 1] += row_start[i];
  std::vector<std::pair<int, int>> pairs(static_cast<std::size_t>(row_start[n]));
  {
    std::vector<int> next(row_start.begin(), row_start.end() - 1);
    for (std::size_t e = 0; e < model.vertex_bends.size(); ++e)
      for (std::size_t k = 0; k < model.vertex_bends[e].vertices.size(); ++k)
        if (rows_to_set(e, static_cast<int>(k)))
          pairs[static_cast<std::size_t>(
              next[static_cast<std::size_t>(model.vertex_bends[e].vertices[k])]++)] = {
              static_cast<int>(e), static_cast<int>(k)};
  }
  std::vector<int> position(static_cast<std::size_t>(n), 0);
  for (int i = 0; i < n; ++i) {
    if (row_start[i] == row_start[i + 1]) continue;
    const int* run = neighbours.list.data() + neighbours.start[static_cast<std::size_t>(i)];
    for (int m = 0; m < neighbours.size[static_cast<std::size_t>(i)]; ++m)
      position[static_cast<std::size_t>(run[m])] = 3 * m;
    for (int p = row_start[i]; p < row_start[i + 1]; ++p) {
      const auto [e, k] = pairs[static_cast<std::size_t>(p)];
      VertexBendElement& b = model.vertex_bends[static_cast<std::size_t>(e)];
      const int count = static_cast<int>(b.vertices.size());
      for (int l = 0; l < count; ++l)
        b.blocks[static_cast<std::size_t>(count * k + l)] =
            position[static_cast<std::size_t>(b.vertices[static_cast<std::size_t>(l)])];
    }
  }
  for (BendStencil& b : model.stencils) {
    const int count = static_cast<int>(b.vertices.size());
    for (int k = 0; k < count; ++k)
      for (int l = 0; l < count; ++l)
        b.blocks[static_cast<std::size_t>(count * k + l)] = neighbours.offset(
            b.vertices[static_cast<std::size_t>(k)], b.vertices[static_cast<std::size_t>(l)]);
  }
}

// The even extension of the free cloth across a clamp's edge, in a free vertex's rows: a pinned
// point p behind the edge (pinned, not on the edge) is read as its ghost x_m + 2·x_p − 2·x_c,
// where m is a free point of the element and c, the midpoint of p and m in `positions`, is a
// clamp-edge vertex of the element or the midpoint of two. For the clamp's flat layout the ghost
// is the free side's point m moved back by p − m along the cloth, with the height of m: the
// extension w(−s) = w(s) of a clamped beam (w = w' = 0 at the edge), whose curvature continues
// the free side's instead of dropping to the clamp's zero. The rows stay exact for affine maps (c
// is the midpoint of p and m), so rigid motions and stretches still cost nothing. The nearest such
// m is taken; a point without one keeps its row. Flat rests only (a curved element's rest terms
// would change); applied once per element.
void ghost_clamped_points(VertexBendElement& b, const std::vector<char>& is_pinned,
                          const std::vector<char>& edge, const Eigen::VectorXd& positions) {
  if (b.ghosted || !b.fan.empty()) return;
  const auto at = [&](int v) { return Eigen::Vector3d(positions.segment<3>(3 * v)); };
  const int count = static_cast<int>(b.vertices.size());
  const int centre = b.vertices[static_cast<std::size_t>(b.centre)];
  double reach = 0.0;
  for (int j : b.vertices) reach = std::max(reach, (at(j) - at(centre)).norm());
  const double tolerance = 1e-7 * reach;
  const auto pinned = [&](int k) {
    return is_pinned[static_cast<std::size_t>(b.vertices[static_cast<std::size_t>(k)])] != 0;
  };
  const auto on_edge = [&](int k) {
    return edge[static_cast<std::size_t>(b.vertices[static_cast<std::size_t>(k)])] != 0;
  };
  const auto point = [&](int k) { return at(b.vertices[static_cast<std::size_t>(k)]); };
  Eigen::Matrix<double, 3, Eigen::Dynamic> rows = b.rows;
  for (int k = 0; k < count; ++k) {
    if (!pinned(k) || on_edge(k) || b.rows.col(k).isZero(0.0)) continue;
    int mirror = -1, first = -1, second = -1;
    double nearest = std::numeric_limits<double>::infinity();
    for (int m = 0; m < count; ++m) {
      const double distance = (point(m) - point(k)).norm();
      if (pinned(m) || distance >= nearest) continue;
      const Eigen::Vector3d middle = 0.5 * (point(k) + point(m));
      for (int c1 = 0; c1 < count; ++c1) {
        if (!on_edge(c1)) continue;
        for (int c2 = c1; c2 < count; ++c2)
          if (on_edge(c2) && (0.5 * (point(c1) + point(c2)) - middle).norm() < tolerance) {
            mirror = m, first = c1, second = c2, nearest = distance;
            break;
          }
        if (mirror == m) break;
      }
    }
    if (mirror < 0) continue;
    const Eigen::Vector3d w = b.rows.col(k);
    rows.col(mirror) += w;
    rows.col(k) += w;
    rows.col(first) -= w;
    rows.col(second) -= w;
    b.ghosted = true;
  }
  b.rows = rows;
}

// The triangles in no diamond (ClothModelOptions::diamond_membrane) and the diamonds' block
// offsets. A diamond couples its centre, corners and the corners' neighbours (the predicted
// centre, sim/diamond_membrane.hpp); run_starts and collect_neighbours put those pairs in the
// pattern. A diamond whose pairs are still missing (an adaptive update's unchanged rows) is left
// out, its triangles evaluated alone.
void set_diamonds(ClothModel& model, const Neighbours& neighbours,
                  const ClothModelOptions& options) {
  model.lone_triangles.clear();
  if (!options.diamond_membrane) return;
  constexpr int kVertices = DiamondElement::kVertices;
  std::erase_if(model.diamonds, [&](DiamondElement& d) {
    for (int k = 0; k < kVertices; ++k)
      for (int l = 0; l < kVertices; ++l) {
        const int i = d.vertices[static_cast<std::size_t>(k)];
        const int j = d.vertices[static_cast<std::size_t>(l)];
        const int offset = neighbours.offset(i, j);
        if (offset / 3 >= neighbours.size[static_cast<std::size_t>(i)] ||
            neighbours.list[static_cast<std::size_t>(neighbours.start[static_cast<std::size_t>(i)] +
                                                     offset / 3)] != j)
          return true;
        d.blocks[static_cast<std::size_t>(kVertices * k + l)] = offset;
      }
    return false;
  });
  std::vector<char> in_diamond(model.triangles.size(), 0);
  for (const DiamondElement& d : model.diamonds)
    for (int f : d.triangles)
      if (f >= 0) in_diamond[static_cast<std::size_t>(f)] = 1;
  for (std::size_t f = 0; f < model.triangles.size(); ++f)
    if (!in_diamond[f]) model.lone_triangles.push_back(static_cast<int>(f));
}
}  // namespace

Eigen::MatrixX2d rest_widths(const ClothInput& input) {
  check_input(input);
  const double extent = rest_extent(input.rest_positions);
  Eigen::MatrixX2d widths(input.triangles.rows(), 2);
  for (Eigen::Index f = 0; f < input.triangles.rows(); ++f) {
    const TriangleElement t = make_triangle(input, f, extent, /*own_widths=*/true);
    widths.row(f) << t.width_u, t.width_v;
  }
  return widths;
}

void scale_rest_shapes(ClothModel& model, const Eigen::MatrixXd& scale) {
  if (scale.rows() != static_cast<Eigen::Index>(model.triangles.size()) || scale.cols() < 1 ||
      scale.cols() > 2)
    throw InvalidClothError("a rest-shape scale (1 or 2 columns) is needed for every triangle (" +
                            std::to_string(scale.rows()) + " by " + std::to_string(scale.cols()) +
                            " given, " + std::to_string(model.triangles.size()) + " triangles)");
  model.mass.setZero();
  model.vertex_area.setZero();
  for (std::size_t t = 0; t < model.triangles.size(); ++t) {
    TriangleElement& element = model.triangles[t];
    scale_triangle(element, scale, t);
    for (int v : element.vertices) {
      model.vertex_area[v] += element.rest_area / 3.0;
      model.mass[v] += model.fabric.area_density * element.rest_area / 3.0;
    }
  }
}

void clamp_bending(ClothModel& model, const std::vector<int>& pinned,
                   const Eigen::VectorXd* positions) {
  const auto n = static_cast<std::size_t>(model.vertex_count);
  std::vector<char> is_pinned(n, 0), in_pinned_triangle(n, 0), in_free_triangle(n, 0);
  for (int v : pinned)
    if (v >= 0 && static_cast<std::size_t>(v) < n) is_pinned[static_cast<std::size_t>(v)] = 1;
  for (const TriangleElement& t : model.triangles) {
    bool all = true;
    for (int v : t.vertices) all = all && is_pinned[static_cast<std::size_t>(v)];
    for (int v : t.vertices)
      (all ? in_pinned_triangle : in_free_triangle)[static_cast<std::size_t>(v)] = 1;
  }
  if (positions != nullptr && model.clamp_ghost_points &&
      positions->size() == 3 * static_cast<Eigen::Index>(n)) {
    std::vector<char> edge(n, 0);
    for (std::size_t v = 0; v < n; ++v)
      edge[v] = is_pinned[v] && in_pinned_triangle[v] && in_free_triangle[v];
    for (VertexBendElement& b : model.vertex_bends)
      if (!is_pinned[static_cast<std::size_t>(b.vertices[static_cast<std::size_t>(b.centre)])])
        ghost_clamped_points(b, is_pinned, edge, *positions);
  }
  for (VertexBendElement& b : model.vertex_bends) {
    const auto v = static_cast<std::size_t>(b.vertices[static_cast<std::size_t>(b.centre)]);
    // Doubled once: a model updated after an adaptive change keeps the elements it can, with
    // their clamp (halving and doubling are exact).
    const bool clamp = is_pinned[v] && in_pinned_triangle[v] && in_free_triangle[v];
    if (clamp != b.clamped) b.inverse_area *= clamp ? 2.0 : 0.5;
    b.clamped = clamp;
  }
  build_flat_bend_operator(model);
}

void build_flat_bend_operator(ClothModel& model) {
  FlatBendOperator& k = model.flat_bends;
  k = FlatBendOperator();
  if (model.vertex_bends.empty()) return;
  const SparseMatrixR& pattern = model.pattern.zero_matrix;
  const int n = model.vertex_count;
  if (pattern.rows() != 3 * n) return;
  const int* outer = pattern.outerIndexPtr();
  const int* inner = pattern.innerIndexPtr();
  // K's entries on the pattern's blocks, dense by row (block b of row i at block_start[i] + b).
  std::vector<int> block_start(static_cast<std::size_t>(n) + 1, 0);
  for (int i = 0; i < n; ++i)
    block_start[i + 1] = block_start[i] + (outer[3 * i + 1] - outer[3 * i]) / 3;
  std::vector<double> dense(static_cast<std::size_t>(block_start[n]), 0.0);
  std::vector<char> touched(dense.size(), 0);
  const Eigen::Vector3d scales(0.5, 0.5, 2.0);  // vertex_bend_contribution's row weights
  std::vector<int> vertex_count(static_cast<std::size_t>(n) + 1, 0);
  k.row_start.assign(1, 0);
  for (std::size_t e = 0; e < model.vertex_bends.size(); ++e) {
    const VertexBendElement& b = model.vertex_bends[e];
    if (!b.fan.empty()) {
      k.curved.push_back(static_cast<int>(e));
      continue;
    }
    const auto m = static_cast<Eigen::Index>(b.vertices.size());
    for (int row = 0; row < 3; ++row) {
      for (Eigen::Index j = 0; j < m; ++j) {
        k.row_vertex.push_back(b.vertices[static_cast<std::size_t>(j)]);
        k.row_value.push_back(b.rows(row, j));
        ++vertex_count[static_cast<std::size_t>(b.vertices[static_cast<std::size_t>(j)]) + 1];
      }
      k.row_start.push_back(static_cast<int>(k.row_vertex.size()));
      k.row_weight.push_back(b.inverse_area * scales(row));
    }
    const Eigen::MatrixXd coupling = b.rows.transpose() * scales.asDiagonal() * b.rows;
    for (Eigen::Index j = 0; j < m; ++j) {
      const int row = b.vertices[static_cast<std::size_t>(j)];
      for (Eigen::Index l = 0; l < m; ++l) {
        const auto slot = static_cast<std::size_t>(
            block_start[row] + b.blocks[static_cast<std::size_t>(m * j + l)] / 3);
        dense[slot] += b.inverse_area * coupling(j, l);
        touched[slot] = 1;
      }
    }
  }
  // Rᵀ by vertex, rows increasing within each vertex.
  for (int i = 0; i < n; ++i) vertex_count[i + 1] += vertex_count[i];
  k.vertex_start = vertex_count;
  k.vertex_row.resize(k.row_vertex.size());
  k.vertex_value.resize(k.row_vertex.size());
  std::vector<int> next(vertex_count.begin(), vertex_count.end() - 1);
  for (int r = 0; r + 1 < static_cast<int>(k.row_start.size()); ++r)
    for (int p = k.row_start[static_cast<std::size_t>(r)];
         p < k.row_start[static_cast<std::size_t>(r) + 1]; ++p) {
      const auto at = static_cast<std::size_t>(
          next[static_cast<std::size_t>(k.row_vertex[static_cast<std::size_t>(p)])]++);
      k.vertex_row[at] = r;
      k.vertex_value[at] = k.row_value[static_cast<std::size_t>(p)];
    }
  k.k_start.assign(1, 0);
  for (int i = 0; i < n; ++i) {
    for (int slot = block_start[i]; slot < block_start[i + 1]; ++slot) {
      if (!touched[static_cast<std::size_t>(slot)]) continue;
      const int offset = 3 * (slot - block_start[i]);
      k.k_column.push_back(inner[outer[3 * i] + offset] / 3);
      k.k_offset.push_back(offset);
      k.k_value.push_back(dense[static_cast<std::size_t>(slot)]);
    }
    k.k_start.push_back(static_cast<int>(k.k_column.size()));
  }
  k.elements = model.vertex_bends.size();
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
  const double extent = rest_extent(rest);

  model.triangles.resize(input.triangles.rows());
  for (Eigen::Index f = 0; f < input.triangles.rows(); ++f) {
    TriangleElement& t = model.triangles[f];
    t = make_triangle(input, f, extent);
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
    const TriangleElement& first = model.triangles[e0.face];
    const TriangleElement& second = model.triangles[e1.face];
    model.hinges.push_back(make_hinge(rest, first.vertices, e0.corner, second.vertices, e1.corner,
                                      first.rest_area + second.rest_area, options));
  }
  if (non_manifold > 0)
    spdlog::warn("cloth mesh: {} non-manifold edges get no bending stiffness", non_manifold);
  if (options.bend_weights == BendWeights::calibrated) calibrate_hinge_weights(rest, model.hinges);
  model.bend_stencil_stiffness = options.bend_stencil_stiffness;
  model.clamp_ghost_points = options.clamp_ghost_points;
  if (options.bend_stencil_stiffness > 0.0)
    model.stencils = make_bend_stencils(rest, input.triangles);
  model.bend_model = options.bend_model;
  model.bend_rest = options.bend_rest;
  model.compression = options.compression;
  if (options.bend_model == BendModel::quadratic)
    model.vertex_bends = make_vertex_bends(rest, input.triangles, options.bend_rest);
  model.diamonds.clear();
  if (options.diamond_membrane)
    model.diamonds = make_diamonds(input.rest_positions, model.triangles, input.rest_uv.rows() > 0);

  // Block sparsity pattern: vertex adjacency through triangles and hinges, as one flat array
  // (CSR by vertex: room for every element's entries, then each vertex's run sorted and
  // deduplicated in place).
  Neighbours neighbours;
  neighbours.start = run_starts(n, model.triangles, model.hinges, model.stencils,
                                model.vertex_bends, model.diamonds);
  neighbours.list.resize(static_cast<std::size_t>(neighbours.start[n]));
  neighbours.size.resize(n);
  collect_neighbours(neighbours, model.triangles, model.hinges, model.stencils, model.vertex_bends,
                     model.diamonds, {});
  model.pattern.zero_matrix = zero_pattern_matrix(neighbours);
  set_block_offsets(model, neighbours, {});
  set_diamonds(model, neighbours, options);
  build_flat_bend_operator(model);
  return model;
}

ClothModel update_cloth_model(const ClothModel& previous, const ClothModelReuse& reuse,
                              const ClothInput& input, const Eigen::MatrixXd& scale,
                              const ClothModelOptions& options) {
  check_input(input);
  const int n = static_cast<int>(input.rest_positions.rows());
  const int face_count = static_cast<int>(input.triangles.rows());
  if (static_cast<int>(reuse.previous_vertex.size()) != n ||
      static_cast<int>(reuse.previous_triangle.size()) != face_count ||
      (scale.size() != 0 && (scale.rows() != face_count || scale.cols() > 2)))
    throw InvalidClothError("the reuse map and the scale must have a row per vertex (" +
                            std::to_string(n) + ") and per triangle (" +
                            std::to_string(face_count) + ")");
  const Eigen::MatrixX3d& rest = input.rest_positions;
  const double extent = rest_extent(rest);
  ClothModel model;
  model.fabric = previous.fabric;
  model.vertex_count = n;
  model.mass = Eigen::VectorXd::Zero(n);
  model.vertex_area = Eigen::VectorXd::Zero(n);

  std::vector<int> next_vertex(static_cast<std::size_t>(previous.vertex_count), -1);
  for (int i = 0; i < n; ++i)
    if (const int p = reuse.previous_vertex[static_cast<std::size_t>(i)]; p >= 0)
      next_vertex.at(static_cast<std::size_t>(p)) = i;
  const auto renumber = [&](int p) {
    const int i = next_vertex[static_cast<std::size_t>(p)];
    if (i < 0)
      throw InvalidClothError("a kept element uses vertex " + std::to_string(p) +
                              " that the reuse map drops");
    return i;
  };
  // Every triangle the change removed has its three vertices marked here (previous rows). A
  // triangle with an unmarked vertex was kept; a kept triangle with three marked vertices is
  // treated as new, and so is every hinge on it, which keeps the test local and exact.
  std::vector<char> kept(previous.triangles.size(), 0);
  for (int p : reuse.previous_triangle)
    if (p >= 0) kept.at(static_cast<std::size_t>(p)) = 1;
  std::vector<char> around_removed(static_cast<std::size_t>(previous.vertex_count), 0);
  for (std::size_t p = 0; p < previous.triangles.size(); ++p)
    if (!kept[p])
      for (int v : previous.triangles[p].vertices) around_removed[static_cast<std::size_t>(v)] = 1;
  const auto all_marked = [&](int a, int b, int c) {
    return around_removed[static_cast<std::size_t>(a)] &&
           around_removed[static_cast<std::size_t>(b)] &&
           around_removed[static_cast<std::size_t>(c)];
  };

  // Triangles: kept ones copied (already scaled), the others made and scaled. `changed_row`
  // marks the vertices whose elements are not all kept: their pattern rows are rebuilt.
  std::vector<char> new_face(static_cast<std::size_t>(face_count), 0);
  std::vector<char> changed_row(static_cast<std::size_t>(n), 0);
  for (std::size_t p = 0; p < next_vertex.size(); ++p)
    if (around_removed[p] && next_vertex[p] >= 0)
      changed_row[static_cast<std::size_t>(next_vertex[p])] = 1;
  for (int i = 0; i < n; ++i)
    if (reuse.previous_vertex[static_cast<std::size_t>(i)] < 0) changed_row[i] = 1;
  model.triangles.resize(static_cast<std::size_t>(face_count));
  for (int f = 0; f < face_count; ++f) {
    TriangleElement& t = model.triangles[static_cast<std::size_t>(f)];
    const int p = reuse.previous_triangle[static_cast<std::size_t>(f)];
    if (p >= 0) {
      t = previous.triangles[static_cast<std::size_t>(p)];
      new_face[f] = all_marked(t.vertices[0], t.vertices[1], t.vertices[2]);
      for (int k = 0; k < 3; ++k) {
        t.vertices[k] = renumber(t.vertices[k]);
        if (t.vertices[k] != input.triangles(f, k))
          throw InvalidClothError(triangle_name(f) + " is not the kept triangle " +
                                  std::to_string(p) + " of the reuse map");
      }
    } else {
      t = make_triangle(input, f, extent);
      if (scale.size() > 0) scale_triangle(t, scale, static_cast<std::size_t>(f));
      new_face[f] = 1;
    }
    for (int k = 0; k < 3; ++k) {
      if (new_face[f]) changed_row[static_cast<std::size_t>(t.vertices[k])] = 1;
      model.vertex_area[t.vertices[k]] += t.rest_area / 3.0;
      model.mass[t.vertices[k]] += model.fabric.area_density * t.rest_area / 3.0;
    }
  }

  // Hinges between two kept triangles keep their order; the others are found from the faces
  // around each vertex, sorted like build_cloth_model's (by lower, higher vertex) and merged in.
  std::vector<HingeElement> kept_hinges;
  kept_hinges.reserve(previous.hinges.size());
  for (const HingeElement& old : previous.hinges) {
    const auto& v = old.vertices;
    if (all_marked(v[0], v[1], v[2]) || all_marked(v[1], v[0], v[3])) {
      for (int p : v)
        if (next_vertex[static_cast<std::size_t>(p)] >= 0)
          changed_row[static_cast<std::size_t>(next_vertex[static_cast<std::size_t>(p)])] = 1;
      continue;
    }
    HingeElement h = old;
    for (int& vertex : h.vertices) vertex = renumber(vertex);
    kept_hinges.push_back(h);
  }
  std::vector<int> face_start(static_cast<std::size_t>(n) + 1, 0);
  for (int f = 0; f < face_count; ++f)
    for (int k = 0; k < 3; ++k) ++face_start[static_cast<std::size_t>(input.triangles(f, k)) + 1];
  for (int i = 0; i < n; ++i) face_start[i + 1] += face_start[i];
  std::vector<int> faces_around(static_cast<std::size_t>(face_start[n]));
  {
    std::vector<int> fill(face_start.begin(), face_start.end() - 1);
    for (int f = 0; f < face_count; ++f)
      for (int k = 0; k < 3; ++k) faces_around[fill[input.triangles(f, k)]++] = f;
  }
  std::vector<HingeElement> made_hinges;
  for (int f = 0; f < face_count; ++f) {
    if (!new_face[f]) continue;
    const std::array<int, 3>& fv = model.triangles[static_cast<std::size_t>(f)].vertices;
    for (int k = 0; k < 3; ++k) {
      const int a = fv[k], b = fv[(k + 1) % 3];
      int other = -1, other_corner = -1, count = 0;
      for (int m = face_start[a]; m < face_start[a + 1]; ++m) {
        const int g = faces_around[static_cast<std::size_t>(m)];
        if (g == f) continue;
        const std::array<int, 3>& gv = model.triangles[static_cast<std::size_t>(g)].vertices;
        for (int j = 0; j < 3; ++j)
          if (std::minmax(gv[j], gv[(j + 1) % 3]) == std::minmax(a, b)) {
            other = g;
            other_corner = j;
            ++count;
          }
      }
      // A boundary edge, a non-manifold one (no hinge, as in build_cloth_model), or a hinge
      // made from the other face.
      if (count != 1 || (new_face[other] && other < f)) continue;
      const std::array<int, 3>& ov = model.triangles[static_cast<std::size_t>(other)].vertices;
      const double areas = unscaled_rest_area(rest, fv) + unscaled_rest_area(rest, ov);
      made_hinges.push_back(f < other ? make_hinge(rest, fv, k, ov, other_corner, areas, options)
                                      : make_hinge(rest, ov, other_corner, fv, k, areas, options));
      for (int v : made_hinges.back().vertices) changed_row[static_cast<std::size_t>(v)] = 1;
    }
  }
  const auto edge_key = [](const HingeElement& h) {
    return std::minmax(h.vertices[0], h.vertices[1]);
  };
  const auto by_edge = [&](const HingeElement& p, const HingeElement& q) {
    return edge_key(p) < edge_key(q);
  };
  std::sort(made_hinges.begin(), made_hinges.end(), by_edge);
  model.hinges.resize(kept_hinges.size() + made_hinges.size());
  std::merge(kept_hinges.begin(), kept_hinges.end(), made_hinges.begin(), made_hinges.end(),
             model.hinges.begin(), by_edge);
  // Calibrated weights depend on the hinges around both ends: all are recomputed (linear time),
  // as build_cloth_model does.
  if (options.bend_weights == BendWeights::calibrated) calibrate_hinge_weights(rest, model.hinges);
  // Stencils are rebuilt too; a row whose stencils are not all the previous ones (the same
  // vertices) is rebuilt.
  model.bend_stencil_stiffness = options.bend_stencil_stiffness;
  model.clamp_ghost_points = options.clamp_ghost_points;
  if (options.bend_stencil_stiffness > 0.0)
    model.stencils = make_bend_stencils(rest, input.triangles);
  // Marks the rows of the elements over several vertices (stencils, vertex bends) that are not
  // one of the previous ones over the same vertices, and the rows a vanished one covered.
  const auto mark_changed_rows = [&](const auto& previous_elements, const auto& elements) {
    std::set<std::vector<int>> before, after;
    for (const auto& b : previous_elements) before.insert(b.vertices);
    for (const auto& b : elements) {
      std::vector<int> key;
      for (int v : b.vertices) key.push_back(reuse.previous_vertex[static_cast<std::size_t>(v)]);
      std::sort(key.begin(), key.end());
      after.insert(key);
      if (key.front() < 0 || before.count(key) == 0)
        for (int v : b.vertices) changed_row[static_cast<std::size_t>(v)] = 1;
    }
    for (const std::vector<int>& key : before)
      if (after.count(key) == 0)
        for (int p : key)
          if (const int i = next_vertex[static_cast<std::size_t>(p)]; i >= 0)
            changed_row[static_cast<std::size_t>(i)] = 1;
  };
  mark_changed_rows(previous.stencils, model.stencils);
  model.bend_model = options.bend_model;
  model.bend_rest = options.bend_rest;
  model.compression = options.compression;
  // Vertex bends: an element reads the faces around its vertex and around its one-ring (and
  // the rest positions there), so where none of those faces changed it is the previous one
  // with its vertices renumbered (renumbering keeps the order, so its sorted vertices stay
  // sorted). The others are made anew (`fresh`: all their block offsets are set below).
  std::vector<char> fresh_bends;
  if (options.bend_model == BendModel::quadratic) {
    const bool reusable =
        previous.bend_model == BendModel::quadratic && options.bend_rest == previous.bend_rest;
    // Vertices on a triangle the change removed or made (new rows).
    std::vector<char> touched(static_cast<std::size_t>(n), 0);
    for (std::size_t p = 0; p < next_vertex.size(); ++p)
      if (around_removed[p] && next_vertex[p] >= 0)
        touched[static_cast<std::size_t>(next_vertex[p])] = 1;
    for (int f = 0; f < face_count; ++f)
      if (reuse.previous_triangle[static_cast<std::size_t>(f)] < 0)
        for (int k = 0; k < 3; ++k) touched[static_cast<std::size_t>(input.triangles(f, k))] = 1;
    for (int i = 0; i < n; ++i)
      if (reuse.previous_vertex[static_cast<std::size_t>(i)] < 0) touched[i] = 1;
    // Made anew: a touched vertex and every vertex with a touched neighbour.
    std::vector<char> remake(static_cast<std::size_t>(n), reusable ? 0 : 1);
    if (reusable)
      for (int f = 0; f < face_count; ++f) {
        const int a = input.triangles(f, 0), b = input.triangles(f, 1), c = input.triangles(f, 2);
        if (touched[a] || touched[b] || touched[c]) remake[a] = remake[b] = remake[c] = 1;
      }
    std::vector<int> previous_element(static_cast<std::size_t>(previous.vertex_count), -1);
    for (std::size_t e = 0; e < previous.vertex_bends.size(); ++e) {
      const VertexBendElement& b = previous.vertex_bends[e];
      previous_element[static_cast<std::size_t>(b.vertices[static_cast<std::size_t>(b.centre)])] =
          static_cast<int>(e);
    }
    std::vector<VertexBendElement> made =
        make_vertex_bends(rest, input.triangles, options.bend_rest, remake);
    std::vector<char> matched(previous.vertex_bends.size(), 0);
    model.vertex_bends.reserve(made.size() + previous.vertex_bends.size());
    std::size_t next_made = 0;
    for (int i = 0; i < n; ++i) {
      const int p = reuse.previous_vertex[static_cast<std::size_t>(i)];
      const int e = p >= 0 ? previous_element[static_cast<std::size_t>(p)] : -1;
      if (!remake[i]) {
        if (e < 0) continue;  // no triangle around it before, none now
        VertexBendElement b = previous.vertex_bends[static_cast<std::size_t>(e)];
        for (int& vertex : b.vertices) vertex = renumber(vertex);
        matched[static_cast<std::size_t>(e)] = 1;
        model.vertex_bends.push_back(std::move(b));
        fresh_bends.push_back(0);
        continue;
      }
      if (next_made == made.size() ||
          made[next_made].vertices[static_cast<std::size_t>(made[next_made].centre)] != i)
        continue;  // no element for i (no triangle, or no area)
      VertexBendElement& b = made[next_made++];
      // Its rows keep their pattern only if the previous element of the same vertex had the
      // same vertices.
      bool same = e >= 0;
      if (same) {
        const VertexBendElement& old = previous.vertex_bends[static_cast<std::size_t>(e)];
        same = old.vertices.size() == b.vertices.size();
        for (std::size_t j = 0; same && j < b.vertices.size(); ++j)
          same = reuse.previous_vertex[static_cast<std::size_t>(b.vertices[j])] == old.vertices[j];
        matched[static_cast<std::size_t>(e)] = 1;
        if (!same)
          for (int q : old.vertices)
            if (const int k = next_vertex[static_cast<std::size_t>(q)]; k >= 0)
              changed_row[static_cast<std::size_t>(k)] = 1;
      }
      if (!same)
        for (int v : b.vertices) changed_row[static_cast<std::size_t>(v)] = 1;
      model.vertex_bends.push_back(std::move(b));
      fresh_bends.push_back(1);
    }
    // A previous element that has none of the same vertex now: its rows lose its entries.
    for (std::size_t e = 0; e < previous.vertex_bends.size(); ++e)
      if (!matched[e])
        for (int q : previous.vertex_bends[e].vertices)
          if (const int k = next_vertex[static_cast<std::size_t>(q)]; k >= 0)
            changed_row[static_cast<std::size_t>(k)] = 1;
  } else {
    for (const VertexBendElement& b : previous.vertex_bends)
      for (int q : b.vertices)
        if (const int k = next_vertex[static_cast<std::size_t>(q)]; k >= 0)
          changed_row[static_cast<std::size_t>(k)] = 1;
  }

  // The diamonds afresh; a diamond, old or new, touching a changed row has all its rows
  // collected anew (its pairs reach up to four rings, which an unchanged row's previous run may
  // lack, or hold when the diamond is gone).
  model.diamonds.clear();
  if (options.diamond_membrane)
    model.diamonds = make_diamonds(input.rest_positions, model.triangles, input.rest_uv.rows() > 0);
  // Touched means by a row the elements changed (not one marked here): a diamond that differs
  // from the previous model's has such a row, and one that does not kept its pairs' runs.
  const std::vector<char> element_changed = changed_row;
  const auto mark = [&](const DiamondElement& d, const auto& row_of) {
    bool touched = false;
    for (int q : d.vertices) {
      const int k = row_of(q);
      touched = touched || k < 0 || element_changed[static_cast<std::size_t>(k)] != 0;
    }
    if (touched)
      for (int q : d.vertices)
        if (const int k = row_of(q); k >= 0) changed_row[static_cast<std::size_t>(k)] = 1;
  };
  for (const DiamondElement& d : previous.diamonds)
    mark(d, [&](int q) { return next_vertex[static_cast<std::size_t>(q)]; });
  for (const DiamondElement& d : model.diamonds) mark(d, [](int v) { return v; });

  // Pattern: unchanged rows are the previous rows renumbered (kept vertices keep their order,
  // so each run stays sorted), the changed ones are collected from the elements and sorted.
  const SparseMatrixR& old_pattern = previous.pattern.zero_matrix;
  const auto previous_size = [&](int i) {  // neighbours in the previous row of vertex i
    const int p = reuse.previous_vertex[static_cast<std::size_t>(i)];
    return (old_pattern.outerIndexPtr()[3 * p + 1] - old_pattern.outerIndexPtr()[3 * p]) / 3;
  };
  // A changed row gets room as in build_cloth_model, an unchanged one its previous size.
  const std::vector<int> room = run_starts(n, model.triangles, model.hinges, model.stencils,
                                           model.vertex_bends, model.diamonds);
  Neighbours neighbours;
  neighbours.start.assign(static_cast<std::size_t>(n) + 1, 0);
  for (int i = 0; i < n; ++i)
    neighbours.start[i + 1] =
        neighbours.start[i] + (changed_row[i] ? room[i + 1] - room[i] : previous_size(i));
  neighbours.list.resize(static_cast<std::size_t>(neighbours.start[n]));
  neighbours.size.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    if (changed_row[i]) continue;
    const int p = reuse.previous_vertex[static_cast<std::size_t>(i)];
    const int* columns = old_pattern.innerIndexPtr() + old_pattern.outerIndexPtr()[3 * p];
    const int size = previous_size(i);
    for (int m = 0; m < size; ++m)
      neighbours.list[static_cast<std::size_t>(neighbours.start[i] + m)] =
          renumber(columns[3 * m] / 3);
    neighbours.size[i] = size;
  }
  collect_neighbours(neighbours, model.triangles, model.hinges, model.stencils, model.vertex_bends,
                     model.diamonds, changed_row);
  model.pattern.zero_matrix = zero_pattern_matrix(neighbours);
  // Offsets in unchanged rows are the previous ones (kept elements brought them along).
  model.pattern.diagonal_offsets.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i)
    if (!changed_row[i])
      model.pattern.diagonal_offsets[static_cast<std::size_t>(i)] =
          previous.pattern.diagonal_offsets[static_cast<std::size_t>(
              reuse.previous_vertex[static_cast<std::size_t>(i)])];
  set_block_offsets(model, neighbours, changed_row, fresh_bends);
  set_diamonds(model, neighbours, options);
  build_flat_bend_operator(model);
  return model;
}

}  // namespace sd::sim
