#include "garment/pattern_layout.hpp"

// GCC 12 sees a possibly uninitialised value inside CGAL's Polygon_2 simplicity test (a false
// positive in the library's sweep code).
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_2.h>
#include <CGAL/create_offset_polygons_2.h>
#include <fmt/format.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace sd::garment {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Polygon = CGAL::Polygon_2<Kernel>;

double signed_area(const Eigen::MatrixX2d& p) {
  double a = 0;
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    const Eigen::Index j = (i + 1) % p.rows();
    a += p(i, 0) * p(j, 1) - p(j, 0) * p(i, 1);
  }
  return 0.5 * a;
}

// Douglas-Peucker on a closed polyline: the points kept lie within `tolerance` of the original.
// Point 0 and the point farthest from it are always kept.
Eigen::MatrixX2d simplify_closed(const Eigen::MatrixX2d& p, double tolerance) {
  const Eigen::Index n = p.rows();
  if (n <= 4) return p;
  std::vector<bool> keep(static_cast<size_t>(n), false);
  Eigen::Index far = 0;
  (p.rowwise() - p.row(0)).rowwise().squaredNorm().maxCoeff(&far);
  keep[0] = keep[static_cast<size_t>(far)] = true;
  std::vector<std::pair<Eigen::Index, Eigen::Index>> stack = {{0, far}, {far, n}};
  while (!stack.empty()) {
    const auto [a, b] = stack.back();
    stack.pop_back();
    const Eigen::Vector2d pa = p.row(a), pb = p.row(b % n);
    const Eigen::Vector2d d = pb - pa;
    double worst = -1;
    Eigen::Index at = -1;
    for (Eigen::Index i = a + 1; i < b; ++i) {
      const Eigen::Vector2d q = Eigen::Vector2d(p.row(i)) - pa;
      const double dist =
          d.norm() > 0 ? std::abs(d.x() * q.y() - d.y() * q.x()) / d.norm() : q.norm();
      if (dist > worst) {
        worst = dist;
        at = i;
      }
    }
    if (at >= 0 && worst > tolerance) {
      keep[static_cast<size_t>(at)] = true;
      stack.emplace_back(a, at);
      stack.emplace_back(at, b);
    }
  }
  std::vector<Eigen::Index> rows;
  for (Eigen::Index i = 0; i < n; ++i)
    if (keep[static_cast<size_t>(i)]) rows.push_back(i);
  Eigen::MatrixX2d out(static_cast<Eigen::Index>(rows.size()), 2);
  for (size_t k = 0; k < rows.size(); ++k) out.row(static_cast<Eigen::Index>(k)) = p.row(rows[k]);
  return out;
}

// Douglas-Peucker on the open polyline p[first .. last] (indices modulo p.rows()): marks in
// `keep` the points the simplified run keeps (its two ends always).
void simplify_run(const Eigen::MatrixX2d& p, Eigen::Index first, Eigen::Index last,
                  double tolerance, std::vector<bool>& keep) {
  const Eigen::Index n = p.rows();
  keep[static_cast<size_t>(first % n)] = keep[static_cast<size_t>(last % n)] = true;
  std::vector<std::pair<Eigen::Index, Eigen::Index>> stack = {{first, last}};
  while (!stack.empty()) {
    const auto [a, b] = stack.back();
    stack.pop_back();
    const Eigen::Vector2d pa = p.row(a % n), pb = p.row(b % n);
    const Eigen::Vector2d d = pb - pa;
    double worst = -1;
    Eigen::Index at = -1;
    for (Eigen::Index i = a + 1; i < b; ++i) {
      const Eigen::Vector2d q = Eigen::Vector2d(p.row(i % n)) - pa;
      const double dist =
          d.norm() > 0 ? std::abs(d.x() * q.y() - d.y() * q.x()) / d.norm() : q.norm();
      if (dist > worst) {
        worst = dist;
        at = i;
      }
    }
    if (at >= 0 && worst > tolerance) {
      keep[static_cast<size_t>(at % n)] = true;
      stack.emplace_back(a, at);
      stack.emplace_back(at, b);
    }
  }
}

