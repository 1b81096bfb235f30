// Self-contact response: the fail-safe leaves no colliding path and conserves momentum, and a
// simulated fold comes to rest on itself without passing through (with and without a body).

#include "sim/self_contact.hpp"

#include <gtest/gtest.h>

#include "sim/simulation.hpp"
#include "tests/sim/self_contact_helpers.hpp"
#include "tests/sim/test_bodies.hpp"
#include "tests/sim/test_scenes.hpp"

namespace sd::sim {
namespace {

ClothModel folded_model(const testing::FoldedSheet& flat) {
  ClothInput input;
  const Eigen::Index n = flat.x.size() / 3;
  input.rest_positions.resize(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) input.rest_positions.row(i) = flat.x.segment<3>(3 * i);
  input.triangles.resize(static_cast<Eigen::Index>(flat.triangles.size()), 3);
  for (std::size_t t = 0; t < flat.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k)
      input.triangles(static_cast<Eigen::Index>(t), k) = flat.triangles[t][k];
  return build_cloth_model(input, fabric_preset("cotton"));
}

TEST(SelfContactResponse, FailSafeLeavesNoCollisionAndKeepsMomentum) {
  const testing::FoldedSheet sheet = testing::folded_sheet(6, 0.3, 0.01);
  const ClothModel model = folded_model(testing::folded_sheet(6, 0.3, -1.0));
  Eigen::VectorXd x1 = sheet.x;
  for (int i = 0; i < model.vertex_count; ++i)
    // the far part of the upper layer 2 cm through the lower one, the rest sloping through it
    if (sheet.upper[i] && sheet.x[3 * i] < -0.1) x1[3 * i + 1] -= 0.03;
  ASSERT_GT(testing::count_intersecting_pairs(sheet.triangles, x1), 0);
  SelfContactSettings settings;
  settings.enabled = true;
  SelfContactResponse response(settings);
  response.set_cloth(model, sheet.x);
  Eigen::VectorXd v1 = (x1 - sheet.x) / 0.01;
  const Eigen::VectorXd before = x1;
  response.resolve(sheet.x, x1, v1, 0.01, model.mass, {}, StepForces{});
  EXPECT_GT(response.step_stats().collisions, 0);
  EXPECT_FALSE(response.step_stats().unresolved);
  SelfCollider check(sheet.triangles, sheet.x);
  check.set_culling(false);
  EXPECT_TRUE(check.find_collisions(sheet.x, x1, 1e-7).empty());
  EXPECT_EQ(testing::count_intersecting_pairs(sheet.triangles, x1), 0);
  // Impulses and rigid zones are internal: total momentum does not change.
  Eigen::Vector3d momentum = Eigen::Vector3d::Zero();
  for (int i = 0; i < model.vertex_count; ++i)
    momentum += model.mass[i] * (x1 - before).segment<3>(3 * i);
  EXPECT_LT(momentum.norm(), 1e-12 * model.total_mass());
  // v1 follows x1: x1 = x0 + β v1.
  EXPECT_LT((sheet.x + 0.01 * v1 - x1).lpNorm<Eigen::Infinity>(), 1e-12);
}

// Friction between layers: a vertex of the upper layer of a fold sliding at 0.1 m/s over the lower
// layer, pressed by one repulsion spring of force F. Coulomb: the pair's relative tangential
// velocity drops by μ β F Σ w²/m (the impulse bound), or to zero when that is more; the normal
// velocity and the total momentum do not change.
TEST(SelfContactResponse, FrictionBetweenLayersIsCoulombsBound) {
  const testing::FoldedSheet sheet = testing::folded_sheet(6, 0.3, 0.01);
  const ClothModel model = folded_model(testing::folded_sheet(6, 0.3, -1.0));
  const double beta = 0.01;
  for (const double mu : {0.3, 1e6}) {
    SelfContactSettings settings;
    settings.enabled = true;
    settings.friction = mu;
    SelfContactResponse response(settings);
    response.set_cloth(model, sheet.x);
    SelfPair pair;
    bool found = false;
    for (const SelfPair& p : response.collider().find_proximities(sheet.x, 0.015))
      if (p.kind == SelfPairKind::vertex_face && sheet.upper[p.vertices[0]]) {
        pair = p;
        found = true;
        break;
      }
    ASSERT_TRUE(found);
    const int vertex = pair.vertices[0];
    // Sliding along a direction in the layer's plane.
    Eigen::Vector3d along = pair.normal.cross(Eigen::Vector3d::UnitZ());
    if (along.norm() < 0.5) along = pair.normal.cross(Eigen::Vector3d::UnitX());
    along.normalize();
    Eigen::VectorXd v1 = Eigen::VectorXd::Zero(sheet.x.size());
    v1.segment<3>(3 * vertex) = 0.1 * along;
    Eigen::VectorXd x1 = sheet.x + beta * v1;
    StepForces extra;
    PairSpring spring;
    spring.vertices = pair.vertices;
    spring.weights = pair.weights;
    spring.normal = pair.normal;
    spring.target = pair.distance + 0.001;
    spring.stiffness = 1.0;  // N/m: a 1 mm push, F ≈ 1 mN
    extra.pair_springs.push_back(spring);
    const double force = spring.stiffness * (spring.target - along_pair_normal(spring, x1));
    ASSERT_GT(force, 0.0);
    double inverse = 0.0;
    for (int k = 0; k < 4; ++k)
      inverse += pair.weights[k] * pair.weights[k] / model.mass[pair.vertices[k]];
    const double bound = mu * beta * force * inverse;
    const Eigen::VectorXd v_before = v1;
    response.resolve(sheet.x, x1, v1, beta, model.mass, {}, extra);
    EXPECT_EQ(response.step_stats().collisions, 0);
    Eigen::Vector3d relative = Eigen::Vector3d::Zero(), momentum = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) relative += pair.weights[k] * v1.segment<3>(3 * pair.vertices[k]);
    for (int i = 0; i < model.vertex_count; ++i)
      momentum += model.mass[i] * (v1 - v_before).segment<3>(3 * i);
    const double expected = std::max(0.0, 0.1 - bound);
    EXPECT_NEAR(relative.dot(along), expected, 1e-12);
    EXPECT_NEAR(relative.dot(pair.normal), 0.0, 1e-12);
    EXPECT_LT(momentum.norm(), 1e-15);
    if (mu < 1.0) {
      EXPECT_GT(bound, 1e-3);  // the premise: friction slows the slide, without stopping it
      EXPECT_LT(bound, 0.1);
    }
    // x1 follows v1.
    EXPECT_LT((sheet.x + beta * v1 - x1).lpNorm<Eigen::Infinity>(), 1e-15);
  }
}

TEST(SelfContactResponse, UntangleSeparatesAStartThatPassesThroughItself) {
  // The far part of the upper layer of a fold pushed 2 cm through the lower layer.
  const testing::FoldedSheet sheet = testing::folded_sheet(6, 0.3, 0.01);
  const ClothModel model = folded_model(testing::folded_sheet(6, 0.3, -1.0));
  Eigen::VectorXd x = sheet.x;
  for (int i = 0; i < model.vertex_count; ++i)
    if (sheet.upper[i] && sheet.x[3 * i] < -0.1) x[3 * i + 1] -= 0.03;
  const int before = testing::count_intersecting_pairs(sheet.triangles, x);
  ASSERT_GT(before, 0);
  SelfContactSettings settings;
  settings.enabled = true;
  SelfContactResponse response(settings);
  response.set_cloth(model, x);
  // The tree's own test finds at least the pairs the brute-force count finds (it also counts
  // pairs that share a vertex).
  EXPECT_GE(static_cast<int>(response.collider().find_intersections(x).size()), before);
  int found = 0, remaining = -1;
  const int moved = response.untangle(model, x, {}, &found, &remaining);
  EXPECT_GE(found, before);
  EXPECT_EQ(remaining, 0);
  EXPECT_GT(moved, 0);
  EXPECT_EQ(testing::count_intersecting_pairs(sheet.triangles, x), 0);
  EXPECT_TRUE(response.collider().find_intersections(x).empty());
  // A clean start is left alone.
  Eigen::VectorXd clean = sheet.x;
  response.set_cloth(model, clean);
  EXPECT_EQ(response.untangle(model, clean, {}, &found, &remaining), 0);
  EXPECT_EQ(found, 0);
  EXPECT_EQ(clean, sheet.x);
}

struct FoldRun {
  SimulationReport report;
  Eigen::VectorXd x;
  int path_collisions = 0;  // colliding paths between consecutive accepted states
};

// The upper layer of a fold falls 2 cm onto the lower one, which is pinned flat like a table.
FoldRun run_fold(bool self_collision, double duration) {
  const testing::FoldedSheet sheet = testing::folded_sheet(8, 0.3, 0.02);
  ClothModel model = folded_model(testing::folded_sheet(8, 0.3, -1.0));
  std::vector<Pin> pins;
  for (int i = 0; i < model.vertex_count; ++i)
    if (!sheet.upper[i]) pins.push_back({i, {}});
  SimulationSettings settings;
  settings.duration = duration;
  settings.stop_at_rest = false;
  settings.self_contact.enabled = self_collision;
  Simulation simulation(std::move(model), sheet.x, std::move(pins), settings);
  FoldRun run;
  SelfCollider check(sheet.triangles, sheet.x);
  check.set_culling(false);
  Eigen::VectorXd previous = sheet.x;
  run.report = simulation.run([&](const Simulation& s) {
    run.path_collisions +=
        static_cast<int>(check.find_collisions(previous, s.positions(), 1e-7).size());
    previous = s.positions();
  });
  run.x = simulation.positions();
  return run;
}

TEST(SelfContactSimulation, FoldRestsOnItselfInsteadOfPassingThrough) {
  const testing::FoldedSheet sheet = testing::folded_sheet(8, 0.3, 0.02);
  const FoldRun off = run_fold(false, 0.5);
  // Premise: without self-contact the upper layer falls through the lower one.
  ASSERT_GT(off.path_collisions, 0);
  EXPECT_LT(off.x[off.x.size() - 2], 0.0);  // the far corner of the upper layer hangs below
  const FoldRun on = run_fold(true, 1.0);
  EXPECT_FALSE(on.report.failed);
  EXPECT_EQ(on.path_collisions, 0);
  EXPECT_EQ(testing::count_intersecting_pairs(sheet.triangles, on.x), 0);
  EXPECT_GT(on.report.self_contacts_max, 0);
  EXPECT_EQ(on.report.self_unresolved_steps, 0);
  // The upper layer has landed on the lower one: every upper vertex away from the crease is
  // above y = 0, and they lie within the thickness (2 mm) on average, not at the 2 cm they fell
  // from, and above the fail-safe's landing separation (a tenth of the thickness): the springs
  // hold them (measured 0.59 mm: each spring pushes a tenth of the way per step against gravity).
  double mean = 0.0;
  int count = 0;
  for (int i = 0; i < static_cast<int>(sheet.upper.size()); ++i) {
    if (!sheet.upper[i] || sheet.x[3 * i] > -0.1) continue;
    EXPECT_GT(on.x[3 * i + 1], 0.0) << "vertex " << i;
    mean += on.x[3 * i + 1];
    ++count;
  }
  mean /= count;
  EXPECT_GT(mean, 0.0003);
  EXPECT_LT(mean, 0.002);
}

TEST(SelfContactSimulation, SheetOnASphereWithBodyAndSelfContact) {
  // A 0.5 m sheet dropped on a 6 cm ball: its sides hang and fold against each other while the
  // ball holds its middle. Both contacts at once.
  testing::SheetSetup s = testing::horizontal_sheet(16, 0.5, Eigen::Vector3d(0, 0.08, 0));
  SimulationSettings settings;
  settings.duration = 0.8;
  settings.stop_at_rest = false;
  settings.self_contact.enabled = true;
  Simulation simulation(s.model, flatten_positions(s.scene.input.rest_positions), {}, settings);
  simulation.set_body(testing::make_sphere(0.06, 3));
  std::vector<std::array<int, 3>> triangles;
  for (const TriangleElement& t : s.model.triangles) triangles.push_back(t.vertices);
  const SimulationReport report = simulation.run();
  EXPECT_FALSE(report.failed);
  EXPECT_EQ(report.self_unresolved_steps, 0);
  EXPECT_EQ(testing::count_intersecting_pairs(triangles, simulation.positions()), 0);
  EXPECT_LE(report.max_penetration_m, settings.contact.penetration_tolerance + 1e-9);
}

}  // namespace
}  // namespace sd::sim
