// Self-contact response: the fail-safe leaves no colliding path and conserves momentum, and a
// simulated fold comes to rest on itself without passing through (with and without a body).

#include "sim/self_contact.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "sim/forces.hpp"
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

// The fail-safe's landing: a layer that starts the step 0.1 mm above another (closer than the
// landing separation, a tenth of the 2 mm thickness) and is driven 1 mm through it lands where it
// started (inelastic, no lift to 0.2 mm): lifted, a resting layer fell back within a step and was
// lifted again, a cycle that kept the t-shirt's underarm moving.
TEST(SelfContactResponse, FailSafeLandsAPairThatStartedCloseWhereItStarted) {
  const double gap = 1.0e-4;
  const testing::FoldedSheet sheet = testing::folded_sheet(6, 0.3, gap);
  const ClothModel model = folded_model(testing::folded_sheet(6, 0.3, -1.0));
  std::vector<unsigned char> pinned(static_cast<std::size_t>(model.vertex_count), 0);
  for (int i = 0; i < model.vertex_count; ++i) pinned[i] = sheet.upper[i] ? 0 : 1;
  Eigen::VectorXd x1 = sheet.x;
  for (int i = 0; i < model.vertex_count; ++i)
    if (sheet.upper[i]) x1[3 * i + 1] -= 0.001;
  SelfContactSettings settings;
  settings.enabled = true;
  SelfContactResponse response(settings);
  response.set_cloth(model, sheet.x);
  Eigen::VectorXd v1 = (x1 - sheet.x) / 0.01;
  response.resolve(sheet.x, x1, v1, 0.01, model.mass, pinned, StepForces{});
  EXPECT_GT(response.step_stats().collisions, 0);
  EXPECT_FALSE(response.step_stats().unresolved);
  EXPECT_EQ(testing::count_intersecting_pairs(sheet.triangles, x1), 0);
  for (int i = 0; i < model.vertex_count; ++i) {
    if (!sheet.upper[i] || sheet.x[3 * i] > -0.1) continue;
    EXPECT_NEAR(x1[3 * i + 1], gap, 1e-9) << "vertex " << i;  // where it started, not 0.2 mm
    EXPECT_NEAR(v1[3 * i + 1], 0.0, 1e-7) << "vertex " << i;  // and at rest along the normal
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

// The untangling's strain bound: a round of smoothing that would stretch a triangle past the
// bound is undone and the untangling stops, leaving pairs. Unbounded, smoothing the sliver quads
// of a crumpled sleeve stretched it by 761 % and every first step of the drape was rejected down
// to the minimum step (docs/collision.md, "An untangled start").
TEST(SelfContactResponse, UntangleStopsBeforeStretchingPastItsBound) {
  const testing::FoldedSheet sheet = testing::folded_sheet(6, 0.3, 0.01);
  const ClothModel model = folded_model(testing::folded_sheet(6, 0.3, -1.0));
  Eigen::VectorXd start = sheet.x;
  for (int i = 0; i < model.vertex_count; ++i)
    if (sheet.upper[i] && sheet.x[3 * i] < -0.1) start[3 * i + 1] -= 0.03;
  SelfContactSettings settings;
  settings.enabled = true;
  const double designed = max_stretch_strain(model, start);
  // Unbounded: separated, with more stretch than the start had.
  Eigen::VectorXd free = start;
  SelfContactResponse unbounded(settings);
  unbounded.set_cloth(model, free);
  int found = 0, remaining = -1;
  ASSERT_GT(unbounded.untangle(model, free, {}, &found, &remaining), 0);
  ASSERT_EQ(remaining, 0);
  const double stretched = max_stretch_strain(model, free);
  ASSERT_GT(stretched, designed + 1e-3);
  // Bounded halfway between: never past the bound, and pairs are left where it stopped.
  const double bound = 0.5 * (designed + stretched);
  Eigen::VectorXd x = start;
  SelfContactResponse bounded(settings);
  bounded.set_cloth(model, x);
  Eigen::Vector3d where = Eigen::Vector3d::Constant(-1.0);
  bounded.untangle(model, x, {}, &found, &remaining, bound, &where);
  EXPECT_LE(max_stretch_strain(model, x), bound);
  EXPECT_GT(remaining, 0);
  EXPECT_EQ(remaining, static_cast<int>(bounded.collider().find_intersections(x).size()));
  // The place of a pair left lies on the pushed part of the upper layer (x < -0.1 m, 3 cm down).
  EXPECT_LT(where.x(), -0.05);
  // A bound below the start's own strain keeps the start's as the bound: it still untangles.
  Eigen::VectorXd y = start;
  SelfContactResponse below(settings);
  below.set_cloth(model, y);
  below.untangle(model, y, {}, &found, &remaining, 0.0);
  EXPECT_LE(max_stretch_strain(model, y), std::max(designed, 0.0) + 1e-12);
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

// A square sheet of side `size` with `quads` quads a side, centred at `centre` in the plane of
// the unit vectors `along` and `across`, appended to `input`.
void add_sheet(ClothInput& input, int quads, double size, const Eigen::Vector3d& centre,
               const Eigen::Vector3d& along, const Eigen::Vector3d& across) {
  const Eigen::Index first = input.rest_positions.rows();
  const int side = quads + 1;
  input.rest_positions.conservativeResize(first + side * side, 3);
  for (int i = 0; i < side; ++i)
    for (int j = 0; j < side; ++j)
      input.rest_positions.row(first + i * side + j) =
          (centre + (size * (static_cast<double>(i) / quads - 0.5)) * along +
           (size * (static_cast<double>(j) / quads - 0.5)) * across)
              .transpose();
  const Eigen::Index triangles = input.triangles.rows();
  input.triangles.conservativeResize(triangles + 2 * quads * quads, 3);
  Eigen::Index t = triangles;
  for (int i = 0; i < quads; ++i)
    for (int j = 0; j < quads; ++j) {
      const int a = static_cast<int>(first) + i * side + j, b = a + side;
      input.triangles.row(t++) << a, b, a + 1;
      input.triangles.row(t++) << a + 1, b, b + 1;
    }
}

struct Slide {
  double start = 0.0;     // m: the upper sheet's mean position along the slope at `early`
  double end = 0.0;       // m: at the end
  double v_early = 0.0;   // m/s: mean velocity along the slope at `early`
  double v_end = 0.0;     // m/s: at the end
  int intersections = 0;  // intersecting triangle pairs at the end
};

// A 0.1 m cotton square lies 1 mm above a pinned 1 m square (within the 2 mm thickness), both
// tilted θ = 20° about z; gravity pulls it down the slope. Air drag off: friction between the
// layers is the only tangential force on the upper sheet's centre of mass.
Slide slide_on_incline(double mu, double duration, double early) {
  const double theta = 20.0 * M_PI / 180.0;
  const Eigen::Vector3d down(std::cos(theta), -std::sin(theta), 0.0);  // down the slope
  const Eigen::Vector3d normal(std::sin(theta), std::cos(theta), 0.0);
  const Eigen::Vector3d across = Eigen::Vector3d::UnitZ();
  ClothInput input;
  input.rest_positions.resize(0, 3);
  input.triangles.resize(0, 3);
  // The lower sheet is one quad: the upper sheet's vertices stay over one triangle's interior
  // (on a fine lower mesh, a vertex near an element's edge also meets the neighbour's edge along
  // a tilted normal, and those springs push against the slide: docs/collision.md).
  add_sheet(input, 1, 1.0, Eigen::Vector3d::Zero(), down, across);
  const int lower = static_cast<int>(input.rest_positions.rows());
  // Turned 30° in its plane: no edge of one sheet parallel to an edge of the other (parallel
  // edges a millimetre apart push each other sideways along the line between them).
  const double turn = 30.0 * M_PI / 180.0;
  add_sheet(input, 4, 0.1, -0.35 * down - 0.25 * across + 0.001 * normal,
            std::cos(turn) * down + std::sin(turn) * across,
            -std::sin(turn) * down + std::cos(turn) * across);
  ClothModel model = build_cloth_model(input, fabric_preset("cotton"));
  std::vector<Pin> pins;
  for (int i = 0; i < lower; ++i) pins.push_back({i, {}});
  SimulationSettings settings;
  settings.duration = duration;
  settings.stop_at_rest = false;
  settings.forces.air_drag = 0.0;
  settings.self_contact.enabled = true;
  settings.self_contact.friction = mu;
  const int n = model.vertex_count;
  Simulation simulation(std::move(model), flatten_positions(input.rest_positions), std::move(pins),
                        settings);
  const auto mean_along = [&](const Eigen::VectorXd& y) {
    double sum = 0.0;
    for (int i = lower; i < n; ++i) sum += down.dot(y.segment<3>(3 * i));
    return sum / (n - lower);
  };
  Slide slide;
  bool seen_early = false;
  simulation.run([&](const Simulation& s) {
    if (!seen_early && s.time() >= early - 1e-9) {
      seen_early = true;
      slide.start = mean_along(s.positions());
      slide.v_early = mean_along(s.velocities());
    }
  });
  slide.end = mean_along(simulation.positions());
  slide.v_end = mean_along(simulation.velocities());
  std::vector<std::array<int, 3>> triangles;
  for (Eigen::Index t = 0; t < input.triangles.rows(); ++t)
    triangles.push_back({input.triangles(t, 0), input.triangles(t, 1), input.triangles(t, 2)});
  // The collider's own test: the tilted flat sheet's coplanar neighbours are not intersections.
  SelfCollider check(triangles, simulation.positions());
  slide.intersections = static_cast<int>(check.find_intersections(simulation.positions()).size());
  return slide;
}

// Friction between layers acts inside the solve. Above tan θ (μ = 0.6 > tan 20° = 0.36) the
// upper sheet sticks: from 0.1 s (after it has settled onto the lower one) to 0.6 s it moves
// less than 1 mm down the slope, where sliding freely it would move 0.42 m; the regularised
// Coulomb law lets a sticking pair creep at most ε tanθ/μ = 0.6 mm/s, 0.3 mm in 0.5 s. Below it
// (μ = 0.1) the sheet slides with Coulomb's acceleration g (sin θ − μ cos θ) = 2.43 m/s², measured
// between 0.1 s and 0.4 s from the mean velocity along the slope, within 5 %.
TEST(SelfContactSimulation, LayerSticksOrSlidesOnAnInclineByCoulombsLaw) {
  const double theta = 20.0 * M_PI / 180.0, g = 9.81;
  const Slide stick = slide_on_incline(0.6, 0.6, 0.1);
  EXPECT_LT(std::abs(stick.end - stick.start), 1e-3);
  EXPECT_LT(std::abs(stick.v_end), 5e-3);
  EXPECT_EQ(stick.intersections, 0);
  const Slide slide = slide_on_incline(0.1, 0.4, 0.1);
  const double expected = g * (std::sin(theta) - 0.1 * std::cos(theta));
  const double measured = (slide.v_end - slide.v_early) / 0.3;
  EXPECT_NEAR(measured, expected, 0.05 * expected);
  EXPECT_EQ(slide.intersections, 0);
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