// The sewing line offset outwards by a different allowance per edge (allowance[i]: edge i from
// point i to i + 1, at least two values). CGAL 5.5's straight skeleton has no weights, so: each
// run of one allowance is simplified (Douglas-Peucker, 0.1 mm; the points where the allowance
// changes are kept), every simplified edge's line is moved out by its allowance, and the lines
// of consecutive edges meet at their intersection (the mitre a pattern maker draws where two
// allowances meet at a corner). Where two different allowances meet with their edges nearly in
// line, or their lines would meet farther than 4 allowances out, the cutting line steps across
// at the point instead. Throws PatternError if the result crosses itself.
Eigen::MatrixX2d offset_by_edge(const std::string& name, const Eigen::MatrixX2d& sewing,
                                const std::vector<double>& allowance) {
  const Eigen::Index n = sewing.rows();
  std::vector<Eigen::Index> changes;  // points where the allowance changes
  for (Eigen::Index i = 0; i < n; ++i)
    if (allowance[static_cast<size_t>(i)] != allowance[static_cast<size_t>((i + n - 1) % n)])
      changes.push_back(i);
  std::vector<bool> keep(static_cast<size_t>(n), false);
  for (size_t k = 0; k < changes.size(); ++k) {
    const Eigen::Index a = changes[k];
    Eigen::Index b = changes[(k + 1) % changes.size()];
    if (b <= a) b += n;
    simplify_run(sewing, a, b, 1e-4, keep);
  }
  std::vector<Eigen::Index> kept;
  for (Eigen::Index i = 0; i < n; ++i)
    if (keep[static_cast<size_t>(i)]) kept.push_back(i);
  const size_t m = kept.size();
  // Simplified edge j: kept[j] → kept[j + 1], inside one run: the allowance of its first edge.
  std::vector<Eigen::Vector2d> tangent(m), normal(m);
  std::vector<double> d(m);
  for (size_t j = 0; j < m; ++j) {
    const Eigen::Vector2d a = sewing.row(kept[j]), b = sewing.row(kept[(j + 1) % m]);
    tangent[j] = (b - a).normalized();
    normal[j] = Eigen::Vector2d(tangent[j].y(), -tangent[j].x());  // outwards on a CCW outline
    d[j] = allowance[static_cast<size_t>(kept[j])];
  }
  std::vector<Eigen::Vector2d> out;
  for (size_t j = 0; j < m; ++j) {
    const size_t i = (j + m - 1) % m;  // the edge before point kept[j]
    const Eigen::Vector2d p = sewing.row(kept[j]);
    const Eigen::Vector2d on_a = p + d[i] * normal[i], on_b = p + d[j] * normal[j];
    Eigen::Matrix2d lines;
    lines << tangent[i], -tangent[j];
    const double sine = tangent[i].x() * tangent[j].y() - tangent[i].y() * tangent[j].x();
    const bool same = d[i] == d[j];
    if (std::abs(sine) < (same ? 1e-12 : 1e-3)) {
      out.push_back(on_a);
      if (!same) out.push_back(on_b);
      continue;
    }
    const Eigen::Vector2d st = lines.partialPivLu().solve(on_b - on_a);
    const Eigen::Vector2d corner = on_a + st.x() * tangent[i];
    if (!same && (corner - p).norm() > 4 * std::max(d[i], d[j])) {
      out.push_back(on_a);
      out.push_back(on_b);
    } else {
      out.push_back(corner);
    }
  }
  Polygon polygon;
  Eigen::MatrixX2d cutting(static_cast<Eigen::Index>(out.size()), 2);
  for (size_t k = 0; k < out.size(); ++k) {
    cutting.row(static_cast<Eigen::Index>(k)) = out[k].transpose();
    polygon.push_back(Kernel::Point_2(out[k].x(), out[k].y()));
  }
  if (!polygon.is_simple() || polygon.orientation() != CGAL::COUNTERCLOCKWISE)
    throw PatternError(name, fmt::format("the seam allowances of panel '{}' cross each other: "
                                         "a concave curve of its outline is tighter than the "
                                         "allowance along it; give that seam a smaller one",
                                         name));
  return cutting;
}

// The sewing line offset outwards by `allowance` (straight skeleton: corners stay sharp).
Eigen::MatrixX2d offset_outwards(const std::string& name, const Eigen::MatrixX2d& sewing,
                                 double allowance) {
  if (allowance <= 0) return sewing;
  // A cutting line needs no finer detail than a tenth of a millimetre; fewer vertices keep the
  // skeleton quick.
  const Eigen::MatrixX2d coarse = simplify_closed(sewing, 1e-4);
  Polygon polygon;
  for (Eigen::Index i = 0; i < coarse.rows(); ++i)
    polygon.push_back(Kernel::Point_2(coarse(i, 0), coarse(i, 1)));
  if (!polygon.is_simple())
    throw PatternError(name, fmt::format("the flat piece of panel '{}' overlaps itself: it cannot "
                                         "be cut as one piece; split it with a seam",
                                         name));
  const auto result = CGAL::create_exterior_skeleton_and_offset_polygons_2(allowance, polygon);
  // The result holds the offset of an enclosing frame (counter-clockwise, large) and the offset
  // of the piece as its hole (clockwise): take the largest clockwise one.
  const Polygon* best = nullptr;
  for (const auto& p : result)
    if (p->orientation() == CGAL::CLOCKWISE && (!best || p->area() < best->area())) best = p.get();
  if (!best)
    throw PatternError(name,
                       fmt::format("the seam allowance of panel '{}' could not be drawn", name));
  Eigen::MatrixX2d out(static_cast<Eigen::Index>(best->size()), 2);
  Eigen::Index row = out.rows() - 1;  // reversed: counter-clockwise like the sewing line
  for (auto v = best->vertices_begin(); v != best->vertices_end(); ++v, --row)
    out.row(row) << v->x(), v->y();
  return out;
}

