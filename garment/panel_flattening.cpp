#include "garment/panel_flattening.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_parameterization/LSCM_parameterizer_3.h>
#include <CGAL/Surface_mesh_parameterization/parameterize.h>
#include <fmt/format.h>

#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <set>
#include <unordered_map>

#include "garment/material_frames.hpp"
#include "garment/piece_grain.hpp"

namespace sd::garment {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace SMP = CGAL::Surface_mesh_parameterization;

// Singular values σ₁ ≥ σ₂ ≥ 0 of a 2×2 matrix (closed form), and the closest rotation.
struct Polar2 {
  double s1 = 1, s2 = 1;
  Eigen::Matrix2d rotation = Eigen::Matrix2d::Identity();
};
Polar2 polar(const Eigen::Matrix2d& j) {
  const double e = 0.5 * (j(0, 0) + j(1, 1)), f = 0.5 * (j(0, 0) - j(1, 1));
  const double g = 0.5 * (j(1, 0) + j(0, 1)), h = 0.5 * (j(1, 0) - j(0, 1));
  const double q = std::hypot(e, h), r = std::hypot(f, g);
  Polar2 p;
  p.s1 = q + r;
  p.s2 = std::abs(q - r);
  const double angle = std::atan2(h, e);
  p.rotation << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
  return p;
}

// A triangle of the 3D mesh in its own plane: gradient operator of the linear map to 2D.
struct RestTriangle {
  double area = 0;          // m², 3D
  Eigen::Matrix2d inverse;  // D⁻¹, D = [x1 − x0, x2 − x0] in the triangle's plane
  Eigen::Vector3d e1, e2;   // the plane's orthonormal frame (3D)
  Eigen::Vector3d centroid;
};

std::vector<RestTriangle> rest_triangles(const Eigen::MatrixX3d& v, const Eigen::MatrixX3i& t,
                                         const std::string& name) {
  std::vector<RestTriangle> rest(static_cast<size_t>(t.rows()));
  for (Eigen::Index f = 0; f < t.rows(); ++f) {
    const Eigen::Vector3d p0 = v.row(t(f, 0)), p1 = v.row(t(f, 1)), p2 = v.row(t(f, 2));
    const Eigen::Vector3d n = (p1 - p0).cross(p2 - p0);
    RestTriangle& r = rest[static_cast<size_t>(f)];
    r.area = 0.5 * n.norm();
    if (!(r.area > 0))
      throw PatternError(name, fmt::format("panel '{}' has a triangle of zero area", name));
    r.e1 = (p1 - p0).normalized();
    r.e2 = n.normalized().cross(r.e1);
    Eigen::Matrix2d d;
    d << (p1 - p0).dot(r.e1), (p2 - p0).dot(r.e1), 0.0, (p2 - p0).dot(r.e2);
    r.inverse = d.inverse();
    r.centroid = (p0 + p1 + p2) / 3;
  }
  return rest;
}

// J = [u1 − u0, u2 − u0]·D⁻¹: the triangle's 3D (plane frame) → 2D map.
Eigen::Matrix2d jacobian(const Eigen::MatrixX2d& uv, const Eigen::MatrixX3i& t, Eigen::Index f,
                         const RestTriangle& r) {
  Eigen::Matrix2d u;
  u.col(0) = (uv.row(t(f, 1)) - uv.row(t(f, 0))).transpose();
  u.col(1) = (uv.row(t(f, 2)) - uv.row(t(f, 0))).transpose();
  return u * r.inverse;
}

double signed_area_2d(const Eigen::MatrixX2d& uv, const Eigen::MatrixX3i& t, Eigen::Index f) {
  const Eigen::Vector2d a = uv.row(t(f, 1)) - uv.row(t(f, 0));
  const Eigen::Vector2d b = uv.row(t(f, 2)) - uv.row(t(f, 0));
  return 0.5 * (a.x() * b.y() - a.y() * b.x());
}

int folded_triangles(const Eigen::MatrixX2d& uv, const Eigen::MatrixX3i& t,
                     const std::vector<RestTriangle>& rest) {
  int folded = 0;
  for (Eigen::Index f = 0; f < t.rows(); ++f)
    if (!(signed_area_2d(uv, t, f) > 1e-9 * rest[static_cast<size_t>(f)].area)) ++folded;
  return folded;
}

// Where a flat piece's outline crosses itself: two boundary edges (not sharing a point) whose
// 2D segments cross properly. A disk mapped without an inverted triangle is one layer of cloth
// everywhere unless its outline crosses itself; then part of it lies over another part (a
// sleeve drawn with its end turned up, a flounce wound more than once round): no flat cloth
// holds both. Returns the number of crossing pairs and the first pair's edges (boundary
// positions, edge i runs from boundary[i] to boundary[i + 1]). O(n²) over the outline's n
// edges behind a box test: a 30 × 45 cm panel at 2 mm has about 750.
struct OutlineCrossing {
  int pairs = 0;
  int edge_a = -1, edge_b = -1;
};

OutlineCrossing outline_crossings(const Eigen::MatrixX2d& uv, const std::vector<int>& boundary) {
  OutlineCrossing out;
  const int n = static_cast<int>(boundary.size());
  const auto point = [&](int i) -> Eigen::Vector2d {
    return uv.row(boundary[static_cast<size_t>((i % n + n) % n)]).transpose();
  };
  const auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a,
                        const Eigen::Vector2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d a0 = point(i), a1 = point(i + 1);
    for (int j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;  // the loop's last edge meets its first
      const Eigen::Vector2d b0 = point(j), b1 = point(j + 1);
      if (std::max(a0.x(), a1.x()) < std::min(b0.x(), b1.x()) ||
          std::max(b0.x(), b1.x()) < std::min(a0.x(), a1.x()) ||
          std::max(a0.y(), a1.y()) < std::min(b0.y(), b1.y()) ||
          std::max(b0.y(), b1.y()) < std::min(a0.y(), a1.y()))
        continue;
      const double d1 = cross(a0, a1, b0), d2 = cross(a0, a1, b1);
      const double d3 = cross(b0, b1, a0), d4 = cross(b0, b1, a1);
      if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) &&
          ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) {
        if (out.pairs == 0) out.edge_a = i, out.edge_b = j;
        ++out.pairs;
      }
    }
  }
  return out;
}

// The boundary of a disk as one counter-clockwise loop of local vertices; throws PatternError
// when the triangles do not form a disk (V − E + F ≠ 1, or several boundary loops).
std::vector<int> disk_boundary(const std::string& name, Eigen::Index vertex_count,
                               const Eigen::MatrixX3i& t) {
  std::unordered_map<long long, int> directed;
  const auto key = [&](int a, int b) { return static_cast<long long>(a) * vertex_count + b; };
  for (Eigen::Index f = 0; f < t.rows(); ++f)
    for (int k = 0; k < 3; ++k) ++directed[key(t(f, k), t(f, (k + 1) % 3))];
  std::vector<int> next(static_cast<size_t>(vertex_count), -1);
  long long edges = 0;
  int boundary_edges = 0;
  for (const auto& [k, count] : directed) {
    const int a = static_cast<int>(k / vertex_count), b = static_cast<int>(k % vertex_count);
    if (count > 1 || (directed.count(key(b, a)) > 0 && directed.at(key(b, a)) > 1))
      throw PatternError(name, fmt::format("panel '{}' has an edge used twice in one direction "
                                           "(its faces are not consistently oriented)",
                                           name));
    const bool interior = directed.count(key(b, a)) > 0;
    edges += interior ? 1 : 2;  // an interior edge is counted from both sides
    if (interior) continue;
    if (next[static_cast<size_t>(a)] >= 0)
      throw PatternError(name, fmt::format("panel '{}' touches itself at a vertex: it cannot be "
                                           "laid flat as one piece",
                                           name));
    next[static_cast<size_t>(a)] = b;
    ++boundary_edges;
  }
  edges /= 2;
  const long long euler = vertex_count - edges + t.rows();
  if (boundary_edges == 0 || euler != 1)
    throw PatternError(
        name, fmt::format("panel '{}' is not a disk (it closes around the body like a tube, or has "
                          "a hole): a flat pattern piece needs it cut open; split it into two "
                          "panels with a seam",
                          name));
  std::vector<int> loop;
  int start = -1;
  for (Eigen::Index v = 0; v < vertex_count && start < 0; ++v)
    if (next[static_cast<size_t>(v)] >= 0) start = static_cast<int>(v);
  for (int v = start; loop.empty() || v != start; v = next[static_cast<size_t>(v)]) {
    loop.push_back(v);
    if (static_cast<int>(loop.size()) > boundary_edges) break;
  }
  if (static_cast<int>(loop.size()) != boundary_edges)
    throw PatternError(name, fmt::format("panel '{}' has more than one boundary loop (a hole): "
                                         "cut it open with a seam",
                                         name));
  return loop;
}

