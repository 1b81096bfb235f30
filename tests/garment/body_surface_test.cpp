#include "garment/body_surface.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <utility>

#include "garment/body.hpp"

namespace sd::garment {
namespace {

// A hint only bounds the search: with the previous answer, a far-away surface point, or none,
// the closest point is the same, on a body with thin parts (arms next to the torso) where a
// wrong local answer would show.
TEST(BodySurface, HintedClosestPointIsTheClosestPoint) {
  const BodySurface body(load_body("builtin").mesh);
  const meshing::BoundingBox& box = body.box();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto random_point = [&] {
    const Eigen::Vector3d t(unit(rng), unit(rng), unit(rng));
    return Eigen::Vector3d(box.min + t.cwiseProduct(box.max - box.min));
  };
  SurfacePoint previous;  // face -1: no hint at first
  const SurfacePoint far_away = body.closest_point(box.max + Eigen::Vector3d(1.0, 1.0, 1.0));
  for (int i = 0; i < 2000; ++i) {
    // Queries in small steps (as a relaxation makes them) and random jumps.
    const Eigen::Vector3d p =
        i % 10 == 0 ? random_point()
                    : previous.position + 0.02 * (random_point() - box.min).normalized();
    const SurfacePoint exact = body.closest_point(p);
    for (const SurfacePoint& hint : {previous, far_away}) {
      const SurfacePoint hinted = body.closest_point(p, hint);
      EXPECT_NEAR(hinted.distance, exact.distance, 1e-12);
      EXPECT_LT((hinted.position - exact.position).norm(), 1e-9);
    }
    previous = exact;
  }
}

// The query's own tree (median splits, Ericson's point-triangle test) against every triangle
// with an independent closest point: the plane's foot when it lies inside the triangle, else
// the nearest of the three edges' nearest points.
Eigen::Vector3d nearest_by_plane_and_edges(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                           const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const Eigen::Vector3d foot = p - (p - a).dot(n) / n.squaredNorm() * n;
  const auto inside = [&](const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
    return (v - u).cross(foot - u).dot(n) >= 0;
  };
  if (inside(a, b) && inside(b, c) && inside(c, a)) return foot;
  Eigen::Vector3d best = a;
  for (const auto& [u, v] : {std::pair(a, b), std::pair(b, c), std::pair(c, a)}) {
    const double t = std::clamp((p - u).dot(v - u) / (v - u).squaredNorm(), 0.0, 1.0);
    const Eigen::Vector3d q = u + t * (v - u);
    if ((q - p).squaredNorm() < (best - p).squaredNorm()) best = q;
  }
  return best;
}

TEST(BodySurface, ClosestPointIsTheNearestOfAllTriangles) {
  const meshing::TriMesh mesh = load_body("builtin").mesh;
  const BodySurface body(mesh);
  const meshing::BoundingBox& box = body.box();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(-0.2, 1.2);  // inside, on and around the body
  for (int i = 0; i < 300; ++i) {
    const Eigen::Vector3d t(unit(rng), unit(rng), unit(rng));
    const Eigen::Vector3d p = box.min + t.cwiseProduct(box.max - box.min);
    double nearest = std::numeric_limits<double>::infinity();
    for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
      const auto corner = [&](int k) -> Eigen::Vector3d {
        return mesh.vertices.row(mesh.faces(f, k)).transpose();
      };
      nearest = std::min(
          nearest, (nearest_by_plane_and_edges(p, corner(0), corner(1), corner(2)) - p).norm());
    }
    const SurfacePoint found = body.closest_point(p);
    EXPECT_NEAR(found.distance, nearest, 1e-12 * (1 + nearest)) << p.transpose();
    EXPECT_NEAR((found.position - p).norm(), found.distance, 1e-12);
  }
}

}  // namespace
}  // namespace sd::garment
