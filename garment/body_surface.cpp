// The only translation unit of sd_garment that includes CGAL (it takes ~20 s to compile).
#include "garment/body_surface.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <mutex>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

namespace sd::garment {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Ray = Kernel::Ray_3;
using Iterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, Iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

Point to_cgal(const Eigen::Vector3d& p) {
  return {p.x(), p.y(), p.z()};
}
Eigen::Vector3d to_eigen(const Point& p) {
  return {p.x(), p.y(), p.z()};
}

// The point of triangle abc nearest to p (Ericson, "Real-Time Collision Detection", 5.1.5:
// Voronoi regions of the vertices, then the edges, else the face), in about 30 flops.
Eigen::Vector3d nearest_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                    const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0)
    return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

// A bounding-volume hierarchy over the body's triangles for closest-point queries: median
// splits along the longest axis down to kLeafSize triangles, nodes in depth-first order. The
// query starts from a hint face's distance (the previous answer nearby), visits the nearer
// child first and skips every box farther than the best distance so far, so it is exact. It
// replaces CGAL's tree for these queries: CGAL's traversal and its generic point-triangle
// projection were 58 % of a garment's meshing time (docs/benchmarks.md). Where the nearest
// point is not unique (a tie, below) CGAL's tree still answers: garments mesh as before.
class ClosestPointTree {
 public:
  static constexpr int kLeafSize = 2;

  explicit ClosestPointTree(const meshing::TriMesh& mesh) : mesh_(mesh) {
    const auto nf = static_cast<int>(mesh.face_count());
    order_.resize(static_cast<size_t>(nf));
    std::iota(order_.begin(), order_.end(), 0);
    centroids_.resize(static_cast<size_t>(nf));
    for (int f = 0; f < nf; ++f)
      centroids_[static_cast<size_t>(f)] = (corner(f, 0) + corner(f, 1) + corner(f, 2)) / 3;
    nodes_.reserve(static_cast<size_t>(2 * nf / kLeafSize + 2));
    build(0, nf);
    // The triangles in tree order, so that a leaf reads one contiguous block (the mesh's
    // vertex matrix is column-major and indexed through the faces: three scattered reads per
    // corner), with each one's plane.
    packed_.resize(static_cast<size_t>(nf));
    for (int k = 0; k < nf; ++k) {
      const int f = order_[static_cast<size_t>(k)];
      Packed& t = packed_[static_cast<size_t>(k)];
      t.a = corner(f, 0);
      t.b = corner(f, 1);
      t.c = corner(f, 2);
      t.normal = (t.b - t.a).cross(t.c - t.a);
      const double length = t.normal.norm();
      t.normal = length > 0 ? Eigen::Vector3d(t.normal / length) : Eigen::Vector3d::Zero();
      t.plane = t.normal.dot(t.a);
    }
  }

