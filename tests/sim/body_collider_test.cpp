#include "sim/body_collider.hpp"

#include <fcl/fcl.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <utility>

#include "garment/body.hpp"
#include "sim/collision_geometry.hpp"
#include "sim/collision_repair.hpp"
#include "tests/sim/test_bodies.hpp"

namespace sd::sim {
namespace {

using Eigen::Vector3d;

using testing::make_box;
using testing::make_sphere;

// Closed prism along z whose cross-section is a thin isosceles triangle with apex (0, apex_y):
// a knife edge with apex angle `apex_degrees`.
meshing::TriMesh make_wedge(double apex_degrees, double apex_y, double half_length) {
  const double half_base = apex_y * std::tan(apex_degrees * M_PI / 360.0);
  meshing::TriMesh mesh;
  mesh.vertices.resize(6, 3);
  mesh.vertices << -half_base, 0, -half_length, half_base, 0, -half_length, 0, apex_y, -half_length,
      -half_base, 0, half_length, half_base, 0, half_length, 0, apex_y, half_length;
  mesh.faces.resize(8, 3);
  mesh.faces << 0, 2, 1,  // back cap (z = −L), normal −z
      3, 4, 5,            // front cap, +z
      0, 1, 4, 0, 4, 3,   // base, −y
      1, 2, 5, 1, 5, 4,   // right slope
      2, 0, 3, 2, 3, 5;   // left slope
  return mesh;
}

Eigen::VectorXd flatten(const std::vector<Vector3d>& points) {
  Eigen::VectorXd x(3 * points.size());
  for (std::size_t i = 0; i < points.size(); ++i) x.segment<3>(3 * i) = points[i];
  return x;
}

TEST(ClosestPointOnTriangle, MatchesDenseSamplingAndClassifiesRegions) {
  const Vector3d a(0, 0, 0), b(1, 0, 0), c(0.3, 0.8, 0);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.7, 1.5);
  for (int trial = 0; trial < 200; ++trial) {
    const Vector3d p(u(rng), u(rng), 0.5 * u(rng));
    const TriangleClosestPoint cp = closest_point_on_triangle(p, a, b, c);
    // Sampling the triangle on a fine grid can only find points at least as far.
    double sampled = std::numeric_limits<double>::infinity();
    const int n = 200;
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        const Vector3d q = a + (b - a) * i / n + (c - a) * j / n;
        sampled = std::min(sampled, (p - q).norm());
      }
    const double d = std::sqrt(cp.squared_distance);
    EXPECT_LE(d, sampled + 1e-12);
    EXPECT_GE(d, sampled - 1.2 / n);  // grid spacing bounds how much closer the truth can be
    EXPECT_NEAR(cp.barycentric.sum(), 1.0, 1e-12);
    EXPECT_TRUE((cp.barycentric.array() >= -1e-12).all());
    EXPECT_LT(
        (cp.barycentric[0] * a + cp.barycentric[1] * b + cp.barycentric[2] * c - cp.point).norm(),
        1e-12);
  }
  EXPECT_EQ(closest_point_on_triangle(Vector3d(0.4, 0.3, 1), a, b, c).feature,
            TriangleFeature::face);
  const TriangleClosestPoint edge = closest_point_on_triangle(Vector3d(0.5, -1, 0), a, b, c);
  EXPECT_EQ(edge.feature, TriangleFeature::edge);
  EXPECT_EQ(edge.index, 0);
  const TriangleClosestPoint corner = closest_point_on_triangle(Vector3d(1.5, -0.2, 0), a, b, c);
  EXPECT_EQ(corner.feature, TriangleFeature::vertex);
  EXPECT_EQ(corner.index, 1);
}

TEST(BodyCollider, SphereSignedDistanceWithinChordalBound) {
  const double r = 0.2;
  const meshing::TriMesh sphere = make_sphere(r, 3);
  const double r_inner = testing::inscribed_radius(sphere, Vector3d::Zero());
  ASSERT_LT(r - r_inner, 0.002);  // the mesh is fine enough for the bounds below to be tight
  const BodyCollider collider(sphere);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> radius(0.01, 0.4);
  std::normal_distribution<double> gauss;
  for (int trial = 0; trial < 500; ++trial) {
    const Vector3d direction = Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized();
    const double rho = radius(rng);
    const Vector3d p = rho * direction;
    const std::optional<BodyProximity> hit = collider.closest_point(p);
    ASSERT_TRUE(hit);
    // The polyhedron lies between the inscribed and the circumscribed sphere, so the signed
    // distance lies between the two spheres' signed distances.
    EXPECT_GE(hit->distance, rho - r - 1e-12) << rho;
    EXPECT_LE(hit->distance, rho - r_inner + 1e-12) << rho;
    EXPECT_GT(hit->normal.dot(direction), 0.97) << rho;  // within a facet's angular size
    EXPECT_NEAR(hit->normal.norm(), 1.0, 1e-12);
    EXPECT_NEAR((p - hit->point).dot(hit->normal), hit->distance, 1e-12);
  }
}

TEST(BodyCollider, BoxEdgesAndCornersGetExactDistancesAndNormals) {
  const BodyCollider box(make_box(Vector3d(-0.1, -0.1, -0.1), Vector3d(0.1, 0.1, 0.1)));
  struct Case {
    Vector3d p;
    double distance;
    Vector3d normal;
  };
  const std::vector<Case> cases = {
      {{0.13, 0.14, 0.02}, std::hypot(0.03, 0.04), Vector3d(0.03, 0.04, 0).normalized()},
      {{0.12, 0.12, 0.11}, Vector3d(0.02, 0.02, 0.01).norm(), Vector3d(2, 2, 1).normalized()},
      {{-0.11, -0.12, -0.13}, Vector3d(0.01, 0.02, 0.03).norm(), -Vector3d(1, 2, 3).normalized()},
      {{0.09, 0.08, 0.0}, -0.01, Vector3d::UnitX()},           // inside, near an edge
      {{0.09, 0.08, 0.07}, -0.01, Vector3d::UnitX()},          // inside, near a corner
      {{0.0, 0.0, 0.1001}, 0.0001, Vector3d::UnitZ()},         // above a face diagonal
      {{0.02, -0.02, -0.095}, -0.005, -Vector3d::UnitZ()},     // just inside a face
      {{0.1, 0.1, 0.1}, 0.0, Vector3d(1, 1, 1).normalized()},  // on a corner
      {{0.1, 0.1, 0.0}, 0.0, Vector3d(1, 1, 0).normalized()},  // on an edge
  };
  for (const Case& c : cases) {
    const std::optional<BodyProximity> hit = box.closest_point(c.p);
    ASSERT_TRUE(hit);
    EXPECT_NEAR(hit->distance, c.distance, 1e-12) << c.p.transpose();
    EXPECT_LT((hit->normal - c.normal).norm(), 1e-9) << c.p.transpose();
  }
}