// The sewing line of a piece cut on the fold, offset by one allowance all round but along the
// fold (points s → e of `sewing`, a straight run, which has none): the piece opened out across
// the fold (its reflection joined to it there), offset as one piece by the straight skeleton and
// cut back along the fold line. So the offsets of a concave curve tighter than the allowance merge
// as on a piece with one allowance all round, where offset_by_edge's mitred lines would cross
// (trial 43, P1: the jumpsuit's back leg, then folded along its crotch curve, was refused at the
// default 1 cm; docs/pattern.md, "Seam allowance per seam"). std::nullopt when the opened piece
// is no simple polygon (the piece reaches across its fold line): the caller mitres edge by edge.
std::optional<Eigen::MatrixX2d> offset_on_fold(const std::string& name,
                                               const Eigen::MatrixX2d& sewing, Eigen::Index s,
                                               Eigen::Index e, double allowance) {
  const Eigen::Index n = sewing.rows();
  const Eigen::Vector2d a = sewing.row(s).transpose();
  const Eigen::Vector2d along = (sewing.row(e).transpose() - a).normalized();
  const Eigen::Vector2d inside(-along.y(), along.x());  // left of the fold on a CCW outline
  // The outline off the fold, e → s; then its reflection back, s → e, ends left out (on the fold).
  std::vector<Eigen::Vector2d> rest;
  for (Eigen::Index i = e;; i = (i + 1) % n) {
    const Eigen::Vector2d p = sewing.row(i).transpose();
    if (inside.dot(p - a) < -1e-9) return std::nullopt;
    rest.push_back(p);
    if (i == s) break;
  }
  std::vector<Eigen::Vector2d> opened = rest;
  for (size_t k = rest.size() - 1; k-- > 1;) {
    const Eigen::Vector2d q = rest[k] - a;
    opened.push_back(a + 2 * q.dot(along) * along - q);
  }
  Eigen::MatrixX2d whole(static_cast<Eigen::Index>(opened.size()), 2);
  for (size_t k = 0; k < opened.size(); ++k)
    whole.row(static_cast<Eigen::Index>(k)) = opened[k].transpose();
  Eigen::MatrixX2d offset;
  try {
    offset = offset_outwards(name, whole, allowance);
  } catch (const PatternError&) {
    return std::nullopt;
  }
  // Clipped to the piece's side of the fold line (Sutherland-Hodgman against one half-plane):
  // the skeleton of a symmetric polygon is symmetric, so this is its half, and the cutting line
  // runs along the fold between where the allowances of the fold's neighbours reach it.
  const auto side = [&](const Eigen::Vector2d& p) {
    const double f = inside.dot(p - a);
    return std::abs(f) < 1e-12 ? 0.0 : f;
  };
  std::vector<Eigen::Vector2d> half;
  for (Eigen::Index i = 0; i < offset.rows(); ++i) {
    const Eigen::Vector2d p = offset.row(i).transpose();
    const Eigen::Vector2d q = offset.row((i + 1) % offset.rows()).transpose();
    const double fp = side(p), fq = side(q);
    if (fp >= 0) half.push_back(p);
    if (fp * fq < 0) half.push_back(p + fp / (fp - fq) * (q - p));
  }
  std::vector<Eigen::Vector2d> cut;
  for (const Eigen::Vector2d& p : half)
    if (cut.empty() || (p - cut.back()).norm() > 1e-12) cut.push_back(p);
  while (cut.size() > 1 && (cut.front() - cut.back()).norm() <= 1e-12) cut.pop_back();
  Polygon polygon;
  Eigen::MatrixX2d out(static_cast<Eigen::Index>(cut.size()), 2);
  for (size_t k = 0; k < cut.size(); ++k) {
    out.row(static_cast<Eigen::Index>(k)) = cut[k].transpose();
    polygon.push_back(Kernel::Point_2(cut[k].x(), cut[k].y()));
  }
  if (cut.size() < 3 || !polygon.is_simple() || polygon.orientation() != CGAL::COUNTERCLOCKWISE)
    return std::nullopt;
  return out;
}

// Outward unit normal of a counter-clockwise polygon at vertex i (bisector of its two edges).
Eigen::Vector2d outward_normal(const Eigen::MatrixX2d& p, Eigen::Index i) {
  const Eigen::Index n = p.rows();
  const Eigen::Vector2d a = (p.row(i) - p.row((i + n - 1) % n)).transpose().normalized();
  const Eigen::Vector2d b = (p.row((i + 1) % n) - p.row(i)).transpose().normalized();
  const Eigen::Vector2d normal = Eigen::Vector2d(a.y(), -a.x()) + Eigen::Vector2d(b.y(), -b.x());
  return normal.norm() > 1e-12 ? normal.normalized() : Eigen::Vector2d(a.y(), -a.x());
}

// A grain line along +y through the piece's centroid, inside the piece: the middle 60 % of the
// stretch of the vertical line that holds the centroid.
void grain_line(PatternPiece& piece) {
  const Eigen::MatrixX2d& p = piece.sewing;
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  double area = 0;
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    const Eigen::Vector2d a = p.row(i), b = p.row((i + 1) % p.rows());
    const double cross = a.x() * b.y() - b.x() * a.y();
    area += cross;
    centroid += cross * (a + b);
  }
  centroid /= 3 * area;
  std::vector<double> hits;
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    const Eigen::Vector2d a = p.row(i), b = p.row((i + 1) % p.rows());
    if ((a.x() <= centroid.x()) != (b.x() <= centroid.x()))
      hits.push_back(a.y() + (centroid.x() - a.x()) / (b.x() - a.x()) * (b.y() - a.y()));
  }
  std::sort(hits.begin(), hits.end());
  double lo = p.col(1).minCoeff(), hi = p.col(1).maxCoeff();
  for (size_t k = 0; k + 1 < hits.size(); k += 2)
    if (hits[k] <= centroid.y() && centroid.y() <= hits[k + 1]) {
      lo = hits[k];
      hi = hits[k + 1];
    }
  piece.grain_start = {centroid.x(), lo + 0.2 * (hi - lo)};
  piece.grain_end = {centroid.x(), hi - 0.2 * (hi - lo)};
}