  // The nearest point's face and position; `hint` (a face, or -1) bounds the search first.
  // `tied` is set when another triangle comes within kTie of the same distance: the nearest
  // point lies on an edge or a corner the triangles share, or is not unique at all (a point on
  // a symmetric body's mirror plane, a centre seam between the legs of the Collada human, is
  // as near to both sides). Which triangle wins is then a matter of traversal order and
  // rounding, and the caller lets CGAL's tree decide, so that every answer is CGAL's to the
  // bit (docs/benchmarks.md: a drape with self-collision amplifies a difference of 1e-16 m).
  struct Found {
    int face = -1;
    Eigen::Vector3d point = Eigen::Vector3d::Zero();
    bool tied = false;
    // Every triangle within kTie of the nearest distance (the nearest first), when they all
    // fit; `overflow` otherwise.
    std::array<int, 8> near_faces{};
    size_t near_count = 0;
    bool overflow = false;
  };
  Found closest(const Eigen::Vector3d& p, int hint) const {
    Found found;
    double best = std::numeric_limits<double>::infinity();  // squared distance
    double bound = best;  // (√best + kTie)²: boxes farther than this cannot hold a rival
    // Candidates within `bound` when they were seen, sorted out at the end; more than the
    // array holds counts as a tie (CGAL decides).
    std::array<std::pair<double, int>, 8> near;  // squared distance, face
    size_t near_count = 0;
    bool overflow = false;
    const auto consider = [&](int f, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                              const Eigen::Vector3d& c) {
      const Eigen::Vector3d q = nearest_on_triangle(p, a, b, c);
      const double d = (q - p).squaredNorm();
      if (!(d <= bound)) return;
      if (near_count < near.size())
        near[near_count++] = {d, f};
      else
        overflow = true;
      if (d < best) {
        best = d;
        found.face = f;
        found.point = q;
        bound = std::pow(std::sqrt(best) + kTie, 2);
      }
    };
    if (hint >= 0 && hint < static_cast<int>(order_.size()))
      consider(hint, corner(hint, 0), corner(hint, 1), corner(hint, 2));
    std::array<int, 64> stack;
    int top = 0;
    stack[static_cast<size_t>(top++)] = 0;
    while (top > 0) {
      const Node& node = nodes_[static_cast<size_t>(stack[static_cast<size_t>(--top)])];
      if (box_distance(node, p) > bound) continue;
      if (node.count > 0) {
        for (int k = node.first; k < node.first + node.count; ++k) {
          const Packed& t = packed_[static_cast<size_t>(k)];
          // The distance from the triangle's plane is a lower bound of the distance from
          // the triangle: most of a leaf's triangles are passed over on it.
          const double plane = t.normal.dot(p) - t.plane;
          if (plane * plane > bound) continue;
          consider(order_[static_cast<size_t>(k)], t.a, t.b, t.c);
        }
        continue;
      }
      const int left = node.first, right = node.second;
      const double dl = box_distance(nodes_[static_cast<size_t>(left)], p);
      const double dr = box_distance(nodes_[static_cast<size_t>(right)], p);
      // The nearer child is popped first.
      if (dl <= dr) {
        if (dr <= bound) stack[static_cast<size_t>(top++)] = right;
        if (dl <= bound) stack[static_cast<size_t>(top++)] = left;
      } else {
        if (dl <= bound) stack[static_cast<size_t>(top++)] = left;
        if (dr <= bound) stack[static_cast<size_t>(top++)] = right;
      }
    }
    found.tied = overflow;
    found.overflow = overflow;
    if (found.face >= 0) found.near_faces[found.near_count++] = found.face;
    for (size_t k = 0; k < near_count; ++k) {
      const int f = near[k].second;
      if (!(near[k].first <= bound) || f == found.face) continue;
      found.tied = true;
      if (std::find(found.near_faces.begin(), found.near_faces.begin() + found.near_count, f) ==
          found.near_faces.begin() + found.near_count)
        found.near_faces[found.near_count++] = f;  // fits: near_count ≤ near.size()
    }
    return found;
  }

  // Distances within kTie (m) are ties: far above the rounding of either computation (~1e-15 m
  // on a body of 2 m), so that a triangle this tree finds alone is the one CGAL's finds.
  static constexpr double kTie = 1e-10;

 private:
  struct Node {
    Eigen::Vector3d min, max;
    int first = 0, count = 0;  // a leaf: order_[first, first + count)
    int second = 0;            // an inner node: children `first` and `second`
  };

  Eigen::Vector3d corner(int f, int k) const {
    return mesh_.vertices.row(mesh_.faces(f, k)).transpose();
  }

  static double box_distance(const Node& node, const Eigen::Vector3d& p) {
    return (p - p.cwiseMax(node.min).cwiseMin(node.max)).squaredNorm();
  }

  int build(int begin, int end) {
    const int index = static_cast<int>(nodes_.size());
    nodes_.emplace_back();
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d hi = -lo;
    for (int k = begin; k < end; ++k)
      for (int c = 0; c < 3; ++c) {
        const Eigen::Vector3d v = corner(order_[static_cast<size_t>(k)], c);
        lo = lo.cwiseMin(v);
        hi = hi.cwiseMax(v);
      }
    nodes_[static_cast<size_t>(index)].min = lo;
    nodes_[static_cast<size_t>(index)].max = hi;
    if (end - begin <= kLeafSize) {
      nodes_[static_cast<size_t>(index)].first = begin;
      nodes_[static_cast<size_t>(index)].count = end - begin;
      return index;
    }
    int axis = 0;
    (hi - lo).maxCoeff(&axis);
    const int middle = begin + (end - begin) / 2;
    std::nth_element(order_.begin() + begin, order_.begin() + middle, order_.begin() + end,
                     [&](int a, int b) {
                       return centroids_[static_cast<size_t>(a)][axis] <
                              centroids_[static_cast<size_t>(b)][axis];
                     });
    const int left = build(begin, middle);
    const int right = build(middle, end);
    nodes_[static_cast<size_t>(index)].first = left;
    nodes_[static_cast<size_t>(index)].second = right;
    return index;
  }

  struct Packed {
    Eigen::Vector3d a, b, c;
    Eigen::Vector3d normal;  // unit (zero for a degenerate triangle)
    double plane = 0;        // normal · a
  };

  const meshing::TriMesh& mesh_;
  std::vector<Packed> packed_;  // the triangles in tree order: packed_[k] is face order_[k]
  std::vector<int> order_;
  std::vector<Eigen::Vector3d> centroids_;
  std::vector<Node> nodes_;
};

}  // namespace