// LSCM (CGAL, two pinned vertices): a conformal start, scaled to the 3D area and oriented so the
// triangles keep their counter-clockwise order.
Eigen::MatrixX2d lscm_start(const std::string& name, const Eigen::MatrixX3d& v,
                            const Eigen::MatrixX3i& t, double area_3d) {
  SurfaceMesh mesh;
  std::vector<SurfaceMesh::Vertex_index> handles;
  handles.reserve(static_cast<size_t>(v.rows()));
  for (Eigen::Index i = 0; i < v.rows(); ++i)
    handles.push_back(mesh.add_vertex(Kernel::Point_3(v(i, 0), v(i, 1), v(i, 2))));
  for (Eigen::Index f = 0; f < t.rows(); ++f)
    if (mesh.add_face(handles[static_cast<size_t>(t(f, 0))], handles[static_cast<size_t>(t(f, 1))],
                      handles[static_cast<size_t>(t(f, 2))]) == SurfaceMesh::null_face())
      throw PatternError(name, fmt::format("panel '{}' is not a manifold surface", name));
  auto uvmap = mesh.add_property_map<SurfaceMesh::Vertex_index, Kernel::Point_2>("v:uv").first;
  // The panel is a disk (checked before): its one border loop starts at any border halfedge.
  SurfaceMesh::Halfedge_index border;
  for (const SurfaceMesh::Halfedge_index h : mesh.halfedges())
    if (mesh.is_border(h)) {
      border = h;
      break;
    }
  const SMP::Error_code status =
      SMP::parameterize(mesh, SMP::LSCM_parameterizer_3<SurfaceMesh>(), border, uvmap);
  if (status != SMP::OK)
    throw PatternError(name, fmt::format("panel '{}' could not be flattened: {}", name,
                                         SMP::get_error_message(status)));
  Eigen::MatrixX2d uv(v.rows(), 2);
  for (Eigen::Index i = 0; i < v.rows(); ++i) {
    const Kernel::Point_2& p = uvmap[handles[static_cast<size_t>(i)]];
    uv.row(i) << p.x(), p.y();
  }
  double area_2d = 0;
  for (Eigen::Index f = 0; f < t.rows(); ++f) area_2d += signed_area_2d(uv, t, f);
  if (area_2d < 0) {
    uv.col(0) *= -1;
    area_2d = -area_2d;
  }
  if (!(area_2d > 0)) throw PatternError(name, fmt::format("panel '{}' flattens to nothing", name));
  uv *= std::sqrt(area_3d / area_2d);
  return uv;
}

// As-rigid-as-possible local/global iterations (Liu et al. 2008) on the energy
//   Σ_t A_t ‖J_t − R_t‖²  +  Σ_boundary w ‖(u_i − u_j) − l_ij·d̂_ij‖²,
// where l_ij is the edge's 3D length and d̂_ij its current 2D direction: the second term holds
// the outline at its true length, so both sides of a seam come out as long as the seam is.
// With `on_line` (local vertices) the energy is minimised with those vertices' x held at 0: they
// stay on the y axis, free to slide along it (ARAP is blind to rigid motions, so holding them on
// one fixed line loses nothing; the outline terms still hold their edges at their 3D lengths).
// Returns the sweeps made.
int arap(Eigen::MatrixX2d& uv, const Eigen::MatrixX3d& v, const Eigen::MatrixX3i& t,
         const std::vector<RestTriangle>& rest, const std::vector<int>& boundary,
         const FlatteningOptions& options, const std::vector<int>& on_line = {}) {
  const Eigen::Index n = v.rows();
  const double w = 0.5 * options.boundary_weight;
  std::vector<Eigen::Triplet<double>> entries;
  const auto gradients = [&](Eigen::Index f) {
    const Eigen::Matrix2d& inv = rest[static_cast<size_t>(f)].inverse;
    std::array<Eigen::Vector2d, 3> g;
    g[1] = inv.row(0).transpose();
    g[2] = inv.row(1).transpose();
    g[0] = -g[1] - g[2];
    return g;
  };
  for (Eigen::Index f = 0; f < t.rows(); ++f) {
    const auto g = gradients(f);
    const double a = rest[static_cast<size_t>(f)].area;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) entries.emplace_back(t(f, i), t(f, j), a * g[i].dot(g[j]));
  }
  const size_t nb = boundary.size();
  std::vector<double> length(nb);
  for (size_t k = 0; k < nb; ++k) {
    const int i = boundary[k], j = boundary[(k + 1) % nb];
    length[k] = (v.row(i) - v.row(j)).norm();
    entries.emplace_back(i, i, w);
    entries.emplace_back(j, j, w);
    entries.emplace_back(i, j, -w);
    entries.emplace_back(j, i, -w);
  }
  // Translation is free: a weak spring holds vertex 0 where it is.
  const double pin = 1e-6 * w;
  entries.emplace_back(0, 0, pin);
  Eigen::SparseMatrix<double> matrix(n, n);
  matrix.setFromTriplets(entries.begin(), entries.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(matrix);
  if (solver.info() != Eigen::Success) return 0;
  // x on the line: those rows and columns become the identity (x = 0 there, so nothing moves
  // to the right-hand side); y keeps the matrix above.
  std::vector<char> held(static_cast<size_t>(n), 0);
  for (const int i : on_line) held[static_cast<size_t>(i)] = 1;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver_x;
  if (!on_line.empty()) {
    std::vector<Eigen::Triplet<double>> kept;
    kept.reserve(entries.size() + on_line.size());
    for (const Eigen::Triplet<double>& e : entries)
      if (!held[static_cast<size_t>(e.row())] && !held[static_cast<size_t>(e.col())])
        kept.push_back(e);
    for (const int i : on_line) kept.emplace_back(i, i, 1.0);
    Eigen::SparseMatrix<double> matrix_x(n, n);
    matrix_x.setFromTriplets(kept.begin(), kept.end());
    solver_x.compute(matrix_x);
    if (solver_x.info() != Eigen::Success) return 0;
    for (const int i : on_line) uv(i, 0) = 0;
  }

  const double extent = (v.colwise().maxCoeff() - v.colwise().minCoeff()).norm();
  int sweeps = 0;
  Eigen::MatrixX2d rhs(n, 2);
  for (; sweeps < options.max_iterations; ++sweeps) {
    rhs.setZero();
    for (Eigen::Index f = 0; f < t.rows(); ++f) {
      const RestTriangle& r = rest[static_cast<size_t>(f)];
      const Eigen::Matrix2d rotation = polar(jacobian(uv, t, f, r)).rotation;
      const auto g = gradients(f);
      for (int k = 0; k < 3; ++k) rhs.row(t(f, k)) += r.area * (rotation * g[k]).transpose();
    }
    for (size_t k = 0; k < nb; ++k) {
      const int i = boundary[k], j = boundary[(k + 1) % nb];
      Eigen::RowVector2d d = uv.row(i) - uv.row(j);
      const double norm = d.norm();
      if (norm > 0) d *= length[k] / norm;
      rhs.row(i) += w * d;
      rhs.row(j) -= w * d;
    }
    rhs.row(0) += pin * uv.row(0);
    Eigen::MatrixX2d next(n, 2);
    if (on_line.empty()) {
      next = solver.solve(rhs);
    } else {
      for (const int i : on_line) rhs(i, 0) = 0;
      next.col(0) = solver_x.solve(rhs.col(0));
      next.col(1) = solver.solve(rhs.col(1));
    }
    const double move = (next - uv).rowwise().norm().maxCoeff();
    uv = next;
    if (move < 1e-7 * extent) {  // 0.1 µm on a 1 m piece
      ++sweeps;
      break;
    }
  }
  return sweeps;
}

FlatDistortion measure(const Eigen::MatrixX2d& uv, const Eigen::MatrixX3i& t,
                       const std::vector<RestTriangle>& rest) {
  FlatDistortion d;
  double total = 0;
  std::vector<std::pair<double, Eigen::Index>> by_length;  // (length distortion, triangle)
  for (Eigen::Index f = 0; f < t.rows(); ++f) {
    const RestTriangle& r = rest[static_cast<size_t>(f)];
    const Polar2 p = polar(jacobian(uv, t, f, r));
    const double length = std::max(p.s1 - 1, 1 - p.s2);
    const double area = std::abs(p.s1 * p.s2 - 1);
    d.length_max = std::max(d.length_max, length);
    d.area_max = std::max(d.area_max, area);
    d.length_mean += r.area * length;
    d.area_mean += r.area * area;
    total += r.area;
    by_length.emplace_back(length, f);
  }
  d.length_mean /= total;
  d.area_mean /= total;
  // The worst 5 % of the area: its lowest distortion is the 95th percentile, its area-weighted
  // centroid the place the stretch concentrates.
  std::sort(by_length.begin(), by_length.end(), std::greater<>());
  double area = 0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector2d centre_2d = Eigen::Vector2d::Zero();
  for (const auto& [length, f] : by_length) {
    const double a = rest[static_cast<size_t>(f)].area;
    area += a;
    centre += a * rest[static_cast<size_t>(f)].centroid;
    centre_2d += a * (uv.row(t(f, 0)) + uv.row(t(f, 1)) + uv.row(t(f, 2))).transpose() / 3;
    d.length_p95 = length;
    if (area >= 0.05 * total) break;
  }
  d.worst_point = centre / area;
  d.worst_point_2d = centre_2d / area;
  return d;
}

