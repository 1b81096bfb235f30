// The bend elements of the cloth model (docs/simulator.md, "Bending on any mesh"): the hinges
// and their calibrated weights, the bend stencils and the quadratic vertex bends, made from the
// rest mesh for build_cloth_model and update_cloth_model (sim/cloth_model.cpp).
#include "sim/bend_elements.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <tuple>
#include <utility>

#include "sim/element_forces.hpp"

namespace sd::sim::detail {
namespace {

using Eigen::Vector3d;

// A row's weight below this fraction of the row's largest is a zero: the rounding a
// least-squares fit leaves where a symmetric stencil has an exact zero (~1e-16 of the largest).
constexpr double kNegligibleWeight = 1e-13;

// A neighbourhood wider than the one-ring is fitted only with at least this many points, nearly
// twice the quadratic's six coefficients. A fit that just interpolates a few points follows
// their chord errors: with the nearest points alone a cylinder's energy on the irregular strip
// erred by 3.6 % (1.9 % on the whole two-ring), and with 9 points Peirce's chord on the 4-8 mesh at
// 45° came out 0.3° stiffer than with the whole two-ring (silk 39.97° against 41.49°); with 11 the
// chords are the whole two-ring's within 0.05° (tests/sim/textile_presets_test.cpp). The 9-point
// fit is the more accurate bending (0.981 B at 16 cells at 45° against 0.962); silk's chord is
// stiffened by the membrane locking on that layout, which the 11-point fit's softness offsets
// (docs/simulator.md, "Elongated cells", "Still open").
constexpr std::size_t kFewestFitPoints = 11;

// The points an element's rows read: its centre and every point with a weight in some row.
std::vector<char> read_columns(const VertexBendElement& element) {
  const auto count = static_cast<Eigen::Index>(element.vertices.size());
  std::vector<char> read(static_cast<std::size_t>(count), 0);
  read[static_cast<std::size_t>(element.centre)] = 1;
  for (int k = 0; k < 3; ++k) {
    const double largest = element.rows.row(k).cwiseAbs().maxCoeff();
    for (Eigen::Index j = 0; j < count; ++j)
      if (std::abs(element.rows(k, j)) > kNegligibleWeight * largest)
        read[static_cast<std::size_t>(j)] = 1;
  }
  return read;
}

// Drops the points an element neither reads nor needs for its fan (G(x) reads the fan). The
// rows are fitted on the two-ring, but most use the one-ring alone, and every pair of an
// element's points is a block of the system matrix: a two-ring element couples each vertex to
// its four-ring (on the 4-8 mesh 72 blocks a row, against the hinges' 11). The energy, force
// and matrix entries change only by the dropped weights' rounding-level products.
void prune_columns(VertexBendElement& element) {
  const auto count = static_cast<Eigen::Index>(element.vertices.size());
  std::vector<char> keep = read_columns(element);
  for (const auto& [b, c] : element.fan)
    keep[static_cast<std::size_t>(b)] = keep[static_cast<std::size_t>(c)] = 1;
  std::vector<int> local(static_cast<std::size_t>(count), -1);
  std::vector<int> vertices;
  for (Eigen::Index j = 0; j < count; ++j)
    if (keep[static_cast<std::size_t>(j)]) {
      local[static_cast<std::size_t>(j)] = static_cast<int>(vertices.size());
      vertices.push_back(element.vertices[static_cast<std::size_t>(j)]);
    }
  if (static_cast<Eigen::Index>(vertices.size()) == count) return;
  Eigen::Matrix<double, 3, Eigen::Dynamic> rows(3, static_cast<Eigen::Index>(vertices.size()));
  for (Eigen::Index j = 0; j < count; ++j)
    if (const int l = local[static_cast<std::size_t>(j)]; l >= 0) rows.col(l) = element.rows.col(j);
  element.rows = std::move(rows);
  element.vertices = std::move(vertices);
  element.centre = local[static_cast<std::size_t>(element.centre)];
  for (auto& [b, c] : element.fan) {
    b = local[static_cast<std::size_t>(b)];
    c = local[static_cast<std::size_t>(c)];
  }
}

// Whether every point's mirror through vertex v is also among `points` (to 1e-6 of the reach).
bool centrally_symmetric(const Eigen::MatrixX3d& rest, int v, const std::vector<int>& points,
                         double reach2) {
  const Vector3d centre = rest.row(v);
  for (int j : points) {
    const Vector3d mirror = 2.0 * centre - Vector3d(rest.row(j));
    bool found = false;
    for (int k : points)
      found = found || (Vector3d(rest.row(k)) - mirror).squaredNorm() <= 1e-12 * reach2;
    if (!found) return false;
  }
  return true;
}

// The centrally symmetric parts of a vertex's one-ring, nearest first: the vertex with the
// one-ring's points up to each distance (equal distances together) wherever every point's mirror
// through the vertex is also among them, short of the whole one-ring. On regular meshes these
// are the nearest opposite pairs (on the 4-8 mesh with w × h cells the pair at w, then the pair
// at h, then the diagonals); irregular one-rings have none.
std::vector<std::vector<int>> symmetric_shells(const Eigen::MatrixX3d& rest, int v,
                                               const std::vector<int>& one_ring) {
  const Vector3d centre = rest.row(v);
  std::vector<std::pair<double, int>> by_distance;
  double reach2 = 0.0;
  for (int j : one_ring) {
    const double d2 = (Vector3d(rest.row(j)) - centre).squaredNorm();
    by_distance.emplace_back(d2, j);
    reach2 = std::max(reach2, d2);
  }
  std::sort(by_distance.begin(), by_distance.end());
  std::vector<std::vector<int>> shells;
  std::vector<int> points{v};
  for (std::size_t first = 0; first < by_distance.size();) {
    std::size_t last = first + 1;
    while (last < by_distance.size() &&
           by_distance[last].first - by_distance[first].first <= 1e-9 * reach2)
      ++last;
    for (std::size_t j = first; j < last; ++j) points.push_back(by_distance[j].second);
    first = last;
    if (last == by_distance.size()) break;
    if (centrally_symmetric(rest, v, points, reach2)) {
      shells.push_back(points);
      std::sort(shells.back().begin(), shells.back().end());
    }
  }
  return shells;
}

}  // namespace

// The hinge on the edge that starts at corner `first_corner` of triangle `first` (the one of
// the two with the lower row); `second_corner` is where the edge starts in `second`.
// `areas`: the sum of the two triangles' unscaled rest areas.
HingeElement make_hinge(const Eigen::MatrixX3d& rest, const std::array<int, 3>& first,
                        int first_corner, const std::array<int, 3>& second, int second_corner,
                        double areas, const ClothModelOptions& options) {
  HingeElement h;
  h.vertices[0] = first[first_corner];
  h.vertices[1] = first[(first_corner + 1) % 3];
  h.vertices[2] = first[(first_corner + 2) % 3];
  h.vertices[3] = second[(second_corner + 2) % 3];
  const Vector3d p0 = rest.row(h.vertices[0]);
  const Vector3d p1 = rest.row(h.vertices[1]);
  h.weight = (p1 - p0).squaredNorm() / areas;
  if (options.bend_rest == BendRestShape::designed)
    h.rest_angle = dihedral_angle(p0, p1, rest.row(h.vertices[2]).transpose(),
                                  rest.row(h.vertices[3]).transpose());
  return h;
}

namespace {

// How a hinge's angle responds to a smooth bend, from its rest geometry: for the height field
// w = ½·pᵀKp over the hinge's (unfolded) plane, interpolated linearly on its two triangles, the
// linearised dihedral angle is θ = a_nn·nᵀKn + a_tt·tᵀKt + a_nt·tᵀKn (t along the edge, n
// towards apex x2). Each apex contributes its height above the edge's interpolation over its
// distance d_i: a_nn = (d2 + d3)/2, a_tt = Σ s_i(s_i − ℓ)/(2 d_i), a_nt = s2 − s3, where s_i
// is where apex i projects along the edge (from x0) and ℓ the edge length (docs/simulator.md,
// "Bending on any mesh").
struct HingeResponse {
  double a_nn = 0.0, a_tt = 0.0, a_nt = 0.0;
  double areas = 0.0;  // A1 + A2, m²
};

HingeResponse hinge_response(const Eigen::MatrixX3d& rest, const HingeElement& h) {
  const Vector3d p0 = rest.row(h.vertices[0]);
  const Vector3d p1 = rest.row(h.vertices[1]);
  const double length = (p1 - p0).norm();
  const Vector3d t = (p1 - p0) / length;
  HingeResponse r;
  double s[2], d[2];
  for (int i = 0; i < 2; ++i) {
    const Vector3d q = Vector3d(rest.row(h.vertices[2 + i])) - p0;
    s[i] = q.dot(t);
    const Vector3d across = q - s[i] * t;
    d[i] = across.norm();
  }
  r.a_nn = 0.5 * (d[0] + d[1]);
  r.a_tt = s[0] * (s[0] - length) / (2.0 * d[0]) + s[1] * (s[1] - length) / (2.0 * d[1]);
  r.a_nt = s[0] - s[1];
  r.areas = 0.5 * length * (d[0] + d[1]);
  return r;
}

}  // namespace

// Scales each hinge's weight |e|²/(A1+A2) by a_nn²/(a_nn² + a_tt² + a_nt²/2), the share of
// the hinge's response that comes from bends across its edge. |e|²/(A1+A2) alone is exact for a
// bend across the edge (θ = a_nn·κ, ½·B·weight·θ² = ½·B·κ²·(A1+A2)), but a hinge whose apexes
// are not symmetric about the edge's normal line also bends under bends along the edge (a_tt)
// and under twist (a_nt): on the 4-8 mesh each hypotenuse hinge bends as much under a bend along
// it as across, so a bend at 45° to the grid costs 1.5 times the continuum energy. With the
// factor (1 for the 4-8 legs, ½ for its hypotenuses) the 4-8 mesh's hinges hold ½·B·tr(K²) per
// area for every smooth curvature K, in either orientation: the legs measure the normal
// curvatures along the grid, the hypotenuses the twist.
void calibrate_hinge_weights(const Eigen::MatrixX3d& rest, std::vector<HingeElement>& hinges) {
  for (HingeElement& h : hinges) {
    const HingeResponse r = hinge_response(rest, h);
    const double length2 =
        (Vector3d(rest.row(h.vertices[1])) - Vector3d(rest.row(h.vertices[0]))).squaredNorm();
    const double across = r.a_nn * r.a_nn;
    h.weight = length2 / r.areas * across / (across + r.a_tt * r.a_tt + 0.5 * r.a_nt * r.a_nt);
  }
}

// The bend stencils of every vertex whose one-ring has more points than the smooth shapes
// (1, u, v, u², uv, v² and the rest surface's own height over the tangent plane) constrain:
// the null space of that 7-row condition matrix, from an SVD.
std::vector<BendStencil> make_bend_stencils(const Eigen::MatrixX3d& rest,
                                            const Eigen::MatrixX3i& faces) {
  const int n = static_cast<int>(rest.rows());
  std::vector<std::vector<int>> ring(static_cast<std::size_t>(n));
  std::vector<Vector3d> vertex_normal(static_cast<std::size_t>(n), Vector3d::Zero());
  std::vector<double> area(static_cast<std::size_t>(n), 0.0);
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const Vector3d p0 = rest.row(faces(f, 0));
    const Vector3d area_normal =
        (Vector3d(rest.row(faces(f, 1))) - p0).cross(Vector3d(rest.row(faces(f, 2))) - p0);
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<std::size_t>(faces(f, k));
      vertex_normal[v] += area_normal;
      area[v] += area_normal.norm() / 6.0;
      for (int l = 0; l < 3; ++l) ring[v].push_back(faces(f, l));
    }
  }
  std::vector<BendStencil> stencils;
  for (int v = 0; v < n; ++v) {
    std::vector<int>& points = ring[static_cast<std::size_t>(v)];
    std::sort(points.begin(), points.end());
    points.erase(std::unique(points.begin(), points.end()), points.end());
    const int count = static_cast<int>(points.size());
    if (count < 7) continue;
    const Vector3d normal = vertex_normal[static_cast<std::size_t>(v)].normalized();
    const Vector3d centre = rest.row(v);
    double radius2 = 0.0;
    for (int j : points) radius2 += (Vector3d(rest.row(j)) - centre).squaredNorm();
    const double radius = std::sqrt(radius2 / (count - 1));
    const Vector3d e1 = normal.unitOrthogonal();
    const Vector3d e2 = normal.cross(e1);
    Eigen::MatrixXd conditions(7, count);
    for (int j = 0; j < count; ++j) {
      const Vector3d d =
          (Vector3d(rest.row(points[static_cast<std::size_t>(j)])) - centre) / radius;
      const double u = d.dot(e1), w = d.dot(e2);
      conditions.col(j) << 1.0, u, w, u * u, u * w, w * w, d.dot(normal);
    }
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(conditions, Eigen::ComputeFullV);
    const Eigen::VectorXd& sigma = svd.singularValues();
    int rank = 0;
    while (rank < sigma.size() && sigma(rank) > 1e-9 * sigma(0)) ++rank;
    if (rank >= count) continue;
    const Eigen::MatrixXd null = svd.matrixV().rightCols(count - rank);  // count × k, orthonormal
    BendStencil stencil;
    stencil.vertices = points;
    const double rho2 = radius2 / (count - 1);  // m², mean squared distance of the ring
    stencil.coupling =
        (area[static_cast<std::size_t>(v)] / (rho2 * rho2)) * (null * null.transpose());
    stencil.blocks.assign(static_cast<std::size_t>(count * count), 0);
    stencils.push_back(std::move(stencil));
  }
  return stencils;
}

