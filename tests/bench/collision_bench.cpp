// Body collision kernels on the built-in mannequin (4,414 vertices, 8,560 triangles): FCL tree
// build per bounding-volume type, refit, point queries (near the surface and far from it), and
// the per-step contact queries with and without the cache. Numbers in docs/benchmarks.md.

#include <benchmark/benchmark.h>
#include <fcl/fcl.h>

#include <memory>
#include <random>
#include <vector>

#include "garment/body.hpp"
#include "sim/body_collider.hpp"
#include "sim/body_motion.hpp"

namespace {

using Eigen::Vector3d;

const sd::meshing::TriMesh& body() {
  static const sd::meshing::TriMesh mesh = sd::garment::load_body("builtin").mesh;
  return mesh;
}

// Points 0-3 cm outside the skin (a garment's vertices) and points anywhere in a box around the
// figure (most of them far from it).
struct PointSets {
  std::vector<Vector3d> near, far;
};

const PointSets& points() {
  static const PointSets sets = [] {
    PointSets s;
    const sd::meshing::TriMesh& mesh = body();
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int i = 0; i < 20000; ++i) {
      const Eigen::Index f = static_cast<Eigen::Index>(rng() % mesh.face_count());
      double a = u(rng), b = u(rng);
      if (a + b > 1) a = 1 - a, b = 1 - b;
      const Vector3d p0 = mesh.vertices.row(mesh.faces(f, 0)).transpose();
      const Vector3d p1 = mesh.vertices.row(mesh.faces(f, 1)).transpose();
      const Vector3d p2 = mesh.vertices.row(mesh.faces(f, 2)).transpose();
      const Vector3d n = (p1 - p0).cross(p2 - p0).normalized();
      s.near.push_back(p0 + a * (p1 - p0) + b * (p2 - p0) + 0.03 * u(rng) * n);
      s.far.emplace_back(1.2 * u(rng) - 0.6, 1.9 * u(rng), 0.8 * u(rng) - 0.4);
    }
    return s;
  }();
  return sets;
}

Eigen::VectorXd flatten(const std::vector<Vector3d>& p, std::size_t count) {
  Eigen::VectorXd x(3 * count);
  for (std::size_t i = 0; i < count; ++i) x.segment<3>(3 * i) = p[i];
  return x;
}

template <typename BV>
std::shared_ptr<fcl::BVHModel<BV>> build_model() {
  const sd::meshing::TriMesh& mesh = body();
  std::vector<fcl::Vector3d> v;
  for (Eigen::Index i = 0; i < mesh.vertex_count(); ++i)
    v.push_back(mesh.vertices.row(i).transpose());
  std::vector<fcl::Triangle> t;
  for (Eigen::Index i = 0; i < mesh.face_count(); ++i)
    t.emplace_back(mesh.faces(i, 0), mesh.faces(i, 1), mesh.faces(i, 2));
  auto model = std::make_shared<fcl::BVHModel<BV>>();
  model->beginModel();
  model->addSubModel(v, t);
  model->endModel();
  return model;
}

template <typename BV>
void BM_FclBuild(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(build_model<BV>());
}
BENCHMARK_TEMPLATE(BM_FclBuild, fcl::RSSd)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_FclBuild, fcl::OBBRSSd)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_FclBuild, fcl::kIOSd)->Unit(benchmark::kMillisecond);