// How a surface curves: its interior vertices' angle defects 2π − Σθ (rad), the positive ones
// and the negative ones summed (FlatDistortion::dome, saddle), and the defect-weighted centre of
// the domed ones (m). The boundary's vertices are left out: their defect is the outline's
// turning, not the surface's curvature.
struct SurfaceCurvature {
  double dome = 0, saddle = 0;
  Eigen::Vector3d dome_centre = Eigen::Vector3d::Zero();
};

SurfaceCurvature angle_defects(const Eigen::MatrixX3d& v, const Eigen::MatrixX3i& t,
                               const std::vector<int>& boundary) {
  std::vector<double> angle(static_cast<size_t>(v.rows()), 0.0);
  for (Eigen::Index f = 0; f < t.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d p = v.row(t(f, k));
      const Eigen::Vector3d u = Eigen::Vector3d(v.row(t(f, (k + 1) % 3))) - p;
      const Eigen::Vector3d w = Eigen::Vector3d(v.row(t(f, (k + 2) % 3))) - p;
      angle[static_cast<size_t>(t(f, k))] += std::atan2(u.cross(w).norm(), u.dot(w));
    }
  for (const int b : boundary) angle[static_cast<size_t>(b)] = 2 * std::numbers::pi;
  SurfaceCurvature c;
  for (size_t i = 0; i < angle.size(); ++i) {
    const double defect = 2 * std::numbers::pi - angle[i];
    if (defect > 0) {
      c.dome += defect;
      c.dome_centre += defect * v.row(static_cast<Eigen::Index>(i)).transpose();
    } else {
      c.saddle += defect;
    }
  }
  if (c.dome > 0) c.dome_centre /= c.dome;
  return c;
}

// A surface that curves round past its widest girth (a cap beyond a hemisphere, a hood closing
// round the head) is refused whatever the mesh: its net curvature (dome + saddle, which the
// facets' noise does not build up) is above the 2π of a hemisphere. Its rim is then shorter than
// a girth inside it, which a flat piece can only follow by folding or by stretching a third or
// more. The stretch's 95th percentile alone missed such caps at fine meshes: a 110° spherical
// cap was refused at 32-128 quads across and only warned at 192 (ARAP makes fewer sweeps there
// before its moves fall under the stop), while its curvature is the same at every size.
void refuse_closing_surface(const std::string& name, const SurfaceCurvature& c) {
  const double net = c.dome + c.saddle;
  if (!(net > 2 * std::numbers::pi)) return;
  // The spherical cap with the same total curvature 2π(1 − cos α).
  const double cap_degrees =
      std::acos(std::max(-1.0, 1 - net / (2 * std::numbers::pi))) * 180 / std::numbers::pi;
  throw PatternError(
      name,
      fmt::format("panel '{}' cannot be cut from flat cloth: it curves round like a nearly "
                  "closed cap ({:.1f} rad of curvature, as much as a cap reaching {:.0f}° "
                  "from its top; a hemisphere has 6.28), centred near ({:.3f}, {:.3f}, "
                  "{:.3f}) m, so its edge is shorter than the girth inside it and a flat "
                  "piece would fold or stretch by a third or more; split it with seams or "
                  "darts (a hood or a close cap is cut from two or more pieces)",
                  name, net, cap_degrees, c.dome_centre.x(), c.dome_centre.y(), c.dome_centre.z()));
}

// Where on the piece a 2D point lies, in words ("at the upper left", "in the middle").
std::string where_on_piece(const Eigen::MatrixX2d& uv, const Eigen::Vector2d& p) {
  const Eigen::Vector2d lo = uv.colwise().minCoeff(), hi = uv.colwise().maxCoeff();
  const Eigen::Vector2d s = (p - lo).cwiseQuotient((hi - lo).cwiseMax(1e-12));
  const char* vertical = s.y() > 2.0 / 3 ? "upper" : (s.y() < 1.0 / 3 ? "lower" : "");
  const char* horizontal = s.x() > 2.0 / 3 ? "right" : (s.x() < 1.0 / 3 ? "left" : "");
  if (*vertical == 0 && *horizontal == 0) return "in the middle";
  if (*vertical == 0) return fmt::format("at the {} side", horizontal);
  if (*horizontal == 0) return fmt::format("in the {} part", vertical);
  return fmt::format("at the {} {}", vertical, horizontal);
}

// Refuses a piece beyond refuse_stretch, warns above warn_stretch (sets out.warning), naming
// where the stretch concentrates. The dart advice depends on the panel's place: one lying on the
// body (`on_body`, fit "body": a bodice) takes a waist or shoulder dart; a free-hanging one (a
// skirt, trial 35 was told of a bodice dart) a seam through the place or a dart from its top edge.
void judge_stretch(FlatPanel& out, const FlatteningOptions& options, bool on_body) {
  const std::string& name = out.id;
  const Eigen::MatrixX2d& uv = out.uv;
  const FlatDistortion& d = out.distortion;
  if (d.length_p95 > options.refuse_stretch)
    throw PatternError(
        name,
        fmt::format("panel '{}' cannot be cut from flat cloth: flattened, it must stretch or "
                    "shrink by {:.0f} % or more over a twentieth of its area, {} of the piece "
                    "(near ({:.3f}, {:.3f}, {:.3f}) m); it curves too much, like a nearly closed "
                    "cap: split it with seams or darts",
                    name, 100 * d.length_p95, where_on_piece(uv, d.worst_point_2d),
                    d.worst_point.x(), d.worst_point.y(), d.worst_point.z()));
  if (d.length_p95 <= options.warn_stretch) return;
  // What to do depends on how the surface curves: the larger of its domed and saddle parts,
  // and for a saddle, where it is. The piece is turned with its grain up, so a saddle in the
  // lowest third lies towards the hem, where a flare drawn wider than a cone makes one and a
  // godet is the tailor's answer; higher up (a bodice back between the shoulder blades and the
  // waist) the answer is a dart or a seam.
  const double lo = uv.col(1).minCoeff(), hi = uv.col(1).maxCoeff();
  const bool towards_hem = d.worst_point_2d.y() - lo < (hi - lo) / 3;
  const std::string saddle_cure =
      towards_hem
          ? "as where a hem is drawn wider than a cone from the seam above would make it: cut "
            "flat, the piece keeps its seams and hem at their drawn lengths and gathers the "
            "difference into a point or a kink of its outline; a seam there or a godet (a wedge "
            "of cloth let in at the hem) would let the cloth lie as drawn"
      : on_body ? "as where cloth is drawn into the hollow of the back or the waist: cut flat, the "
                  "piece keeps its seams at their drawn lengths and gathers the difference into a "
                  "point or a kink of its outline; a dart or a seam through that place (on a "
                  "bodice, a waist or shoulder dart) would let the cloth lie as drawn"
                : "as where a hanging panel is drawn in towards the body: cut flat, the piece "
                  "keeps its seams at their drawn lengths and gathers the difference into a point "
                  "or a kink of its outline; a seam through that place, or a dart from the panel's "
                  "top edge towards it (a skirt's waist dart), would let the cloth lie as drawn";
  const std::string advice =
      -d.saddle > d.dome
          ? fmt::format(
                "the surface is saddle-shaped ({:.2f} rad more angle round its points "
                "than flat cloth has, {:.2f} rad less), {}",
                -d.saddle, d.dome, saddle_cure)
          : fmt::format(
                "the surface is domed ({:.2f} rad less angle round its points than flat cloth "
                "has, {:.2f} rad more), like the seat or the shoulder blades: a dart or a seam "
                "there would let the cloth lie as drawn",
                d.dome, -d.saddle);
  out.warning = fmt::format(
      "panel '{}': the flat piece is {:.1f} % or more longer or shorter than the surface over a "
      "twentieth of its area, {} of the piece (near ({:.3f}, {:.3f}, {:.3f}) m; mean {:.2f} %); "
      "{}",
      name, 100 * d.length_p95, where_on_piece(uv, d.worst_point_2d), d.worst_point.x(),
      d.worst_point.y(), d.worst_point.z(), 100 * d.length_mean, advice);
}

