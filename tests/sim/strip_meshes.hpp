#pragma once
// Cantilever strips on the triangulations the bending model must handle: the 4-8 mesh along
// and at 45 degrees to the strip, an equilateral mesh with edges across the strip, and an
// irregular (jittered, randomly split) grid. The strip lies in the plane y = `height`, runs
// along +Z from its clamped end at z = 0 and spans x in [0, width].

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "sim/cloth_model.hpp"

namespace sd::sim::test {

enum class StripMesh {
  four_eight,          // squares split along alternating diagonals (the 4-8 mesh, even level)
  four_eight_45,       // squares split into four around their centre (the 4-8 mesh, odd level)
  equilateral_across,  // equilateral triangles, one edge of each across the strip
  irregular,           // jittered grid, each square split along a random diagonal
};

inline std::string strip_mesh_name(StripMesh m) {
  switch (m) {
    case StripMesh::four_eight:
      return "4-8";
    case StripMesh::four_eight_45:
      return "4-8 at 45 deg";
    case StripMesh::equilateral_across:
      return "equilateral, edges across";
    case StripMesh::irregular:
      return "irregular";
  }
  return "?";
}

struct Strip {
  ClothInput input;
  std::vector<int> clamped;     // vertices held (z <= clamp_end)
  std::vector<int> clamp_line;  // vertices on z = clamp_end (where the free length starts)
  std::vector<int> tip;         // vertices at the free end
  double clamp_end = 0.0;       // m
  double free_length = 0.0;     // m
};

// `cells`: cells (rows of triangles) along the free length; `across`: cells across the width.
inline Strip make_strip(StripMesh mesh, double free_length, double width, int cells, int across,
                        double height = 0.0, unsigned seed = 7) {
  Strip strip;
  strip.free_length = free_length;
  const double h = free_length / cells;  // spacing of the vertex rows along the strip
  std::vector<Eigen::Vector2d> points;   // (x, z)
  std::vector<Eigen::Vector3i> faces;
  const auto grid = [&](int rows, int columns, double dx, const auto& offset) {
    for (int r = 0; r <= rows; ++r)
      for (int c = 0; c <= columns; ++c) points.emplace_back(c * dx + offset(r), r * h);
  };
  const int rows = cells + 2;  // two rows clamped
  strip.clamp_end = 2 * h;
  switch (mesh) {
    case StripMesh::four_eight:
    case StripMesh::irregular: {
      const double dx = width / across;
      grid(rows, across, dx, [](int) { return 0.0; });
      std::mt19937 random(seed);
      std::uniform_int_distribution<int> coin(0, 1);
      const auto id = [&](int r, int c) { return r * (across + 1) + c; };
      for (int r = 0; r < rows; ++r)
        for (int c = 0; c < across; ++c) {
          const bool flip = mesh == StripMesh::four_eight ? (r + c) % 2 == 0 : coin(random) == 0;
          const int a = id(r, c), b = id(r, c + 1), p = id(r + 1, c), q = id(r + 1, c + 1);
          if (flip) {
            faces.emplace_back(a, q, b);
            faces.emplace_back(a, p, q);
          } else {
            faces.emplace_back(a, p, b);
            faces.emplace_back(b, p, q);
          }
        }
      if (mesh == StripMesh::irregular) {
        std::uniform_real_distribution<double> jitter(-0.2, 0.2);
        for (int r = 0; r <= rows; ++r)
          for (int c = 0; c <= across; ++c) {
            Eigen::Vector2d& p = points[static_cast<std::size_t>(id(r, c))];
            if (c > 0 && c < across) p.x() += jitter(random) * dx;
            if (r > 2 && r < rows) p.y() += jitter(random) * h;  // clamp rows and tip stay
          }
      }
      break;
    }
    case StripMesh::four_eight_45: {
      const double dx = width / across;
      grid(rows, across, dx, [](int) { return 0.0; });
      const auto id = [&](int r, int c) { return r * (across + 1) + c; };
      for (int r = 0; r < rows; ++r)
        for (int c = 0; c < across; ++c) {
          const int centre = static_cast<int>(points.size());
          points.emplace_back((c + 0.5) * dx, (r + 0.5) * h);
          const int a = id(r, c), b = id(r, c + 1), p = id(r + 1, c), q = id(r + 1, c + 1);
          faces.emplace_back(a, centre, b);
          faces.emplace_back(b, centre, q);
          faces.emplace_back(q, centre, p);
          faces.emplace_back(p, centre, a);
        }
      break;
    }
    case StripMesh::equilateral_across: {
      // Rows of vertices across the strip, h apart; edge length a = 2h/√3, alternate rows
      // shifted by a/2.
      const double a = 2.0 * h / std::sqrt(3.0);
      const int columns = std::max(1, static_cast<int>(std::lround(width / a)));
      grid(rows, columns, a, [&](int r) { return r % 2 == 0 ? 0.0 : 0.5 * a; });
      const auto id = [&](int r, int c) { return r * (columns + 1) + c; };
      for (int r = 0; r < rows; ++r)
        for (int c = 0; c < columns; ++c) {
          if (r % 2 == 0) {
            faces.emplace_back(id(r, c), id(r + 1, c), id(r, c + 1));
            if (c + 1 < columns) faces.emplace_back(id(r, c + 1), id(r + 1, c), id(r + 1, c + 1));
          } else {
            faces.emplace_back(id(r, c), id(r + 1, c), id(r + 1, c + 1));
            if (c + 1 < columns) faces.emplace_back(id(r, c), id(r + 1, c + 1), id(r, c + 1));
          }
        }
      break;
    }
  }
  // Drop the vertices no triangle uses (the row ends of the equilateral meshes).
  {
    std::vector<int> index(points.size(), -1);
    for (const Eigen::Vector3i& f : faces)
      for (int k = 0; k < 3; ++k) index[static_cast<std::size_t>(f[k])] = 0;
    std::vector<Eigen::Vector2d> used;
    for (std::size_t i = 0; i < points.size(); ++i)
      if (index[i] == 0) {
        index[i] = static_cast<int>(used.size());
        used.push_back(points[i]);
      }
    for (Eigen::Vector3i& f : faces)
      for (int k = 0; k < 3; ++k) f[k] = index[static_cast<std::size_t>(f[k])];
    points.swap(used);
  }
  strip.input.rest_positions.resize(static_cast<Eigen::Index>(points.size()), 3);
  double tip_z = 0.0;
  for (const Eigen::Vector2d& p : points) tip_z = std::max(tip_z, p.y());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector2d& p = points[i];
    strip.input.rest_positions.row(static_cast<Eigen::Index>(i)) << p.x(), height, p.y();
    const int v = static_cast<int>(i);
    if (p.y() <= strip.clamp_end + 1e-9 * h) strip.clamped.push_back(v);
    if (std::abs(p.y() - strip.clamp_end) < 1e-9 * h) strip.clamp_line.push_back(v);
    if (std::abs(p.y() - tip_z) < 1e-9 * h) strip.tip.push_back(v);
  }
  strip.input.triangles.resize(static_cast<Eigen::Index>(faces.size()), 3);
  strip.input.warp.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (std::size_t f = 0; f < faces.size(); ++f) {
    strip.input.triangles.row(static_cast<Eigen::Index>(f)) = faces[f].transpose();
    strip.input.warp.row(static_cast<Eigen::Index>(f)) << 0.0, 0.0, 1.0;
  }
  return strip;
}

}  // namespace sd::sim::test