TEST(BodyCollider, KnifeEdgeSignUsesThePseudoNormal) {
  // Apex angle 20°: the two slope normals make 160°, so a point just outside the edge can lie
  // behind one of the faces that contain its closest point.
  const meshing::TriMesh wedge = make_wedge(20.0, 0.1, 0.1);
  const BodyCollider collider(wedge);
  const Vector3d apex(0, 0.1, 0);
  const Vector3d outside = apex + Vector3d(0.004, 0.002, 0);
  const std::optional<BodyProximity> hit = collider.closest_point(outside);
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->feature, TriangleFeature::edge);
  EXPECT_NEAR(hit->distance, Vector3d(0.004, 0.002, 0).norm(), 1e-12);
  // The premise: one face holding the closest point would call this point inside.
  bool some_face_disagrees = false;
  for (Eigen::Index f = 0; f < wedge.face_count(); ++f) {
    const Vector3d a = wedge.vertices.row(wedge.faces(f, 0)).transpose();
    const Vector3d b = wedge.vertices.row(wedge.faces(f, 1)).transpose();
    const Vector3d c = wedge.vertices.row(wedge.faces(f, 2)).transpose();
    const TriangleClosestPoint cp = closest_point_on_triangle(outside, a, b, c);
    if (std::abs(std::sqrt(cp.squared_distance) - hit->distance) < 1e-12 &&
        (outside - cp.point).dot(triangle_normal(a, b, c)) < 0)
      some_face_disagrees = true;
  }
  EXPECT_TRUE(some_face_disagrees);

  // Just inside the edge: negative, pushed out through the nearer slope.
  const Vector3d inside(0.0, 0.095, 0.0);
  const double expected = -0.005 * std::sin(10.0 * M_PI / 180.0);
  EXPECT_NEAR(collider.signed_distance(inside), expected, 1e-12);
  // The tip of the edge at a cap: a corner with three faces.
  EXPECT_GT(collider.signed_distance(Vector3d(0.001, 0.1005, 0.1003)), 0.0);
  EXPECT_LT(collider.signed_distance(Vector3d(0.0, 0.099, 0.0999)), 0.0);
}

TEST(BodyCollider, DeepInsidePointsAreContactsWithTheRightPushDirection) {
  const double r = 0.2;
  const meshing::TriMesh sphere = make_sphere(r, 3);
  const double r_inner = testing::inscribed_radius(sphere, Vector3d::Zero());
  const BodyCollider collider(sphere);
  const Vector3d direction = Vector3d(0.3, -0.5, 0.8).normalized();
  const std::vector<Vector3d> points = {
      0.17 * direction,       // 3 cm inside
      Vector3d(0.001, 0, 0),  // centre
      0.5 * direction,        // far outside
      0.203 * direction,      // 3 mm outside
  };
  ContactQuery query;
  query.thickness = 0.005;
  ContactQueryStats stats;
  const std::vector<BodyContact> contacts =
      collider.find_contacts(flatten(points), query, nullptr, &stats);
  ASSERT_EQ(contacts.size(), 3u);
  EXPECT_EQ(contacts[0].vertex, 0);
  EXPECT_LE(contacts[0].distance, -(r_inner - 0.17) + 1e-12);
  EXPECT_GE(contacts[0].distance, -(r - 0.17) - 1e-12);
  EXPECT_GT(contacts[0].normal.dot(direction), 0.97);
  EXPECT_EQ(contacts[1].vertex, 1);
  EXPECT_LT(contacts[1].distance, -r_inner + 0.002);
  EXPECT_EQ(contacts[2].vertex, 3);
  EXPECT_GT(contacts[2].distance, 0.0);
  EXPECT_GE(stats.full_searches, 2);  // the two deep points needed the full search for the sign
}

TEST(BodyCollider, BuiltinBodyPointsInsideAndAgreementWithFcl) {
  const garment::Body body = garment::load_body("builtin");
  const BodyCollider collider(body.mesh);
  const Eigen::MatrixX3d normals = meshing::vertex_normals(body.mesh);
  // 3 cm under the skin of the front torso.
  int tested = 0;
  for (Eigen::Index v = 0; v < body.mesh.vertex_count(); v += 7) {
    const Vector3d x = body.mesh.vertices.row(v).transpose();
    if (std::abs(x.x()) > 0.1 || x.y() < 1.0 || x.y() > 1.4 || x.z() < 0.05) continue;
    const Vector3d n = normals.row(v).transpose();
    const std::optional<BodyProximity> hit = collider.closest_point(x - 0.03 * n);
    ASSERT_TRUE(hit);
    EXPECT_LT(hit->distance, -0.02) << v;
    EXPECT_GE(hit->distance, -0.03 - 1e-9) << v;
    EXPECT_GT(hit->normal.dot(n), 0.8) << v;
    ++tested;
  }
  EXPECT_GT(tested, 5);

  // Unsigned distances agree with FCL's own distance query (a zero-radius sphere as the point).
  std::vector<fcl::Vector3d> points;
  for (Eigen::Index v = 0; v < body.mesh.vertex_count(); ++v)
    points.push_back(body.mesh.vertices.row(v).transpose());
  std::vector<fcl::Triangle> triangles;
  for (Eigen::Index f = 0; f < body.mesh.face_count(); ++f)
    triangles.emplace_back(body.mesh.faces(f, 0), body.mesh.faces(f, 1), body.mesh.faces(f, 2));
  auto model = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
  model->beginModel();
  model->addSubModel(points, triangles);
  model->endModel();
  fcl::CollisionObjectd mesh_object(model);
  fcl::CollisionObjectd point_object(std::make_shared<fcl::Sphered>(0.0));
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const Vector3d p(0.8 * u(rng) - 0.4, 1.8 * u(rng), 0.4 * u(rng) - 0.2);
    point_object.setTranslation(p);
    point_object.computeAABB();
    fcl::DistanceRequestd request(true);
    fcl::DistanceResultd result;
    fcl::distance(&mesh_object, &point_object, request, result);
    const std::optional<BodyProximity> hit = collider.closest_point(p);
    ASSERT_TRUE(hit);
    EXPECT_NEAR(std::abs(hit->distance), result.min_distance, 1e-9);
  }
}

