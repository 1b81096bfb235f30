#include "garment/pattern_outline.hpp"

#include <algorithm>
#include <cmath>

namespace sd::garment {

void mark_sharp_turns(const Eigen::MatrixX2d& outline, double max_turn, std::vector<bool>& corner) {
  const Eigen::Index n = outline.rows();
  corner.resize(static_cast<size_t>(n), false);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector2d a = outline.row(i) - outline.row((i + n - 1) % n);
    const Eigen::Vector2d b = outline.row((i + 1) % n) - outline.row(i);
    const double turn = std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));
    if (std::abs(turn) > max_turn) corner[static_cast<size_t>(i)] = true;
  }
}

SmoothOutline smooth_outline(const Eigen::MatrixX2d& outline, const std::vector<bool>& corner,
                             double tolerance) {
  const Eigen::Index n = outline.rows();
  SmoothOutline out;
  out.spans.resize(static_cast<size_t>(n));
  out.at.resize(static_cast<size_t>(n));
  out.corner = corner;
  const auto point = [&](Eigen::Index i) -> Eigen::Vector2d {
    return outline.row(((i % n) + n) % n).transpose();
  };
  const auto is_corner = [&](Eigen::Index i) {
    return corner[static_cast<size_t>(((i % n) + n) % n)];
  };
  // Centripetal Catmull-Rom (knot spacing √chord) through p0 p1 p2 p3 as a Bézier from p1 to p2;
  // at a corner the missing neighbour is the reflection of the far one, so the span leaves the
  // corner along its own chord.
  std::vector<Eigen::Vector2d> dense;
  for (Eigen::Index k = 0; k < n; ++k) {
    const Eigen::Vector2d p1 = point(k), p2 = point(k + 1);
    const Eigen::Vector2d p0 = is_corner(k) ? Eigen::Vector2d(2 * p1 - p2) : point(k - 1);
    const Eigen::Vector2d p3 = is_corner(k + 1) ? Eigen::Vector2d(2 * p2 - p1) : point(k + 2);
    const double d1 = std::sqrt((p1 - p0).norm()), d2 = std::sqrt((p2 - p1).norm()),
                 d3 = std::sqrt((p3 - p2).norm());
    BezierSpan& span = out.spans[static_cast<size_t>(k)];
    if (d1 < 1e-9 || d2 < 1e-9 || d3 < 1e-9) {  // a repeated point: a straight span
      span.b1 = p1 + (p2 - p1) / 3;
      span.b2 = p2 - (p2 - p1) / 3;
    } else {
      span.b1 = (d1 * d1 * p2 - d2 * d2 * p0 + (2 * d1 * d1 + 3 * d1 * d2 + d2 * d2) * p1) /
                (3 * d1 * (d1 + d2));
      span.b2 = (d3 * d3 * p1 - d2 * d2 * p3 + (2 * d3 * d3 + 3 * d3 * d2 + d2 * d2) * p2) /
                (3 * d3 * (d3 + d2));
    }
    const double bend =
        std::max((p1 - 2 * span.b1 + span.b2).norm(), (span.b1 - 2 * span.b2 + p2).norm());
    const int pieces = std::max(1, static_cast<int>(std::ceil(std::sqrt(0.75 * bend / tolerance))));
    out.at[static_cast<size_t>(k)] = static_cast<Eigen::Index>(dense.size());
    for (int j = 0; j < pieces; ++j) {
      const double t = static_cast<double>(j) / pieces, s = 1 - t;
      dense.push_back(s * s * s * p1 + 3 * s * s * t * span.b1 + 3 * s * t * t * span.b2 +
                      t * t * t * p2);
    }
  }
  out.points.resize(static_cast<Eigen::Index>(dense.size()), 2);
  for (size_t i = 0; i < dense.size(); ++i)
    out.points.row(static_cast<Eigen::Index>(i)) = dense[i].transpose();
  return out;
}

std::pair<Eigen::Vector2d, Eigen::Vector2d> point_on_span(const SmoothOutline& curve, int k,
                                                          double t) {
  const Eigen::Index m = curve.points.rows();
  const Eigen::Index first = curve.at[static_cast<size_t>(k)];
  const Eigen::Index last = (k + 1 < static_cast<int>(curve.at.size()))
                                ? curve.at[static_cast<size_t>(k + 1)]
                                : m;  // the last span ends at row 0 (= m, cyclically)
  double length = 0;
  for (Eigen::Index i = first; i < last; ++i)
    length += (curve.points.row((i + 1) % m) - curve.points.row(i)).norm();
  double left = t * length;
  for (Eigen::Index i = first; i < last; ++i) {
    const Eigen::Vector2d a = curve.points.row(i), b = curve.points.row((i + 1) % m);
    const double l = (b - a).norm();
    if (left <= l || i + 1 == last) {
      const Eigen::Vector2d along = l > 0 ? Eigen::Vector2d((b - a) / l) : Eigen::Vector2d::UnitX();
      return {a + std::clamp(left / std::max(l, 1e-300), 0.0, 1.0) * (b - a),
              Eigen::Vector2d(along.y(), -along.x())};
    }
    left -= l;
  }
  const Eigen::Vector2d a = curve.points.row(first);
  return {a, Eigen::Vector2d::UnitY()};
}

}  // namespace sd::garment
