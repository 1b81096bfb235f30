#include "sim/collision_geometry.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace sd::sim {

namespace {

TriangleClosestPoint make_result(const Eigen::Vector3d& p, const Eigen::Vector3d& point,
                                 const Eigen::Vector3d& barycentric, TriangleFeature feature,
                                 int index) {
  TriangleClosestPoint result;
  result.point = point;
  result.barycentric = barycentric;
  result.feature = feature;
  result.index = index;
  result.squared_distance = (p - point).squaredNorm();
  return result;
}

}  // namespace

TriangleClosestPoint closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                               const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a;
  const Eigen::Vector3d ac = c - a;
  const Eigen::Vector3d ap = p - a;
  const double d1 = ab.dot(ap);
  const double d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0)
    return make_result(p, a, Eigen::Vector3d(1, 0, 0), TriangleFeature::vertex, 0);

  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp);
  const double d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3)
    return make_result(p, b, Eigen::Vector3d(0, 1, 0), TriangleFeature::vertex, 1);

  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    return make_result(p, a + v * ab, Eigen::Vector3d(1 - v, v, 0), TriangleFeature::edge, 0);
  }

  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp);
  const double d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6)
    return make_result(p, c, Eigen::Vector3d(0, 0, 1), TriangleFeature::vertex, 2);

  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    return make_result(p, a + w * ac, Eigen::Vector3d(1 - w, 0, w), TriangleFeature::edge, 2);
  }

  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return make_result(p, b + w * (c - b), Eigen::Vector3d(0, 1 - w, w), TriangleFeature::edge, 1);
  }

  const double sum = va + vb + vc;
  if (!(sum > 0.0)) {
    // Degenerate (zero-area) triangle that slipped through the region tests: use the closest
    // of its three edges.
    TriangleClosestPoint best;
    best.squared_distance = std::numeric_limits<double>::infinity();
    const Eigen::Vector3d corners[3] = {a, b, c};
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& s = corners[k];
      const Eigen::Vector3d e = corners[(k + 1) % 3] - s;
      const double length2 = e.squaredNorm();
      const double t = length2 > 0.0 ? std::clamp((p - s).dot(e) / length2, 0.0, 1.0) : 0.0;
      Eigen::Vector3d weights = Eigen::Vector3d::Zero();
      weights[k] = 1 - t;
      weights[(k + 1) % 3] += t;
      TriangleClosestPoint candidate = make_result(p, s + t * e, weights, TriangleFeature::edge, k);
      if (candidate.squared_distance < best.squared_distance) best = candidate;
    }
    return best;
  }
  const double v = vb / sum;
  const double w = vc / sum;
  return make_result(p, a + ab * v + ac * w, Eigen::Vector3d(1 - v - w, v, w),
                     TriangleFeature::face, 0);
}

Eigen::Vector3d triangle_normal(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                const Eigen::Vector3d& c) {
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const double length = n.norm();
  return length > 0.0 ? Eigen::Vector3d(n / length) : Eigen::Vector3d::Zero();
}

double corner_angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d u = b - a;
  const Eigen::Vector3d v = c - a;
  // atan2 of |u×v| and u·v is accurate for angles near 0 and π, unlike acos.
  return std::atan2(u.cross(v).norm(), u.dot(v));
}

SegmentClosestPoints closest_points_on_segments(const Eigen::Vector3d& p0,
                                                const Eigen::Vector3d& p1,
                                                const Eigen::Vector3d& q0,
                                                const Eigen::Vector3d& q1) {
  const Eigen::Vector3d d1 = p1 - p0;
  const Eigen::Vector3d d2 = q1 - q0;
  const Eigen::Vector3d r = p0 - q0;
  const double a = d1.squaredNorm();
  const double e = d2.squaredNorm();
  const double f = d2.dot(r);
  // Lengths below 1e-30 m² are points (a cloth edge is never that short).
  constexpr double kTiny = 1e-30;
  double s = 0.0;
  double t = 0.0;
  if (a <= kTiny && e <= kTiny) {
    // two points
  } else if (a <= kTiny) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= kTiny) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2);
      const double denominator = a * e - b * b;  // |d1 × d2|², ≥ 0
      // Parallel (to rounding): any s works; take 0 and let t follow.
      s = denominator > 1e-14 * a * e ? std::clamp((b * f - c * e) / denominator, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  SegmentClosestPoints result;
  result.s = s;
  result.t = t;
  result.p = p0 + s * d1;
  result.q = q0 + t * d2;
  result.squared_distance = (result.p - result.q).squaredNorm();
  return result;
}

namespace {

int sign_of(double value, double zero) {
  return value > zero ? 1 : (value < -zero ? -1 : 0);
}

}  // namespace