TEST(BodyCollider, RefitAnswersLikeARebuild) {
  const meshing::TriMesh rest = make_sphere(0.2, 2);
  BodyCollider moved(rest);
  meshing::TriMesh pose = rest;
  for (int step = 1; step <= 2; ++step) {
    for (Eigen::Index v = 0; v < pose.vertex_count(); ++v) {
      const Vector3d x = rest.vertices.row(v).transpose();
      pose.vertices.row(v) = (Vector3d(1.0 + 0.3 * step, 1.0, 0.8).asDiagonal() * x +
                              Vector3d(0.05 * step, 0.02 * std::sin(20 * x.y()), -0.03 * step))
                                 .transpose();
    }
    moved.set_pose(pose.vertices);
    const BodyCollider rebuilt(pose);
    std::mt19937 rng(step);
    std::uniform_real_distribution<double> u(-0.5, 0.5);
    for (int trial = 0; trial < 300; ++trial) {
      const Vector3d p(u(rng), u(rng), u(rng));
      const BodyProximity a = *moved.closest_point(p);
      const BodyProximity b = *rebuilt.closest_point(p);
      EXPECT_NEAR(a.distance, b.distance, 1e-12);
      EXPECT_LT((a.point - b.point).norm(), 1e-9);
      EXPECT_LT((a.normal - b.normal).norm(), 1e-6);
    }
  }
  EXPECT_GT(moved.last_motion(), 0.05);
}

TEST(BodyCollider, CacheSkipsWorkWithoutChangingTheContacts) {
  meshing::TriMesh sphere = make_sphere(0.2, 3);
  BodyCollider collider(sphere);
  std::mt19937 rng(11);
  std::normal_distribution<double> gauss;
  std::uniform_real_distribution<double> shell(0.12, 0.3);
  std::vector<Vector3d> points;
  for (int i = 0; i < 1500; ++i)
    points.push_back(shell(rng) * Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized());
  ContactQuery query;
  query.thickness = 0.01;
  ContactCache cache;
  int skipped = 0;
  for (int step = 0; step < 25; ++step) {
    if (step % 5 == 4) {  // the body moves now and then
      const Vector3d shift(0.003 * step, -0.002 * step, 0.001 * step);
      Eigen::MatrixX3d moved = sphere.vertices.rowwise() + shift.transpose();
      collider.set_pose(moved);
    }
    for (auto& p : points) p += 0.004 * Vector3d(gauss(rng), gauss(rng), gauss(rng));
    const Eigen::VectorXd x = flatten(points);
    ContactQueryStats stats;
    const std::vector<BodyContact> cached = collider.find_contacts(x, query, &cache, &stats);
    const std::vector<BodyContact> fresh = collider.find_contacts(x, query);
    ASSERT_EQ(cached.size(), fresh.size()) << step;
    // The cached searches also start from last step's nearest triangle (a hint that bounds the
    // search): the same triangle and the same bits as a search without it.
    for (std::size_t k = 0; k < fresh.size(); ++k) {
      EXPECT_EQ(cached[k].vertex, fresh[k].vertex);
      EXPECT_EQ(cached[k].triangle, fresh[k].triangle);
      EXPECT_EQ(cached[k].distance, fresh[k].distance);
      EXPECT_EQ(cached[k].point, fresh[k].point);
      EXPECT_EQ(cached[k].normal, fresh[k].normal);
    }
    skipped += stats.skipped;
  }
  EXPECT_GT(skipped, 1000);  // the cache did let vertices go unsearched
}

// A 2 cm slab y ∈ [0, 0.02], wide in x and z.
meshing::TriMesh make_slab(double y_low = 0.0) {
  return make_box(Vector3d(-0.5, y_low, -0.5), Vector3d(0.5, y_low + 0.02, 0.5));
}

TEST(BodyCollider, ContinuousCheckCatchesAPointPassingThroughAThinBody) {
  const BodyCollider slab(make_slab());
  ContactQuery query;
  query.thickness = 0.003;
  const auto one = [](const Vector3d& p) { return flatten({p}); };

  // Straight through in one step: the end position alone looks fine.
  const Vector3d start(0.1, 0.1, 0.05), end(0.1, -0.1, 0.05);
  EXPECT_TRUE(slab.find_contacts(one(end), query).empty());
  ContactQueryStats stats;
  std::vector<BodyContact> contacts =
      slab.find_contacts_swept(one(start), one(end), query, nullptr, &stats);
  ASSERT_EQ(contacts.size(), 1u);
  EXPECT_TRUE(contacts[0].crossed);
  EXPECT_LT((contacts[0].normal - Vector3d::UnitY()).norm(), 1e-9);
  EXPECT_NEAR(contacts[0].point.y(), 0.02, 1e-9);
  EXPECT_NEAR(contacts[0].distance, -0.12, 1e-9);
  EXPECT_EQ(stats.crossings, 1);

  // Ending past the middle of the slab: the nearest surface is the far one, the entry side wins.
  contacts = slab.find_contacts_swept(one(start), one(Vector3d(0.1, 0.004, 0.05)), query);
  ASSERT_EQ(contacts.size(), 1u);
  EXPECT_TRUE(contacts[0].crossed);
  EXPECT_LT((contacts[0].normal - Vector3d::UnitY()).norm(), 1e-9);
  EXPECT_NEAR(contacts[0].distance, 0.004 - 0.02, 1e-9);

  // Ending shallow on the entry side: the ordinary contact.
  contacts = slab.find_contacts_swept(one(start), one(Vector3d(0.1, 0.017, 0.05)), query);
  ASSERT_EQ(contacts.size(), 1u);
  EXPECT_FALSE(contacts[0].crossed);
  EXPECT_NEAR(contacts[0].distance, -0.003, 1e-9);

  // Moving near but not through: nothing.
  EXPECT_TRUE(slab.find_contacts_swept(one(start), one(Vector3d(0.3, 0.03, 0.1)), query).empty());
}

