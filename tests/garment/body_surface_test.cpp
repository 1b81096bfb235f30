#include "garment/body_surface.hpp"

#include <gtest/gtest.h>

#include <random>

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

}  // namespace
}  // namespace sd::garment
