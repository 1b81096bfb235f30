#include "meshing/patch_fill.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <string>

#include "meshing/patch_relaxation.hpp"
#include "meshing/quad_layout.hpp"
#include "meshing/region_partition.hpp"

namespace sd::meshing {
namespace {

// Feasibility checks the corner search may spend per fill (each is O(n²) integer work).
constexpr int kSearchBudget = 4000;

void check_counts(std::span<const int> counts) {
  if (counts.size() < 2)
    throw FillError("a region needs at least 2 sides to be filled, got " +
                    std::to_string(counts.size()));
  long total = 0;
  for (size_t i = 0; i < counts.size(); ++i) {
    if (counts[i] < 1)
      throw FillError("side " + std::to_string(i) + " has " + std::to_string(counts[i]) +
                      " edges; every side needs at least 1");
    total += counts[i];
  }
  if (total % 2 != 0)
    throw FillError("the sides have " + std::to_string(total) +
                    " edges in total; a quad mesh needs an even total (change one side by 1)");
  if (total < 4)
    throw FillError("the sides have only 2 edges in total, both joining the same two corners; "
                    "a quad mesh needs at least 4 boundary edges");
}

struct Built {
  detail::QuadMeshBuilder builder;
  std::vector<std::vector<int>> sides;  // vertex ids per side, corner to corner
  std::string partition;
};

// Creates the boundary vertices from side_points (corner i = side_points[i].row(0)).
std::vector<std::vector<int>> add_boundary(detail::QuadMeshBuilder& builder,
                                           const std::vector<Eigen::MatrixX3d>& side_points) {
  const size_t n = side_points.size();
  std::vector<std::vector<int>> sides(n);
  for (size_t i = 0; i < n; ++i)
    for (Eigen::Index r = 0; r + 1 < side_points[i].rows(); ++r)
      sides[i].push_back(builder.add_vertex(side_points[i].row(r).transpose()));
  for (size_t i = 0; i < n; ++i) {
    sides[i].push_back(sides[(i + 1) % n].front());
    builder.add_path(sides[i]);
  }
  return sides;
}

std::vector<int> boundary_loop_of(const std::vector<std::vector<int>>& sides) {
  std::vector<int> loop;
  for (const auto& side : sides) loop.insert(loop.end(), side.begin(), side.end() - 1);
  return loop;
}

Built build_layout(const std::vector<Eigen::MatrixX3d>& side_points,
                   std::span<const int> counts) {
  Built built;
  built.sides = add_boundary(built.builder, side_points);
  const detail::PolygonLayout layout = detail::best_layout(detail::region_costs(counts), kSearchBudget);
  detail::fill_polygon(built.builder, boundary_loop_of(built.sides), layout);
  std::vector<int> real_corners;
  for (int p = 0; const int count : counts) {
    real_corners.push_back(p);
    p += count;
  }
  built.partition = layout.corners == real_corners ? "nasri" : "shifted-corners";
  return built;
}

std::optional<Built> build_yasseen(const std::vector<Eigen::MatrixX3d>& side_points) {
  Built built;
  built.sides = add_boundary(built.builder, side_points);
  if (!detail::fill_yasseen(built.builder, built.sides, kSearchBudget)) return std::nullopt;
  built.partition = "yasseen";
  return built;
}

std::vector<int> corners_of(const std::vector<std::vector<int>>& sides) {
  std::vector<int> corners;
  for (const auto& side : sides) corners.push_back(side.front());
  return corners;
}

// The least distorted of the constructions that apply (ties keep the corner search's).
PatchTopology build_topology(const std::vector<Eigen::MatrixX3d>& side_points,
                             std::span<const int> counts) {
  Built best = build_layout(side_points, counts);
  QuadMesh best_mesh = best.builder.build();
  QuadQuality best_figures = measure_valence(best_mesh, corners_of(best.sides));
  if (auto yasseen = build_yasseen(side_points)) {
    QuadMesh mesh = yasseen->builder.build();
    const QuadQuality figures = measure_valence(mesh, corners_of(yasseen->sides));
    if (validate(mesh).ok() &&
        std::pair(figures.distortion, figures.irregular_vertices) <
            std::pair(best_figures.distortion, best_figures.irregular_vertices)) {
      best = std::move(*yasseen);
      best_mesh = std::move(mesh);
      best_figures = figures;
    }
  }
  PatchTopology topology;
  topology.mesh = std::move(best_mesh);
  topology.side_vertices = std::move(best.sides);
  topology.partition = std::move(best.partition);
  topology.distortion = best_figures.distortion;
  topology.irregular_vertices = best_figures.irregular_vertices;
  return topology;
}

// Sides for display: every boundary vertex on the unit circle at an angle proportional to its
// position along the boundary, so no three are collinear (a promoted corner never sits on a
// straight line) and side lengths follow the counts.
std::vector<Eigen::MatrixX3d> display_sides(std::span<const int> counts) {
  const int total = std::accumulate(counts.begin(), counts.end(), 0);
  std::vector<Eigen::MatrixX3d> sides;
  int start = 0;
  for (const int count : counts) {
    Eigen::MatrixX3d side(count + 1, 3);
    for (int k = 0; k <= count; ++k) {
      const double angle =
          2 * std::numbers::pi * ((start + k) % total) / total - std::numbers::pi / 2;
      side.row(k) << std::cos(angle), std::sin(angle), 0.0;
    }
    sides.push_back(side);
    start += count;
  }
  return sides;
}

void check_side_points(const std::vector<Eigen::MatrixX3d>& side_points) {
  if (side_points.size() < 2)
    throw FillError("a region needs at least 2 sides to be filled, got " +
                    std::to_string(side_points.size()));
  double scale = 0;
  for (size_t i = 0; i < side_points.size(); ++i) {
    if (side_points[i].rows() < 2)
      throw FillError("side " + std::to_string(i) + " has " +
                      std::to_string(side_points[i].rows()) +
                      " point(s); every side needs its two corners at least");
    if (!side_points[i].allFinite())
      throw FillError("side " + std::to_string(i) + " has a coordinate that is not a number");
    scale = std::max(scale, side_points[i].cwiseAbs().maxCoeff());
  }
  for (size_t i = 0; i < side_points.size(); ++i) {
    const auto& next = side_points[(i + 1) % side_points.size()];
    const double gap = (side_points[i].bottomRows<1>() - next.topRows<1>()).norm();
    if (gap > 1e-9 * std::max(scale, 1e-300))
      throw FillError("side " + std::to_string(i) + " does not end where side " +
                      std::to_string((i + 1) % side_points.size()) + " starts (gap " +
                      std::to_string(gap) + ")");
  }
}

}  // namespace

std::vector<int> PatchTopology::corner_vertices() const { return corners_of(side_vertices); }

PatchTopology fill_region(std::span<const int> side_counts) {
  check_counts(side_counts);
  return build_topology(display_sides(side_counts), side_counts);
}

FilledPatch fill_region(const std::vector<Eigen::MatrixX3d>& side_points,
                        const FillGeometryOptions& options) {
  check_side_points(side_points);
  std::vector<int> counts;
  for (const auto& side : side_points) counts.push_back(static_cast<int>(side.rows()) - 1);
  check_counts(counts);
  FilledPatch patch;
  patch.topology = fill_region(counts);
  patch.mesh = build_topology(side_points, counts).mesh;
  if (patch.mesh.faces != patch.topology.mesh.faces)
    throw std::logic_error("the fill's connectivity depends on geometry");
  std::vector<char> fixed(static_cast<size_t>(patch.mesh.vertices.rows()), 0);
  for (const auto& side : patch.topology.side_vertices)
    for (const int v : side) fixed[static_cast<size_t>(v)] = 1;
  if (options.project)
    for (Eigen::Index v = 0; v < patch.mesh.vertices.rows(); ++v)
      if (!fixed[static_cast<size_t>(v)])
        patch.mesh.vertices.row(v) = options.project(patch.mesh.vertices.row(v).transpose()).transpose();
  relax_interior(patch.mesh, fixed, options.relax_iterations, options.project);
  patch.quality = measure_quality(patch.mesh, patch.topology.corner_vertices());
  return patch;
}

Eigen::MatrixX3d resample_by_arc_length(const Eigen::MatrixX3d& polyline, int count) {
  if (polyline.rows() < 2) throw FillError("a side polyline needs at least 2 points");
  if (count < 1) throw FillError("a side needs at least 1 edge");
  std::vector<double> along{0.0};
  for (Eigen::Index r = 1; r < polyline.rows(); ++r)
    along.push_back(along.back() + (polyline.row(r) - polyline.row(r - 1)).norm());
  const double length = along.back();
  Eigen::MatrixX3d points(count + 1, 3);
  points.row(0) = polyline.row(0);
  points.row(count) = polyline.bottomRows<1>();
  size_t segment = 1;
  for (int k = 1; k < count; ++k) {
    const double target = length * k / count;
    while (segment + 1 < along.size() && along[segment] < target) ++segment;
    const double span = along[segment] - along[segment - 1];
    const double t = span > 0 ? (target - along[segment - 1]) / span : 0.0;
    const auto s = static_cast<Eigen::Index>(segment);
    points.row(k) = (1 - t) * polyline.row(s - 1) + t * polyline.row(s);
  }
  return points;
}

FilledPatch fill_region(const std::vector<Eigen::MatrixX3d>& side_polylines,
                        std::span<const int> side_counts, const FillGeometryOptions& options) {
  if (side_polylines.size() != side_counts.size())
    throw FillError("got " + std::to_string(side_polylines.size()) + " side polylines but " +
                    std::to_string(side_counts.size()) + " edge counts");
  check_counts(side_counts);
  check_side_points(side_polylines);
  std::vector<Eigen::MatrixX3d> points;
  for (size_t i = 0; i < side_polylines.size(); ++i)
    points.push_back(resample_by_arc_length(side_polylines[i], side_counts[i]));
  // Consecutive sides share their corner exactly.
  for (size_t i = 0; i < points.size(); ++i)
    points[i].bottomRows<1>() = points[(i + 1) % points.size()].topRows<1>();
  return fill_region(points, options);
}

}  // namespace sd::meshing
