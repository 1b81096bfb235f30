// The only translation unit of sd_garment that includes CGAL (it takes ~20 s to compile).
#include "garment/body_surface.hpp"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <Eigen/Geometry>
#include <stdexcept>
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

}  // namespace

struct BodySurface::Impl {
  meshing::TriMesh mesh;
  meshing::BoundingBox box;
  Eigen::MatrixX3d normals;         // #V by 3, unit
  std::vector<Triangle> triangles;  // #F, same order as mesh.faces
  Tree tree;

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

  // The SurfacePoint of a closest-point query's answer for the query point p.
  SurfacePoint answer(const Eigen::Vector3d& p, const Tree::Point_and_primitive_id& found) const;
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
  impl_->tree.accelerate_distance_queries();
}

BodySurface::~BodySurface() = default;
BodySurface::BodySurface(BodySurface&&) noexcept = default;
BodySurface& BodySurface::operator=(BodySurface&&) noexcept = default;

SurfacePoint BodySurface::closest_point(const Eigen::Vector3d& p) const {
  return impl_->answer(p, impl_->tree.closest_point_and_primitive(to_cgal(p)));
}

SurfacePoint BodySurface::closest_point(const Eigen::Vector3d& p, const SurfacePoint& near) const {
  if (near.face < 0 || near.face >= static_cast<int>(impl_->triangles.size()))
    return closest_point(p);
  const Tree::Point_and_primitive_id hint(to_cgal(near.position),
                                          impl_->triangles.cbegin() + near.face);
  return impl_->answer(p, impl_->tree.closest_point_and_primitive(to_cgal(p), hint));
}

SurfacePoint BodySurface::Impl::answer(const Eigen::Vector3d& p,
                                       const Tree::Point_and_primitive_id& found) const {
  const auto& [point, id] = found;
  SurfacePoint s;
  s.position = to_eigen(point);
  s.face = static_cast<int>(id - triangles.cbegin());
  s.normal = normal_at(s.face, s.position);
  s.distance = (s.position - p).norm();
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

const meshing::TriMesh& BodySurface::mesh() const {
  return impl_->mesh;
}
const meshing::BoundingBox& BodySurface::box() const {
  return impl_->box;
}

}  // namespace sd::garment