CoplanarTimes coplanar_times(const std::array<Eigen::Vector3d, 4>& x0,
                             const std::array<Eigen::Vector3d, 4>& x1) {
  // Relative to point 0: u, w, z at t = 0 and their changes over the step.
  const Eigen::Vector3d u0 = x0[1] - x0[0], w0 = x0[2] - x0[0], z0 = x0[3] - x0[0];
  const Eigen::Vector3d du = (x1[1] - x1[0]) - u0, dw = (x1[2] - x1[0]) - w0,
                        dz = (x1[3] - x1[0]) - z0;
  // (u × w)(t) = A + B t + C t², f(t) = (A + B t + C t²) · (z0 + t dz).
  const Eigen::Vector3d A = u0.cross(w0);
  const Eigen::Vector3d B = u0.cross(dw) + du.cross(w0);
  const Eigen::Vector3d C = du.cross(dw);
  const std::array<double, 4> c = {A.dot(z0), A.dot(dz) + B.dot(z0), B.dot(dz) + C.dot(z0),
                                   C.dot(dz)};
  const auto f = [&](double t) { return ((c[3] * t + c[2]) * t + c[1]) * t + c[0]; };
  // Rounding of f is about 1e-15 of the product of three lengths of the configuration.
  double scale = 0.0;
  for (const Eigen::Vector3d& v :
       {u0, w0, z0, Eigen::Vector3d(u0 + du), Eigen::Vector3d(w0 + dw), Eigen::Vector3d(z0 + dz)})
    scale = std::max(scale, v.norm());
  const double zero = 1e-12 * scale * scale * scale;

  CoplanarTimes result;
  result.sign_at_start = sign_of(c[0], zero);
  if (std::abs(c[0]) <= zero && std::abs(c[1]) <= zero && std::abs(c[2]) <= zero &&
      std::abs(c[3]) <= zero) {
    result.degenerate = true;
    return result;
  }
  // No root in [0, 1] when f's four Bernstein coefficients there are all beyond the zero on one
  // side: f(t) is their convex combination, so it never comes within the zero (the non-penetration
  // filter of Tang et al. 2010). Most pairs of a pile end here, before the bisections (which were
  // a fifth of the piling sheet's run).
  const std::array<double, 4> bernstein = {
      c[0], c[0] + c[1] / 3.0, c[0] + (2.0 * c[1] + c[2]) / 3.0, c[0] + c[1] + c[2] + c[3]};
  if (std::all_of(bernstein.begin(), bernstein.end(), [zero](double b) { return b > zero; }) ||
      std::all_of(bernstein.begin(), bernstein.end(), [zero](double b) { return b < -zero; }))
    return result;
  // Break [0, 1] where f' = c1 + 2 c2 t + 3 c3 t² vanishes: f is monotone between breaks.
  std::vector<double> breaks = {0.0};
  const double qa = 3.0 * c[3], qb = 2.0 * c[2], qc = c[1];
  if (std::abs(qa) > 0.0) {
    const double disc = qb * qb - 4.0 * qa * qc;
    if (disc >= 0.0) {
      const double root = std::sqrt(disc);
      // Stable quadratic roots (no cancellation).
      const double q = -0.5 * (qb + std::copysign(root, qb));
      if (q != 0.0) {
        breaks.push_back(q / qa);
        breaks.push_back(qc / q);
      } else {
        breaks.push_back(0.0);
      }
    }
  } else if (std::abs(qb) > 0.0) {
    breaks.push_back(-qc / qb);
  }
  breaks.push_back(1.0);
  std::erase_if(breaks, [](double t) { return !(t >= 0.0 && t <= 1.0); });
  std::sort(breaks.begin(), breaks.end());
  breaks.erase(std::unique(breaks.begin(), breaks.end()), breaks.end());

  int sign = result.sign_at_start;  // sign of f before the next root
  const auto add = [&](double t, bool crosses) {
    if (!result.roots.empty() && t - result.roots.back().t <= 1e-12) return;
    result.roots.push_back({t, sign});
    if (crosses) sign = -sign;
  };
  for (std::size_t k = 0; k < breaks.size(); ++k) {
    const double a = breaks[k];
    const double fa = f(a);
    if (std::abs(fa) <= zero) {
      // A zero at a break: f touches or crosses here; the side after it is f's sign at the next
      // break (or, touching, the side it came from).
      const int after = k + 1 < breaks.size() ? sign_of(f(breaks[k + 1]), zero) : 0;
      result.roots.push_back({a, sign});
      if (after != 0) sign = after;
      continue;
    }
    sign = sign_of(fa, zero);
    if (k + 1 == breaks.size()) break;
    const double b = breaks[k + 1];
    const double fb = f(b);
    if (std::abs(fb) <= zero || (fa > 0.0) == (fb > 0.0)) continue;  // zero at b: next break
    // One sign change on a monotone piece: the Illinois variant of regula falsi, which keeps the
    // bracket and halves the value at an end that stays put, so both ends close in
    // superlinearly (bisection to the last bit took ~50 evaluations a root, a fifth of the
    // piling sheet's run). A step that would leave the bracket bisects instead.
    double lo = a, hi = b, flo = fa, fhi = fb;
    int kept = 0;  // the end that stayed put last: −1 hi, +1 lo
    for (int i = 0; i < 100 && hi - lo > 1e-15; ++i) {
      double mid = (lo * fhi - hi * flo) / (fhi - flo);
      if (!(mid > lo && mid < hi)) mid = 0.5 * (lo + hi);
      const double fm = f(mid);
      if (fm == 0.0) {
        lo = hi = mid;
        break;
      }
      if ((fm > 0.0) == (flo > 0.0)) {
        lo = mid;
        flo = fm;
        if (kept == -1) fhi *= 0.5;
        kept = -1;
      } else {
        hi = mid;
        fhi = fm;
        if (kept == 1) flo *= 0.5;
        kept = 1;
      }
    }
    add(0.5 * (lo + hi), true);
  }
  return result;
}

}  // namespace sd::sim
