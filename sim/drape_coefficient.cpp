#include "sim/drape_coefficient.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace sd::sim {

DrapeShadow measure_drape_shadow(const Eigen::MatrixX3d& positions,
                                 const Eigen::MatrixX3i& triangles, const Eigen::Vector3d& centre,
                                 const Eigen::Vector3d& up, const DrapeShadowOptions& options) {
  if (!(options.specimen_radius > options.support_radius && options.support_radius >= 0.0 &&
        options.pixel > 0.0 && options.angle_bins >= 8))
    throw std::invalid_argument("drape shadow: needs R > r >= 0, a positive pixel, >= 8 bins");
  // Plane axes (e, f) perpendicular to up.
  const Eigen::Vector3d n = up.normalized();
  const Eigen::Vector3d e = (std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX().cross(n)
                                                   : Eigen::Vector3d::UnitY().cross(n))
                                .normalized();
  const Eigen::Vector3d f = n.cross(e);
  Eigen::MatrixX2d p(positions.rows(), 2);
  for (Eigen::Index v = 0; v < positions.rows(); ++v) {
    const Eigen::Vector3d d = positions.row(v).transpose() - centre;
    p(v, 0) = d.dot(e);
    p(v, 1) = d.dot(f);
  }
  // Raster of (2k)² pixels centred on the centre, wide enough for every projected vertex.
  const double reach = std::max(p.cwiseAbs().maxCoeff(), options.specimen_radius);
  const int k = static_cast<int>(std::ceil(reach / options.pixel)) + 1;
  const int side = 2 * k;
  std::vector<unsigned char> inside(static_cast<size_t>(side) * side, 0);
  for (Eigen::Index t = 0; t < triangles.rows(); ++t) {
    const Eigen::Vector2d a = p.row(triangles(t, 0)), b = p.row(triangles(t, 1)),
                          c = p.row(triangles(t, 2));
    const double area2 = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
    if (area2 == 0.0) continue;  // seen edge-on: no shadow of its own
    const Eigen::Vector2d lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
    // Pixel (i, j) has its centre at ((i − k + ½)·pixel, (j − k + ½)·pixel).
    const int i0 = std::max(0, static_cast<int>(std::floor(lo.x() / options.pixel)) + k);
    const int i1 = std::min(side - 1, static_cast<int>(std::floor(hi.x() / options.pixel)) + k);
    const int j0 = std::max(0, static_cast<int>(std::floor(lo.y() / options.pixel)) + k);
    const int j1 = std::min(side - 1, static_cast<int>(std::floor(hi.y() / options.pixel)) + k);
    const double sign = area2 > 0.0 ? 1.0 : -1.0;
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const Eigen::Vector2d q((i - k + 0.5) * options.pixel, (j - k + 0.5) * options.pixel);
        const auto edge = [&](const Eigen::Vector2d& u, const Eigen::Vector2d& w) {
          return sign * ((w - u).x() * (q - u).y() - (w - u).y() * (q - u).x());
        };
        if (edge(a, b) >= 0.0 && edge(b, c) >= 0.0 && edge(c, a) >= 0.0)
          inside[static_cast<size_t>(j) * side + i] = 1;
      }
  }
  DrapeShadow shadow;
  shadow.outline.assign(static_cast<size_t>(options.angle_bins), 0.0);
  const double pi = std::numbers::pi;
  size_t count = 0;
  for (int j = 0; j < side; ++j)
    for (int i = 0; i < side; ++i) {
      if (!inside[static_cast<size_t>(j) * side + i]) continue;
      ++count;
      const double x = (i - k + 0.5) * options.pixel, y = (j - k + 0.5) * options.pixel;
      const double angle = std::atan2(y, x) + pi;  // [0, 2π]
      const int bin =
          std::min(options.angle_bins - 1, static_cast<int>(angle / (2 * pi) * options.angle_bins));
      double& r = shadow.outline[static_cast<size_t>(bin)];
      r = std::max(r, std::hypot(x, y));
    }
  shadow.shadow_area = static_cast<double>(count) * options.pixel * options.pixel;
  const double support = pi * options.support_radius * options.support_radius;
  const double specimen = pi * options.specimen_radius * options.specimen_radius;
  shadow.drape_coefficient = (shadow.shadow_area - support) / (specimen - support);
  shadow.nodes = count_nodes(shadow.outline);
  return shadow;
}

int count_nodes(const std::vector<double>& outline) {
  const int n = static_cast<int>(outline.size());
  if (n < 8) return 0;
  const int half = std::max(1, static_cast<int>(std::lround(0.015 * n)));
  std::vector<double> smooth(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    double sum = 0.0;
    for (int d = -half; d <= half; ++d) sum += outline[static_cast<size_t>((i + d + n) % n)];
    smooth[static_cast<size_t>(i)] = sum / (2 * half + 1);
  }
  const auto [lo, hi] = std::minmax_element(smooth.begin(), smooth.end());
  double mean = 0.0;
  for (const double r : smooth) mean += r / n;
  const double delta = std::max(1e-3, 0.1 * 0.5 * (*hi - *lo));
  if (*hi - mean < delta || mean - *lo < delta) return 0;
  // Start from a point below the band so that every climb is counted once round the circle.
  const int start = static_cast<int>(lo - smooth.begin());
  int crests = 0;
  bool below = true;
  for (int s = 1; s <= n; ++s) {
    const double r = smooth[static_cast<size_t>((start + s) % n)];
    if (below && r > mean + delta) {
      ++crests;
      below = false;
    } else if (!below && r < mean - delta) {
      below = true;
    }
  }
  return crests;
}

}  // namespace sd::sim