// m: the farthest any point of closed polygon a lies from closed polygon b's outline.
double farthest_from(const Eigen::MatrixX2d& a, const Eigen::MatrixX2d& b) {
  double worst = 0;
  for (Eigen::Index i = 0; i < a.rows(); ++i) {
    const Eigen::Vector2d p = a.row(i).transpose();
    double nearest = std::numeric_limits<double>::infinity();
    for (Eigen::Index k = 0; k < b.rows(); ++k) {
      const Eigen::Vector2d s = b.row(k).transpose(), e = b.row((k + 1) % b.rows()).transpose();
      const Eigen::Vector2d d = e - s;
      const double t =
          d.squaredNorm() > 0 ? std::clamp((p - s).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
      nearest = std::min(nearest, (s + t * d - p).norm());
    }
    worst = std::max(worst, nearest);
  }
  return worst;
}

// Whether `copy` is `original` turned over (x → size.x − x of its cutting line's box) to
// `tolerance`: cutting and sewing lines each within it of the other's both ways, and every
// notch of each within it of a notch of the same kind of the other.
bool is_mirror_image(const PatternPiece& original, const PatternPiece& copy, double tolerance) {
  if (std::abs(original.size.x() - copy.size.x()) > tolerance ||
      std::abs(original.size.y() - copy.size.y()) > tolerance ||
      original.notches.size() != copy.notches.size() || !(original.ease == copy.ease))
    return false;
  const auto reflect = [&](Eigen::MatrixX2d p) {
    p.col(0) = original.size.x() - p.col(0).array();
    return p;
  };
  for (const auto& [a, b] :
       {std::pair{&original.cutting, &copy.cutting}, std::pair{&original.sewing, &copy.sewing}}) {
    const Eigen::MatrixX2d turned = reflect(*a);
    if (farthest_from(turned, *b) > tolerance || farthest_from(*b, turned) > tolerance)
      return false;
  }
  for (const PatternNotch& n : original.notches) {
    const Eigen::Vector2d at(original.size.x() - n.point.x(), n.point.y());
    const bool matched = std::any_of(copy.notches.begin(), copy.notches.end(), [&](const auto& m) {
      return m.balance == n.balance && (m.point - at).norm() <= tolerance;
    });
    if (!matched) return false;
  }
  return true;
}

// A piece as the fabric it takes on the bolt: its cutting line(s) in a frame whose bounding box
// starts at (0, 0), `offset` the piece frame's origin in it.
struct FabricShape {
  std::vector<Eigen::MatrixX2d> outlines;
  Eigen::Vector2d offset = Eigen::Vector2d::Zero();
  Eigen::Vector2d size = Eigen::Vector2d::Zero();
};

// A piece cut on the fold, opened out: its cutting line and that line reflected across the fold
// (the other half, cut through the fold of the fabric under it, or traced a second time with
// the piece turned over on a single layer). The fold runs along the warp, so both halves keep
// the grain; the fabric they take is what cutting the piece takes.
FabricShape unfolded_shape(const PatternPiece& piece) {
  const Eigen::Vector2d a = piece.fold_start;
  const Eigen::Vector2d d = (piece.fold_end - piece.fold_start).normalized();
  const Eigen::Matrix2d mirror = 2 * d * d.transpose() - Eigen::Matrix2d::Identity();
  Eigen::MatrixX2d other = piece.cutting;
  for (Eigen::Index i = 0; i < other.rows(); ++i)
    other.row(i) = (a + mirror * (other.row(i).transpose() - a)).transpose();
  FabricShape shape;
  const Eigen::Vector2d lo =
      piece.cutting.colwise().minCoeff().cwiseMin(other.colwise().minCoeff());
  const Eigen::Vector2d hi =
      piece.cutting.colwise().maxCoeff().cwiseMax(other.colwise().maxCoeff());
  shape.offset = -lo;
  shape.size = hi - lo;
  shape.outlines = {piece.cutting.rowwise() - lo.transpose(), other.rowwise() - lo.transpose()};
  return shape;
}

}  // namespace

