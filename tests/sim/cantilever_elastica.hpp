#pragma once
// The reference shape of the cantilever bending test (Peirce 1930; ASTM D1388): the elastica of
// a strip clamped flat at one end under its own weight, which depends only on alpha = w L^3 / B
// (w weight per area, L free length, B bending rigidity).

#include <cmath>
#include <numbers>

namespace sd::sim::test {

// The tip of a cantilever elastica of unit length, relative to the clamp: `along` the clamp's
// direction and `drop` below it.
struct ElasticaTip {
  double along = 0.0;
  double drop = 0.0;
  double chord_angle_deg() const { return std::atan2(drop, along) * 180.0 / std::numbers::pi; }
};

// theta'' = -alpha (1 - s) cos(theta) on s in [0, 1], theta(0) = 0 (clamped flat),
// theta'(1) = 0 (no moment at the free end); theta is the slope angle below the horizontal.
// Integrates with RK4 from a guessed theta'(0) = k and bisects on k until theta'(1) = 0.
inline ElasticaTip cantilever_elastica(double alpha, int steps = 4000) {
  const double h = 1.0 / steps;
  auto shoot = [&](double k, ElasticaTip* tip) {
    double theta = 0.0, omega = k, s = 0.0;
    auto rate = [&](double si, double t) { return -alpha * (1.0 - si) * std::cos(t); };
    for (int i = 0; i < steps; ++i) {
      const double t1 = omega, w1 = rate(s, theta);
      const double t2 = omega + 0.5 * h * w1, w2 = rate(s + 0.5 * h, theta + 0.5 * h * t1);
      const double t3 = omega + 0.5 * h * w2, w3 = rate(s + 0.5 * h, theta + 0.5 * h * t2);
      const double t4 = omega + h * w3, w4 = rate(s + h, theta + h * t3);
      const double next = theta + h / 6 * (t1 + 2 * t2 + 2 * t3 + t4);
      if (tip) {  // trapezoid rule on the tangent (cos, sin)
        tip->along += 0.5 * h * (std::cos(theta) + std::cos(next));
        tip->drop += 0.5 * h * (std::sin(theta) + std::sin(next));
      }
      omega += h / 6 * (w1 + 2 * w2 + 2 * w3 + w4);
      theta = next;
      s += h;
    }
    return omega;  // theta'(1)
  };
  double low = 0.0, high = alpha;  // theta'(0) lies between 0 and the linear bound alpha / 2
  for (int i = 0; i < 60; ++i) {
    const double k = 0.5 * (low + high);
    (shoot(k, nullptr) > 0.0 ? high : low) = k;
  }
  ElasticaTip tip;
  shoot(0.5 * (low + high), &tip);
  return tip;
}

// The alpha of the elastica whose tip drops `drop` (a fraction of L), by bisection: the effective
// rigidity of a simulated strip is B·alpha/alpha_measured.
inline double elastica_alpha_for_drop(double drop) {
  double low = 1e-6, high = 200.0;
  for (int i = 0; i < 60; ++i) {
    const double mid = std::sqrt(low * high);
    (cantilever_elastica(mid, 1000).drop > drop ? high : low) = mid;
  }
  return std::sqrt(low * high);
}

}  // namespace sd::sim::test