TEST(BodyCollider, ContinuousCheckCatchesAFastBodyPassingAStillPoint) {
  // The slab jumps 0.2 m up in one step (4.8 m/s at 24 steps per second) past a still point.
  const meshing::TriMesh below = make_slab(-0.1);
  BodyCollider slab(below);
  const Vector3d velocity(0, 4.8, 0);
  ContactQuery query;
  query.thickness = 0.003;
  const Eigen::VectorXd x = flatten({Vector3d(0.05, 0.05, 0.0), Vector3d(0.05, 0.3, 0.0)});
  ContactCache cache;
  EXPECT_TRUE(slab.find_contacts(x, query, &cache).empty());
  const Eigen::MatrixX3d above = below.vertices.rowwise() + Vector3d(0, 0.2, 0).transpose();
  slab.set_pose(above, Eigen::MatrixX3d(velocity.transpose().replicate(above.rows(), 1)));
  EXPECT_TRUE(slab.find_contacts(x, query).empty());
  ContactQueryStats stats;
  const std::vector<BodyContact> contacts = slab.find_contacts_swept(x, x, query, &cache, &stats);
  ASSERT_EQ(contacts.size(), 1u);
  EXPECT_EQ(contacts[0].vertex, 0);
  EXPECT_TRUE(contacts[0].crossed);
  EXPECT_LT((contacts[0].normal - Vector3d::UnitY()).norm(), 1e-9);
  EXPECT_NEAR(contacts[0].point.y(), 0.12, 1e-9);
  EXPECT_NEAR(contacts[0].distance, 0.05 - 0.12, 1e-9);
  EXPECT_LT((contacts[0].body_velocity - velocity).norm(), 1e-12);
  EXPECT_GT(stats.sweep_samples, 1);
}

TEST(BodyCollider, SegmentStepsRefitOnceAndMatchARebuild) {
  const meshing::TriMesh rest = make_sphere(0.2, 2);
  const Eigen::MatrixX3d from = rest.vertices;
  const Eigen::MatrixX3d to =
      (1.2 * rest.vertices).rowwise() + Vector3d(0.1, -0.05, 0.02).transpose();
  BodyCollider collider(rest);
  const double fractions[] = {0.0, 0.3, 0.7, 1.0};
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-0.4, 0.4);
  for (int k = 0; k < 3; ++k) {
    collider.set_pose_on_segment(from, to, fractions[k], fractions[k + 1]);
    EXPECT_EQ(collider.refit_count(), 1);
    const double s = fractions[k + 1];
    meshing::TriMesh pose = rest;
    pose.vertices = from + s * (to - from);
    EXPECT_LT((collider.vertices() - pose.vertices).norm(), 1e-12);
    EXPECT_NEAR(collider.last_motion(),
                (fractions[k + 1] - fractions[k]) * (to - from).rowwise().norm().maxCoeff(), 1e-12);
    const BodyCollider rebuilt(pose);
    for (int trial = 0; trial < 100; ++trial) {
      const Vector3d p(u(rng), u(rng), u(rng));
      EXPECT_NEAR(collider.signed_distance(p), rebuilt.signed_distance(p), 1e-12);
    }
  }
  // Back to a plain pose: one more refit, and the segment is forgotten.
  collider.set_pose(from);
  EXPECT_EQ(collider.refit_count(), 2);
  EXPECT_LT((collider.vertices() - from).norm(), 1e-15);
}

TEST(BodyCollider, ContinuousCheckWithinASegment) {
  // The slab rises 0.2 m along one segment, swept in four steps; the still point at y = 0.045 is
  // passed during the third (top face from 0.045 at s = 0.625, bottom at s = 0.725).
  const meshing::TriMesh below = make_slab(-0.1);
  const Eigen::MatrixX3d above = below.vertices.rowwise() + Vector3d(0, 0.2, 0).transpose();
  BodyCollider slab(below);
  ContactQuery query;
  query.thickness = 0.003;
  const Eigen::VectorXd x = flatten({Vector3d(0.05, 0.045, 0.0)});
  ContactCache cache;
  for (int step = 0; step < 4; ++step) {
    slab.set_pose_on_segment(below.vertices, above, 0.25 * step, 0.25 * (step + 1));
    const std::vector<BodyContact> contacts = slab.find_contacts_swept(x, x, query, &cache);
    if (step != 2) {
      EXPECT_TRUE(contacts.empty()) << step;
      continue;
    }
    ASSERT_EQ(contacts.size(), 1u);
    EXPECT_TRUE(contacts[0].crossed);
    EXPECT_LT((contacts[0].normal - Vector3d::UnitY()).norm(), 1e-9);
    EXPECT_NEAR(contacts[0].point.y(), -0.08 + 0.2 * 0.75, 1e-9);
    EXPECT_NEAR(contacts[0].distance, 0.045 - (-0.08 + 0.2 * 0.75), 1e-9);
  }
  EXPECT_EQ(slab.refit_count(), 1);
}