struct BodySurface::Impl {
  meshing::TriMesh mesh;
  meshing::BoundingBox box;
  Eigen::MatrixX3d normals;                   // #V by 3, unit
  std::vector<Triangle> triangles;            // #F, same order as mesh.faces
  Tree tree;                                  // ray casts
  std::unique_ptr<ClosestPointTree> nearest;  // closest-point queries (over `mesh`)
  std::once_flag landmarks_once;              // landmarks(): found on the first call
  std::optional<BodyLandmarks> landmarks;

  // Smooth outward normal at `p` inside face f (barycentric blend of vertex normals).
  Eigen::Vector3d normal_at(int f, const Eigen::Vector3d& p) const {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.faces(f, 0)).transpose();
    const Eigen::Vector3d b = mesh.vertices.row(mesh.faces(f, 1)).transpose();
    const Eigen::Vector3d c = mesh.vertices.row(mesh.faces(f, 2)).transpose();
    const Eigen::Vector3d n = (b - a).cross(c - a);
    const double area2 = n.squaredNorm();
    Eigen::Vector3d blended = n;
    if (area2 > 0) {
      const double wa = (c - b).cross(p - b).dot(n) / area2;
      const double wb = (a - c).cross(p - c).dot(n) / area2;
      const double wc = 1.0 - wa - wb;
      blended = wa * normals.row(mesh.faces(f, 0)).transpose() +
                wb * normals.row(mesh.faces(f, 1)).transpose() +
                wc * normals.row(mesh.faces(f, 2)).transpose();
    }
    if (blended.squaredNorm() < 1e-20) blended = n;
    return blended.normalized();
  }

  // The closest point to p, the search bounded first by face `hint` (or not, when -1) at
  // the point `hint_point` on it (for CGAL's tree, which answers ties).
  SurfacePoint answer(const Eigen::Vector3d& p, int hint,
                      const Eigen::Vector3d& hint_point = Eigen::Vector3d::Zero()) const;
};

BodySurface::BodySurface(const meshing::TriMesh& mesh) : impl_(std::make_unique<Impl>()) {
  if (mesh.face_count() == 0) throw std::invalid_argument("the body mesh has no triangles");
  impl_->mesh = mesh;
  impl_->box = meshing::bounding_box(mesh);
  impl_->normals = meshing::vertex_normals(mesh);
  impl_->triangles.reserve(static_cast<size_t>(mesh.face_count()));
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f)
    impl_->triangles.emplace_back(to_cgal(mesh.vertices.row(mesh.faces(f, 0)).transpose()),
                                  to_cgal(mesh.vertices.row(mesh.faces(f, 1)).transpose()),
                                  to_cgal(mesh.vertices.row(mesh.faces(f, 2)).transpose()));
  impl_->tree.insert(impl_->triangles.cbegin(), impl_->triangles.cend());
  impl_->tree.build();
  // Ties are decided by CGAL exactly as before the own tree, unhinted queries included (their
  // first bound comes from this search tree).
  impl_->tree.accelerate_distance_queries();
  impl_->nearest = std::make_unique<ClosestPointTree>(impl_->mesh);
}

BodySurface::~BodySurface() = default;
BodySurface::BodySurface(BodySurface&&) noexcept = default;
BodySurface& BodySurface::operator=(BodySurface&&) noexcept = default;

SurfacePoint BodySurface::closest_point(const Eigen::Vector3d& p) const {
  return impl_->answer(p, -1);
}

SurfacePoint BodySurface::closest_point(const Eigen::Vector3d& p, const SurfacePoint& near) const {
  return impl_->answer(p, near.face, near.position);
}