// FCL's refit after moving every vertex. Arg 0: top-down (what the collider uses), 1: bottom-up
// (faster, but in FCL 0.7 its merged RSS boxes do not contain their children: wrong answers).
template <typename BV>
void BM_FclRefit(benchmark::State& state) {
  auto model = build_model<BV>();
  const sd::meshing::TriMesh& mesh = body();
  const bool bottom_up = state.range(0) == 1;
  int flip = 0;
  for (auto _ : state) {
    const Vector3d shift(0.001 * (flip ^= 1), 0, 0);
    model->beginUpdateModel();
    for (Eigen::Index i = 0; i < mesh.vertex_count(); ++i)
      model->updateVertex(mesh.vertices.row(i).transpose() + shift);
    model->endUpdateModel(true, bottom_up);
  }
}
BENCHMARK_TEMPLATE(BM_FclRefit, fcl::RSSd)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_FclRefit, fcl::OBBRSSd)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_FclRefit, fcl::kIOSd)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// FCL's own distance() with a zero-radius sphere as the point: the baseline the collider's
// traversal replaces. Arg 0: near points, 1: far points.
template <typename BV>
void BM_FclPointDistance(benchmark::State& state) {
  fcl::CollisionObjectd mesh_object(build_model<BV>());
  fcl::CollisionObjectd point(std::make_shared<fcl::Sphered>(0.0));
  const std::vector<Vector3d>& p = state.range(0) == 0 ? points().near : points().far;
  const fcl::DistanceRequestd request(true);
  std::size_t i = 0;
  for (auto _ : state) {
    point.setTranslation(p[i++ % p.size()]);
    point.computeAABB();
    fcl::DistanceResultd result;
    fcl::distance(&mesh_object, &point, request, result);
    benchmark::DoNotOptimize(result.min_distance);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK_TEMPLATE(BM_FclPointDistance, fcl::RSSd)->Arg(0)->Arg(1);
BENCHMARK_TEMPLATE(BM_FclPointDistance, fcl::OBBRSSd)->Arg(0)->Arg(1);
BENCHMARK_TEMPLATE(BM_FclPointDistance, fcl::kIOSd)->Arg(0)->Arg(1);

void BM_ColliderBuild(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(sd::sim::BodyCollider(body()));
}
BENCHMARK(BM_ColliderBuild)->Unit(benchmark::kMillisecond);

// set_pose: FCL refit plus pseudo-normals, with the arms-lowering motion.
void BM_ColliderSetPose(benchmark::State& state) {
  sd::sim::BodyCollider collider(body());
  const sd::sim::PoseSequence motion = sd::sim::make_arm_lowering(body());
  const Eigen::MatrixX3d a = motion.vertices_at(0.4), b = motion.vertices_at(0.45);
  int flip = 0;
  for (auto _ : state) collider.set_pose((flip ^= 1) ? a : b);
}
BENCHMARK(BM_ColliderSetPose)->Unit(benchmark::kMillisecond);

// Signed closest point, unbounded (Arg 0 near, 1 far) or bounded to 1 cm (2 near, 3 far).
void BM_ColliderClosestPoint(benchmark::State& state) {
  const sd::sim::BodyCollider collider(body());
  const std::vector<Vector3d>& p = state.range(0) % 2 == 0 ? points().near : points().far;
  const double bound = state.range(0) >= 2 ? 0.01 : std::numeric_limits<double>::infinity();
  std::size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(collider.closest_point(p[i++ % p.size()], bound));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ColliderClosestPoint)->Arg(0)->Arg(1)->Arg(2)->Arg(3);

// find_contacts over 5,000 points, thickness 5 mm. Arg 0: near set, 1: far set. Arg 2: 0 no
// cache, 1 cache with the points jittering 1 mm per call (a settling garment).
void BM_FindContacts(benchmark::State& state) {
  const sd::sim::BodyCollider collider(body());
  const std::size_t n = 5000;
  const Eigen::VectorXd x0 = flatten(state.range(0) == 0 ? points().near : points().far, n);
  sd::sim::ContactQuery query;
  sd::sim::ContactCache cache;
  const bool cached = state.range(1) == 1;
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> jitter(-0.001, 0.001);
  Eigen::VectorXd x = x0;
  sd::sim::ContactQueryStats stats;
  for (auto _ : state) {
    if (cached)
      for (Eigen::Index k = 0; k < x.size(); ++k) x[k] += jitter(rng);
    benchmark::DoNotOptimize(collider.find_contacts(x, query, cached ? &cache : nullptr, &stats));
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(n));
  state.counters["skipped"] = stats.skipped;
  state.counters["full"] = stats.full_searches;
  state.counters["contacts"] = stats.contacts;
}
BENCHMARK(BM_FindContacts)->Args({0, 0})->Args({0, 1})->Args({1, 0})->Args({1, 1});

// A cloth step against the moving body: move to the next pose of the arms-lowering motion
// (1/24 s steps of a 1 s motion, 6 keyframes) and the swept query for 5,000 near points moving
// 2 mm. Arg 0: set_pose every step (a refit per step); 1: move_body (a refit per keyframe
// segment, boxes bounding the whole segment).
void BM_SweptStep(benchmark::State& state) {
  const bool segments = state.range(0) == 1;
  sd::sim::BodyCollider collider(body());
  const sd::sim::PoseSequence motion = sd::sim::make_arm_lowering(body());
  const std::size_t n = 5000;
  Eigen::VectorXd x = flatten(points().near, n);
  sd::sim::ContactQuery query;
  sd::sim::ContactCache cache;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-0.002, 0.002);
  int step = 0;
  sd::sim::ContactQueryStats stats;
  for (auto _ : state) {
    const double t1 = (step++ % 24 + 1) / 24.0;
    if (segments)
      sd::sim::move_body(collider, motion, t1 - 1.0 / 24.0, t1);
    else
      collider.set_pose(motion.vertices_at(t1), motion.average_velocity(t1 - 1.0 / 24.0, t1));
    const Eigen::VectorXd x0 = x;
    for (Eigen::Index k = 0; k < x.size(); ++k) x[k] += jitter(rng);
    benchmark::DoNotOptimize(collider.find_contacts_swept(x0, x, query, &cache, &stats));
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(n));
  state.counters["samples"] = stats.sweep_samples;
  state.counters["skipped"] = stats.skipped;
  state.counters["contacts"] = stats.contacts;
  state.counters["refits_per_step"] = static_cast<double>(collider.refit_count()) / step;
}
BENCHMARK(BM_SweptStep)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
