#pragma once
// Meshes and an independent intersection count for the self-contact tests.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <vector>

namespace sd::sim::testing {

// A strip of 2n × n quads (2·size by size metres in the XZ plane) folded over the line x = 0:
// columns 0..n lie flat at y = 0 from x = −size to 0, columns n+1..2n lie over them at y = gap
// (column n + k above column n − k). gap < 0: the strip stays flat, from x = −size to size.
struct FoldedSheet {
  std::vector<std::array<int, 3>> triangles;
  Eigen::VectorXd x;        // 3n positions
  std::vector<bool> upper;  // per vertex: on the folded-over layer
};

inline FoldedSheet folded_sheet(int n, double size, double gap) {
  FoldedSheet sheet;
  const int columns = 2 * n, rows = n;
  const double dx = size / n;
  const int count = (columns + 1) * (rows + 1);
  sheet.x.resize(3 * count);
  sheet.upper.assign(static_cast<std::size_t>(count), false);
  const auto id = [&](int i, int j) { return j * (columns + 1) + i; };
  for (int j = 0; j <= rows; ++j)
    for (int i = 0; i <= columns; ++i) {
      Eigen::Vector3d p((i - n) * dx, 0.0, j * dx);
      if (gap >= 0.0 && i > n) {
        p = Eigen::Vector3d(-(i - n) * dx, gap, j * dx);
        sheet.upper[id(i, j)] = true;
      }
      sheet.x.segment<3>(3 * id(i, j)) = p;
    }
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < columns; ++i) {
      const int a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      if ((i + j) % 2 == 0) {
        sheet.triangles.push_back({a, b, c});
        sheet.triangles.push_back({a, c, d});
      } else {
        sheet.triangles.push_back({a, b, d});
        sheet.triangles.push_back({b, c, d});
      }
    }
  return sheet;
}

// Does segment pq cross triangle abc (touching counts)? Signs of orientation determinants,
// the standard exact-predicate formulation evaluated in double (enough for test meshes).
inline bool segment_crosses_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                                     const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                     const Eigen::Vector3d& c) {
  const auto orient = [](const Eigen::Vector3d& u, const Eigen::Vector3d& v,
                         const Eigen::Vector3d& w,
                         const Eigen::Vector3d& z) { return (v - u).cross(w - u).dot(z - u); };
  const double sp = orient(a, b, c, p), sq = orient(a, b, c, q);
  if ((sp > 0 && sq > 0) || (sp < 0 && sq < 0) || (sp == 0 && sq == 0)) return false;
  const double s1 = orient(p, q, a, b), s2 = orient(p, q, b, c), s3 = orient(p, q, c, a);
  return (s1 >= 0 && s2 >= 0 && s3 >= 0) || (s1 <= 0 && s2 <= 0 && s3 <= 0);
}

// Pairs of triangles sharing no vertex that intersect at x (3n): one crosses an edge of the
// other. All pairs, O(F²): small test meshes only.
inline int count_intersecting_pairs(const std::vector<std::array<int, 3>>& triangles,
                                    const Eigen::VectorXd& x) {
  const auto p = [&](int i) { return Eigen::Vector3d(x.segment<3>(3 * i)); };
  int count = 0;
  const int f = static_cast<int>(triangles.size());
  std::vector<Eigen::AlignedBox3d> boxes(static_cast<std::size_t>(f));
  for (int t = 0; t < f; ++t)
    for (int k = 0; k < 3; ++k) boxes[t].extend(p(triangles[t][k]));
  for (int s = 0; s < f; ++s)
    for (int t = s + 1; t < f; ++t) {
      const auto& a = triangles[s];
      const auto& b = triangles[t];
      bool shared = false;
      for (int i : a)
        for (int j : b) shared = shared || i == j;
      if (shared || !boxes[s].intersects(boxes[t])) continue;
      bool hit = false;
      for (int k = 0; k < 3 && !hit; ++k) {
        hit = segment_crosses_triangle(p(a[k]), p(a[(k + 1) % 3]), p(b[0]), p(b[1]), p(b[2])) ||
              segment_crosses_triangle(p(b[k]), p(b[(k + 1) % 3]), p(a[0]), p(a[1]), p(a[2]));
      }
      count += hit;
    }
  return count;
}

}  // namespace sd::sim::testing