// How far the points of `run` (local vertices) lie from the chord between its ends (m, 2D).
double bow_from_chord(const Eigen::MatrixX2d& uv, const std::vector<int>& run) {
  const Eigen::Vector2d a = uv.row(run.front()).transpose();
  const Eigen::Vector2d along = (Eigen::Vector2d(uv.row(run.back()).transpose()) - a).normalized();
  double bow = 0;
  for (const int i : run) {
    const Eigen::Vector2d q = uv.row(i).transpose() - a;
    bow = std::max(bow, std::abs(along.x() * q.y() - along.y() * q.x()));
  }
  return bow;
}

FlatPanel flatten_freely(const std::string& name, const Eigen::MatrixX3d& v,
                         const Eigen::MatrixX3i& t, const Eigen::MatrixX3d& triangle_warp,
                         const FlatteningOptions& options, bool on_body,
                         const std::vector<int>& centre_run, double max_fold_turn_deg);

// flatten_freely, with the cause said when a refused piece is drawn folded: a panel taken into a
// crease of the body (trial 41, P1: a kimono front whose underarm curve dives into the armpit)
// turns back on itself there, and its flattening folds or stretches beyond use. It was told it
// "curves too much, like a nearly closed cap", which sent the designer to seams and darts; the
// place and the fold are what to change.
FlatPanel flatten_with_warp(const std::string& name, const Eigen::MatrixX3d& v,
                            const Eigen::MatrixX3i& t, const Eigen::MatrixX3d& triangle_warp,
                            const FlatteningOptions& options, bool on_body = true,
                            const std::vector<int>& centre_run = {},
                            double max_fold_turn_deg = std::numeric_limits<double>::infinity()) {
  try {
    return flatten_freely(name, v, t, triangle_warp, options, on_body, centre_run,
                          max_fold_turn_deg);
  } catch (const PatternError& e) {
    const std::string why = e.what();
    const std::string lead = fmt::format("panel '{}' cannot be cut from flat cloth: ", name);
    if (!why.starts_with(lead)) throw;  // not a disk, not oriented: no flattening was made
    const SurfaceFold fold = sharpest_fold(v, t, kTurnedBackDeg);
    if (fold.edges == 0) throw;
    std::string cause = why.substr(lead.size());
    if (const size_t cut = cause.find("; it curves too much"); cut != std::string::npos)
      cause.erase(cut);
    if (const size_t cut = cause.find(", so its edge is shorter"); cut != std::string::npos)
      cause.erase(cut);
    throw PatternError(
        name,
        fmt::format("panel '{}' cannot be cut from flat cloth: it is drawn folded into a crease "
                    "of the body, where its surface turns back on itself (two neighbouring "
                    "triangles of it face {:.0f}° apart at {}), and no flat piece lies like "
                    "that: {}. Draw the panel's curve there across the crease instead of into "
                    "it (a kimono's underarm seam bridges the armpit from the sleeve to the side "
                    "seam: docs/garment.md, \"Seams across a gap\"), or split the panel there",
                    name, fold.angle_deg, point_text(fold.where), cause),
        fold.where);
  }
}

FlatPanel flatten_freely(const std::string& name, const Eigen::MatrixX3d& v,
                         const Eigen::MatrixX3i& t, const Eigen::MatrixX3d& triangle_warp,
                         const FlatteningOptions& options, bool on_body,
                         const std::vector<int>& centre_run, double max_fold_turn_deg) {
  FlatPanel out;
  out.id = name;
  out.triangles = t;
  out.boundary = disk_boundary(name, v.rows(), t);
  const std::vector<RestTriangle> rest = rest_triangles(v, t, name);
  for (const RestTriangle& r : rest) out.area_3d += r.area;
  const SurfaceCurvature curvature = angle_defects(v, t, out.boundary);
  refuse_closing_surface(name, curvature);

  const Eigen::MatrixX2d start = lscm_start(name, v, t, out.area_3d);
  Eigen::MatrixX2d uv = start;
  out.iterations = arap(uv, v, t, rest, out.boundary, options);
  int folded = folded_triangles(uv, t, rest);
  if (folded > 0 && folded_triangles(start, t, rest) == 0) {
    uv = start;  // ARAP folded what LSCM kept unfolded: keep the conformal map
    folded = 0;
  }
  // The mean 2D image of the warp in a flattening (area-weighted unit images; +y when none),
  // over the triangles `use` marks (all when empty); the images' best axis instead where it fits
  // them better by more than options.axis_grain_gain (a strap whose warp runs up it on the front
  // and up it the other way on the back), turned to agree with their mean.
  const auto mean_grain = [&](const Eigen::MatrixX2d& map, const std::vector<char>& use = {}) {
    Eigen::Vector2d grain = Eigen::Vector2d::Zero();
    Eigen::Vector2d doubled = Eigen::Vector2d::Zero();  // Σ area · (cos 2θ, sin 2θ)
    double area = 0;
    for (Eigen::Index f = 0; f < t.rows(); ++f) {
      if (!use.empty() && !use[static_cast<size_t>(f)]) continue;
      const RestTriangle& r = rest[static_cast<size_t>(f)];
      const Eigen::Vector3d w3 = triangle_warp.row(triangle_warp.rows() == 1 ? 0 : f).transpose();
      const Eigen::Vector2d local(w3.dot(r.e1), w3.dot(r.e2));
      const Eigen::Vector2d image = jacobian(map, t, f, r) * local;
      if (!(image.norm() > 0)) continue;
      const Eigen::Vector2d u = image.normalized();
      grain += r.area * u;
      doubled += r.area * Eigen::Vector2d(u.x() * u.x() - u.y() * u.y(), 2 * u.x() * u.y());
      area += r.area;
    }
    if (grain.norm() >= 1e-12 && area > 0) {
      // The mean sin² of the images' angles to a line at angle φ is (1 − R₂ cos 2(φ − φ₂)) / 2
      // (R₂ = |doubled| / area, φ₂ its half angle): the axis φ₂ fits better than the arrows'
      // mean φ₁ by R₂ sin²(φ₁ − φ₂).
      const double axis_angle = 0.5 * std::atan2(doubled.y(), doubled.x());
      const double off = std::atan2(grain.y(), grain.x()) - axis_angle;
      if (doubled.norm() / area * std::sin(off) * std::sin(off) > options.axis_grain_gain) {
        Eigen::Vector2d axis(std::cos(axis_angle), std::sin(axis_angle));
        return axis.dot(grain) < 0 ? Eigen::Vector2d(-axis) : axis;
      }
    }
    return grain.norm() < 1e-12 ? Eigen::Vector2d::UnitY() : grain;
  };
  // A centre line to hold straight (the piece is then cut on the fold): flattened again from the
  // same start turned with the run's chord on the y axis, the run's x held at 0; kept when it
  // folds nothing, costs at most `straight_centre_cost` of 95th-percentile stretch and turns the
  // piece's threads off its mean warp by at most `max_fold_turn_deg` (a fitted piece's
  // FlatteningOptions::fitted_fold_turn_deg). (The caller passes no run for a panel whose grain
  // is turned off the threads: flatten_garment.)
  bool straight = false;
  bool cross = false;  // the held centre line lies along the weft, not the warp
  if (folded == 0 && centre_run.size() >= 3 && options.straight_centre_cost >= 0) {
    const Eigen::RowVector2d a = start.row(centre_run.front());
    const Eigen::Vector2d chord = (start.row(centre_run.back()) - a).transpose();
    const double angle = std::numbers::pi / 2 - std::atan2(chord.y(), chord.x());
    const Eigen::Matrix2d turn = Eigen::Rotation2Dd(angle).toRotationMatrix();
    Eigen::MatrixX2d held = ((start.rowwise() - a) * turn.transpose()).eval();
    const int sweeps = arap(held, v, t, rest, out.boundary, options, centre_run);
    if (folded_triangles(held, t, rest) == 0) {
      const FlatDistortion free = measure(uv, t, rest);
      const FlatDistortion line = measure(held, t, rest);
      // The fold (+y here) against the warp's mean image: the nearer thread's angle to it.
      const Eigen::Vector2d warp = mean_grain(held).normalized();
      const double off = std::acos(std::min(1.0, std::abs(warp.y()))) * 180.0 / std::numbers::pi;
      out.fold_turn_deg = std::min(off, 90.0 - off);
      const bool cheap = line.length_p95 <= free.length_p95 + options.straight_centre_cost;
      out.fold_turn_refused = cheap && out.fold_turn_deg > max_fold_turn_deg;
      if (cheap && !out.fold_turn_refused) {
        out.centre_run = centre_run;
        out.free_centre_bow = bow_from_chord(uv, centre_run);
        out.free_distortion = free;
        out.free_distortion.dome = curvature.dome;
        out.free_distortion.saddle = curvature.saddle;
        out.iterations = sweeps;
        uv = held;
        straight = true;
        // A panel turned 90° (a collar cut across the grain) is folded across the warp.
        const Eigen::Vector2d grain = mean_grain(held);
        cross = std::abs(grain.x()) > std::abs(grain.y());
      }
    }
  }
  if (folded > 0) {
    const FlatDistortion d = measure(uv, t, rest);
    throw PatternError(
        name, fmt::format("panel '{}' cannot be cut from flat cloth: flattened, {} of its {} "
                          "triangles fold over (worst near ({:.3f}, {:.3f}, {:.3f}) m); it curves "
                          "too much, like a nearly closed cap: split it with seams or darts",
                          name, folded, t.rows(), d.worst_point.x(), d.worst_point.y(),
                          d.worst_point.z()));
  }

  // Not folded, but lying over itself: refused like a fold (trial 41, P7).
  if (const OutlineCrossing c = outline_crossings(uv, out.boundary); c.pairs > 0) {
    const auto middle = [&](int edge) -> Eigen::Vector3d {
      const size_t n = out.boundary.size();
      return 0.5 * (v.row(out.boundary[static_cast<size_t>(edge)]) +
                    v.row(out.boundary[(static_cast<size_t>(edge) + 1) % n]))
                       .transpose();
    };
    const Eigen::Vector3d a = middle(c.edge_a), b = middle(c.edge_b);
    throw PatternError(
        name,
        fmt::format("panel '{}' cannot be cut from flat cloth: flattened, the piece lies over "
                    "itself (no triangle folds, but its outline crosses itself{}: its edge near "
                    "({:.3f}, {:.3f}, {:.3f}) m comes down over its edge near ({:.3f}, {:.3f}, "
                    "{:.3f}) m), as a sleeve drawn with its end turned back up or a flounce "
                    "wound more than once round would; cut it in two with a seam across the "
                    "turn between those places (a turned-up cuff is a piece of its own)",
                    name, c.pairs > 1 ? fmt::format(" at {} places", c.pairs) : std::string(),
                    a.x(), a.y(), a.z(), b.x(), b.y(), b.z()));
  }

  // Grain: the mean 2D image of the warp, turned onto +y. A straight centre line is the fold,
  // and a fold lies along a thread: the piece is turned with it on +y (along the warp, the way
  // nearer the warp's mean image) or on +x (along the weft); for a symmetric panel that is the
  // grain of the whole piece the half and its mirror make.
  const Eigen::Vector2d grain = mean_grain(uv);
  double turn = std::numbers::pi / 2 - std::atan2(grain.y(), grain.x());
  if (straight && !cross) turn = grain.y() >= 0 ? 0.0 : std::numbers::pi;
  if (straight && cross) turn = grain.x() >= 0 ? std::numbers::pi / 2 : -std::numbers::pi / 2;
  const Eigen::Matrix2d rotation = Eigen::Rotation2Dd(turn).toRotationMatrix();
  uv = (uv * rotation.transpose()).eval();
  uv.rowwise() -= uv.colwise().minCoeff();
  out.uv = uv;
  for (Eigen::Index f = 0; f < t.rows(); ++f) out.area_2d += signed_area_2d(uv, t, f);
  out.distortion = measure(uv, t, rest);
  out.distortion.dome = curvature.dome;
  out.distortion.saddle = curvature.saddle;
  judge_stretch(out, options, on_body);
  return out;
}

