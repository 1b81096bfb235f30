// Cutting a widening arm off a region and filling the two parts (arm_widening.hpp).
#include "meshing/arm_widening.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

#include "meshing/patch_relaxation.hpp"
#include "meshing/quad_quality.hpp"

namespace sd::meshing {
namespace {

// An arm's end has at most this many edges ...
constexpr int kArmEndEdges = 4;
// ... between two sides each at least this many times as long (garment/quality_gate.cpp's
// thin_arm_advice, which only advises, asks for 3 and 6; the walk below decides how long the
// arm really is: an 8 cm halter strap of 4 edges between sides of 20 and 27 widens too).
constexpr int kArmSideRatio = 4;
// The arm ends where its width grows by more than this share of the step along its side (its
// sides diverge by more than about 30°: the body's outline turns away from the strap's; the
// sides of a regular triangle diverge by 60°).
constexpr double kJoinSlope = 0.5;
// ... or where it is this many times as wide as its end (a cut across a wider part would be a
// seam through the body rather than across the arm).
constexpr double kMostWidening = 3.0;
// A cut nearer the end than this many edges leaves no room for the transition ...
constexpr int kLeastArmEdges = 3;
// ... and an arm shorter than this many times its width at the cut is no long thin arm.
constexpr double kLeastArmLength = 2.0;
// An arm that widens by less than this factor (or narrows: a triangle walked from one side to the
// opposite corner) needs no widening.
constexpr double kLeastWidening = 1.25;

double polyline_length(const Eigen::MatrixX3d& points) {
  double length = 0;
  for (Eigen::Index r = 0; r + 1 < points.rows(); ++r)
    length += (points.row(r + 1) - points.row(r)).norm();
  return length;
}

}  // namespace

std::optional<ArmCut> find_arm_cut(const std::vector<Eigen::MatrixX3d>& side_points) {
  const auto n = static_cast<int>(side_points.size());
  if (n < 3) return std::nullopt;
  double boundary = 0;
  Eigen::Index edges = 0;
  for (const auto& side : side_points) {
    boundary += polyline_length(side);
    edges += side.rows() - 1;
  }
  if (edges == 0 || boundary <= 0) return std::nullopt;
  const double edge = boundary / static_cast<double>(edges);
  std::optional<ArmCut> best;
  int best_gain = 0;  // quads across the cut more than across the end
  for (int s = 0; s < n; ++s) {
    const Eigen::MatrixX3d& end = side_points[static_cast<size_t>(s)];
    const Eigen::MatrixX3d& before = side_points[static_cast<size_t>((s + n - 1) % n)];
    const Eigen::MatrixX3d& after = side_points[static_cast<size_t>((s + 1) % n)];
    const auto l_end = static_cast<int>(end.rows()) - 1;
    const auto l_before = static_cast<int>(before.rows()) - 1;
    const auto l_after = static_cast<int>(after.rows()) - 1;
    if (l_end > kArmEndEdges || l_before < kArmSideRatio * l_end || l_after < kArmSideRatio * l_end)
      continue;
    const double end_width = (end.row(0) - end.row(l_end)).norm();
    double width = end_width;
    int k_cut = 0, j_cut = 0, j = 0;
    double cut_width = 0, length = 0;  // length: along the side before the end, up to the cut
    // Vertex l_before − k of the side before the end, k edges from the arm's end, paired with
    // the nearest vertex of the side after it not behind the last pair (and not a corner).
    for (int k = 1; k < l_before; ++k) {
      const Eigen::RowVector3d a = before.row(l_before - k);
      int nearest = -1;
      double distance = std::numeric_limits<double>::infinity();
      for (int r = std::max(j, 1); r < l_after; ++r)
        if (const double d = (after.row(r) - a).norm(); d < distance) {
          distance = d;
          nearest = r;
        }
      const double step = (a - before.row(l_before - k + 1)).norm();
      if (nearest < 0 || distance - width > kJoinSlope * step ||
          distance > kMostWidening * end_width)
        break;
      width = distance;
      j = nearest;
      k_cut = k;
      j_cut = nearest;
      cut_width = distance;
      length += step;
    }
    if (k_cut < kLeastArmEdges || j_cut < kLeastArmEdges || length < kLeastArmLength * cut_width ||
        cut_width < kLeastWidening * end_width)
      continue;
    // The arm's boundary (k_cut + l_end + j_cut + across) must be even, and so then is the rest's.
    const int parity = (k_cut + l_end + j_cut) % 2;
    int across = static_cast<int>(std::lround(cut_width / edge));
    if (across % 2 != parity)
      across += cut_width / edge > across ? 1 : -1;  // the nearer count of the right parity
    across = std::max(across, parity == 0 ? 2 : 1);
    if (across <= l_end) continue;  // as many quads across as the end has fit the cut
    if (across - l_end > best_gain) {
      best_gain = across - l_end;
      best = ArmCut{s, l_before - k_cut, j_cut, across, end_width, cut_width};
    }
  }
  return best;
}

ArmParts split_at_arm_cut(const std::vector<Eigen::MatrixX3d>& side_points, const ArmCut& cut,
                          const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& project) {
  const auto n = static_cast<int>(side_points.size());
  const int s = cut.end_side;
  const Eigen::MatrixX3d& before = side_points[static_cast<size_t>((s + n - 1) % n)];
  const Eigen::MatrixX3d& after = side_points[static_cast<size_t>((s + 1) % n)];
  const auto l_before = static_cast<int>(before.rows()) - 1;
  const auto l_after = static_cast<int>(after.rows()) - 1;
  const Eigen::RowVector3d from = before.row(cut.from_vertex);
  const Eigen::RowVector3d to = after.row(cut.to_vertex);
  Eigen::MatrixX3d chain(cut.across + 1, 3);
  for (int t = 0; t <= cut.across; ++t) {
    const double u = static_cast<double>(t) / cut.across;
    Eigen::Vector3d p = ((1 - u) * from + u * to).transpose();
    if (project && t > 0 && t < cut.across) p = project(p);
    chain.row(t) = p.transpose();
  }
  chain.row(0) = from;  // the ends exactly
  chain.row(cut.across) = to;
  ArmParts parts;
  parts.arm.push_back(before.bottomRows(l_before - cut.from_vertex + 1));
  parts.arm.push_back(side_points[static_cast<size_t>(s)]);
  parts.arm.push_back(after.topRows(cut.to_vertex + 1));
  parts.arm.push_back(chain.colwise().reverse());
  parts.rest.push_back(before.topRows(cut.from_vertex + 1));
  parts.rest.push_back(chain);
  parts.rest.push_back(after.bottomRows(l_after - cut.to_vertex + 1));
  for (int m = 2; m < n - 1; ++m)
    parts.rest.push_back(side_points[static_cast<size_t>((s + m) % n)]);
  return parts;
}

FilledPatch fill_with_arm_cut(
    const std::vector<Eigen::MatrixX3d>& side_points, const ArmCut& cut,
    const std::function<FilledPatch(const std::vector<Eigen::MatrixX3d>&)>& fill_part,
    const FillGeometryOptions& options) {
  const auto n = static_cast<int>(side_points.size());
  const int s = cut.end_side;
  const ArmParts parts = split_at_arm_cut(side_points, cut, options.project);
  const FilledPatch rest = fill_part(parts.rest);
  const FilledPatch arm = fill_part(parts.arm);
  const auto& rest_sides = rest.topology.side_vertices;
  const auto& arm_sides = arm.topology.side_vertices;
  // The rest keeps its vertex ids; the arm's come after them, but for the cut's, which the
  // rest already has (the arm's last side runs along the cut the other way).
  const auto rest_vertices = static_cast<int>(rest.mesh.vertex_count());
  std::vector<int> id(static_cast<size_t>(arm.mesh.vertex_count()), -1);
  for (int t = 0; t <= cut.across; ++t)
    id[static_cast<size_t>(arm_sides[3][static_cast<size_t>(t)])] =
        rest_sides[1][static_cast<size_t>(cut.across - t)];
  int next = rest_vertices;
  for (int& v : id)
    if (v < 0) v = next++;
  QuadMesh mesh;
  mesh.vertices.resize(next, 3);
  mesh.vertices.topRows(rest_vertices) = rest.mesh.vertices;
  for (Eigen::Index v = 0; v < arm.mesh.vertex_count(); ++v)
    if (id[static_cast<size_t>(v)] >= rest_vertices)
      mesh.vertices.row(id[static_cast<size_t>(v)]) = arm.mesh.vertices.row(v);
  mesh.faces.resize(rest.mesh.face_count() + arm.mesh.face_count(), 4);
  mesh.faces.topRows(rest.mesh.face_count()) = rest.mesh.faces;
  for (Eigen::Index f = 0; f < arm.mesh.face_count(); ++f)
    for (int k = 0; k < 4; ++k)
      mesh.faces(rest.mesh.face_count() + f, k) = id[static_cast<size_t>(arm.mesh.faces(f, k))];
  // The region's sides: before the end = the rest's first side and the arm's first; the end =
  // the arm's second; after the end = the arm's third and the rest's third; then the others.
  const auto mapped = [&](const std::vector<int>& side, size_t from) {
    std::vector<int> out;
    for (size_t t = from; t < side.size(); ++t) out.push_back(id[static_cast<size_t>(side[t])]);
    return out;
  };
  std::vector<std::vector<int>> sides(static_cast<size_t>(n));
  std::vector<int>& before = sides[static_cast<size_t>((s + n - 1) % n)];
  before = rest_sides[0];
  for (const int v : mapped(arm_sides[0], 1)) before.push_back(v);
  sides[static_cast<size_t>(s)] = mapped(arm_sides[1], 0);
  std::vector<int>& after = sides[static_cast<size_t>((s + 1) % n)];
  after = mapped(arm_sides[2], 0);
  after.insert(after.end(), rest_sides[2].begin() + 1, rest_sides[2].end());
  for (int m = 2; m < n - 1; ++m)
    sides[static_cast<size_t>((s + m) % n)] = rest_sides[static_cast<size_t>(m + 1)];
  // The joined interior, the cut's vertices now among it, relaxed together.
  std::vector<Eigen::Vector3d> positions(static_cast<size_t>(next));
  for (Eigen::Index v = 0; v < next; ++v) positions[static_cast<size_t>(v)] = mesh.vertices.row(v);
  std::vector<std::array<int, 4>> quads(static_cast<size_t>(mesh.face_count()));
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f)
    for (int k = 0; k < 4; ++k)
      quads[static_cast<size_t>(f)][static_cast<size_t>(k)] = mesh.faces(f, k);
  std::vector<char> fixed(positions.size(), 0);
  for (const auto& side : sides)
    for (const int v : side) fixed[static_cast<size_t>(v)] = 1;
  detail::relax_interior(positions, quads, fixed, options.relax_iterations, options.project);
  for (Eigen::Index v = 0; v < next; ++v)
    mesh.vertices.row(v) = positions[static_cast<size_t>(v)].transpose();
  FilledPatch patch;
  patch.mesh = mesh;
  patch.topology.mesh = std::move(mesh);
  patch.topology.side_vertices = std::move(sides);
  patch.topology.partition = "arm-cut";
  patch.quality = measure_quality(patch.mesh, patch.topology.corner_vertices());
  patch.topology.distortion = patch.quality.distortion;
  patch.topology.irregular_vertices = patch.quality.irregular_vertices;
  return patch;
}

double worst_quad_size(const QuadMesh& mesh, double edge) {
  double worst = 1;
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
    const double side = mean_side(mesh, f);
    worst = std::max({worst, side / edge, edge / std::max(side, 1e-300)});
  }
  return worst;
}

}  // namespace sd::meshing