TEST(StartRepair, PushesInsideVerticesOutAlongTheNearestSurface) {
  const double r = 0.2;
  const meshing::TriMesh sphere = make_sphere(r, 3);
  const double r_inner = testing::inscribed_radius(sphere, Vector3d::Zero());
  const BodyCollider collider(sphere);
  // A flat sheet at z = 0.1 cutting through the sphere's cap.
  std::vector<Vector3d> grid;
  for (int i = 0; i <= 20; ++i)
    for (int j = 0; j <= 20; ++j) grid.emplace_back(-0.3 + 0.03 * i, -0.3 + 0.03 * j, 0.1);
  const Eigen::VectorXd x = flatten(grid);
  StartRepairOptions options;
  options.thickness = 0.004;
  options.steps = 8;
  const StartRepair repair = plan_start_repair(collider, x, options);
  ASSERT_FALSE(repair.empty());
  EXPECT_NEAR(repair.max_depth, r - 0.1, r - r_inner + 1e-9);
  std::vector<bool> pushed(grid.size(), false);
  for (const BodyContact& c : repair.pushed) pushed[c.vertex] = true;
  for (std::size_t i = 0; i < grid.size(); ++i) {
    const bool inside = grid[i].norm() < r_inner;
    if (inside) {
      EXPECT_TRUE(pushed[i]) << i;
    }
    if (grid[i].norm() > r) {
      EXPECT_FALSE(pushed[i]) << i;
    }
    const Vector3d target = repair.target.segment<3>(3 * i);
    if (!pushed[i]) {
      EXPECT_EQ(target, grid[i]);
      continue;
    }
    EXPECT_NEAR(collider.signed_distance(target), options.thickness, 1e-9) << i;
    EXPECT_GT((target - grid[i]).normalized().dot(grid[i].normalized()), 0.95);  // radially out
    // Linear over the steps, then held.
    EXPECT_EQ(repair.goal(static_cast<int>(i), 0), grid[i]);
    EXPECT_LT((repair.goal(static_cast<int>(i), 4) - 0.5 * (grid[i] + target)).norm(), 1e-15);
    EXPECT_EQ(repair.goal(static_cast<int>(i), 8), target);
    EXPECT_EQ(repair.goal(static_cast<int>(i), 20), target);
  }
  // After the last step no vertex is inside any more.
  ContactQuery strict;
  strict.thickness = 0.0;
  EXPECT_TRUE(collider.find_contacts(repair.positions_after(options.steps), strict).empty());
  EXPECT_EQ(repair.positions_after(0), x);
}

// A vertical panel drawn 2 cm into the front of a leg (a 10 cm square box standing along y):
// the band of it inside the box. Pushed vertex by vertex to the nearest skin, the band's outer
// thirds go out through the leg's sides, to both sides (the cloth caught round the leg, as a
// hem drawn 4 cm into the legs was). With the cloth's triangles the band is one region, moved out
// of the front as one piece (the same push for every vertex: 2 cm and the thickness, +z), and the
// cloth round it follows over the falloff, no edge's push differing from its other end's by
// more than the falloff's slope times its length, so no edge is stretched more than about
// slope²/2 (3.1 %).
TEST(StartRepair, ARegionInsideALegMovesOutAsOnePieceWithTheClothRoundIt) {
  const BodyCollider leg(make_box({-0.05, -0.5, -0.05}, {0.05, 0.5, 0.05}));
  // 1 cm cells over x in [-0.195, 0.195] (no vertex on the leg's sides, x = ±0.05, where
  // rounding would count one side's column inside and not the other's), y in [-0.08, 0.08].
  const int nx = 39, ny = 16;
  std::vector<Vector3d> grid;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) grid.emplace_back(-0.195 + 0.01 * i, -0.08 + 0.01 * j, 0.03);
  std::vector<std::array<int, 3>> triangles;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int a = j * (nx + 1) + i, b = a + 1, c = a + nx + 1, d = c + 1;
      triangles.push_back({a, b, d});
      triangles.push_back({a, d, c});
    }
  const Eigen::VectorXd x = flatten(grid);
  StartRepairOptions options;
  options.thickness = 0.004;

  const StartRepair alone = plan_start_repair(leg, x, options);
  bool left = false, right = false;
  for (const RepairMove& m : alone.moved) {
    left = left || m.direction.x() < -0.9;
    right = right || m.direction.x() > 0.9;
  }
  EXPECT_TRUE(left && right) << "the nearest skin no longer splits the band";

  const ClothTriangles cloth(triangles);
  const StartRepair repair = plan_start_repair(leg, x, options, &cloth);
  EXPECT_EQ(repair.regions, 1);
  EXPECT_EQ(repair.pushed.size(), alone.pushed.size());
  EXPECT_NEAR(repair.max_depth, 0.02, 1e-9);
  const Vector3d out(0, 0, 0.02 + options.thickness);
  std::vector<char> inside(grid.size(), 0);
  for (const BodyContact& c : repair.pushed) inside[static_cast<size_t>(c.vertex)] = 1;
  for (size_t v = 0; v < grid.size(); ++v) {
    const Vector3d push = repair.target.segment<3>(3 * v) - grid[v];
    if (inside[v]) {
      EXPECT_LT((push - out).norm(), 1e-9) << v;
      EXPECT_GE(leg.signed_distance(repair.target.segment<3>(3 * v)), options.thickness - 1e-9);
    }
    // Along +z only, never more than the region's push, nothing beyond the falloff's reach
    // (1.5 · push / slope = 14.4 cm from the band's edge at |x| = 4.5 cm).
    EXPECT_LT(std::hypot(push.x(), push.y()), 1e-12) << v;
    EXPECT_LE(push.z(), out.z() + 1e-12) << v;
    if (std::abs(grid[v].x()) > 0.045 + 0.144) {
      EXPECT_EQ(push.z(), 0.0) << v;
    }
  }
  double worst_stretch = 0.0;
  for (const auto& t : triangles)
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      const double length = (grid[a] - grid[b]).norm();
      const Vector3d pa = repair.target.segment<3>(3 * a), pb = repair.target.segment<3>(3 * b);
      EXPECT_LE((pa - grid[a] - (pb - grid[b])).norm(), options.falloff_slope * length * (1 + 1e-9))
          << a << "-" << b;
      worst_stretch = std::max(worst_stretch, (pa - pb).norm() / length - 1.0);
    }
  EXPECT_LT(worst_stretch, 0.5 * options.falloff_slope * options.falloff_slope);
  EXPECT_GT(worst_stretch, 0.0);
  // Every moved vertex is listed once, with its push.
  for (const RepairMove& m : repair.moved)
    EXPECT_LT((m.distance * m.direction -
               (repair.target.segment<3>(3 * m.vertex) - x.segment<3>(3 * m.vertex)))
                  .norm(),
              1e-12);
}