// The two triangles of quad (a, b, c, d): split along the diagonal whose triangles have the
// larger smallest angle.
std::array<Eigen::Vector3i, 2> split_quad(const Eigen::MatrixX3d& v, const Eigen::Vector4i& q) {
  const auto min_angle = [&](int a, int b, int c) {
    double smallest = std::numbers::pi;
    const std::array<int, 3> idx = {a, b, c};
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d p = v.row(idx[k]);
      const Eigen::Vector3d u = Eigen::Vector3d(v.row(idx[(k + 1) % 3])) - p;
      const Eigen::Vector3d w = Eigen::Vector3d(v.row(idx[(k + 2) % 3])) - p;
      smallest = std::min(smallest, std::atan2(u.cross(w).norm(), u.dot(w)));
    }
    return smallest;
  };
  const double a02 = std::min(min_angle(q[0], q[1], q[2]), min_angle(q[0], q[2], q[3]));
  const double a13 = std::min(min_angle(q[0], q[1], q[3]), min_angle(q[1], q[2], q[3]));
  if (a02 >= a13) return {Eigen::Vector3i(q[0], q[1], q[2]), Eigen::Vector3i(q[0], q[2], q[3])};
  return {Eigen::Vector3i(q[0], q[1], q[3]), Eigen::Vector3i(q[1], q[2], q[3])};
}

// The largest angle (degrees, 0 .. 90) between a centre line (`line`: local vertices along the
// outline) and the warp beside it: each edge of the line against the grain axis projected into
// the plane of the triangle on that edge (the warp there before the panel's turn). On a bodice
// or a skirt, however far its centre flares from the vertical, that warp runs down the line
// (0.3-24° on the examples and designs); on a crotch curve, which turns from the vertical at the
// waist to forward under the seat while the leg's warp hangs along the leg, it crosses the
// line's lower part (59-90°), and so does it a hood's crown.
double centre_across_warp_deg(const Eigen::MatrixX3d& v, const Eigen::MatrixX3i& t,
                              const std::vector<int>& line, const Eigen::Vector3d& axis) {
  double worst = 0;
  for (size_t k = 1; k < line.size(); ++k) {
    const int a = line[k - 1], b = line[k];
    for (Eigen::Index f = 0; f < t.rows(); ++f) {
      const auto has = [&](int i) { return t(f, 0) == i || t(f, 1) == i || t(f, 2) == i; };
      if (!has(a) || !has(b)) continue;
      const Eigen::Vector3d p0 = v.row(t(f, 0)), p1 = v.row(t(f, 1)), p2 = v.row(t(f, 2));
      const Eigen::Vector3d normal = (p1 - p0).cross(p2 - p0).normalized();
      const Eigen::Vector3d warp = axis - axis.dot(normal) * normal;
      const Eigen::Vector3d edge = (v.row(b) - v.row(a)).transpose();
      if (warp.norm() < 1e-9 || edge.norm() < 1e-12) break;  // no warp in the plane: no figure
      const double c = std::abs(edge.normalized().dot(warp.normalized()));
      worst = std::max(worst, std::acos(std::min(1.0, c)) * 180.0 / std::numbers::pi);
      break;
    }
  }
  return worst;
}

// The angle (degrees, 0 .. 45) between the chord of `line` (local vertices) in the flat piece
// `uv` and the nearer thread, warp (+y) or weft (+x).
double chord_off_thread_deg(const Eigen::MatrixX2d& uv, const std::vector<int>& line) {
  const Eigen::Vector2d chord = (uv.row(line.back()) - uv.row(line.front())).transpose();
  if (!(chord.norm() > 0)) return 0.0;
  const double off =
      std::acos(std::min(1.0, std::abs(chord.normalized().y()))) * 180.0 / std::numbers::pi;
  return std::min(off, 90.0 - off);
}

double polyline_length(const Eigen::MatrixX2d& uv, const std::vector<int>& vertices) {
  double length = 0;
  for (size_t k = 1; k < vertices.size(); ++k)
    length += (uv.row(vertices[k]) - uv.row(vertices[k - 1])).norm();
  return length;
}

// Balance notches on one side of a seam (`run`: local vertices along the seam, consecutive on
// the piece's outline in either direction), at `fractions` of the side's 2D length.
void add_balance_notches(FlatPanel& flat, const std::vector<int>& run,
                         const std::vector<double>& fractions) {
  if (fractions.empty() || run.size() < 2) return;
  const size_t n = flat.boundary.size();
  std::unordered_map<int, size_t> position;  // local vertex → its place on the outline
  for (size_t k = 0; k < n; ++k) position[flat.boundary[k]] = k;
  std::vector<double> at(run.size(), 0.0);  // arc length at each run vertex
  for (size_t k = 1; k < run.size(); ++k)
    at[k] = at[k - 1] + (flat.uv.row(run[k]) - flat.uv.row(run[k - 1])).norm();
  for (const double f : fractions) {
    const double s = f * at.back();
    size_t k = 0;  // the segment run[k] → run[k + 1] holding arc length s
    while (k + 2 < run.size() && at[k + 1] < s) ++k;
    const double piece = at[k + 1] - at[k];
    const double t = piece > 0 ? std::clamp((s - at[k]) / piece, 0.0, 1.0) : 0.0;
    const size_t i = position.at(run[k]), j = position.at(run[k + 1]);
    if (j == (i + 1) % n)  // the run follows the outline's direction
      flat.balance_notches.push_back({static_cast<int>(i), t});
    else  // it runs against it: the outline edge is run[k + 1] → run[k]
      flat.balance_notches.push_back({static_cast<int>(j), 1 - t});
  }
}

