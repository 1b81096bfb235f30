#include "sim/diamond_membrane.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <type_traits>

#include "sim/cloth_model.hpp"

namespace sd::sim {
namespace {

using Eigen::Vector3d;
using Gradient = Eigen::Matrix<double, 18, 1>;
using Hessian = Eigen::Matrix<double, 18, 18>;
using Points = Eigen::Matrix<double, 18, 1>;
constexpr int kVertices = DiamondElement::kVertices;

// A value with its exact derivatives with respect to the six points' 18 coordinates (forward
// mode): the gradient, and with kSecond the Hessian. The map is a few dozen operations, so
// carrying both through them is cheaper and safer than a hand-expanded second derivative.
template <bool kSecond>
struct Jet {
  double value = 0.0;
  Gradient gradient = Gradient::Zero();
  std::conditional_t<kSecond, Hessian, char> hessian{};

  Jet() {
    if constexpr (kSecond) hessian.setZero();
  }
  explicit Jet(double v) : Jet() { value = v; }
};

template <bool S>
Jet<S> operator+(const Jet<S>& a, const Jet<S>& b) {
  Jet<S> r(a.value + b.value);
  r.gradient = a.gradient + b.gradient;
  if constexpr (S) r.hessian = a.hessian + b.hessian;
  return r;
}

template <bool S>
Jet<S> operator-(const Jet<S>& a, const Jet<S>& b) {
  Jet<S> r(a.value - b.value);
  r.gradient = a.gradient - b.gradient;
  if constexpr (S) r.hessian = a.hessian - b.hessian;
  return r;
}

template <bool S>
Jet<S> operator*(double s, const Jet<S>& a) {
  Jet<S> r(s * a.value);
  r.gradient = s * a.gradient;
  if constexpr (S) r.hessian = s * a.hessian;
  return r;
}

template <bool S>
Jet<S> operator*(const Jet<S>& a, const Jet<S>& b) {
  Jet<S> r(a.value * b.value);
  r.gradient = a.value * b.gradient + b.value * a.gradient;
  if constexpr (S) {
    const Hessian outer = a.gradient * b.gradient.transpose();
    r.hessian = a.value * b.hessian + b.value * a.hessian + outer + outer.transpose();
  }
  return r;
}

// 1/a and √a by the chain rule: φ(a) with φ', φ''.
template <bool S>
Jet<S> apply(const Jet<S>& a, double value, double slope, double curvature) {
  Jet<S> r(value);
  r.gradient = slope * a.gradient;
  if constexpr (S) r.hessian = slope * a.hessian + curvature * a.gradient * a.gradient.transpose();
  return r;
}

template <bool S>
Jet<S> inverse(const Jet<S>& a) {
  const double i = 1.0 / a.value;
  return apply(a, i, -i * i, 2.0 * i * i * i);
}

template <bool S>
Jet<S> square_root(const Jet<S>& a) {
  const double s = std::sqrt(a.value);
  return apply(a, s, 0.5 / s, -0.25 / (s * a.value));
}

template <bool S>
using JetVector = std::array<Jet<S>, 3>;

template <bool S>
JetVector<S> minus(const JetVector<S>& a, const JetVector<S>& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}

template <bool S>
Jet<S> dot(const JetVector<S>& a, const JetVector<S>& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

template <bool S>
JetVector<S> cross(const JetVector<S>& a, const JetVector<S>& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

// The map's value g and its derivatives in the six points z = (x_c, x₁, …, x₄, p); false where
// the diagonals are (nearly) parallel.
template <bool S>
bool centre_map(const DiamondElement& d, const Points& x, JetVector<S>& offset) {
  std::array<JetVector<S>, 6> p;
  for (int k = 0; k < 6; ++k)
    for (int i = 0; i < 3; ++i) {
      p[k][i] = Jet<S>(x(3 * k + i));
      p[k][i].gradient(3 * k + i) = 1.0;
    }
  const JetVector<S> m = cross(minus(p[3], p[1]), minus(p[4], p[2]));
  const Jet<S> m2 = dot(m, m);
  // Parallel diagonals: |m|² is 1e-12 of the diagonals' squared lengths' product.
  const double scale = (x.segment<3>(9) - x.segment<3>(3)).squaredNorm() *
                       (x.segment<3>(12) - x.segment<3>(6)).squaredNorm();
  if (!(m2.value > 1e-24 * scale)) return false;
  const Jet<S> inverse_length = inverse(square_root(m2));
  const JetVector<S> n = {inverse_length * m[0], inverse_length * m[1], inverse_length * m[2]};
  // Heights of the corner pairs' midpoints above the predicted centre p: n·(½(x₁ + x₃) − p),
  // n·(½(x₂ + x₄) − p). The centre x_c is not in them: the map adds to it.
  JetVector<S> q1, q2;
  for (int i = 0; i < 3; ++i) {
    q1[i] = 0.5 * (p[1][i] + p[3][i]) - p[5][i];
    q2[i] = 0.5 * (p[2][i] + p[4][i]) - p[5][i];
  }
  const Jet<S> h1 = dot(n, q1), h2 = dot(n, q2);
  const Jet<S> f = h1 * h2 * (h1 + h2) * inverse(h1 * h1 + h2 * h2 + Jet<S>(d.regularisation));
  const Jet<S> lift = f - Jet<S>(d.rest_offset);
  offset = {lift * n[0], lift * n[1], lift * n[2]};
  return true;
}

// The corners' neighbours and the weights of the predicted centre p (docs/simulator.md, "The
// diamond membrane"). The corners of the diamonds form a grid of their own, the diamond one of its
// cells; the second difference D(k, j) = x_j − 2·x_k + o(k, j) of corner k along the line from
// its fellow corner j is, on a smooth surface, κ·L² with κ the curvature along that line and L
// the corners' spacing. On a quadratic surface z = ½(A·s² + 2B·s·t + C·t²) (s, t along the
// diagonals, corners at a) the corners' mean lies (A + C)·a²/4 above the centre and the eight
// second differences sum to 8·(A + C)·a², so p = x̄ − ΣD/32 = (5/16)·Σx_k − (1/32)·Σo: exact on
// any quadratic (and, by symmetry, with errors of fourth order), without the centre. A second
// difference the mesh lacks (a border) is the mean of those along the same direction (the lines
// 1-2 and 3-4, or 2-3 and 4-1); with none along a direction, that direction's curvature is taken
// as zero.
template <class Beyond>
void set_predictor(DiamondElement& d, const Beyond& beyond) {
  // Outer slots 5..12 as (k, j) pairs, corners 1..4.
  static constexpr std::array<std::array<int, 2>, 8> kPairs = {
      {{1, 4}, {1, 2}, {2, 1}, {2, 3}, {3, 2}, {3, 4}, {4, 3}, {4, 1}}};
  d.weights.fill(0.0);
  for (int k = 1; k <= 4; ++k) d.weights[static_cast<std::size_t>(k)] = 0.25;
  std::array<char, 8> found{};
  for (std::size_t s = 0; s < 8; ++s) {
    const int o = beyond(d.vertices[static_cast<std::size_t>(kPairs[s][0])],
                         d.vertices[static_cast<std::size_t>(kPairs[s][1])]);
    found[s] =
        o >= 0 && std::find(d.vertices.begin(), d.vertices.begin() + 5 + static_cast<long>(s), o) ==
                      d.vertices.begin() + 5 + static_cast<long>(s);
    d.vertices[5 + s] = found[s] ? o : d.vertices[0];
  }
  // Direction of a pair's line: 1-2 and 3-4 one, 2-3 and 4-1 the other.
  const auto direction = [](std::size_t s) {
    const int k = kPairs[s][0], j = kPairs[s][1];
    return (std::min(k, j) == 1 && std::max(k, j) == 2) ||
                   (std::min(k, j) == 3 && std::max(k, j) == 4)
               ? 0
               : 1;
  };
  for (int dir = 0; dir < 2; ++dir) {
    int count = 0;
    for (std::size_t s = 0; s < 8; ++s) count += direction(s) == dir && found[s];
    if (count == 0) continue;
    const double share = -(4.0 / count) / 32.0;  // each found D stands for 4/count of the four
    for (std::size_t s = 0; s < 8; ++s) {
      if (direction(s) != dir || !found[s]) continue;
      d.weights[5 + s] += share;
      d.weights[static_cast<std::size_t>(kPairs[s][0])] -= 2.0 * share;
      d.weights[static_cast<std::size_t>(kPairs[s][1])] += share;
    }
  }
}

}  // namespace

void diamond_centre_map(const DiamondElement& diamond, const DiamondVector& x, bool with_hessian,
                        DiamondMap& out) {
  out.offset.setZero();
  out.jacobian.setZero();
  out.points.setZero();
  for (int k = 0; k < 15; ++k) out.points(k, k) = 1.0;
  for (int s = 1; s < kVertices; ++s)
    for (int i = 0; i < 3; ++i)
      out.points(15 + i, 3 * s + i) = diamond.weights[static_cast<std::size_t>(s)];
  const Points z = out.points * x;
  if (with_hessian) {
    for (auto& h : out.point_hessian) h.setZero();
    JetVector<true> g;
    if (!centre_map<true>(diamond, z, g)) return;
    for (int i = 0; i < 3; ++i) {
      out.offset(i) = g[i].value;
      out.jacobian.row(i) = g[i].gradient.transpose() * out.points;
      out.point_hessian[static_cast<std::size_t>(i)] = g[i].hessian;
    }
    return;
  }
  JetVector<false> g;
  if (!centre_map<false>(diamond, z, g)) return;
  for (int i = 0; i < 3; ++i) {
    out.offset(i) = g[i].value;
    out.jacobian.row(i) = g[i].gradient.transpose() * out.points;
  }
}

DiamondMatrix diamond_map_hessian(const DiamondMap& map, int i) {
  return map.points.transpose() * map.point_hessian[static_cast<std::size_t>(i)] * map.points;
}

std::vector<DiamondElement> make_diamonds(const Eigen::MatrixX3d& rest,
                                          const std::vector<TriangleElement>& triangles,
                                          bool flat_rest) {
  const auto n = static_cast<std::size_t>(rest.rows());
  // The triangles around each vertex (CSR).
  std::vector<int> start(n + 1, 0);
  for (const TriangleElement& t : triangles)
    for (int v : t.vertices) ++start[static_cast<std::size_t>(v) + 1];
  for (std::size_t i = 0; i < n; ++i) start[i + 1] += start[i];
  std::vector<int> around(static_cast<std::size_t>(start[n]));
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (std::size_t f = 0; f < triangles.size(); ++f)
      for (int v : triangles[f].vertices)
        around[static_cast<std::size_t>(fill[static_cast<std::size_t>(v)]++)] = static_cast<int>(f);
  }
  // The vertex of `corner`'s triangles nearest to 2·x_corner − x_fellow (the next vertex on the
  // line from its fellow corner through it), if within a quarter of their distance; else -1.
  const auto beyond = [&](int corner, int fellow) {
    const Vector3d xc = rest.row(corner).transpose();
    const Vector3d target = 2.0 * xc - Vector3d(rest.row(fellow).transpose());
    const double tolerance = 0.25 * (Vector3d(rest.row(fellow).transpose()) - xc).norm();
    int best = -1;
    double best_distance = tolerance;
    for (int k = start[static_cast<std::size_t>(corner)];
         k < start[static_cast<std::size_t>(corner) + 1]; ++k)
      for (int v :
           triangles[static_cast<std::size_t>(around[static_cast<std::size_t>(k)])].vertices) {
        const double distance = (Vector3d(rest.row(v).transpose()) - target).norm();
        if (distance <= best_distance) {
          best = v;
          best_distance = distance;
        }
      }
    return best;
  };
  std::vector<char> taken(triangles.size(), 0);
  std::vector<DiamondElement> diamonds;
  for (std::size_t c = 0; c < n; ++c) {
    if (start[c + 1] - start[c] != 4) continue;
    // Each triangle as (c, a, b) in its own order: the fan closes when the b of one is the a of
    // the next, four times round.
    std::array<int, 4> faces{}, a{}, b{};
    bool free = true;
    for (int k = 0; k < 4; ++k) {
      const int f = around[static_cast<std::size_t>(start[c] + k)];
      const auto& v = triangles[static_cast<std::size_t>(f)].vertices;
      const int at = v[0] == static_cast<int>(c) ? 0 : v[1] == static_cast<int>(c) ? 1 : 2;
      faces[static_cast<std::size_t>(k)] = f;
      a[static_cast<std::size_t>(k)] = v[static_cast<std::size_t>((at + 1) % 3)];
      b[static_cast<std::size_t>(k)] = v[static_cast<std::size_t>((at + 2) % 3)];
      free = free && !taken[static_cast<std::size_t>(f)];
    }
    if (!free) continue;
    DiamondElement d;
    d.vertices[0] = static_cast<int>(c);
    std::array<int, 4> order{};
    std::array<char, 4> used{};
    int current = 0;
    bool closed = true;
    for (int k = 0; k < 4 && closed; ++k) {
      order[static_cast<std::size_t>(k)] = current;
      used[static_cast<std::size_t>(current)] = 1;
      d.vertices[static_cast<std::size_t>(k) + 1] = a[static_cast<std::size_t>(current)];
      int next = -1;
      for (int j = 0; j < 4; ++j)
        if (a[static_cast<std::size_t>(j)] == b[static_cast<std::size_t>(current)]) next = j;
      if (next < 0 || (k < 3 && used[static_cast<std::size_t>(next)]) || (k == 3 && next != 0))
        closed = false;
      current = next;
    }
    if (!closed) continue;
    for (int k = 0; k < 4; ++k)
      d.triangles[static_cast<std::size_t>(k)] = faces[static_cast<std::size_t>(order[k])];
    // The centre near the midpoint of both diagonals (a quarter of the half-diagonal).
    const auto at = [&](int k) {
      return Vector3d(rest.row(d.vertices[static_cast<std::size_t>(k)]).transpose());
    };
    const double a13 = 0.5 * (at(3) - at(1)).norm(), a24 = 0.5 * (at(4) - at(2)).norm();
    if (!(a13 > 0.0) || !(a24 > 0.0) || (0.5 * (at(1) + at(3)) - at(0)).norm() > 0.25 * a13 ||
        (0.5 * (at(2) + at(4)) - at(0)).norm() > 0.25 * a24)
      continue;
    const double epsilon = 0.01 * 0.5 * (a13 + a24);
    d.regularisation = epsilon * epsilon;
    set_predictor(d, beyond);
    if (!flat_rest) {
      DiamondVector x;
      for (int k = 0; k < kVertices; ++k)
        x.segment<3>(3 * k) =
            Vector3d(rest.row(d.vertices[static_cast<std::size_t>(k)]).transpose());
      DiamondMap map;
      diamond_centre_map(d, x, false, map);
      const Vector3d m = (at(3) - at(1)).cross(at(4) - at(2));
      d.rest_offset = m.norm() > 0.0 ? map.offset.dot(m.normalized()) : 0.0;
    }
    for (int f : d.triangles) taken[static_cast<std::size_t>(f)] = 1;
    diamonds.push_back(d);
  }
  // Partial diamonds: an adaptive split of a diamond's triangle leaves the centre with fewer
  // than four of its own. Each remaining triangle keeps the centre's map (taken from the four
  // corners, which are still vertices), so a split changes the membrane of the split triangles
  // only. Exact 4-8 geometry only (right isosceles triangles, the corners' mirror images present
  // to rounding), so imported and irregular meshes, and the interior of a fixed 4-8 mesh, where
  // every such centre is a whole diamond, are not affected.
  const auto point = [&](int v) { return Vector3d(rest.row(v).transpose()); };
  const auto right_angle_at = [&](const std::array<int, 3>& v, int k, double& leg) {
    const Vector3d c = point(v[static_cast<std::size_t>(k)]);
    const Vector3d u = point(v[static_cast<std::size_t>((k + 1) % 3)]) - c;
    const Vector3d w = point(v[static_cast<std::size_t>((k + 2) % 3)]) - c;
    leg = u.norm();
    constexpr double kExact = 1e-9;  // rounding of midpoints a few levels deep
    return leg > 0.0 && std::abs(w.norm() - leg) <= kExact * leg &&
           std::abs(u.dot(w)) <= kExact * leg * leg;
  };
  for (std::size_t c = 0; c < n; ++c) {
    // c's free triangles with their right angle at c: (c, b_k, b_k+1) in their own order.
    std::array<int, 4> corners{-1, -1, -1, -1};
    std::array<int, 4> faces{-1, -1, -1, -1};
    double leg = 0.0;
    bool ok = true;
    for (int k = start[c]; k < start[c + 1] && ok; ++k) {
      const int f = around[static_cast<std::size_t>(k)];
      if (taken[static_cast<std::size_t>(f)]) continue;
      const auto& v = triangles[static_cast<std::size_t>(f)].vertices;
      const int at = v[0] == static_cast<int>(c) ? 0 : v[1] == static_cast<int>(c) ? 1 : 2;
      double l = 0.0;
      if (!right_angle_at(v, at, l)) continue;
      const int u = v[static_cast<std::size_t>((at + 1) % 3)];
      const int w = v[static_cast<std::size_t>((at + 2) % 3)];
      if (corners[0] < 0) {
        leg = l;
        corners[0] = u;
        corners[1] = w;
        faces[0] = f;
        continue;
      }
      if (std::abs(l - leg) > 1e-9 * leg) {
        ok = false;
        break;
      }
      // Which sector: u is corner s, w corner s + 1, with corners 2, 3 the mirrors of 0, 1.
      const Vector3d xc = point(static_cast<int>(c));
      const auto is_corner = [&](int vertex, int s) {
        const int base = s % 2;
        const Vector3d expected =
            s < 2 ? point(corners[static_cast<std::size_t>(base)])
                  : Vector3d(2.0 * xc - point(corners[static_cast<std::size_t>(base)]));
        return (point(vertex) - expected).norm() <= 1e-9 * leg;
      };
      int sector = -1;
      for (int s = 1; s < 4; ++s)
        if (is_corner(u, s) && is_corner(w, (s + 1) % 4)) sector = s;
      if (sector < 0 || faces[static_cast<std::size_t>(sector)] >= 0) {
        ok = false;
        break;
      }
      faces[static_cast<std::size_t>(sector)] = f;
      corners[static_cast<std::size_t>(sector)] = u;
      corners[static_cast<std::size_t>((sector + 1) % 4)] = w;
    }
    if (!ok || corners[0] < 0) continue;
    // Corners no remaining triangle names: the vertex at the mirror image, within c's two-ring
    // (a split of the sector (c, b, b') joins c to the midpoint of b b', which is joined to b').
    const Vector3d xc = point(static_cast<int>(c));
    for (int s = 2; s < 4 && ok; ++s) {
      if (corners[static_cast<std::size_t>(s)] >= 0) continue;
      const Vector3d target = 2.0 * xc - point(corners[static_cast<std::size_t>(s - 2)]);
      int found = -1;
      for (int k = start[c]; k < start[c + 1] && found < 0; ++k)
        for (int m :
             triangles[static_cast<std::size_t>(around[static_cast<std::size_t>(k)])].vertices)
          for (int j = start[static_cast<std::size_t>(m)];
               j < start[static_cast<std::size_t>(m) + 1] && found < 0; ++j)
            for (int o :
                 triangles[static_cast<std::size_t>(around[static_cast<std::size_t>(j)])].vertices)
              if ((point(o) - target).norm() <= 1e-9 * leg) found = o;
      corners[static_cast<std::size_t>(s)] = found;
      ok = found >= 0;
    }
    if (!ok) continue;
    // The same mirror test for corners a triangle named (1 from 0's triangle, 3 from 1's).
    for (int s = 0; s < 2 && ok; ++s)
      ok = (point(corners[static_cast<std::size_t>(s)]) +
            point(corners[static_cast<std::size_t>(s + 2)]) - 2.0 * xc)
               .norm() <= 1e-9 * leg;
    if (!ok) continue;
    DiamondElement d;
    d.vertices[0] = static_cast<int>(c);
    for (int k = 0; k < 4; ++k) {
      d.vertices[static_cast<std::size_t>(k) + 1] = corners[static_cast<std::size_t>(k)];
      d.triangles[static_cast<std::size_t>(k)] = faces[static_cast<std::size_t>(k)];
    }
    const double epsilon = 0.01 * leg;  // the half-diagonals are the legs
    d.regularisation = epsilon * epsilon;
    set_predictor(d, beyond);
    if (!flat_rest) {
      DiamondVector x;
      for (int k = 0; k < kVertices; ++k)
        x.segment<3>(3 * k) = point(d.vertices[static_cast<std::size_t>(k)]);
      DiamondMap map;
      diamond_centre_map(d, x, false, map);
      const Vector3d m =
          (point(corners[2]) - point(corners[0])).cross(point(corners[3]) - point(corners[1]));
      d.rest_offset = m.norm() > 0.0 ? map.offset.dot(m.normalized()) : 0.0;
    }
    for (int f : d.triangles)
      if (f >= 0) taken[static_cast<std::size_t>(f)] = 1;
    diamonds.push_back(d);
  }
  return diamonds;
}

}  // namespace sd::sim