using Triangles = std::vector<std::array<int, 3>>;

// One cloth triangle (x, z corners at height y), 3 cloth vertices as 3n positions.
Eigen::VectorXd flat_triangle(double y) {
  Eigen::VectorXd x(9);
  x << -0.3, y, -0.2, 0.0, y, 0.3, 0.3, y, -0.2;  // counter-clockwise seen from below
  return x;
}

// A cloth of 0.15 mm edges (a sketched strip at a fine resolution) searched with a 5 cm reach:
// the broad-phase grid used cells of the longest edge, so each triangle's grown box covered
// (2 * 5 cm / 0.15 mm)^3 ~ 3e8 cells and the query ran out of memory (17 GB). The cells now
// grow with the reach: at most 4 per axis per triangle, and the piercing is still found.
TEST(BodyCollider, FineClothWithALongReachKeepsTheGridSmall) {
  const meshing::TriMesh cone = testing::make_cone(0.1, 0.2, 24);
  const BodyCollider collider(cone);
  const int n = 60;  // 60 x 60 cells of 0.15 mm: a 9 mm square centred under the apex
  const double edge = 1.5e-4;
  Eigen::VectorXd x(3 * (n + 1) * (n + 1));
  for (int r = 0; r <= n; ++r)
    for (int c = 0; c <= n; ++c)
      x.segment<3>(3 * (r * (n + 1) + c)) =
          Vector3d((c - 0.5 * n) * edge + 1e-5, 0.19, (r - 0.5 * n) * edge + 2e-5);
  std::vector<std::array<int, 3>> triangles;
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      const int a = r * (n + 1) + c, b = a + 1, d = a + n + 1, e = d + 1;
      triangles.push_back({a, b, e});  // counter-clockwise seen from below
      triangles.push_back({a, e, d});
    }
  PiercingQueryStats stats;
  const std::vector<BodyPiercing> found =
      collider.find_piercings(x, triangles, 0.0, 0.05, 0.0, &stats);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found.front().body_vertex, 0);
  EXPECT_NEAR(found.front().height, 0.01, 1e-12);
  EXPECT_LE(stats.grid_entries, 64 * static_cast<std::int64_t>(triangles.size()));
}

// The broad-phase grid counts its cells densely when they are few and keeps a sorted list when
// the cloth is spread thin (here a second triangle 100 km away: about 170,000 cells of 0.58 m,
// the longest edge, along x for a handful of entries); both give the piercing under the apex,
// with the same height and barycentric coordinates bit for bit.
TEST(BodyCollider, PiercingsAreTheSameOnADenseAndASparseGrid) {
  const BodyCollider collider(testing::make_cone(0.1, 0.2, 24));
  const Eigen::VectorXd near = flat_triangle(0.19);  // 1 cm under the apex
  Eigen::VectorXd spread(18);
  spread << near, near;
  for (int k = 3; k < 6; ++k) spread[3 * k] += 1e5;
  const std::vector<std::array<int, 3>> one = {{0, 1, 2}};
  const std::vector<std::array<int, 3>> two = {{0, 1, 2}, {3, 4, 5}};
  PiercingQueryStats dense_stats, sparse_stats;
  const std::vector<BodyPiercing> dense =
      collider.find_piercings(near, one, 0.0, 0.05, 0.0, &dense_stats);
  const std::vector<BodyPiercing> sparse =
      collider.find_piercings(spread, two, 0.0, 0.05, 0.0, &sparse_stats);
  ASSERT_EQ(dense.size(), 1u);
  ASSERT_EQ(sparse.size(), 1u);
  EXPECT_EQ(sparse.front().cloth_triangle, 0);
  EXPECT_EQ(sparse.front().body_vertex, dense.front().body_vertex);
  EXPECT_EQ(sparse.front().height, dense.front().height);
  EXPECT_EQ(sparse.front().barycentric, dense.front().barycentric);
  EXPECT_NEAR(dense.front().height, 0.01, 1e-12);
  EXPECT_EQ(sparse_stats.pairs, dense_stats.pairs);  // the far triangle shares no cell
}