// A gathered piece's ease gathers by g across one axis (x when the weft factor is the larger,
// else y) and keeps n (the other factor) along the other. Scaled by diag(weft, warp) at once, a
// seam running θ off the grain would be lengthened by sqrt(n² cos²θ + g² sin²θ) instead of n:
// the tiered skirt's flared tier, its side seams 26-28° off the grain, cut them 11-13 % long and
// its front and back 1.6 % apart (docs/pattern.md, "Gathered seams"). So the piece is slashed
// and spread as a pattern maker spreads a flared piece: about the apex where the lines of its
// seam sides along the grain meet (the chords, closer to the other axis than to the gather, of
// the sides sewn to a piece cut with the same ease: not gathered into anything), every point's
// distance from the apex is scaled by n and its angle from the grain line through the apex by
// g / n. A straight side through the apex keeps n times its length and an arc about it is
// gathered g times. Sides meeting farther than kFanReach extents away (within 3° of parallel,
// where the two maps differ by under 0.2 % for g / n = 1.5), fewer than two sides along the
// grain, or an outline reaching round its apex: diag(weft, warp), the spread's limit for
// parallel sides. The apex and those tests are the outline's; interior points (inside it, so
// within its angles about an apex outside it) follow the same map.
EasedPiece eased_piece(const FlatPattern& pattern, size_t p, const std::vector<PanelEase>& eases) {
  constexpr double kFanReach = 20;
  const auto ease_of = [&](int panel) {
    return static_cast<size_t>(panel) < eases.size() ? eases[static_cast<size_t>(panel)]
                                                     : PanelEase{};
  };
  const PanelEase ease = ease_of(static_cast<int>(p));
  const FlatPanel& flat = pattern.panels[p];
  EasedPiece eased;
  eased.uv = flat.uv;
  eased.uv.col(0) *= ease.weft;
  eased.uv.col(1) *= ease.warp;
  const auto n = static_cast<Eigen::Index>(flat.boundary.size());
  if (ease.isotropic() || n < 3) return eased;
  Eigen::MatrixX2d outline(n, 2);
  for (Eigen::Index k = 0; k < n; ++k)
    outline.row(k) = flat.uv.row(flat.boundary[static_cast<size_t>(k)]);
  const int across = ease.weft > ease.warp ? 0 : 1;
  const double gather = std::max(ease.weft, ease.warp), kept = std::min(ease.weft, ease.warp);
  // The apex: the point nearest (least squares) to the lines of the sides along the grain.
  Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
  Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
  int sides = 0;
  const auto add_side = [&](const std::vector<int>& vertices, int partner) {
    if (vertices.size() < 2 || !(ease_of(partner) == ease)) return;
    const Eigen::Vector2d q = flat.uv.row(vertices.front()).transpose();
    const Eigen::Vector2d d = flat.uv.row(vertices.back()).transpose() - q;
    if (d.norm() <= 0 || std::abs(d[across]) >= std::abs(d[1 - across])) return;
    const Eigen::Vector2d u = d.normalized();
    const Eigen::Matrix2d off = Eigen::Matrix2d::Identity() - u * u.transpose();
    normal += off;
    rhs += off * q;
    ++sides;
  };
  for (const PatternSeam& seam : pattern.seams) {
    if (static_cast<size_t>(seam.panel_a) == p) add_side(seam.vertices_a, seam.panel_b);
    if (static_cast<size_t>(seam.panel_b) == p) add_side(seam.vertices_b, seam.panel_a);
  }
  const Eigen::Vector2d centre = outline.colwise().mean().transpose();
  const double extent = (outline.colwise().maxCoeff() - outline.colwise().minCoeff()).norm();
  if (sides < 2 || normal.determinant() <= 1e-12) return eased;
  const Eigen::Vector2d apex = normal.inverse() * rhs;
  if ((apex - centre).norm() > kFanReach * extent) return eased;
  // The grain line through the apex, pointing into the piece, and its left normal.
  Eigen::Vector2d down = Eigen::Vector2d::Zero();
  down[1 - across] = centre[1 - across] >= apex[1 - across] ? 1 : -1;
  const Eigen::Vector2d left(-down.y(), down.x());
  const double spread = gather / kept;
  const auto angle_of = [&](const Eigen::Vector2d& v) {
    return spread * std::atan2(left.dot(v), down.dot(v));
  };
  // An outline reaching round its apex (half a turn or more once spread) has no fan.
  for (Eigen::Index k = 0; k < n; ++k)
    if (std::abs(angle_of(outline.row(k).transpose() - apex)) >= 0.9 * std::numbers::pi)
      return eased;
  for (Eigen::Index k = 0; k < flat.uv.rows(); ++k) {
    const Eigen::Vector2d v = flat.uv.row(k).transpose() - apex;
    const double angle = angle_of(v);
    eased.uv.row(k) =
        (kept * v.norm() * (std::cos(angle) * down + std::sin(angle) * left)).transpose();
  }
  eased.spread = true;
  return eased;
}