// A quad of a mirrored panel that reaches over the mirror plane x = 0 into its mirror copy:
// two opposite corners on the plane, the other two on either side. garment_mesh.cpp makes one
// where a doublet sits on the centre seam between a panel and its copy (two quads folded onto
// each other there are merged into one, which keeps one panel's id): the garment is symmetric
// but its panels are not, the seam stepping one vertex into the copy. Cut along the plane
// diagonal, each half to the panel on its side, the panel and its copy are mirror images again
// and sewn along the plane (trial 39: the shortalls' `front` was cut 1 and its copy "pair with",
// their cutting lines 18 mm apart at the step).
struct QuadSplit {
  int quad = -1;
  std::array<Eigen::Vector3i, 2> halves;  // corners of the quad, counter-clockwise as the quad
  std::array<int, 2> panels{-1, -1};      // the panel of each half
};

std::vector<QuadSplit> quads_over_mirror_plane(const Garment& garment,
                                               const std::vector<int>& partner) {
  const meshing::QuadMesh& mesh = garment.mesh;
  // The side of the plane each panel lies on: the sign of its quads' summed centroid x.
  std::vector<double> side(garment.panels.size(), 0.0);
  for (Eigen::Index q = 0; q < mesh.face_count(); ++q)
    for (int k = 0; k < 4; ++k)
      side[static_cast<size_t>(garment.face_panel(q))] += mesh.vertices(mesh.faces(q, k), 0);
  // On the plane as centre_run has it (the mirror copies' curves are reflected bit for bit).
  constexpr double kOnPlane = 1e-6;
  std::vector<QuadSplit> out;
  for (Eigen::Index q = 0; q < mesh.face_count(); ++q) {
    const int p = garment.face_panel(q);
    const int m = partner[static_cast<size_t>(p)];
    if (m < 0 || side[static_cast<size_t>(p)] * side[static_cast<size_t>(m)] >= 0) continue;
    const auto x = [&](int k) { return mesh.vertices(mesh.faces(q, k % 4), 0); };
    for (int k = 0; k < 2; ++k) {
      if (std::abs(x(k)) > kOnPlane || std::abs(x(k + 2)) > kOnPlane ||
          std::abs(x(k + 1)) <= kOnPlane || std::abs(x(k + 3)) <= kOnPlane ||
          (x(k + 1) > 0) == (x(k + 3) > 0))
        continue;
      const auto panel_on = [&](double at) {
        return (at > 0) == (side[static_cast<size_t>(p)] > 0) ? p : m;
      };
      QuadSplit split;
      split.quad = static_cast<int>(q);
      split.halves = {Eigen::Vector3i(k, k + 1, k + 2), Eigen::Vector3i(k + 2, (k + 3) % 4, k)};
      split.panels = {panel_on(x(k + 1)), panel_on(x(k + 3))};
      out.push_back(split);
      break;
    }
  }
  return out;
}

// A mirror copy's piece as its original's reflected, when the copy's triangles are exactly the
// original's reflected across x = 0 (build_garment reflects the original's fill, every
// position's x negated bit for bit, and split_quad then picks the same diagonals): the
// flattening of a mirror image is the mirror image of the flattening. Flattened on its own, a
// copy lands elsewhere: LSCM's pinned vertices, ARAP's held vertex 0 and the order of its
// sums follow the vertex numbering, and ARAP stops (200 sweeps) before it has converged, so two
// numberings of one surface ended 2 mm and 0.8 % of stretch apart (the wide shorts' legs).
// Empty when the copy differs in 3D (a fold repaired on one side only), which is flattened on
// its own.
std::optional<FlatPanel> reflected_piece(const FlatPanel& original, const Eigen::MatrixX3d& all,
                                         const std::string& name, const Eigen::MatrixX3d& v,
                                         const Eigen::MatrixX3i& t,
                                         const FlatteningOptions& options, bool on_body) {
  if (original.vertices.size() != static_cast<size_t>(v.rows()) ||
      original.triangles.rows() != t.rows())
    return std::nullopt;
  std::map<std::array<double, 3>, int> at;
  for (size_t i = 0; i < original.vertices.size(); ++i) {
    const auto p = all.row(original.vertices[i]);
    at.emplace(std::array{p.x(), p.y(), p.z()}, static_cast<int>(i));
  }
  std::vector<int> image(static_cast<size_t>(v.rows()), -1);
  std::vector<char> hit(original.vertices.size(), 0);
  for (Eigen::Index i = 0; i < v.rows(); ++i) {
    const auto it = at.find({-v(i, 0), v(i, 1), v(i, 2)});
    if (it == at.end() || hit[static_cast<size_t>(it->second)]) return std::nullopt;
    image[static_cast<size_t>(i)] = it->second;
    hit[static_cast<size_t>(it->second)] = 1;
  }
  // Each copy triangle must be an original one with its corners in the opposite turn (a
  // reflection reverses orientation; the copy's quads are the original's reversed).
  const auto canonical = [](int a, int b, int c) {
    if (b < a && b < c) return std::array{b, c, a};
    if (c < a && c < b) return std::array{c, a, b};
    return std::array{a, b, c};
  };
  std::set<std::array<int, 3>> reversed;
  for (Eigen::Index f = 0; f < original.triangles.rows(); ++f)
    reversed.insert(
        canonical(original.triangles(f, 0), original.triangles(f, 2), original.triangles(f, 1)));
  for (Eigen::Index f = 0; f < t.rows(); ++f)
    if (reversed.count(canonical(image[static_cast<size_t>(t(f, 0))],
                                 image[static_cast<size_t>(t(f, 1))],
                                 image[static_cast<size_t>(t(f, 2))])) == 0)
      return std::nullopt;

  FlatPanel out;
  out.id = name;
  out.triangles = t;
  out.boundary = disk_boundary(name, v.rows(), t);
  // x → width − x keeps the bounding box at (0, 0) and the grain on +y; with the reversed
  // corners the triangles stay counter-clockwise.
  const double width = original.uv.col(0).maxCoeff();
  out.uv.resize(v.rows(), 2);
  for (Eigen::Index i = 0; i < v.rows(); ++i) {
    const auto q = original.uv.row(image[static_cast<size_t>(i)]);
    out.uv.row(i) << width - q.x(), q.y();
  }
  out.area_3d = original.area_3d;
  out.area_2d = original.area_2d;
  out.iterations = original.iterations;
  out.distortion = original.distortion;
  out.centre_run = original.centre_run;  // the original's numbering: the caller renumbers it
  out.free_centre_bow = original.free_centre_bow;
  out.centre_off_grain_deg = original.centre_off_grain_deg;
  out.fold_turn_deg = original.fold_turn_deg;
  out.fold_turn_refused = original.fold_turn_refused;
  out.free_distortion = original.free_distortion;
  out.distortion.worst_point.x() = -original.distortion.worst_point.x();
  out.distortion.worst_point_2d.x() = width - original.distortion.worst_point_2d.x();
  judge_stretch(out, options, on_body);
  return out;
}

}  // namespace

std::string point_text(const Eigen::Vector3d& p) {
  return fmt::format("({:.3f}, {:.3f}, {:.3f}) m", p.x(), p.y(), p.z());
}

SurfaceFold sharpest_fold(const Eigen::MatrixX3d& vertices, const Eigen::MatrixXi& faces,
                          double threshold_deg, const Eigen::VectorXi* group) {
  if (faces.cols() == 4) {
    // Quads as the pattern splits them (split_quad): a warped quad of a crease folds across its
    // diagonal, and the kimono front drawn into the armpit turns 140° between triangles where
    // its quads' normals are 84° apart.
    Eigen::MatrixXi triangles(2 * faces.rows(), 3);
    Eigen::VectorXi halves(2 * faces.rows());
    for (Eigen::Index f = 0; f < faces.rows(); ++f) {
      const auto two = split_quad(vertices, faces.row(f).transpose());
      for (Eigen::Index k = 0; k < 2; ++k) {
        triangles.row(2 * f + k) = two[static_cast<size_t>(k)].transpose();
        halves(2 * f + k) = group != nullptr ? (*group)(f) : 0;
      }
    }
    return sharpest_fold(vertices, triangles, threshold_deg, &halves);
  }
  const Eigen::Index corners = faces.cols();
  const auto normal = [&](Eigen::Index f) -> Eigen::Vector3d {
    const auto p = [&](int k) -> Eigen::Vector3d { return vertices.row(faces(f, k)).transpose(); };
    const Eigen::Vector3d n = corners == 4 ? Eigen::Vector3d((p(2) - p(0)).cross(p(3) - p(1)))
                                           : Eigen::Vector3d((p(1) - p(0)).cross(p(2) - p(0)));
    return n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::Zero();
  };
  std::map<std::pair<int, int>, Eigen::Index> first;  // undirected edge → the face seen first
  SurfaceFold fold;
  const double cos_threshold = std::cos(threshold_deg * std::numbers::pi / 180);
  double lowest_cos = 2;
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (Eigen::Index k = 0; k < corners; ++k) {
      const int a = faces(f, k), b = faces(f, (k + 1) % corners);
      const auto [it, fresh] = first.emplace(std::minmax(a, b), f);
      if (fresh) continue;
      const Eigen::Index g = it->second;
      if (group != nullptr && (*group)(f) != (*group)(g)) continue;
      const Eigen::Vector3d nf = normal(f), ng = normal(g);
      if (nf.isZero() || ng.isZero()) continue;
      const double c = std::clamp(nf.dot(ng), -1.0, 1.0);
      if (c < cos_threshold) ++fold.edges;
      if (c < lowest_cos) {
        lowest_cos = c;
        fold.angle_deg = std::acos(c) * 180 / std::numbers::pi;
        fold.where = 0.5 * (vertices.row(a) + vertices.row(b)).transpose();
      }
    }
  return fold;
}