TEST(BodyCollider, BodyVertexThroughAClothTriangleIsAPiercing) {
  // A cone apex (a sharp body vertex) 20 cm up, under one large cloth triangle: the cloth's
  // vertices are all far outside the body, so the vertex test cannot see it.
  const meshing::TriMesh cone = testing::make_cone(0.1, 0.2, 24);
  const BodyCollider collider(cone);
  const std::vector<std::array<int, 3>> triangles = {{0, 1, 2}};
  const Eigen::VectorXd below = flat_triangle(0.19);  // 1 cm under the apex
  ContactQuery strict;
  strict.thickness = 0.0;
  ASSERT_TRUE(collider.find_contacts(below, strict).empty());  // the premise
  PiercingQueryStats stats;
  const std::vector<BodyPiercing> found =
      collider.find_piercings(below, triangles, 0.0, 0.05, 0.0, &stats);
  ASSERT_EQ(found.size(), 1u);
  const BodyPiercing& p = found.front();
  EXPECT_EQ(p.body_vertex, 0);
  EXPECT_EQ(p.cloth_triangle, 0);
  EXPECT_NEAR(p.height, 0.01, 1e-12);
  EXPECT_NEAR((p.normal - Vector3d::UnitY()).norm(), 0.0, 1e-12);  // oriented outwards
  // The apex (0, 0.2, 0) projects to (0, 0.19, 0): barycentric coordinates in the triangle.
  const Vector3d projected = p.barycentric[0] * below.segment<3>(0) +
                             p.barycentric[1] * below.segment<3>(3) +
                             p.barycentric[2] * below.segment<3>(6);
  EXPECT_NEAR((projected - Vector3d(0.0, 0.19, 0.0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(p.barycentric.sum(), 1.0, 1e-12);
  EXPECT_EQ(stats.piercings, 1);
  // Deeper than the reach asked for: not reported.
  EXPECT_TRUE(collider.find_piercings(below, triangles, 0.0, 0.005).empty());

  // 2 mm above the apex: not through; within a 3 mm thickness when asked for that.
  const Eigen::VectorXd above = flat_triangle(0.202);
  EXPECT_TRUE(collider.find_piercings(above, triangles, 0.0, 0.05).empty());
  const std::vector<BodyPiercing> close = collider.find_piercings(above, triangles, -0.003, 0.05);
  ASSERT_EQ(close.size(), 1u);
  EXPECT_NEAR(close.front().height, -0.002, 1e-12);

  // The same triangle moved sideways so that the apex projects outside it: nothing.
  Eigen::VectorXd aside = below;
  for (int k = 0; k < 3; ++k) aside[3 * k] += 0.4;
  EXPECT_TRUE(collider.find_piercings(aside, triangles, 0.0, 0.05).empty());

  // A pair asked for directly is measured the same way, with none of the search's filters: the
  // reported one has the same height, normal and weights, and the one beside the cloth (what
  // the simulator follows after a spring pushed it there) its height over the plane, 1 cm, with
  // weights of the closest point on the triangle's edge.
  const std::optional<BodyPiercing> pair = collider.piercing_of_pair(below, triangles[0], 0, 0);
  ASSERT_TRUE(pair.has_value());
  EXPECT_NEAR(pair->height, p.height, 1e-15);
  EXPECT_NEAR((pair->normal - p.normal).norm(), 0.0, 1e-15);
  EXPECT_NEAR((pair->barycentric - p.barycentric).norm(), 0.0, 1e-15);
  const std::optional<BodyPiercing> beside = collider.piercing_of_pair(aside, triangles[0], 0, 0);
  ASSERT_TRUE(beside.has_value());
  EXPECT_NEAR(beside->height, 0.01, 1e-12);
  EXPECT_NEAR(beside->barycentric.minCoeff(), 0.0, 1e-12);  // on the boundary of the triangle
}

TEST(BodyCollider, BodyVertexBesideTheClothsOpenEdgeIsNotAPiercing) {
  // The triangle 1 cm under the cone's apex, moved so that its edge z = 3 mm passes beside the
  // apex (a neck beside a neckline): the apex is above the triangle's plane and its closest
  // point on that edge lies inside the cone, but no cloth covers it.
  const meshing::TriMesh cone = testing::make_cone(0.1, 0.2, 24);
  const BodyCollider collider(cone);
  Eigen::VectorXd beside(12);
  beside << flat_triangle(0.19), 0.0, 0.14, -0.3;  // a fourth vertex for the ridge below
  for (int k = 0; k < 3; ++k) beside[3 * k + 2] += 0.203;
  ASSERT_NEAR(beside[8], 0.003, 1e-15);  // edge 2 (corners 2 and 0) runs along z = 3 mm
  EXPECT_TRUE(collider.find_piercings(beside, Triangles{{0, 1, 2}}, 0.0, 0.05).empty());
  // The same edge shared with a second triangle folded down behind it: a ridge of the cloth
  // over the apex, which counts.
  const std::vector<BodyPiercing> ridge =
      collider.find_piercings(beside, Triangles{{0, 1, 2}, {2, 3, 0}}, 0.0, 0.05);
  ASSERT_EQ(ridge.size(), 1u);
  EXPECT_EQ(ridge.front().body_vertex, 0);
  EXPECT_GT(ridge.front().height, 0.0);
}

// A body vertex beside a cloth vertex, in the crease the cloth bridges (an arm vertex in the
// armpit of the arms-lowering t-shirt): above the plane of one triangle around the cloth vertex,
// whose closest point to it is that vertex, but in front of the cloth by the pseudo-normal of the
// triangles around it. The cloth covers it: not a piercing. Lowered by 2 cm, the same fan has the
// apex through it, and that is one.
TEST(BodyCollider, BodyVertexBesideAClothCornerIsSidedByThePseudoNormal) {
  const meshing::TriMesh cone = testing::make_cone(0.1, 0.2, 24);  // apex (0, 0.2, 0)
  const BodyCollider collider(cone);
  // The fan around c = (0.02, 0.2, 0): A rises to +x (away from the apex), B spans over the apex
  // at y = 0.215, C and D close the fan at z = ±0.03.
  const auto fan = [](double dy) {
    Eigen::VectorXd x(15);
    x << 0.02, 0.2 + dy, 0.0,                           // c
        0.05, 0.21 + dy, -0.03, 0.05, 0.21 + dy, 0.03,  // A's far corners
        0.0, 0.215 + dy, -0.03, 0.0, 0.215 + dy, 0.03;  // B's far corners
    return x;
  };
  const Triangles triangles = {{0, 1, 2}, {0, 4, 3}, {0, 2, 4}, {0, 3, 1}};
  const Eigen::VectorXd x = fan(0.0);
  // The premise: the apex is above A's plane, with A's closest point at c.
  const std::optional<BodyPiercing> over_a = collider.piercing_of_pair(x, triangles[0], 0, 0);
  ASSERT_TRUE(over_a.has_value());
  EXPECT_GT(over_a->height, 0.005);
  EXPECT_NEAR(over_a->barycentric[0], 1.0, 1e-12);
  // With the cloth's triangles the pair is sided by the pseudo-normal at c: in front (negative).
  const ClothTriangles cloth(triangles);
  const std::optional<BodyPiercing> sided =
      collider.piercing_of_pair(x, triangles[0], 0, 0, &cloth);
  ASSERT_TRUE(sided.has_value());
  EXPECT_LT(sided->height, -0.002);
  // The search (heights to 1 cm unchecked, as the simulator's reach) finds nothing through.
  EXPECT_TRUE(collider.find_piercings(x, cloth, 0.0, 0.05, 0.01, nullptr, false, true).empty());
  // Over the planes alone (the springs' conservative measure) A reports it.
  EXPECT_EQ(collider.find_piercings(x, cloth, 0.0, 0.05, 0.01).size(), 1u);
  // Lowered 2 cm the apex pokes through the fan (5 mm over B at x = 0): found.
  const std::vector<BodyPiercing> through =
      collider.find_piercings(fan(-0.02), cloth, 0.0, 0.05, 0.03, nullptr, false, true);
  ASSERT_EQ(through.size(), 1u);
  EXPECT_EQ(through.front().body_vertex, 0);
  EXPECT_GT(through.front().height, 0.005);
}

// The simulator's count of body vertices through the cloth (ContactResponse::count_piercing:
// heights over 1 mm, the penetration tolerance, sided by the pseudo-normal, a 1 cm reach taken
// unchecked to 5 mm) on a cloth folded over a body point (the armpit fold of the 2 cm tee,
// docs/collision.md "The piercing count in the armpit fold"): the cone's apex 3 mm through the
// fold's inner layer and 3 mm under its outer one is through the cloth, counted once with the
// inner layer's 3 mm; the same fold lifted 6 mm, the apex 3 mm in front of both layers, is not.
TEST(BodyCollider, BodyVertexThroughOneLayerOfAFoldIsCounted) {
  const BodyCollider collider(testing::make_cone(0.1, 0.2, 24));  // apex (0, 0.2, 0), normal +y
  // Inner layer at y = 0.197 over x in [-0.04, 0.02], folded back at the crease x = 0.02 (edge
  // 1-2) to y = 0.215 at x = -0.04: 3 mm over the apex at x = 0.
  const auto fold = [](double lift) {
    Eigen::VectorXd x(18);
    x << -0.04, 0.197, -0.03, 0.02, 0.197, -0.03, 0.02, 0.197, 0.03, -0.04, 0.197, 0.03,  //
        -0.04, 0.215, -0.03, -0.04, 0.215, 0.03;
    for (int k = 0; k < 6; ++k) x[3 * k + 1] += lift;
    return x;
  };
  const ClothTriangles cloth(Triangles{{0, 1, 2}, {0, 2, 3}, {1, 4, 5}, {1, 5, 2}});
  const auto count = [&](const Eigen::VectorXd& x) {
    return collider.find_piercings(x, cloth, 0.001, 0.01, 0.005, nullptr, false, true);
  };
  const std::vector<BodyPiercing> through = count(fold(0.0));
  ASSERT_EQ(through.size(), 1u);
  EXPECT_EQ(through.front().body_vertex, 0);
  EXPECT_LT(through.front().cloth_triangle, 2);       // the inner layer
  EXPECT_NEAR(through.front().height, 0.003, 1e-12);  // a plane's height: exact to rounding
  EXPECT_TRUE(count(fold(0.006)).empty());
}

TEST(BodyCollider, ClothBeyondAThinBodyPartIsNotAPiercing) {
  // A 1 cm slab; cloth 3 mm under it (a sleeve under the arm): the slab's top corners are
  // 13 mm "in front of" the cloth along their normals, but the cloth does not enter the body.
  const meshing::TriMesh slab = make_box({-0.1, 0.0, -0.1}, {0.1, 0.01, 0.1});
  const BodyCollider collider(slab);
  const std::vector<std::array<int, 3>> triangles = {{0, 1, 2}};
  const Eigen::VectorXd under = flat_triangle(-0.003);
  PiercingQueryStats stats;
  EXPECT_TRUE(collider.find_piercings(under, triangles, 0.0, 0.05, 0.003, &stats).empty());
  EXPECT_GT(stats.pairs, 0);  // candidates were looked at and rejected
  // The same cloth cutting through the middle of the slab (y = 5 mm): all eight corners are
  // 5 mm through it on their own side. (Their closest cloth points lie on the slab's vertical
  // edges, on the surface, so the inside test cannot decide: heights up to 6 mm are taken
  // unchecked here, as the simulator takes heights up to its thickness.)
  const std::vector<BodyPiercing> through =
      collider.find_piercings(flat_triangle(0.005), triangles, 0.0, 0.05, 0.006);
  EXPECT_EQ(through.size(), 8u);
  for (const BodyPiercing& p : through) {
    EXPECT_NEAR(p.height, 0.005, 1e-12);
    // Normal along the corner's side: +y for the top corners, −y for the bottom ones.
    EXPECT_NEAR(p.normal.y(), slab.vertices(p.body_vertex, 1) > 0.0 ? 1.0 : -1.0, 1e-12);
  }
  EXPECT_THROW(collider.find_piercings(under, Triangles{{0, 1, 3}}, 0.0, 0.05),
               std::invalid_argument);
}

TEST(BodyCollider, RejectsUnusableInput) {
  meshing::TriMesh empty;
  EXPECT_THROW(BodyCollider{empty}, InvalidBodyMeshError);
  meshing::TriMesh bad = make_box(Vector3d::Zero(), Vector3d::Ones());
  bad.faces(3, 1) = 8;
  EXPECT_THROW(BodyCollider{bad}, InvalidBodyMeshError);
  BodyCollider box(make_box(Vector3d::Zero(), Vector3d::Ones()));
  EXPECT_THROW(box.set_pose(Eigen::MatrixX3d::Zero(7, 3)), InvalidBodyMeshError);
  EXPECT_THROW(box.find_contacts(Eigen::VectorXd::Zero(4), ContactQuery{}), std::invalid_argument);
  Eigen::VectorXd diverged = Eigen::VectorXd::Zero(6);
  diverged[4] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(box.find_contacts(diverged, ContactQuery{}), std::invalid_argument);
  EXPECT_THROW(box.find_contacts_swept(Eigen::VectorXd::Zero(6), diverged, ContactQuery{}),
               std::invalid_argument);
  EXPECT_TRUE(std::isnan(box.signed_distance(Vector3d(std::nan(""), 0, 0))));
}

}  // namespace
}  // namespace sd::sim