PatternLayout lay_out_pattern(const FlatPattern& pattern, const PatternLayoutOptions& options) {
  PatternLayout layout;
  layout.fabric_width = options.fabric_width;
  for (size_t p = 0; p < pattern.panels.size(); ++p) {
    const FlatPanel& flat = pattern.panels[p];
    PatternPiece piece;
    piece.panel = static_cast<int>(p);
    piece.ease = p < options.panel_ease.size() ? options.panel_ease[p] : PanelEase{};
    piece.allowance = p < options.panel_allowance.size() && options.panel_allowance[p] >= 0
                          ? options.panel_allowance[p]
                          : options.seam_allowance;
    const size_t edges = flat.boundary.size();
    std::vector<double> allowance(edges, piece.allowance);
    if (p < options.edge_allowance.size() && !options.edge_allowance[p].empty()) {
      if (options.edge_allowance[p].size() != edges)
        throw std::invalid_argument(
            fmt::format("edge allowances of piece '{}': {} given for {} outline edges", flat.id,
                        options.edge_allowance[p].size(), edges));
      for (size_t k = 0; k < edges; ++k)
        if (options.edge_allowance[p][k] >= 0) allowance[k] = options.edge_allowance[p][k];
    }
    // A fold is cut, not sewn: no allowance along it.
    if (p < options.fold_edge.size() && options.fold_edge[p].size() == edges)
      for (size_t k = 0; k < edges; ++k)
        if (options.fold_edge[p][k]) allowance[k] = 0;
    for (size_t k = 0; k < edges; ++k)
      if (k == 0 || allowance[k] != allowance[k - 1])
        piece.allowances.push_back({static_cast<int>(k), static_cast<int>(k), allowance[k]});
      else
        piece.allowances.back().last = static_cast<int>(k);
    if (piece.allowances.size() > 1 &&
        piece.allowances.back().allowance == piece.allowances.front().allowance) {
      piece.allowances.front().first = piece.allowances.back().first;  // the run across point 0
      piece.allowances.pop_back();
    }
    {
      const EasedPiece eased = eased_piece(pattern, p, options.panel_ease);
      piece.sewing.resize(static_cast<Eigen::Index>(edges), 2);
      for (size_t k = 0; k < edges; ++k)
        piece.sewing.row(static_cast<Eigen::Index>(k)) = eased.uv.row(flat.boundary[k]);
    }
    // A fold is straight: the points of the fold run are moved onto its chord (within 2 mm,
    // as the app chose it: PatternLayoutOptions::fold_edge).
    if (p < options.fold_edge.size() && options.fold_edge[p].size() == edges)
      for (size_t k = 0; k < edges; ++k)
        if (options.fold_edge[p][k] && !options.fold_edge[p][(k + edges - 1) % edges]) {
          size_t last = k;
          while (options.fold_edge[p][(last + 1) % edges]) last = (last + 1) % edges;
          const auto end = static_cast<Eigen::Index>((last + 1) % edges);
          const Eigen::Vector2d a = piece.sewing.row(static_cast<Eigen::Index>(k)).transpose();
          const Eigen::Vector2d along = (piece.sewing.row(end).transpose() - a).normalized();
          for (size_t i = (k + 1) % edges; i != (last + 1) % edges; i = (i + 1) % edges) {
            const Eigen::Vector2d q = piece.sewing.row(static_cast<Eigen::Index>(i)).transpose();
            piece.sewing.row(static_cast<Eigen::Index>(i)) =
                (a + (q - a).dot(along) * along).transpose();
          }
        }
    // The smooth sewing line: corners where the sketch curve changes, at seam junctions, at
    // sharp turns and at the ends of a fold.
    std::vector<bool> corner(edges, false);
    if (p < options.corners.size() && options.corners[p].size() == edges)
      corner = options.corners[p];
    for (const int v : flat.notches)
      corner[static_cast<size_t>(std::find(flat.boundary.begin(), flat.boundary.end(), v) -
                                 flat.boundary.begin())] = true;
    mark_sharp_turns(piece.sewing, kCornerTurn, corner);
    const bool folds = p < options.fold_edge.size() && options.fold_edge[p].size() == edges;
    if (folds)
      for (size_t k = 0; k < edges; ++k)
        if (options.fold_edge[p][k] != options.fold_edge[p][(k + edges - 1) % edges])
          corner[k] = true;
    piece.curve = smooth_outline(piece.sewing, corner, kCurveTolerance);
    const Eigen::Index dense = piece.curve.points.rows();
    std::vector<double> dense_allowance(static_cast<size_t>(dense));
    for (size_t k = 0; k < edges; ++k) {
      const Eigen::Index end = k + 1 < edges ? piece.curve.at[k + 1] : dense;
      for (Eigen::Index i = piece.curve.at[k]; i < end; ++i)
        dense_allowance[static_cast<size_t>(i)] = allowance[k];
    }
    bool uniform = true;
    for (const double a : dense_allowance) uniform = uniform && a == dense_allowance.front();
    // One allowance but along a fold (none there): the skeleton of the piece opened out.
    std::optional<Eigen::MatrixX2d> folded;
    if (!uniform && folds) {
      size_t first = edges;
      for (size_t k = 0; k < edges; ++k)
        if (options.fold_edge[p][k] && !options.fold_edge[p][(k + edges - 1) % edges]) first = k;
      double other = -1;
      bool one_other = first < edges;
      for (size_t k = 0; k < edges && one_other; ++k)
        if (!options.fold_edge[p][k]) {
          if (other < 0) other = allowance[k];
          one_other = allowance[k] == other && other > 0;
        }
      if (one_other) {
        size_t last = first;
        while (options.fold_edge[p][(last + 1) % edges]) last = (last + 1) % edges;
        folded = offset_on_fold(flat.id, piece.curve.points, piece.curve.at[first],
                                piece.curve.at[(last + 1) % edges], other);
      }
    }
    piece.cutting = folded ? *folded
                    : uniform
                        ? offset_outwards(flat.id, piece.curve.points, dense_allowance.front())
                        : offset_by_edge(flat.id, piece.curve.points, dense_allowance);
    piece.origin = -piece.cutting.colwise().minCoeff().transpose();
    piece.sewing.rowwise() += piece.origin.transpose();
    piece.curve.points.rowwise() += piece.origin.transpose();
    for (BezierSpan& span : piece.curve.spans) {
      span.b1 += piece.origin;
      span.b2 += piece.origin;
    }
    piece.cutting.rowwise() += piece.origin.transpose();
    piece.size = piece.cutting.colwise().maxCoeff().transpose();
    piece.sewn_area = signed_area(piece.curve.points);
    piece.cut_area = signed_area(piece.cutting);
    if (folds) {
      // The fold line: the run of fold edges (one straight run along the centre line).
      for (size_t k = 0; k < edges; ++k)
        if (options.fold_edge[p][k] && !options.fold_edge[p][(k + edges - 1) % edges]) {
          size_t last = k;
          while (options.fold_edge[p][(last + 1) % edges]) last = (last + 1) % edges;
          piece.on_fold = true;
          piece.fold_start = piece.sewing.row(static_cast<Eigen::Index>(k)).transpose();
          piece.fold_end =
              piece.sewing.row(static_cast<Eigen::Index>((last + 1) % edges)).transpose();
        }
    }
    for (const int v : flat.notches) {
      const auto at = std::find(flat.boundary.begin(), flat.boundary.end(), v);
      const Eigen::Index i = at - flat.boundary.begin();
      const double narrower = std::min(allowance[static_cast<size_t>(i)],
                                       allowance[(static_cast<size_t>(i) + edges - 1) % edges]);
      piece.notches.push_back(
          {piece.sewing.row(i).transpose(),
           outward_normal(piece.curve.points, piece.curve.at[static_cast<size_t>(i)]), narrower});
    }
    for (const OutlinePoint& b : flat.balance_notches) {
      // At the same fraction of the span's length on the smooth curve as of its chord.
      const auto [point, normal] = point_on_span(piece.curve, b.edge, b.t);
      piece.notches.push_back({point, normal, allowance[static_cast<size_t>(b.edge)], true});
    }
    grain_line(piece);
    if (p < options.folded_into.size()) piece.folded_into = options.folded_into[p];
    layout.pieces.push_back(std::move(piece));
  }

  // Bottom-left by skylines on a 2 mm grid across the fabric: pieces one by one, each at the
  // column offset where its top ends lowest. A piece's column profile (lowest and highest point
  // of its cutting line in each 2 mm column, widened by half the gap each side) rests on the
  // fabric's skyline (the highest point placed so far per column) plus the gap, so pieces
  // interlock (a sleeve in a neckline's hollow) yet never overlap: in each column the placed
  // intervals are disjoint.
  constexpr double kCell = 0.002;  // m
  const int columns = static_cast<int>(std::floor((options.fabric_width - options.gap) / kCell));
  const int pad = static_cast<int>(std::ceil(0.5 * options.gap / kCell));
  // The fabric must take the widest piece with its seam allowance, a gap at each selvedge and
  // the grid's rounding (its span of columns, below). Name that piece and the width it needs,
  // so that one change of the fabric width is enough: the first piece too wide in panel order
  // is not always the widest, and its width without the gaps can be less than the fabric's.
  // A piece cut on the fold is as wide as its two halves; the other half is not cut apart.
  const auto cut_width = [&](const PatternPiece& piece) {
    if (piece.folded_into >= 0) return 0.0;
    return piece.on_fold ? unfolded_shape(piece).size.x() : piece.size.x();
  };
  if (!layout.pieces.empty()) {
    double most = 0;
    for (const PatternPiece& piece : layout.pieces) most = std::max(most, cut_width(piece));
    // The first within 0.1 mm of the widest: a panel before its mirror copy ("front", not
    // "front.mirror", which is as wide up to rounding).
    const PatternPiece& widest =
        *std::find_if(layout.pieces.begin(), layout.pieces.end(),
                      [&](const PatternPiece& piece) { return cut_width(piece) >= most - 1e-4; });
    const double widest_x = cut_width(widest);
    const int span = static_cast<int>(std::ceil(widest_x / kCell)) + 1 + 2 * pad;
    if (widest_x > options.fabric_width - 2 * options.gap || span > columns) {
      // Whole millimetres, up to the first width that passes both tests as written (the grid
      // rounds), so that the width named is enough when given back.
      const double least = std::max(widest_x + 2 * options.gap, span * kCell + options.gap);
      int needed_mm = static_cast<int>(std::ceil(1000 * least - 1e-6));
      const auto fits = [&](double width) {
        return widest_x <= width - 2 * options.gap &&
               static_cast<int>(std::floor((width - options.gap) / kCell)) >= span;
      };
      while (!fits(needed_mm / 1000.0)) ++needed_mm;
      const std::string& id = pattern.panels[static_cast<size_t>(widest.panel)].id;
      throw PatternError(
          id,
          fmt::format("the piece of panel '{}' is {:.0f} mm wide{} with its seam allowance "
                      "and needs a fabric at least {} mm wide with the {:.0f} mm gap kept "
                      "free at each selvedge (the piece and both gaps, rounded up to the "
                      "layout's {:.0f} mm grid); the fabric is {:.0f} mm wide: use a wider "
                      "fabric or split the panel",
                      id, 1000 * widest_x, widest.on_fold ? " opened out from its fold" : "",
                      needed_mm, 1000 * options.gap, 1000 * kCell, 1000 * options.fabric_width));
    }
  }
  // Two orders are tried, largest area first and tallest first; the shorter layout is kept.
  // `unfold`: a piece cut on the fold takes the fabric of both its halves (unfolded_shape).
  const auto nest = [&](const std::vector<size_t>& order, bool unfold) {
    std::vector<double> sky(static_cast<size_t>(columns), 0.0);
    double length = 0;
    for (const size_t i : order) {
      PatternPiece& piece = layout.pieces[i];
      const FabricShape shape = unfold && piece.on_fold
                                    ? unfolded_shape(piece)
                                    : FabricShape{{piece.cutting}, {0, 0}, piece.size};
      const int width = static_cast<int>(std::ceil(shape.size.x() / kCell)) + 1;
      std::vector<double> low(static_cast<size_t>(width), std::numeric_limits<double>::infinity());
      std::vector<double> high(static_cast<size_t>(width),
                               -std::numeric_limits<double>::infinity());
      // Each edge is linear: over a column's slab its y lies between its values at the slab's ends.
      for (const Eigen::MatrixX2d& p : shape.outlines)
        for (Eigen::Index k = 0; k < p.rows(); ++k) {
          const Eigen::Vector2d a = p.row(k), b = p.row((k + 1) % p.rows());
          const double x0 = std::min(a.x(), b.x()), x1 = std::max(a.x(), b.x());
          const int c0 = std::clamp(static_cast<int>(std::floor(x0 / kCell)), 0, width - 1);
          const int c1 = std::clamp(static_cast<int>(std::floor(x1 / kCell)), 0, width - 1);
          for (int c = c0; c <= c1; ++c) {
            for (double x : {std::clamp(c * kCell, x0, x1), std::clamp((c + 1) * kCell, x0, x1)}) {
              const double y =
                  b.x() == a.x() ? a.y() : a.y() + (x - a.x()) / (b.x() - a.x()) * (b.y() - a.y());
              low[static_cast<size_t>(c)] =
                  std::min({low[static_cast<size_t>(c)], y, b.x() == a.x() ? b.y() : y});
              high[static_cast<size_t>(c)] =
                  std::max({high[static_cast<size_t>(c)], y, b.x() == a.x() ? b.y() : y});
            }
          }
        }
      // Widened by `pad` columns each side: column j of the profile is piece column j − pad.
      const int span = width + 2 * pad;
      std::vector<double> bottom(static_cast<size_t>(span),
                                 std::numeric_limits<double>::infinity());
      std::vector<double> top(static_cast<size_t>(span), -std::numeric_limits<double>::infinity());
      for (int j = 0; j < span; ++j)
        for (int c = std::max(0, j - 2 * pad); c <= std::min(width - 1, j); ++c) {
          bottom[static_cast<size_t>(j)] =
              std::min(bottom[static_cast<size_t>(j)], low[static_cast<size_t>(c)]);
          top[static_cast<size_t>(j)] =
              std::max(top[static_cast<size_t>(j)], high[static_cast<size_t>(c)]);
        }
      if (span > columns)
        throw PatternError(
            pattern.panels[static_cast<size_t>(piece.panel)].id,
            fmt::format("the piece of panel '{}' is {:.0f} mm wide{} with its seam allowance and "
                        "the gaps beside it; the fabric is {:.0f} mm wide: use a wider fabric or "
                        "split the panel",
                        pattern.panels[static_cast<size_t>(piece.panel)].id,
                        1000 * (shape.size.x() + options.gap),
                        shape.outlines.size() > 1 ? " opened out from its fold" : "",
                        1000 * options.fabric_width));
      int best_x = 0;
      double best_y = 0, best_top = std::numeric_limits<double>::infinity();
      for (int x = 0; x + span <= columns; ++x) {
        double y = options.gap;
        for (int j = 0; j < span; ++j)
          if (std::isfinite(bottom[static_cast<size_t>(j)]) && sky[static_cast<size_t>(x + j)] > 0)
            y = std::max(
                y, sky[static_cast<size_t>(x + j)] + options.gap - bottom[static_cast<size_t>(j)]);
        if (y + shape.size.y() < best_top - 1e-9) {
          best_top = y + shape.size.y();
          best_y = y;
          best_x = x;
        }
      }
      for (int j = 0; j < span; ++j)
        if (std::isfinite(top[static_cast<size_t>(j)]))
          sky[static_cast<size_t>(best_x + j)] =
              std::max(sky[static_cast<size_t>(best_x + j)], best_y + top[static_cast<size_t>(j)]);
      piece.placement =
          Eigen::Vector2d(options.gap + (best_x + pad) * kCell, best_y) + shape.offset;
      length = std::max(length, best_top);
    }
    return length;
  };
  // Nests the pieces drawn (quantity ≥ 1; a piece cut on the fold as its half) or all of them
  // as they are cut (a piece cut on the fold as both its halves); returns the length (m, with
  // the gap after the last piece) and the cut area (m²) they take.
  const auto lay_out = [&](bool drawn_only) {
    std::vector<size_t> by_area;  // a fold piece's other half is not cut on its own
    for (size_t i = 0; i < layout.pieces.size(); ++i)
      if (layout.pieces[i].folded_into < 0 && (!drawn_only || layout.pieces[i].quantity > 0))
        by_area.push_back(i);
    std::vector<size_t> by_height = by_area;
    std::stable_sort(by_area.begin(), by_area.end(), [&](size_t a, size_t b) {
      return layout.pieces[a].cut_area > layout.pieces[b].cut_area;
    });
    std::stable_sort(by_height.begin(), by_height.end(), [&](size_t a, size_t b) {
      return layout.pieces[a].size.y() > layout.pieces[b].size.y();
    });
    const bool unfold = !drawn_only;
    const double tallest_first = nest(by_height, unfold);
    double length = nest(by_area, unfold);
    if (tallest_first < length) length = nest(by_height, unfold);
    double cut = 0;
    for (const size_t i : by_area)
      cut += (unfold && layout.pieces[i].on_fold ? 2 : 1) * layout.pieces[i].cut_area;
    return std::pair{length + options.gap, cut};
  };
  // Every piece from one layer: the fabric a cutter needs. Then the sheet, where a piece that
  // stands for a mirror pair is drawn once ("X" for "X" and "X.mirror").
  // The other half of a piece cut on the fold is cut with it: none of its own.
  for (PatternPiece& piece : layout.pieces)
    if (piece.folded_into >= 0) piece.quantity = 0;
  const auto [length, cut] = lay_out(false);
  layout.length_used = length;
  layout.efficiency = cut / (length * layout.fabric_width);
  if (options.pair_mirrors)
    for (size_t i = 0; i < layout.pieces.size(); ++i) {
      const std::string& id = pattern.panels[i].id;
      if (!id.ends_with(".mirror")) continue;
      const std::string original = id.substr(0, id.size() - 7);
      for (size_t j = 0; j < layout.pieces.size(); ++j)
        if (pattern.panels[j].id == original && layout.pieces[j].quantity == 1 &&
            layout.pieces[i].folded_into < 0 && layout.pieces[j].folded_into < 0 &&
            is_mirror_image(layout.pieces[j], layout.pieces[i], kMirrorPairTolerance)) {
          layout.pieces[j].quantity = 2;
          layout.pieces[i].quantity = 0;
          layout.pieces[i].drawn_as = static_cast<int>(j);
          ++layout.pairs;
          break;
        }
    }
  const bool folds = std::any_of(layout.pieces.begin(), layout.pieces.end(),
                                 [](const PatternPiece& piece) { return piece.on_fold; });
  const auto [sheet, drawn_cut] =
      layout.pairs > 0 || folds ? lay_out(true) : std::pair{length, cut};
  layout.sheet_length = sheet;
  layout.sheet_efficiency = drawn_cut / (sheet * layout.fabric_width);
  for (PatternPiece& piece : layout.pieces)
    if (piece.drawn_as >= 0)
      piece.placement = layout.pieces[static_cast<size_t>(piece.drawn_as)].placement;
  return layout;
}

}  // namespace sd::garment