double PatternSeam::mismatch() const {
  const double longest = std::max(length_a, length_b);
  return longest > 0 ? std::abs(length_a - length_b) / longest : 0.0;
}

FlatPanel flatten_disk(const std::string& name, const Eigen::MatrixX3d& vertices,
                       const Eigen::MatrixX3i& triangles, const Eigen::Vector3d& warp,
                       const FlatteningOptions& options) {
  Eigen::Vector3d w = warp;
  if (w.norm() == 0) {
    const Eigen::Vector3d extent = vertices.colwise().maxCoeff() - vertices.colwise().minCoeff();
    Eigen::Index axis;
    extent.maxCoeff(&axis);
    w = Eigen::Vector3d::Unit(axis);
  }
  FlatPanel out = flatten_with_warp(name, vertices, triangles, w.transpose(), options);
  out.vertices.resize(static_cast<size_t>(vertices.rows()));
  for (size_t i = 0; i < out.vertices.size(); ++i) out.vertices[i] = static_cast<int>(i);
  return out;
}

FlatPattern flatten_garment(const Garment& garment, const FlatteningOptions& options) {
  const meshing::QuadMesh& mesh = garment.mesh;
  const MaterialFrames frames = material_frames(garment);
  FlatPattern pattern;
  const Eigen::Index nv = mesh.vertex_count();

  // Each panel's mirror partner ("front" and "front.mirror"), or −1.
  std::vector<int> mirror_of(garment.panels.size(), -1);
  for (size_t p = 0; p < garment.panels.size(); ++p)
    for (size_t q = 0; q < garment.panels.size(); ++q)
      if (garment.panels[q].id == garment.panels[p].id + ".mirror") {
        mirror_of[p] = static_cast<int>(q);
        mirror_of[q] = static_cast<int>(p);
      }
  const std::vector<QuadSplit> splits = quads_over_mirror_plane(garment, mirror_of);
  std::unordered_map<int, const QuadSplit*> split_of;
  for (const QuadSplit& split : splits) split_of[split.quad] = &split;

  // Which panel lies across each directed garment edge: the one traversing it backwards (a quad
  // split over the mirror plane: each half's panel, the plane diagonal between them).
  std::unordered_map<long long, int> edge_panel;
  const auto key = [&](int a, int b) { return static_cast<long long>(a) * nv + b; };
  for (Eigen::Index q = 0; q < mesh.face_count(); ++q) {
    const auto split = split_of.find(static_cast<int>(q));
    if (split == split_of.end()) {
      for (int k = 0; k < 4; ++k)
        edge_panel[key(mesh.faces(q, k), mesh.faces(q, (k + 1) % 4))] = garment.face_panel(q);
      continue;
    }
    for (int h = 0; h < 2; ++h) {
      const Eigen::Vector3i& tri = split->second->halves[static_cast<size_t>(h)];
      for (int k = 0; k < 3; ++k)
        edge_panel[key(mesh.faces(q, tri[k]), mesh.faces(q, tri[(k + 1) % 3]))] =
            split->second->panels[static_cast<size_t>(h)];
    }
  }
  // The panel's centre line: its one run of outline edges on the mirror plane x = 0 sewn to its
  // own mirror copy ("front" and "front.mirror"), as local vertices in outline order; empty when
  // it has none, or several (then there is no one line to fold along).
  const auto centre_run = [&](size_t p, const std::vector<int>& global,
                              const std::vector<int>& loop) -> std::vector<int> {
    const std::string& id = garment.panels[p].id;
    const std::string partner =
        garment.panels[p].mirror_copy ? id.substr(0, id.rfind('.')) : id + ".mirror";
    int other = -1;
    for (size_t q = 0; q < garment.panels.size(); ++q)
      if (garment.panels[q].id == partner) other = static_cast<int>(q);
    if (other < 0) return {};
    const size_t n = loop.size();
    const auto on_plane = [&](size_t k) {
      return std::abs(mesh.vertices(global[static_cast<size_t>(loop[k % n])], 0)) <= 1e-6;
    };
    std::vector<char> centre(n, 0);
    for (size_t k = 0; k < n; ++k) {
      const int a = global[static_cast<size_t>(loop[k])];
      const int b = global[static_cast<size_t>(loop[(k + 1) % n])];
      const auto it = edge_panel.find(key(b, a));
      centre[k] = on_plane(k) && on_plane(k + 1) && it != edge_panel.end() && it->second == other;
    }
    std::vector<int> run;
    for (size_t k = 0; k < n; ++k) {
      if (!centre[k] || centre[(k + n - 1) % n]) continue;
      if (!run.empty()) return {};  // a second run
      size_t last = k;
      while (centre[(last + 1) % n] && (last + 1) % n != k) last = (last + 1) % n;
      for (size_t i = k;; i = (i + 1) % n) {
        run.push_back(loop[i]);
        if (i == (last + 1) % n) break;
      }
    }
    return run;
  };

  // Per panel: local vertices, triangles, flattening.
  for (size_t p = 0; p < garment.panels.size(); ++p) {
    std::vector<int> local(static_cast<size_t>(nv), -1);
    std::vector<int> global;
    std::vector<Eigen::Vector3i> tris;
    std::vector<int> tri_quad;
    for (Eigen::Index q = 0; q < mesh.face_count(); ++q) {
      // The quad's triangles that are this panel's, as corners of the quad.
      std::vector<Eigen::Vector3i> mine;
      if (const auto split = split_of.find(static_cast<int>(q)); split != split_of.end()) {
        for (int h = 0; h < 2; ++h)
          if (split->second->panels[static_cast<size_t>(h)] == static_cast<int>(p))
            mine.push_back(split->second->halves[static_cast<size_t>(h)]);
      } else if (garment.face_panel(q) == static_cast<int>(p)) {
        Eigen::MatrixX3d positions(4, 3);
        for (int k = 0; k < 4; ++k) positions.row(k) = mesh.vertices.row(mesh.faces(q, k));
        const auto both = split_quad(positions, Eigen::Vector4i(0, 1, 2, 3));
        mine.assign(both.begin(), both.end());
      }
      if (mine.empty()) continue;
      Eigen::Vector4i corners = Eigen::Vector4i::Constant(-1);
      for (int k = 0; k < 4; ++k) {
        if (std::none_of(mine.begin(), mine.end(), [&](const Eigen::Vector3i& tri) {
              return tri[0] == k || tri[1] == k || tri[2] == k;
            }))
          continue;
        int& l = local[static_cast<size_t>(mesh.faces(q, k))];
        if (l < 0) {
          l = static_cast<int>(global.size());
          global.push_back(mesh.faces(q, k));
        }
        corners[k] = l;
      }
      for (const Eigen::Vector3i& tri : mine) {
        tris.emplace_back(corners[tri[0]], corners[tri[1]], corners[tri[2]]);
        tri_quad.push_back(static_cast<int>(q));
      }
    }
    const std::string& name = garment.panels[p].id;
    if (tris.empty()) throw PatternError(name, fmt::format("panel '{}' has no faces", name));
    Eigen::MatrixX3d v(static_cast<Eigen::Index>(global.size()), 3);
    for (size_t i = 0; i < global.size(); ++i)
      v.row(static_cast<Eigen::Index>(i)) = mesh.vertices.row(global[i]);
    Eigen::MatrixX3i t(static_cast<Eigen::Index>(tris.size()), 3);
    Eigen::MatrixX3d warp(t.rows(), 3);
    Eigen::VectorXi quad_of(t.rows());
    for (Eigen::Index f = 0; f < t.rows(); ++f) {
      t.row(f) = tris[static_cast<size_t>(f)].transpose();
      quad_of(f) = tri_quad[static_cast<size_t>(f)];
      warp.row(f) = frames.warp.row(quad_of(f));
    }
    const bool on_body = garment.panels[p].fit == "body";
    std::optional<FlatPanel> reflected;
    if (garment.panels[p].mirror_copy) {
      const std::string base = name.substr(0, name.rfind('.'));
      for (size_t o = 0; o < pattern.panels.size() && !reflected; ++o)
        if (pattern.panels[o].id == base) {
          reflected =
              reflected_piece(pattern.panels[o], mesh.vertices, name, v, t, options, on_body);
          if (reflected) reflected->reflection_of = static_cast<int>(o);
        }
    }
    const std::vector<int> line = centre_run(p, global, disk_boundary(name, v.rows(), t));
    // A fold is a thread of the folded fabric: a panel whose grain is turned off the threads of
    // its centre line (a bias cut, "grain": 45) keeps its centre seam, cut 2 as drawn. By
    // symmetry the warp of a panel not turned runs along its centre line (the vertical, or the
    // limb's axis, projected into the plane x = 0), so the turn is the fold's angle to the grain
    // where the line runs along that axis; where it turns away from it (a crotch curve, vertical
    // at the waist and forward under the seat) the warp beside it crosses it instead, and held
    // straight the line is no thread: the piece's grain is turned off the fold (trial 43, P2).
    const double off_thread = std::abs(std::remainder(garment.panels[p].grain_turn_deg, 90.0));
    const bool has_run = !line.empty();
    const double across_warp =
        has_run ? centre_across_warp_deg(v, t, line, garment.panels[p].grain_axis) : -1.0;
    const bool on_thread =
        off_thread <= options.fold_off_grain_deg && across_warp <= options.fold_across_warp_deg;
    const std::vector<int> run = on_thread ? line : std::vector<int>{};
    const PanelEase& ease = garment.panels[p].ease;
    const double max_turn = ease.warp < 1.0 || ease.weft < 1.0
                                ? options.fitted_fold_turn_deg
                                : std::numeric_limits<double>::infinity();
    FlatPanel flat = reflected
                         ? std::move(*reflected)
                         : flatten_with_warp(name, v, t, warp, options, on_body, run, max_turn);
    if (reflected && !flat.centre_run.empty()) flat.centre_run = run;
    flat.centre_across_warp_deg = across_warp;
    // What the cut piece has: a line on a thread is held (and folded) on the grain line but for
    // the panel's turn; a line off the threads keeps its seam, and its chord in the piece lies
    // that far off the grain line (+y) or the cross grain (a mirror copy cut as its original
    // turned over: the original's); so does a line on a thread whose fold would turn a fitted
    // piece's threads too far (FlatteningOptions::fitted_fold_turn_deg).
    if (!has_run)
      flat.centre_off_grain_deg = -1.0;
    else if (on_thread && !flat.fold_turn_refused)
      flat.centre_off_grain_deg = off_thread;
    else if (!reflected)
      flat.centre_off_grain_deg = chord_off_thread_deg(flat.uv, line);
    flat.panel = static_cast<int>(p);
    flat.vertices = std::move(global);
    flat.triangle_quad = std::move(quad_of);
    // A mirror copy cut as its panel's piece turned over has the panel's warning, mirrored: one
    // warning names both (trial 35: every warning printed twice, 600 characters each).
    bool told_with_original = false;
    if (!flat.warning.empty() && flat.reflection_of >= 0) {
      const FlatPanel& original = pattern.panels[static_cast<size_t>(flat.reflection_of)];
      const auto told =
          std::find(pattern.warnings.begin(), pattern.warnings.end(), original.warning);
      const std::string prefix = "panel '" + original.id + "':";
      if (told != pattern.warnings.end() && told->starts_with(prefix)) {
        *told = fmt::format("panel '{}' and its mirror copy '{}' (the same piece turned over):{}",
                            original.id, name, told->substr(prefix.size()));
        told_with_original = true;
      }
    }
    if (!flat.warning.empty() && !told_with_original) pattern.warnings.push_back(flat.warning);
    // A strap laid across the grain (piece_grain.hpp), said once for a panel and its mirror copy.
    if (!garment.panels[p].mirror_copy)
      if (std::string across = cross_grain_warning(flat, garment.panels[p]); !across.empty()) {
        const std::string prefix = "panel '" + name + "':";
        const bool mirrored =
            std::any_of(garment.panels.begin(), garment.panels.end(),
                        [&](const GarmentPanel& g) { return g.id == name + ".mirror"; });
        if (mirrored && across.starts_with(prefix))
          across = fmt::format("panel '{}' and its mirror copy '{}.mirror':{}", name, name,
                               across.substr(prefix.size()));
        pattern.warnings.push_back(std::move(across));
      }
    pattern.panels.push_back(std::move(flat));
  }

  // Runs of boundary edges with the same panel across; a run's ends are notches.
  struct Run {
    int panel, across;
    std::vector<int> vertices;  // local, in loop order
  };
  std::vector<Run> runs;
  for (size_t p = 0; p < pattern.panels.size(); ++p) {
    FlatPanel& flat = pattern.panels[p];
    const std::vector<int>& loop = flat.boundary;
    const size_t n = loop.size();
    std::vector<int> across(n);
    for (size_t k = 0; k < n; ++k) {
      const int a = flat.vertices[static_cast<size_t>(loop[k])];
      const int b = flat.vertices[static_cast<size_t>(loop[(k + 1) % n])];
      const auto it = edge_panel.find(key(b, a));
      across[k] = it == edge_panel.end() ? -1 : it->second;
    }
    size_t first = 0;
    while (first < n && across[first] == across[(first + n - 1) % n]) ++first;
    if (first == n) {  // one neighbour (or none) all around: no junctions
      if (across[0] >= 0) {
        Run r{static_cast<int>(p), across[0], {}};
        for (size_t k = 0; k <= n; ++k) r.vertices.push_back(loop[k % n]);
        runs.push_back(std::move(r));
      }
      continue;
    }
    for (size_t s = 0; s < n;) {
      const size_t k0 = (first + s) % n;
      Run r{static_cast<int>(p), across[k0], {loop[k0]}};
      flat.notches.push_back(loop[k0]);
      while (s < n && across[(first + s) % n] == r.across) {
        r.vertices.push_back(loop[(first + s + 1) % n]);
        ++s;
      }
      if (r.across >= 0) runs.push_back(std::move(r));
    }
  }

  // Pair each run with the run on the other panel over the same garment vertices.
  std::vector<bool> used(runs.size(), false);
  for (size_t i = 0; i < runs.size(); ++i) {
    if (used[i]) continue;
    const Run& a = runs[i];
    const FlatPanel& fa = pattern.panels[static_cast<size_t>(a.panel)];
    const int a_first = fa.vertices[static_cast<size_t>(a.vertices.front())];
    const int a_last = fa.vertices[static_cast<size_t>(a.vertices.back())];
    for (size_t j = i + 1; j < runs.size(); ++j) {
      const Run& b = runs[j];
      if (used[j] || b.panel != a.across || b.across != a.panel ||
          b.vertices.size() != a.vertices.size())
        continue;
      const FlatPanel& fb = pattern.panels[static_cast<size_t>(b.panel)];
      // The neighbour runs the seam the other way round.
      if (fb.vertices[static_cast<size_t>(b.vertices.back())] != a_first ||
          fb.vertices[static_cast<size_t>(b.vertices.front())] != a_last)
        continue;
      used[i] = used[j] = true;
      PatternSeam seam;
      seam.panel_a = a.panel;
      seam.panel_b = b.panel;
      seam.vertices_a = a.vertices;
      seam.vertices_b.assign(b.vertices.rbegin(), b.vertices.rend());
      for (size_t k = 1; k < a.vertices.size(); ++k)
        seam.length_3d += (mesh.vertices.row(fa.vertices[static_cast<size_t>(a.vertices[k])]) -
                           mesh.vertices.row(fa.vertices[static_cast<size_t>(a.vertices[k - 1])]))
                              .norm();
      seam.length_a = polyline_length(fa.uv, seam.vertices_a);
      seam.length_b = polyline_length(fb.uv, seam.vertices_b);
      if (seam.length_3d > options.balance_from) {
        const int count =
            std::max(1, static_cast<int>(std::ceil(seam.length_3d / options.balance_spacing)) - 1);
        for (int k = 1; k <= count; ++k)
          seam.balance.push_back(static_cast<double>(k) / (count + 1));
      }
      add_balance_notches(pattern.panels[static_cast<size_t>(a.panel)], seam.vertices_a,
                          seam.balance);
      add_balance_notches(pattern.panels[static_cast<size_t>(b.panel)], seam.vertices_b,
                          seam.balance);
      pattern.seams.push_back(std::move(seam));
      break;
    }
  }
  return pattern;
}

}  // namespace sd::garment
