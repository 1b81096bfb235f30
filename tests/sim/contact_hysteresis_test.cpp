// Catching and releasing body contacts (ContactSettings::contact_hysteresis): a sheet lying on a
// box stays caught, step after step, without a single switch; a sheet whose edge is lifted off
// the box has each contact released exactly at the step after its constraint force turned
// adhesive (pulled the vertex towards the body by more than a tenth of its weight), never
// before. And the body-vertex springs' band (ContactSettings::spring_band, off by default):
// a sheet on a sphere with the check stays outside and comes to rest. And the springs' fading push
// (ContactSettings::fade_carried_push): a spring leaves its hold carrying no push, and a hammock
// caught on a cone tip gains no energy.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>
#include <vector>

#include "sim/body_collider.hpp"
#include "sim/contact_response.hpp"
#include "sim/sheet.hpp"
#include "sim/simulation.hpp"
#include "test_bodies.hpp"
#include "test_scenes.hpp"

namespace sd::sim {
namespace {

using Eigen::Vector3d;
using testing::horizontal_sheet;
using testing::SheetSetup;

constexpr double kThickness = 0.003;      // m
constexpr double kReleaseFraction = 0.1;  // of the vertex's weight (sim/contact_response.cpp)

SimulationSettings box_settings(double duration) {
  SimulationSettings settings;
  settings.dt = 1.0 / 60.0;
  settings.solver = LinearSolverKind::cholmod;
  settings.duration = duration;
  settings.stop_at_rest = false;
  settings.contact.thickness = kThickness;
  settings.contact.penetration_tolerance = 0.001;
  return settings;
}

// Box top at y = 0, wider than the sheets.
meshing::TriMesh table() {
  return testing::make_box({-0.5, -0.2, -0.5}, {0.5, 0.0, 0.5});
}

// Per vertex: 1 when its contact was constrained (held, not released) in the last step.
std::vector<unsigned char> held_vertices(const ContactResponse& contact, int n) {
  std::vector<unsigned char> held(static_cast<std::size_t>(n), 0);
  for (const ActiveContact& a : contact.contacts())
    if (!a.released && !a.repair) held[static_cast<std::size_t>(a.contact.vertex)] = 1;
  return held;
}

TEST(ContactHysteresis, SheetLyingOnABoxStaysCaughtWithoutASwitch) {
  // 9×9 vertices placed at the thickness on the top: every one is caught at the first step and
  // must stay caught (its constraint pushes: it carries its weight) for 1.5 s, 90 steps.
  const SheetSetup s = horizontal_sheet(8, 0.3, {0.0, kThickness, 0.0});
  const int n = s.model.vertex_count;
  Simulation sim(s.model, flatten_positions(s.scene.input.rest_positions), {}, box_settings(1.5));
  sim.set_body(table());
  int steps = 0, switches = 0, released = 0, fewest_held = n;
  std::vector<unsigned char> last;
  const SimulationReport report = sim.run([&](const Simulation& step) {
    const std::vector<unsigned char> held = held_vertices(*step.contact(), n);
    if (!last.empty())
      for (int i = 0; i < n; ++i) switches += held[i] != last[i];
    released += step.contact()->step_stats().released;
    fewest_held = std::min(fewest_held, static_cast<int>(std::count(held.begin(), held.end(), 1)));
    last = held;
    ++steps;
  });
  std::printf("sheet on a box: %d steps, %d switches, %d released, fewest held %d of %d\n", steps,
              switches, released, fewest_held, n);
  EXPECT_FALSE(report.failed);
  EXPECT_GE(steps, 89);
  EXPECT_EQ(switches, 0);
  EXPECT_EQ(released, 0);
  EXPECT_EQ(fewest_held, n);
  // Held at the thickness, where it was put.
  for (int i = 0; i < n; ++i) EXPECT_NEAR(sim.positions()[3 * i + 1], kThickness, 1e-4) << i;
}

TEST(ContactHysteresis, ContactIsReleasedExactlyWhenItsForceTurnsAdhesive) {
  // A sheet lying on the box; from 0.2 s its first row is lifted at 0.2 m/s. Row by row the
  // cloth peels off: each contact must be released at the step after the one whose constraint
  // pulled its vertex onto the box by more than a tenth of its weight, and at no other step.
  const SheetSetup s = horizontal_sheet(8, 0.3, {0.0, kThickness, 0.0});
  const int n = s.model.vertex_count;
  const Eigen::VectorXd x0 = flatten_positions(s.scene.input.rest_positions);
  std::vector<Pin> pins;
  for (int c = 0; c <= 8; ++c) {
    const int i = s.scene.vertex(0, c);
    const Vector3d start = x0.segment<3>(3 * i);
    pins.push_back({i, [start](double t) {
                      return Vector3d(start + Vector3d(0.0, 0.2 * std::max(t - 0.2, 0.0), 0.0));
                    }});
  }
  SimulationSettings settings = box_settings(1.0);
  Simulation sim(s.model, x0, pins, settings);
  sim.set_body(table());
  const double g = settings.forces.gravity.norm();
  std::vector<unsigned char> last_held;
  std::vector<double> last_force;
  int releases = 0, checked = 0, wrong = 0;
  const SimulationReport report = sim.run([&](const Simulation& step) {
    const ContactResponse& contact = *step.contact();
    if (!last_held.empty()) {
      for (const ActiveContact& a : contact.contacts()) {
        const int i = a.contact.vertex;
        if (a.repair || !last_held[i]) continue;
        const bool adhesive = last_force[i] < -kReleaseFraction * s.model.mass[i] * g;
        ++checked;
        if (a.released != adhesive) {
          ++wrong;
          ADD_FAILURE() << "t " << step.time() << " vertex " << i << " force " << last_force[i]
                        << " N, released " << a.released;
        }
        releases += a.released;
      }
    }
    last_held = held_vertices(contact, n);
    last_force = contact.last_normal_forces();
  });
  std::printf("peeling: %d held contacts checked, %d released, %d wrong\n", checked, releases,
              wrong);
  EXPECT_FALSE(report.failed);
  EXPECT_GT(releases, 9);  // more than the row next to the lifted one
  EXPECT_GT(checked, 1000);
}

TEST(ContactHysteresis, SpringBandKeepsTheSphereSheetOutsideAndComesToRest) {
  // The sheet of ContactResponsePiercing.SheetOnASphereStaysOutsideWithTheCheck, with the band:
  // nothing through the sphere (independent collider) and at rest. Measured: at rest at 6.33 s
  // (2.13 s without the band, which is why it is off by default), no change of the spring count
  // in the last 0.5 s, 65 springs at the end. The limit was 6 s until the quadratic bending's
  // wider rows took the nearest points of the two-ring (issue 21; at rest at 4.72-4.85 s with
  // the whole two-ring's rows): the same sheet settles later, not through the sphere.
  const meshing::TriMesh sphere = testing::make_sphere(0.2, 3);
  const BodyCollider check_body(sphere);
  const SheetSetup s = horizontal_sheet(16, 0.6, {0.0, 0.25, 0.0});
  SimulationSettings settings = box_settings(8.0);
  settings.stop_at_rest = true;
  settings.forces.air_drag = 0.3;
  settings.contact.check_body_vertices = true;
  settings.contact.spring_band = true;
  Simulation sim(s.model, flatten_positions(s.scene.input.rest_positions), {}, settings);
  sim.set_body(sphere);
  double deepest = 0.0;
  std::vector<std::pair<double, int>> springs;  // (time, springs held at the step's start)
  const SimulationReport r = sim.run([&](const Simulation& step) {
    springs.emplace_back(step.time(), step.contact()->step_stats().piercings_held);
    for (Eigen::Index i = 0; i < step.positions().size() / 3; ++i)
      deepest = std::max(deepest, -check_body.signed_distance(step.positions().segment<3>(3 * i)));
  });
  int switches = 0;
  for (std::size_t k = 1; k < springs.size(); ++k)
    if (springs[k].first > r.sim_time - 0.5) switches += springs[k].second != springs[k - 1].second;
  std::printf(
      "sphere with the band: at rest %d at %.2f s, deepest %.3f mm, %d spring switches in "
      "the last 0.5 s, %d springs at the end\n",
      r.at_rest, r.sim_time, 1e3 * deepest, switches, springs.back().second);
  EXPECT_FALSE(r.failed);
  EXPECT_LE(deepest, settings.contact.penetration_tolerance);
  EXPECT_TRUE(r.at_rest);
}

// A sheet squeezed between a table and a lid 1.5 thicknesses above it (ContactSettings::
// pinch_budget): each side's contact keeps a third of the gap, 1.5 mm, so the sheet settles on
// the table's band and stays clear of the lid's, at rest with no contact switching. Without the
// budget a vertex pushed to the table's thickness (3 mm) is inside the lid's band (1.5 mm from
// it), is caught by the lid and pushed back, step after step.
TEST(ContactHysteresis, SheetPinchedBetweenTwoBodyPartsKeepsAThirdOfTheGapEach) {
  const double gap = 1.5 * kThickness;
  meshing::TriMesh body = table();
  const meshing::TriMesh lid = testing::make_box({-0.5, gap, -0.5}, {0.5, gap + 0.2, 0.5});
  const Eigen::Index table_vertices = body.vertices.rows();
  body.vertices.conservativeResize(table_vertices + lid.vertices.rows(), 3);
  body.vertices.bottomRows(lid.vertices.rows()) = lid.vertices;
  const Eigen::Index table_faces = body.faces.rows();
  body.faces.conservativeResize(table_faces + lid.faces.rows(), 3);
  body.faces.bottomRows(lid.faces.rows()) = lid.faces.array() + static_cast<int>(table_vertices);
  for (const bool budget : {false, true}) {
    const SheetSetup s = horizontal_sheet(8, 0.3, {0.0, 0.5 * gap, 0.0});
    const int n = s.model.vertex_count;
    SimulationSettings settings = box_settings(2.0);
    settings.stop_at_rest = true;
    settings.contact.pinch_budget = budget;
    Simulation sim(s.model, flatten_positions(s.scene.input.rest_positions), {}, settings);
    sim.set_body(body);
    int switches = 0;
    double lowest = gap, highest = 0.0;
    std::vector<unsigned char> last;
    const SimulationReport report = sim.run([&](const Simulation& step) {
      const std::vector<unsigned char> held = held_vertices(*step.contact(), n);
      // After the fall onto the table's band (0.75 mm, 12 ms).
      if (!last.empty() && step.time() > 0.1)
        for (int i = 0; i < n; ++i) switches += held[i] != last[i];
      last = held;
      if (step.time() <= 0.1) return;
      for (int i = 0; i < n; ++i) {
        lowest = std::min(lowest, step.positions()[3 * i + 1]);
        highest = std::max(highest, step.positions()[3 * i + 1]);
      }
    });
    std::printf(
        "pinched sheet, budget %s: at rest %d at %.2f s, %d switches after 0.1 s, heights "
        "%.3f-%.3f mm (gap %.1f mm)\n",
        budget ? "on" : "off", report.at_rest, report.sim_time, switches, 1e3 * lowest,
        1e3 * highest, 1e3 * gap);
    EXPECT_FALSE(report.failed);
    if (!budget) {
      // The cycle the budget ends (measured: 6,156 switches of 81 vertices from 0.1 s to 2 s,
      // heights 0.3-3.0 mm).
      EXPECT_GT(switches, 100);
      EXPECT_FALSE(report.at_rest);
      continue;
    }
    EXPECT_TRUE(report.at_rest);
    EXPECT_GT(report.sim_time, 0.1);
    EXPECT_EQ(switches, 0);
    // On the table's band (a third of the gap), never inside the lid's.
    EXPECT_GT(lowest, gap / 3.0 - 1e-4);
    EXPECT_LT(highest, 2.0 * gap / 3.0);
  }
}

// Two bodies as one mesh (the second's faces renumbered after the first's vertices).
meshing::TriMesh merged(const meshing::TriMesh& a, const meshing::TriMesh& b) {
  meshing::TriMesh mesh = a;
  const Eigen::Index vertices = a.vertices.rows(), faces = a.faces.rows();
  mesh.vertices.conservativeResize(vertices + b.vertices.rows(), 3);
  mesh.vertices.bottomRows(b.vertices.rows()) = b.vertices;
  mesh.faces.conservativeResize(faces + b.faces.rows(), 3);
  mesh.faces.bottomRows(b.faces.rows()) = b.faces.array() + static_cast<int>(vertices);
  return mesh;
}

// The distance each start contact keeps its vertex from the body (m, per vertex; NaN for a
// vertex without one) when the cloth `model` is at x and still: the vertex's distance plus the
// position correction constrain_start gives it along the contact's normal (the body does not
// move, so the correction lands the vertex exactly at its contact's thickness).
std::vector<double> kept_distances(const meshing::TriMesh& body, const ContactSettings& settings,
                                   const ClothModel& model, const Eigen::VectorXd& x) {
  ContactResponse response(body, settings);
  response.set_cloth_triangles(model);
  response.reset_cloth(x, model.mass, 9.81);
  ConstraintFilter filter(model.vertex_count);
  Eigen::VectorXd y;
  StepForces extra;
  response.constrain_start(x, Eigen::VectorXd::Zero(x.size()), 1.0 / 60.0, filter, y, extra);
  response.accept_step(Eigen::VectorXd::Zero(x.size()));  // contacts() are the accepted step's
  std::vector<double> kept(static_cast<std::size_t>(model.vertex_count),
                           std::numeric_limits<double>::quiet_NaN());
  for (const ActiveContact& a : response.contacts())
    kept[a.contact.vertex] =
        a.contact.distance + y.segment<3>(3 * a.contact.vertex).dot(a.contact.normal);
  return kept;
}

// Cloth inside a gap, or bridging its opening (ContactSettings::pinch_budget). Two blocks with a
// slot 1.5 thicknesses wide between them, tops at y = 0. A strip of cloth standing in the slot,
// 1 mm from one wall, lies between the two walls: squeezed, its contacts keep a third of the
// gap (1.5 mm). A strip lying across the slot's opening 4 mm down, its edges 1 mm from each wall,
// has both walls beside it, not across it: it bridges the opening and keeps the full thickness,
// as the back of a skirt over the seat's cleft must (pinched contacts there started a cycle
// under the shaped tee dress, docs/collision.md). Without the budget both keep the thickness.
TEST(ContactHysteresis, PinchBudgetOnlyWhereTheGapCrossesTheCloth) {
  const double gap = 1.5 * kThickness;
  const meshing::TriMesh body = merged(testing::make_box({-0.5, -0.2, -0.5}, {0.0, 0.0, 0.5}),
                                       testing::make_box({gap, -0.2, -0.5}, {0.5 + gap, 0.0, 0.5}));
  const SheetSetup s = horizontal_sheet(2, 0.02, {0.0, 0.0, 0.0});
  const int n = s.model.vertex_count;
  const Eigen::VectorXd rest = flatten_positions(s.scene.input.rest_positions);
  // Standing in the slot: the sheet's x (−1 to 1 cm) turned into depth, 1 mm from the wall x = 0.
  Eigen::VectorXd standing(3 * n), across(3 * n);
  for (int i = 0; i < n; ++i) {
    const double u = rest[3 * i] / 0.02 + 0.5, z = rest[3 * i + 2];  // u in [0, 1]
    standing.segment<3>(3 * i) = Vector3d(0.001, -0.005 - 0.015 * u, z);
    // Across the opening: from 1 mm off one wall to 1 mm off the other, 4 mm down.
    across.segment<3>(3 * i) = Vector3d(0.001 + (gap - 0.002) * u, -0.004, z);
  }
  ContactSettings settings = box_settings(1.0).contact;
  for (const bool budget : {false, true}) {
    settings.pinch_budget = budget;
    const std::vector<double> inside = kept_distances(body, settings, s.model, standing);
    const std::vector<double> bridging = kept_distances(body, settings, s.model, across);
    int inside_checked = 0, bridging_checked = 0;
    for (int i = 0; i < n; ++i) {
      // Every vertex of both strips is within the thickness of a wall: each has a contact.
      ASSERT_FALSE(std::isnan(inside[i])) << "standing vertex " << i;
      ASSERT_FALSE(std::isnan(bridging[i])) << "bridging vertex " << i;
      EXPECT_NEAR(inside[i], budget ? gap / 3.0 : kThickness, 1e-9) << "standing vertex " << i;
      ++inside_checked;
      EXPECT_NEAR(bridging[i], kThickness, 1e-9) << "bridging vertex " << i;
      ++bridging_checked;
    }
    EXPECT_EQ(inside_checked, n);
    EXPECT_EQ(bridging_checked, n);
  }
}

// The body-vertex springs take the same share of a pinch as the contacts: the corners of a lid
// 0.9 thicknesses (2.7 mm) over a table, 0.3 mm through cloth lying on the table at the
// thickness, keep the cloth a third of the gap (0.9 mm) from them when the floor allows it
// (pinch_floor a quarter thickness), not the springs' own clearance (half a thickness, 1.5 mm),
// which would ask for cloth within the table's share. At the default floor (half a thickness)
// the share is the clearance. The lid lies between the sheet's vertices (3.75 cm apart), so
// every vertex stays at the thickness and the cloth flat; a spring's target along its normal n
// is then n·b + clearance, b its body vertex.
TEST(ContactHysteresis, BodyVertexSpringsInAPinchKeepAThirdOfTheGap) {
  const double gap = 0.9 * kThickness;
  const meshing::TriMesh body =
      merged(table(), testing::make_box({0.005, gap, 0.005}, {0.025, gap + 0.02, 0.025}));
  const SheetSetup s = horizontal_sheet(8, 0.3, {0.0, kThickness, 0.0});
  const Eigen::VectorXd x = flatten_positions(s.scene.input.rest_positions);
  ContactSettings settings = box_settings(1.0).contact;
  settings.check_body_vertices = true;
  for (const auto& [budget, floor] : {std::pair{false, 0.25}, {true, 0.5}, {true, 0.25}}) {
    settings.pinch_budget = budget;
    settings.pinch_floor = floor;
    const double expected = budget ? std::max(gap / 3.0, floor * kThickness) : 0.5 * kThickness;
    ContactResponse response(body, settings);
    response.set_cloth_triangles(s.model);
    response.reset_cloth(x, s.model.mass, 9.81);
    ConstraintFilter filter(s.model.vertex_count);
    Eigen::VectorXd y;
    StepForces extra;
    response.constrain_start(x, Eigen::VectorXd::Zero(x.size()), 1.0 / 60.0, filter, y, extra);
    EXPECT_LT(y.cwiseAbs().maxCoeff(), 1e-12);  // no vertex moved: the cloth is flat
    // The lid's four bottom corners, each over one or two of the sheet's triangles.
    ASSERT_GE(extra.springs.size(), 4u);
    for (const PointSpring& spring : extra.springs) {
      ASSERT_NEAR(spring.normal.y(), -1.0, 1e-12);  // pushing the cloth down, off the lid
      const double clearance = spring.target - spring.normal.dot(Vector3d(0.0, gap, 0.0));
      EXPECT_NEAR(clearance, expected, 1e-9) << "budget " << budget << ", floor " << floor;
    }
  }
}

// A body vertex's spring that leaves its hold is released at no load, so catching and releasing
// the cloth puts no energy into it. A jersey hammock of 0.3 m (9 × 9 quads, pinned along two
// edges) lowered 4 cm over 0.3 s onto a cone's tip: the tip is caught, the cloth springs back
// off it and is caught again. The cloth's own energy (stretch, shear, bend, gravity and
// kinetic; the pins stop at 0.3 s, the body is still) can then only fall, except by the work
// of the contacts and springs. Measured from 0.6 s to 2 s: with the springs' carried push
// fading across the hold margin (ContactSettings::fade_carried_push) it rises by 5.3e-4 J in all (a
// spring giving back in a step what it stored in the ones before), falls by 6.1e-5 J net, and no
// spring is caught or dropped (3 held throughout); carried in full (the push a spring built up
// while the cloth was caught still there when it was dropped) it rose by 0.026 J, by 6.2e-4 J net,
// with 42 catches and releases: the t-shirt's hem cycle (docs/collision.md, "The hem's cycle,
// traced").
TEST(ContactHysteresis, BodyVertexSpringsPutNoEnergyIntoACatchAndReleaseCycle) {
  const meshing::TriMesh cone = testing::make_cone(0.1, 0.2, 24, Vector3d(0.013, 0.0, 0.007));
  const SheetSetup s =
      horizontal_sheet(9, 0.3, {0.0, 0.201, 0.0}, fabric_preset("jersey"), {"left", "right"});
  SimulationSettings settings = box_settings(2.0);
  settings.contact.check_body_vertices = true;
  settings.contact.fade_carried_push = true;
  constexpr double kLower = 0.04, kLowerTime = 0.3, kFrom = 0.6;  // m, s, s
  std::vector<Pin> pins;
  for (const int v : s.scene.pinned_vertices) {
    const Vector3d start = s.scene.input.rest_positions.row(v).transpose();
    pins.push_back({v, [start](double t) {
                      return Vector3d(start -
                                      Vector3d(0.0, kLower * std::min(t / kLowerTime, 1.0), 0.0));
                    }});
  }
  Simulation sim(s.model, flatten_positions(s.scene.input.rest_positions), pins, settings);
  sim.set_body(cone);
  std::vector<int> held;  // per step, the springs it started with
  const SimulationReport r = sim.run(
      [&](const Simulation& step) { held.push_back(step.contact()->step_stats().piercings_held); });
  ASSERT_FALSE(r.failed);
  ASSERT_EQ(r.energy.size(), held.size() + 1);  // and the start
  double rise = 0.0, first = 0.0, last = 0.0;
  int switches = 0;
  bool started = false;
  for (std::size_t k = 1; k < r.energy.size(); ++k) {
    const EnergySample& e = r.energy[k];
    if (e.time <= kFrom) continue;
    const EnergySample& b = r.energy[k - 1];
    const double before = b.stretch + b.shear + b.bend + b.kinetic + b.potential;
    const double after = e.stretch + e.shear + e.bend + e.kinetic + e.potential;
    if (!started) first = before;
    started = true;
    last = after;
    rise += std::max(after - before, 0.0);
    if (k >= 2) switches += held[k - 1] != held[k - 2];
  }
  std::printf(
      "hammock lowered onto a cone tip: energy from %.2f s to %.2f s %+.3g J, rising by %.3g J "
      "in all, %d spring switches, %d springs at the end\n",
      kFrom, r.sim_time, last - first, rise, switches, held.back());
  ASSERT_TRUE(started);
  // The sheet's energy scale: its weight times the 4 cm it was lowered, 0.3² m² × 0.18 kg/m²
  // × 9.81 m/s² × 0.04 m = 6e-3 J. The springs' own energy (½ k x² with k = 16 N/m and x at
  // most a few millimetres: 1e-4 J) is what may come back out of them in a step.
  EXPECT_LT(rise, 2e-3);
  EXPECT_LE(last, first);
  EXPECT_EQ(switches, 0);
}

// A body vertex's spring is released at no load: the push it carries to the next step fades to
// nothing by the time its point reaches the edge of its hold, so dropping it there takes no push
// off the cloth. A lid's corners 1 mm through a sheet (the body vertices), the sheet moved
// rigidly as if solved: a step ending 1 mm short of the clearance builds a push (k × 1 mm); the
// next, ending d past the clearance, carries all of its end force at d = 0 and (almost) none at
// the hold's edge. Carried in full, a spring dropped at the edge still pushed (the t-shirt's hem:
// 15 mN; docs/collision.md, "The hem's cycle, traced").
TEST(ContactHysteresis, BodyVertexSpringLeavesItsHoldCarryingNoPush) {
  const meshing::TriMesh lid = testing::make_box({0.005, -0.001, 0.005}, {0.025, 0.02, 0.025});
  const SheetSetup s = horizontal_sheet(8, 0.3, {0.0, 0.0, 0.0});
  const Eigen::VectorXd x = flatten_positions(s.scene.input.rest_positions);
  const Eigen::VectorXd still = Eigen::VectorXd::Zero(x.size());
  const auto lowered = [&](double dy) {  // the sheet moved down by dy (m)
    Eigen::VectorXd moved = x;
    for (Eigen::Index i = 0; i < moved.size() / 3; ++i) moved[3 * i + 1] -= dy;
    return moved;
  };
  const double clearance = 0.5 * kThickness, margin = 0.25 * kThickness;  // 1.5 and 0.75 mm
  ContactSettings settings = box_settings(1.0).contact;
  settings.check_body_vertices = true;
  settings.fade_carried_push = true;
  for (const double past : {0.0, 0.5 * margin, 0.98 * margin}) {
    ContactResponse response(lid, settings);
    response.set_cloth_triangles(s.model);
    response.reset_cloth(x, s.model.mass, 9.81);
    // One step from `start` whose solve ends at `end`: its springs, and the forces they end with.
    const auto step = [&](const Eigen::VectorXd& start, Eigen::VectorXd end, double* end_force) {
      ConstraintFilter filter(s.model.vertex_count);
      Eigen::VectorXd y;
      StepForces extra;
      response.constrain_start(start, still, 1.0 / 60.0, filter, y, extra);
      *end_force = 0.0;
      for (const PointSpring& spring : extra.springs)
        *end_force +=
            spring.preload +
            spring.stiffness *
                (spring.target -
                 along_spring_normal(spring, s.model.triangles[spring.triangle].vertices, end));
      Eigen::VectorXd v = still;
      response.finish_step(end, v, extra);
      response.accept_step(Eigen::VectorXd());
      return extra.springs;
    };
    const auto preload = [](const std::vector<PointSpring>& springs) {
      double sum = 0.0;
      for (const PointSpring& spring : springs) sum += spring.preload;
      return sum;
    };
    // The clearance lies 1 mm (the corners) + 1.5 mm below the sheet's start.
    const double target = 0.001 + clearance;
    double first = 0.0, second = 0.0, third = 0.0;
    const std::vector<PointSpring> caught = step(x, lowered(target - 0.001), &first);
    ASSERT_GE(caught.size(), 4u);  // the lid's four bottom corners
    ASSERT_NEAR(caught[0].normal.y(), -1.0, 1e-12);
    ASSERT_GT(first, 0.0);
    const std::vector<PointSpring> held =
        step(lowered(target - 0.001), lowered(target + past), &second);
    EXPECT_NEAR(preload(held), first, 1e-9 * first);  // 1 mm short: carried in full
    ASSERT_GT(second, 0.0);                           // still pushing where it ended
    const std::vector<PointSpring> next =
        step(lowered(target + past), lowered(target + past), &third);
    ASSERT_EQ(next.size(), held.size()) << "still within the hold, " << 1e3 * past << " mm past";
    const double carried = preload(next);
    std::printf("ended %.3f mm past the clearance pushing %.3f mN: carries %.3f mN\n", 1e3 * past,
                1e3 * second, 1e3 * carried);
    EXPECT_LE(carried, second * (1.0 + 1e-9));
    if (past == 0.0) {
      EXPECT_NEAR(carried, second, 1e-9 * second);
    }
    if (past > 0.9 * margin) {
      EXPECT_LT(carried, 0.05 * second);
    }
  }
}

}  // namespace
}  // namespace sd::sim