SurfacePoint BodySurface::Impl::answer(const Eigen::Vector3d& p, int hint,
                                       const Eigen::Vector3d& hint_point) const {
  const ClosestPointTree::Found found = nearest->closest(p, hint);
  int face = found.face;
  Eigen::Vector3d point = found.point;
  // The answer of CGAL's tree, to the bit (the garments mesh as they did with it; a drape with
  // self-collision amplifies a difference of 1e-16 m): its point on a triangle is CGAL's
  // projection (Ericson's formula differs from it by rounding), and among the triangles as
  // near as the nearest (within kTie: the nearest point on an edge or a corner they share, or
  // equally near points on a symmetric body's mirror plane) the tree keeps the last one it
  // visits that is not farther than the one it holds, starting from the hint. So where one
  // projection is strictly nearest by CGAL's own comparison, the tree ends on it, or on the
  // hint, when that is nearer still (a hint a rounding error away on the same triangle);
  // otherwise the order of its traversal decides and the tree itself is asked.
  bool decided = false;
  const Point query = to_cgal(p);
  if (face >= 0 && !found.overflow && (hint >= 0 || found.near_count == 1)) {
    // Without a hint CGAL starts from a point of its own search tree, which can be as near as
    // the nearest only when several triangles are (a corner): those go to the tree.
    std::array<Point, 8> projected;
    projected.fill(query);
    size_t nearest_k = 0;
    for (size_t k = 0; k < found.near_count; ++k) {
      projected[k] = Kernel::Construct_projected_point_3()(
          triangles[static_cast<size_t>(found.near_faces[k])], query);
      if (Kernel::Compare_distance_3()(query, projected[k], projected[nearest_k]) == CGAL::SMALLER)
        nearest_k = k;
    }
    decided = true;
    for (size_t k = 0; k < found.near_count && decided; ++k)
      decided = k == nearest_k || Kernel::Compare_distance_3()(
                                      query, projected[k], projected[nearest_k]) == CGAL::LARGER;
    if (decided) {
      face = found.near_faces[nearest_k];
      point = to_eigen(projected[nearest_k]);
      if (hint >= 0 && Kernel::Compare_distance_3()(query, projected[nearest_k],
                                                    to_cgal(hint_point)) == CGAL::LARGER) {
        face = hint;
        point = hint_point;
      }
    }
  }
  if (!decided) {
    const auto [cgal_point, id] =
        hint >= 0 ? tree.closest_point_and_primitive(
                        query, Tree::Point_and_primitive_id(to_cgal(hint_point),
                                                            triangles.cbegin() + hint))
                  : tree.closest_point_and_primitive(query);
    face = static_cast<int>(id - triangles.cbegin());
    point = to_eigen(cgal_point);
  }
  SurfacePoint s;
  s.position = point;
  s.face = face;
  s.normal = normal_at(s.face, s.position);
  s.distance = (s.position - p).norm();
  s.tied = found.tied;
  return s;
}

std::optional<SurfacePoint> BodySurface::first_hit(const Eigen::Vector3d& origin,
                                                   const Eigen::Vector3d& direction) const {
  const Ray ray(to_cgal(origin), Kernel::Vector_3(direction.x(), direction.y(), direction.z()));
  const auto hit = impl_->tree.first_intersection(ray);
  if (!hit) return std::nullopt;
  const Point* point = boost::get<Point>(&hit->first);
  if (point == nullptr) return std::nullopt;  // the ray runs inside a triangle's plane
  SurfacePoint s;
  s.position = to_eigen(*point);
  s.face = static_cast<int>(hit->second - impl_->triangles.cbegin());
  s.normal = impl_->normal_at(s.face, s.position);
  s.distance = (s.position - origin).norm();
  return s;
}

double BodySurface::signed_distance(const Eigen::Vector3d& p) const {
  const SurfacePoint s = closest_point(p);
  return (p - s.position).dot(s.normal) >= 0 ? s.distance : -s.distance;
}

Eigen::Vector3d BodySurface::snap_to_offset(const Eigen::Vector3d& p, double offset) const {
  const SurfacePoint s = closest_point(p);
  return s.position + offset * s.normal;
}

bool BodySurface::in_gap(const Eigen::Vector3d& p, double offset) const {
  // m: a point nearer the offset surface than this is on it (a curve written on the skin).
  constexpr double kGapClear = 0.005;
  // The body across may be this many times as far as the nearest point: the middle 3/5 of a
  // gap (a kimono's underarm seam drawn from the arm across to the torso, 5-7 cm apart on the
  // built-in body; with 2, the middle third, the seam still hugged each wall for 2 cm and
  // crossed the rest in one step).
  constexpr double kGapAcross = 4.0;
  const SurfacePoint s = closest_point(p);
  const double near = (p - s.position).dot(s.normal) - offset;
  if (near <= kGapClear) return false;
  const Eigen::Vector3d out = p - s.position;
  const auto across = first_hit(p, out.normalized());
  return across && across->normal.dot(out) < 0 && across->distance - offset <= kGapAcross * near;
}

const BodyLandmarks* BodySurface::landmarks() const {
  std::call_once(impl_->landmarks_once, [this] {
    try {
      impl_->landmarks = find_landmarks(impl_->mesh);
    } catch (const std::runtime_error&) {
      // Not a standing figure (a test sphere, a dress form): no landmarks.
    }
  });
  return impl_->landmarks ? &*impl_->landmarks : nullptr;
}

const meshing::TriMesh& BodySurface::mesh() const {
  return impl_->mesh;
}
const meshing::BoundingBox& BodySurface::box() const {
  return impl_->box;
}

}  // namespace sd::garment