// The quadratic bending elements of every vertex that has a triangle (VertexBendElement).
// Per triangle: the cotangent weights ½·cot(opposite angle) of its edges and Meyer's mixed
// areas; per boundary edge (one triangle): (|e|/2)·∇φ_q·n̄ for each corner q of its triangle,
// added to both ends' rows (n̄ the outward conormal in the rest triangle's plane).
std::vector<VertexBendElement> make_vertex_bends(const Eigen::MatrixX3d& rest,
                                                 const Eigen::MatrixX3i& faces,
                                                 BendRestShape bend_rest,
                                                 const std::vector<char>& wanted) {
  const int n = static_cast<int>(rest.rows());
  // An element reads the faces around its vertex (its row, area, fan and boundary flux) and the
  // faces around its one-ring (the two-ring's points). Only those faces are visited, in the same
  // order as for the whole mesh, so a wanted element is the same bits either way.
  const bool all = wanted.empty();
  const auto want = [&](int v) { return all || wanted[static_cast<std::size_t>(v)] != 0; };
  std::vector<char> near(all ? 0 : static_cast<std::size_t>(n), 0);  // wanted or in a one-ring
  std::vector<char> face_near(all ? 0 : static_cast<std::size_t>(faces.rows()), 0);
  if (!all) {
    for (Eigen::Index f = 0; f < faces.rows(); ++f)
      if (want(faces(f, 0)) || want(faces(f, 1)) || want(faces(f, 2)))
        for (int k = 0; k < 3; ++k) near[static_cast<std::size_t>(faces(f, k))] = 1;
    for (Eigen::Index f = 0; f < faces.rows(); ++f)
      face_near[static_cast<std::size_t>(f)] = near[static_cast<std::size_t>(faces(f, 0))] ||
                                               near[static_cast<std::size_t>(faces(f, 1))] ||
                                               near[static_cast<std::size_t>(faces(f, 2))];
  }
  const auto visit = [&](Eigen::Index f) {
    return all || face_near[static_cast<std::size_t>(f)] != 0;
  };
  const auto wanted_face = [&](Eigen::Index f) {
    return all || want(faces(f, 0)) || want(faces(f, 1)) || want(faces(f, 2));
  };
  std::vector<std::vector<std::pair<int, double>>> row(static_cast<std::size_t>(n));
  std::vector<double> area(static_cast<std::size_t>(n), 0.0);
  const auto add = [&](int i, int j, double w) {
    if (want(i)) row[static_cast<std::size_t>(i)].emplace_back(j, w);
  };
  // Edges (low, high) with the face and corner of the apex opposite, to find boundary edges.
  struct FaceEdge {
    int low, high, face, apex;
  };
  std::vector<FaceEdge> edges;
  edges.reserve(static_cast<std::size_t>(3 * faces.rows()));
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    if (!wanted_face(f)) continue;
    const std::array<int, 3> v{faces(f, 0), faces(f, 1), faces(f, 2)};
    std::array<Vector3d, 3> p;
    for (int k = 0; k < 3; ++k) p[k] = rest.row(v[k]);
    const double twice_area = (p[1] - p[0]).cross(p[2] - p[0]).norm();
    double cot[3];
    bool obtuse[3];
    for (int k = 0; k < 3; ++k) {
      const Vector3d a = p[(k + 1) % 3] - p[k], b = p[(k + 2) % 3] - p[k];
      cot[k] = a.dot(b) / twice_area;
      obtuse[k] = a.dot(b) < -1e-9 * a.norm() * b.norm();  // right angles stay Voronoi
    }
    for (int k = 0; k < 3; ++k) {
      const int a = v[(k + 1) % 3], b = v[(k + 2) % 3];  // the edge opposite corner k
      const double w = 0.5 * cot[k];
      add(a, b, w), add(a, a, -w), add(b, a, w), add(b, b, -w);
      edges.push_back({std::min(a, b), std::max(a, b), static_cast<int>(f), k});
    }
    const bool any_obtuse = obtuse[0] || obtuse[1] || obtuse[2];
    for (int k = 0; k < 3; ++k) {
      double a_k;
      if (!any_obtuse) {
        a_k = 0.125 * ((p[(k + 1) % 3] - p[k]).squaredNorm() * cot[(k + 2) % 3] +
                       (p[(k + 2) % 3] - p[k]).squaredNorm() * cot[(k + 1) % 3]);
      } else {
        a_k = 0.5 * twice_area * (obtuse[k] ? 0.5 : 0.25);  // Meyer et al.: A/2, A/4
      }
      area[static_cast<std::size_t>(v[k])] += a_k;
    }
  }
  std::sort(edges.begin(), edges.end(), [](const FaceEdge& a, const FaceEdge& b) {
    return std::tie(a.low, a.high, a.face) < std::tie(b.low, b.high, b.face);
  });
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const bool single =
        (e == 0 || edges[e - 1].low != edges[e].low || edges[e - 1].high != edges[e].high) &&
        (e + 1 == edges.size() || edges[e + 1].low != edges[e].low ||
         edges[e + 1].high != edges[e].high);
    if (!single) continue;
    const int f = edges[e].face, k = edges[e].apex;
    const std::array<int, 3> v{faces(f, 0), faces(f, 1), faces(f, 2)};
    std::array<Vector3d, 3> p;
    for (int c = 0; c < 3; ++c) p[c] = rest.row(v[c]);
    const Vector3d normal = (p[1] - p[0]).cross(p[2] - p[0]);
    const double twice_area = normal.norm();
    const Vector3d unit_normal = normal / twice_area;
    const Vector3d edge = p[(k + 2) % 3] - p[(k + 1) % 3];
    // Outward conormal: in the plane, perpendicular to the edge, away from the apex.
    Vector3d conormal = edge.cross(unit_normal).normalized();
    if (conormal.dot(p[(k + 1) % 3] - p[k]) < 0.0) conormal = -conormal;
    for (int q = 0; q < 3; ++q) {
      // ∇φ_q = n̂ × (p_{q+2} − p_{q+1}) / (2A) for the counter-clockwise corners.
      const Vector3d gradient = unit_normal.cross(p[(q + 2) % 3] - p[(q + 1) % 3]) / twice_area;
      const double w = 0.5 * edge.norm() * gradient.dot(conormal);
      add(v[(k + 1) % 3], v[q], w);
      add(v[(k + 2) % 3], v[q], w);
    }
  }
  // Per vertex, three rows: row 0, the Laplacian, is the cotangent row, made exact for
  // quadratics (Σ_j w_j·q(p_j) = A_v·Δq for q = 1, u, v, u², uv, v², u and v in the rest tangent
  // plane) by its least-norm change; rows 1 and 2 are A_v·(x_uu − x_vv) and A_v·x_uv of the
  // least-squares quadratic. Each row uses the smallest neighbourhood that determines it: the
  // one-ring, else the one-ring with the nearest points of the two-ring (the tangent frame is
  // aligned with an edge, so on the 4-8 mesh a degree-4 vertex's one-ring determines
  // x_uu − x_vv, and its twist takes the four diagonal points, the usual cross stencil); a row
  // the one-ring determines is read part by part from its nearest symmetric shells where it and
  // its neighbours have them (symmetric_shells, functional_row).
  // Every point an element reads couples its vertex to every other in the system matrix, so
  // the nearest points also keep the matrix narrow: on the 4-8 mesh 25 blocks a row instead of
  // the whole two-ring's 72.
  // Narrow rows matter where the curvature jumps (at a clamp). The cotangent row needs the
  // change where it is not consistent: on irregular meshes (whose cotangent Laplacian does not
  // converge pointwise), and at boundary vertices, whose flux uses one triangle's gradient, half
  // a cell inside. On the 4-8 and equilateral meshes the interior Laplacian rows are the 5- and
  // 7-point stencils, which also hold the grid-scale zigzags least-squares rows cannot see.
  std::vector<std::vector<int>> ring(static_cast<std::size_t>(n));
  std::vector<Vector3d> normal(static_cast<std::size_t>(n), Vector3d::Zero());
  std::vector<std::vector<std::array<int, 2>>> fans(static_cast<std::size_t>(n));
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    if (!visit(f)) continue;
    const Vector3d p0 = rest.row(faces(f, 0));
    const Vector3d a =
        (Vector3d(rest.row(faces(f, 1))) - p0).cross(Vector3d(rest.row(faces(f, 2))) - p0);
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<std::size_t>(faces(f, k));
      if (!all && !near[v]) continue;
      if (want(faces(f, k))) {
        normal[v] += a;
        fans[v].push_back({faces(f, (k + 1) % 3), faces(f, (k + 2) % 3)});
      }
      for (int l = 0; l < 3; ++l)
        if (k != l) ring[v].push_back(faces(f, l));
    }
  }
  for (auto& r : ring) {
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
  }
  // Whether a vertex's one-ring has a symmetric part (symmetric_shells), memoised. The split of
  // the curvature rows by shells cancels the coupling of smooth bends to the sublattice mode only
  // between vertices that both read the mode with central differences: on the 4-8 mesh with
  // w × h cells both kinds of vertices do (the degree-4 ones by their nearer pair), but a vertex
  // next to a free edge or to the centre of a rectangle split into four (whose four neighbours
  // are equidistant) does not, and splitting its neighbours' rows alone made the rhombic mesh
  // softer (docs/simulator.md, "Elongated cells"). Only one-ring points of wanted vertices are
  // asked, whose rings are complete also when only some elements are made.
  std::vector<signed char> shells_known(static_cast<std::size_t>(n), -1);
  const auto has_shells = [&](int j) {
    signed char& known = shells_known[static_cast<std::size_t>(j)];
    if (known < 0)
      known = symmetric_shells(rest, j, ring[static_cast<std::size_t>(j)]).empty() ? 0 : 1;
    return known == 1;
  };
  std::vector<VertexBendElement> elements;
  elements.reserve(static_cast<std::size_t>(n));
  for (int v = 0; v < n; ++v) {
    if (!want(v)) continue;
    auto& entries = row[static_cast<std::size_t>(v)];
    if (entries.empty() || !(area[static_cast<std::size_t>(v)] > 0.0)) continue;
    const double vertex_area = area[static_cast<std::size_t>(v)];
    const Vector3d unit = normal[static_cast<std::size_t>(v)].normalized();
    const Vector3d centre = rest.row(v);
    const std::vector<int>& one_ring = ring[static_cast<std::size_t>(v)];
    Vector3d e1 = Vector3d(rest.row(one_ring.front())) - centre;
    e1 = (e1 - e1.dot(unit) * unit).normalized();
    if (!e1.allFinite()) e1 = unit.unitOrthogonal();
    const Vector3d e2 = unit.cross(e1);
    // The neighbourhoods, each sorted: the vertex and its one-ring, then with the two-ring's
    // other points added by distance from the vertex, those at the same distance together (so a
    // symmetric mesh keeps symmetric rows), from kFewestFitPoints on; the last is the whole
    // two-ring.
    std::vector<int> points = one_ring;
    points.push_back(v);
    for (int j : one_ring)
      points.insert(points.end(), ring[static_cast<std::size_t>(j)].begin(),
                    ring[static_cast<std::size_t>(j)].end());
    std::sort(points.begin(), points.end());
    points.erase(std::unique(points.begin(), points.end()), points.end());
    const int count = static_cast<int>(points.size());
    const auto local = [&](int j) {
      return static_cast<int>(std::lower_bound(points.begin(), points.end(), j) - points.begin());
    };
    const auto distance2 = [&](int j) { return (Vector3d(rest.row(j)) - centre).squaredNorm(); };
    double radius2 = 0.0;
    for (int j : points) radius2 = std::max(radius2, distance2(j));
    const double radius = std::sqrt(radius2);
    // Before the one-ring: its centrally symmetric parts, nearest shells first (see
    // symmetric_shells); `ring_hood` is the one-ring's index among the neighbourhoods.
    // Only where every neighbour has such a part too, so that neighbours read a grid-scale mode
    // alike (see has_shells).
    std::vector<std::vector<int>> hood = symmetric_shells(rest, v, one_ring);
    if (!std::all_of(one_ring.begin(), one_ring.end(), has_shells)) hood.clear();
    const std::size_t ring_hood = hood.size();
    hood.push_back(one_ring);
    hood[ring_hood].push_back(v);
    std::sort(hood[ring_hood].begin(), hood[ring_hood].end());
    std::vector<std::pair<double, int>> farther;
    for (int j : points)
      if (!std::binary_search(hood[ring_hood].begin(), hood[ring_hood].end(), j))
        farther.emplace_back(distance2(j), j);
    std::sort(farther.begin(), farther.end());
    std::vector<char> nested(hood.size(), 1);  // whether a neighbourhood is split into (below)
    std::vector<int> next = hood[ring_hood];
    for (std::size_t first = 0; first < farther.size();) {
      std::size_t last = first + 1;
      while (last < farther.size() && farther[last].first - farther[first].first <= 1e-9 * radius2)
        ++last;
      for (std::size_t j = first; j < last; ++j) next.push_back(farther[j].second);
      if (next.size() >= kFewestFitPoints || last == farther.size()) {
        hood.push_back(next);
        std::sort(hood.back().begin(), hood.back().end());
        nested.push_back(0);
      }
      first = last;
    }
    // The quadratics at the points of a neighbourhood (u and v in units of the two-ring's radius)
    // and their pseudo-inverse (6 × #points; rank-truncated).
    struct Fit {
      Eigen::MatrixXd basis, inverse;
      Eigen::MatrixXd null;  // coefficient directions no data determines (6 × k)
    };
    std::vector<Fit> fits(hood.size());
    for (std::size_t h = 0; h < hood.size(); ++h) {
      const int size = static_cast<int>(hood[h].size());
      Fit& fit = fits[h];
      fit.basis.resize(size, 6);
      for (int j = 0; j < size; ++j) {
        const Vector3d d =
            (Vector3d(rest.row(hood[h][static_cast<std::size_t>(j)])) - centre) / radius;
        const double u = d.dot(e1), w = d.dot(e2);
        fit.basis.row(j) << 1.0, u, w, u * u, u * w, w * w;
      }
      // B (#points × 6) = Q·R·Pᵀ by a column-pivoted QR, then the 6 × 6 R = U·Σ·Vᵀ by a
      // fixed-size Jacobi SVD: B = (Q·U)·Σ·(P·V)ᵀ, the thin SVD JacobiSVD would make of B
      // itself, without its heap-sized work (most of an element's cost, made on every change).
      Eigen::Matrix<double, 6, 6> v_b;
      Eigen::Matrix<double, 6, 1> sigma;
      int rank = 0;
      if (size >= 6) {
        const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(fit.basis);
        const Eigen::Matrix<double, 6, 6> r =
            qr.matrixQR().topRows<6>().triangularView<Eigen::Upper>();
        // With Businger-Golub pivoting σ_min ≥ 3·|r₅₅|/√(4⁶ + 35) > |r₅₅|/22 and
        // σ_max ≤ √6·|r₀₀|, so |r₅₅| ≥ 1e-4·|r₀₀| means σ_min/σ_max > 1e-6, well above the rank
        // cut: B has full rank and B⁺ = P·R⁻¹·Qᵀ, no SVD needed (the common case: a
        // neighbourhood of 6 or more points in general position).
        Eigen::Matrix<double, 6, 6> upper_left;  // U_r·Σ_r⁻¹·(P·V)_rᵀ, or (P·R⁻¹)ᵀ
        if (std::abs(r(5, 5)) >= 1e-4 * std::abs(r(0, 0)) && r(0, 0) != 0.0) {
          rank = 6;
          const Eigen::Matrix<double, 6, 6> r_inverse =
              r.triangularView<Eigen::Upper>().solve(Eigen::Matrix<double, 6, 6>::Identity());
          upper_left = (qr.colsPermutation() * r_inverse).transpose();
          v_b.setIdentity();  // only its rightCols(0) is read
        } else {
          const Eigen::JacobiSVD<Eigen::Matrix<double, 6, 6>> svd(
              r, Eigen::ComputeFullU | Eigen::ComputeFullV);
          sigma = svd.singularValues();
          while (rank < 6 && sigma(rank) > 1e-8 * sigma(0)) ++rank;
          v_b = qr.colsPermutation() * svd.matrixV();
          upper_left.noalias() = svd.matrixU().leftCols(rank) *
                                 sigma.head(rank).cwiseInverse().asDiagonal() *
                                 v_b.leftCols(rank).transpose();
        }
        // B⁺ = P·R⁻¹·Qᵀ = (P·V)_r·Σ_r⁻¹·(Q·U)_rᵀ, made as its transpose Q·[upper_left; 0].
        Eigen::MatrixXd transposed = Eigen::MatrixXd::Zero(size, 6);
        transposed.topRows<6>() = upper_left;
        transposed.applyOnTheLeft(qr.householderQ());
        fit.inverse = transposed.transpose();
      } else {
        const Eigen::JacobiSVD<Eigen::MatrixXd> svd(fit.basis,
                                                    Eigen::ComputeThinU | Eigen::ComputeFullV);
        sigma.setZero();
        sigma.head(svd.singularValues().size()) = svd.singularValues();
        while (rank < 6 && sigma(rank) > 1e-8 * sigma(0)) ++rank;
        v_b = svd.matrixV();
        fit.inverse.noalias() = svd.matrixV().leftCols(rank) *
                                sigma.head(rank).cwiseInverse().asDiagonal() *
                                svd.matrixU().leftCols(rank).transpose();
      }
      fit.null = v_b.rightCols(6 - rank);
    }
    // Row of a functional c ↦ f·c of the fitted coefficients (f zero on 1, u, v): from the
    // smallest neighbourhood that determines it; false if none does. Where that is the one-ring
    // or a symmetric part of it, f is split into the parts each nested neighbourhood adds to
    // what the smaller ones determine (orthogonal in the Frobenius metric of the Hessian, which
    // no choice of tangent frame changes), and each part is read from the smallest one: a
    // curvature the nearest symmetric shell determines is its central difference, as on the
    // vertex's neighbours, whatever the frame (docs/simulator.md, "Elongated cells").
    // Metric on (c₃, c₄, c₅) = (½x_uu, x_uv, ½x_vv): F:G with F = [[f₃/2, f₄/2], [f₄/2, f₅/2]].
    const Eigen::Vector3d metric(0.25, 0.5, 0.25);
    const auto determined = [&](std::size_t h, const Eigen::Matrix<double, 6, 1>& f) {
      const Fit& fit = fits[h];
      return fit.null.cols() == 0 || (fit.null.transpose() * f).norm() <= 1e-8 * f.norm();
    };
    // The metric-orthogonal projector onto the quadratic functionals neighbourhood h determines.
    const auto projector = [&](std::size_t h) {
      const Fit& fit = fits[h];
      if (fit.null.cols() == 0) return Eigen::Matrix3d::Identity().eval();
      const Eigen::MatrixXd constraints = fit.null.bottomRows(3).transpose();  // k × 3
      const Eigen::JacobiSVD<Eigen::MatrixXd> svd(constraints, Eigen::ComputeFullV);
      int rank = 0;
      const Eigen::VectorXd& sigma = svd.singularValues();
      while (rank < sigma.size() && sigma(rank) > 1e-8 * std::max(sigma(0), 1.0)) ++rank;
      Eigen::MatrixXd basis = svd.matrixV().rightCols(3 - rank);  // 3 × m, spans the determined
      // Orthonormal in the metric: basis·L⁻ᵀ (3 × m) with L·Lᵀ = basisᵀ·diag(metric)·basis.
      Eigen::Matrix3d p = Eigen::Matrix3d::Zero();
      if (basis.cols() == 0) return p;
      const Eigen::MatrixXd gram = basis.transpose() * metric.asDiagonal() * basis;
      const Eigen::LLT<Eigen::MatrixXd> llt(gram);
      const Eigen::MatrixXd orthonormal = llt.matrixL().solve(basis.transpose()).transpose();
      p = orthonormal * orthonormal.transpose() * metric.asDiagonal();
      return p;
    };
    const auto functional_row = [&](const Eigen::Matrix<double, 6, 1>& f, Eigen::RowVectorXd& out) {
      for (std::size_t h = 0; h < hood.size(); ++h) {
        if (!determined(h, f)) continue;
        out = Eigen::RowVectorXd::Zero(count);
        const auto add_part = [&](std::size_t k, const Eigen::Matrix<double, 6, 1>& part) {
          const Eigen::RowVectorXd values = part.transpose() * fits[k].inverse;
          for (std::size_t j = 0; j < hood[k].size(); ++j)
            out(local(hood[k][j])) += values(static_cast<Eigen::Index>(j));
        };
        if (!nested[h]) {
          add_part(h, f);
          return true;
        }
        Eigen::Matrix3d previous = Eigen::Matrix3d::Zero();
        for (std::size_t k = 0; k <= h; ++k) {
          if (!nested[k]) continue;
          const Eigen::Matrix3d current = k == h ? Eigen::Matrix3d::Identity() : projector(k);
          Eigen::Matrix<double, 6, 1> part = Eigen::Matrix<double, 6, 1>::Zero();
          part.tail<3>() = (current - previous) * f.tail<3>();
          if (part.norm() > 1e-12 * f.norm()) add_part(k, part);
          previous = current;
        }
        return true;
      }
      return false;
    };
    VertexBendElement element;
    element.vertices = points;
    element.centre = local(v);
    element.inverse_area = 1.0 / vertex_area;
    element.rows = Eigen::Matrix<double, 3, Eigen::Dynamic>::Zero(3, count);
    for (const auto& [j, w] : entries) element.rows(0, local(j)) += w;
    const double scale = vertex_area / radius2;  // A_v per (unit of the fit's coordinates)²
    {
      // The least-norm change of the Laplacian row that makes it exact, on the smallest
      // neighbourhood where one exists.
      Eigen::Matrix<double, 6, 1> target;
      target << 0.0, 0.0, 0.0, 2.0 * scale, 0.0, 2.0 * scale;
      for (std::size_t h = ring_hood; h < hood.size(); ++h) {
        const Fit& fit = fits[h];
        Eigen::VectorXd current(hood[h].size());
        for (std::size_t j = 0; j < hood[h].size(); ++j)
          current(static_cast<Eigen::Index>(j)) = element.rows(0, local(hood[h][j]));
        const Eigen::Matrix<double, 6, 1> defect = target - fit.basis.transpose() * current;
        if (defect.norm() <= 1e-9 * target.norm()) break;
        // δ = B·c with Bᵀ·B·c = defect: δ = (B⁺)ᵀ·defect when defect is in range(Bᵀ).
        if (fit.null.cols() > 0 && (fit.null.transpose() * defect).norm() > 1e-8 * target.norm())
          continue;
        const Eigen::VectorXd change = fit.inverse.transpose() * defect;
        for (std::size_t j = 0; j < hood[h].size(); ++j)
          element.rows(0, local(hood[h][j])) += change(static_cast<Eigen::Index>(j));
        break;
      }
    }
    Eigen::RowVectorXd out;
    Eigen::Matrix<double, 6, 1> f;
    f << 0.0, 0.0, 0.0, 2.0 * scale, 0.0, -2.0 * scale;  // x_uu − x_vv = 2c₃ − 2c₅
    if (functional_row(f, out)) element.rows.row(1) = out;
    f << 0.0, 0.0, 0.0, 0.0, scale, 0.0;  // x_uv = c₄
    if (functional_row(f, out)) element.rows.row(2) = out;
    if (bend_rest == BendRestShape::designed) {
      // Each row's rest vector b̄ = Σ w_j x̄_j: its tangential part (mesh irregularity, and the
      // tangent plane's own curvature terms) is written as a least-norm combination
      // Σ α_j (x̄_j − x̄_v) of the points the rows already read (no wider matrix) and moved
      // into the row; the rest, along N̄, becomes rest_normal·N(x).
      Vector3d area_vector = Vector3d::Zero();
      for (const auto& [b, c] : fans[static_cast<std::size_t>(v)])
        area_vector += 0.5 * (Vector3d(rest.row(b)) - centre).cross(Vector3d(rest.row(c)) - centre);
      Eigen::MatrixX3d offsets(count, 3);
      double reach2 = 0.0;
      for (int j = 0; j < count; ++j) {
        offsets.row(j) = rest.row(points[static_cast<std::size_t>(j)]) - centre.transpose();
        reach2 = std::max(reach2, offsets.row(j).squaredNorm());
      }
      const Eigen::Matrix<double, 3, 3> rest_vectors = element.rows * offsets;  // row k: b̄_k
      if (rest_vectors.norm() > 1e-9 * std::sqrt(reach2) && area_vector.norm() > 0.0) {
        const Vector3d an = area_vector.normalized();
        const Vector3d t1 = an.unitOrthogonal(), t2 = an.cross(t1);
        Eigen::MatrixXd tangent(2, count);
        const std::vector<char> read = read_columns(element);
        for (int j = 0; j < count; ++j)
          if (read[static_cast<std::size_t>(j)])
            tangent.col(j) << offsets.row(j).dot(t1), offsets.row(j).dot(t2);
          else
            tangent.col(j).setZero();
        const Eigen::Matrix2d tgram = tangent * tangent.transpose();
        const bool spans = std::abs(tgram.determinant()) > 1e-12 * tgram.squaredNorm();
        for (int k = 0; k < 3; ++k) {
          const Vector3d b = rest_vectors.row(k).transpose();
          if (spans) {
            const Eigen::VectorXd alpha =
                tangent.transpose() * tgram.inverse() * Eigen::Vector2d(b.dot(t1), b.dot(t2));
            element.rows.row(k) -= alpha.transpose();
            element.rows(k, element.centre) += alpha.sum();
          }
          const Vector3d corrected = (element.rows.row(k) * offsets).transpose();
          element.rest_normal(k) = corrected.dot(area_vector) / area_vector.squaredNorm();
        }
        for (const auto& [b, c] : fans[static_cast<std::size_t>(v)])
          element.fan.push_back({local(b), local(c)});
      }
    }
    prune_columns(element);
    element.blocks.assign(element.vertices.size() * element.vertices.size(), 0);
    elements.push_back(std::move(element));
  }
  return elements;
}

}  // namespace sd::sim::detail
