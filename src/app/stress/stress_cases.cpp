#include "src/app/stress/stress_cases.hpp"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

#include "sim/fabric.hpp"
#include "sim/sheet.hpp"

namespace sd::app {
namespace {

using Eigen::Vector3d;

constexpr double kSheetSize = 0.5;  // m, the hanging sheet's side
constexpr int kSheetQuads = 8;      // quads per side of the hanging sheet (81 vertices)
constexpr double kDuration = 1.0;   // s simulated per case

struct Combo {
  sim::Integrator integrator;
  sim::LinearSolverKind solver;
};
constexpr std::array<Combo, 4> kCombos = {{
    {sim::Integrator::implicit_euler, sim::LinearSolverKind::pcg},
    {sim::Integrator::implicit_euler, sim::LinearSolverKind::cholmod},
    {sim::Integrator::bdf2, sim::LinearSolverKind::pcg},
    {sim::Integrator::bdf2, sim::LinearSolverKind::cholmod},
}};

std::string combo_label(const Combo& c) {
  return fmt::format("{}-{}", sim::integrator_short_name(c.integrator), sim::solver_name(c.solver));
}

sim::SimulationSettings base_settings(double dt, const Combo& combo) {
  sim::SimulationSettings s;
  s.integrator = combo.integrator;
  s.solver = combo.solver;
  s.dt = dt;
  s.duration = kDuration;
  s.stop_at_rest = true;
  s.record_energy = false;  // the runner measures energy itself after every step
  return s;
}

std::vector<sim::Pin> fixed_pins(const std::vector<int>& vertices) {
  std::vector<sim::Pin> pins;
  for (int v : vertices) pins.push_back({v, {}});
  return pins;
}

sim::SheetScene horizontal_sheet(int quads, double size, std::vector<std::string> pins) {
  sim::SheetSpec spec;
  spec.size = {size, size};
  spec.columns = spec.rows = quads;
  spec.orientation = sim::SheetOrientation::horizontal;
  spec.centre = Vector3d(0.0, 1.0, 0.0);
  spec.pins = std::move(pins);
  return sim::build_sheet(spec);
}

// The workhorse: a 0.5 m cotton sheet held horizontally by its two far corners; it falls,
// swings and hangs.
StressScene hanging_sheet(const sim::FabricParameters& fabric) {
  const sim::SheetScene sheet =
      horizontal_sheet(kSheetQuads, kSheetSize, {"top-left", "top-right"});
  StressScene scene;
  scene.model = sim::build_cloth_model(sheet.input, fabric);
  scene.x0 = sim::flatten_positions(sheet.input.rest_positions);
  scene.pins = fixed_pins(sheet.pinned_vertices);
  scene.length = kSheetSize;
  return scene;
}

sim::FabricParameters scaled_stiffness(double factor) {
  sim::FabricParameters fabric = sim::fabric_preset("cotton");
  fabric.stretch_warp *= factor;
  fabric.stretch_weft *= factor;
  fabric.shear *= factor;
  fabric.bend *= factor;
  return fabric;
}

// The hanging sheet with one column of quads `ratio` times as wide as the others: its
// triangles have `ratio` times their area (and aspect ratios near 1/ratio).
StressScene sliver_sheet(double ratio) {
  sim::SheetScene sheet = horizontal_sheet(kSheetQuads, kSheetSize, {"top-left", "top-right"});
  const int sliver = kSheetQuads / 2;
  const double width = kSheetSize / (kSheetQuads - 1 + ratio);
  std::vector<double> x(kSheetQuads + 1, -0.5 * kSheetSize);
  for (int c = 1; c <= kSheetQuads; ++c)
    x[c] = x[c - 1] + (c - 1 == sliver ? ratio * width : width);
  for (int r = 0; r <= kSheetQuads; ++r)
    for (int c = 0; c <= kSheetQuads; ++c) sheet.input.rest_positions(sheet.vertex(r, c), 0) = x[c];
  StressScene scene;
  scene.model = sim::build_cloth_model(sheet.input, sim::fabric_preset("cotton"));
  scene.x0 = sim::flatten_positions(sheet.input.rest_positions);
  scene.pins = fixed_pins(sheet.pinned_vertices);
  scene.length = kSheetSize;
  return scene;
}

// A free 0.6 m sheet at y = 1 m and a 15 cm sphere that starts 30 cm below it and moves up at
// `speed` for `travel` metres, hitting the falling sheet, then stops: the sheet drapes on it.
StressScene sphere_strike(double speed) {
  constexpr double kSize = 0.6, kRadius = 0.15, kTravel = 0.6;
  const sim::SheetScene sheet = horizontal_sheet(12, kSize, {});
  StressScene scene;
  scene.model = sim::build_cloth_model(sheet.input, sim::fabric_preset("cotton"));
  scene.x0 = sim::flatten_positions(sheet.input.rest_positions);
  const meshing::TriMesh sphere =
      meshing::icosphere(kRadius, 3, Vector3d(0.0, 1.0 - kRadius - 0.3, 0.0));
  const double end = kTravel / speed;
  scene.body = sim::make_pose_sequence(sphere, {0.0, end}, [&](double t) {
    Eigen::MatrixX3d d = Eigen::MatrixX3d::Zero(sphere.vertex_count(), 3);
    d.col(1).setConstant(speed * t);
    return d;
  });
  scene.drive_end = end;
  scene.length = kSize;
  return scene;
}

// Self-contact scenes on a still floor slab (top at y = 0): a strip of 24 × 6 quads
// (0.6 × 0.15 m, cotton, rest shape flat).
enum class SelfFold { crumpled, fast, heavy };

StressScene self_contact_scene(SelfFold kind) {
  constexpr int kColumns = 24, kRows = 6;
  constexpr double kLength = 0.6, kGap = 0.008;
  sim::SheetSpec spec;
  spec.size = {kLength, kLength * kRows / kColumns};
  spec.columns = kColumns;
  spec.rows = kRows;
  spec.orientation = sim::SheetOrientation::horizontal;
  spec.centre = Vector3d(0.0, 0.0, 0.0);
  const sim::SheetScene sheet = sim::build_sheet(spec);
  StressScene scene;
  scene.model = sim::build_cloth_model(sheet.input, sim::fabric_preset("cotton"));
  const double dx = kLength / kColumns;
  Eigen::MatrixX3d start = sheet.input.rest_positions;
  for (int r = 0; r <= kRows; ++r)
    for (int c = 0; c <= kColumns; ++c) {
      const int v = sheet.vertex(r, c);
      const double z = start(v, 2);
      Vector3d p(start(v, 0), 0.01, z);
      if (kind == SelfFold::crumpled) {
        // An accordion of six layers 8 mm apart, each fold line midway between its two layers.
        constexpr int kPerLayer = kColumns / 6;
        const int layer = c / kPerLayer, j = c % kPerLayer;
        if (j == 0 && c > 0) {
          p = Vector3d((layer % 2 == 0 ? 0 : kPerLayer) * dx, 0.01 + (layer - 0.5) * kGap, z);
        } else {
          p = Vector3d((layer % 2 == 0 ? j : kPerLayer - j) * dx, 0.01 + layer * kGap, z);
        }
      } else if (kind == SelfFold::fast && c > kColumns / 2) {
        // The right half stands upright on the middle line, about to swing over the left one.
        p = Vector3d(0.0, 0.01 + (c - kColumns / 2) * dx, z);
      } else if (kind == SelfFold::heavy && c > kColumns / 2) {
        // The right half folded over the left one, 2 cm above it.
        p = Vector3d(-(c - kColumns / 2) * dx, 0.03, z);
      }
      start.row(v) = p.transpose();
    }
  scene.x0 = sim::flatten_positions(start);
  if (kind == SelfFold::fast) {
    // The upright half turns about the middle line at 20 rad/s towards −x (its end at 6 m/s)
    // and lands on the other half a twelfth of a second later. (The first version gave the flat
    // half v_y = 20 x instead: the strip's stretch pulled it back and it never folded.)
    scene.v0 = Eigen::VectorXd::Zero(scene.x0.size());
    for (int v = 0; v < start.rows(); ++v)
      if (start(v, 1) > 0.01 + 1e-9) scene.v0(3 * v) = -20.0 * (start(v, 1) - 0.01);
  }
  const meshing::TriMesh floor = [] {
    meshing::TriMesh box;
    const Vector3d lo(-1.0, -0.05, -1.0), hi(1.0, 0.0, 1.0);
    box.vertices.resize(8, 3);
    for (int i = 0; i < 8; ++i)
      box.vertices.row(i) << (i & 1 ? hi.x() : lo.x()), (i & 2 ? hi.y() : lo.y()),
          (i & 4 ? hi.z() : lo.z());
    box.faces.resize(12, 3);
    box.faces << 0, 2, 3, 0, 3, 1, 4, 5, 7, 4, 7, 6, 0, 1, 5, 0, 5, 4, 2, 6, 7, 2, 7, 3, 0, 4, 6, 0,
        6, 2, 1, 3, 7, 1, 7, 5;
    return box;
  }();
  scene.body = sim::make_pose_sequence(
      floor, {0.0, 1.0}, [&](double) { return Eigen::MatrixX3d::Zero(floor.vertex_count(), 3); });
  scene.length = kLength;
  return scene;
}

enum class PinMotion { jump_up, jump_apart, shake };

// The hanging sheet whose pins move: a 10 cm jump upwards at t = 0.1 s (the pin path is
// discontinuous: the step that crosses 0.1 s must move them 10 cm), a 5 cm jump of each pin
// outwards (the edge between them is stretched by 20 % at once), or a ±5 cm vertical shake at
// 10 Hz for 0.5 s (3.1 m/s peak pin speed).
StressScene moving_pins(PinMotion motion) {
  StressScene scene = hanging_sheet(sim::fabric_preset("cotton"));
  constexpr double kJumpTime = 0.1;
  for (sim::Pin& pin : scene.pins) {
    const Vector3d start = scene.x0.segment<3>(3 * pin.vertex);
    switch (motion) {
      case PinMotion::jump_up:
        pin.path = [start](double t) {
          return t < kJumpTime ? start : Vector3d(start + Vector3d(0.0, 0.1, 0.0));
        };
        break;
      case PinMotion::jump_apart: {
        const Vector3d out(start.x() > 0 ? 0.05 : -0.05, 0.0, 0.0);
        pin.path = [start, out](double t) { return t < kJumpTime ? start : Vector3d(start + out); };
        break;
      }
      case PinMotion::shake:
        pin.path = [start](double t) {
          const double s = t < 0.5 ? 0.05 * std::sin(2.0 * M_PI * 10.0 * t) : 0.0;
          return Vector3d(start + Vector3d(0.0, s, 0.0));
        };
        break;
    }
  }
  scene.drive_end = motion == PinMotion::shake ? 0.5 : kJumpTime;
  return scene;
}

// A free sheet whose start positions are its rest shape stretched in its plane by `factor`
// about the centre (strain factor − 1 everywhere), released.
StressScene stretched_sheet(double factor) {
  const sim::SheetScene sheet = horizontal_sheet(kSheetQuads, kSheetSize, {});
  StressScene scene;
  scene.model = sim::build_cloth_model(sheet.input, sim::fabric_preset("cotton"));
  Eigen::MatrixX3d start = sheet.input.rest_positions;
  const Vector3d centre(0.0, 1.0, 0.0);
  for (Eigen::Index i = 0; i < start.rows(); ++i) {
    const Vector3d p = start.row(i).transpose();
    start.row(i) = (centre + factor * (p - centre)).transpose();
  }
  scene.x0 = sim::flatten_positions(start);
  scene.length = kSheetSize;
  return scene;
}

// The hanging sheet as a 4-8 mesh of 4 x 4 quads (vertex ids = sheet grid ids).
StressAdaptive adaptive_sheet() {
  constexpr int kQuads = 4;
  const sim::SheetScene sheet = horizontal_sheet(kQuads, kSheetSize, {"top-left", "top-right"});
  StressAdaptive a{sim::sheet_mesh48(sheet), {}, {}, {}};
  a.material.fabric = sim::fabric_preset("cotton");
  a.material.source_warp = sim::sheet_quad_warp(sheet);
  a.material.up = sheet.input.up;
  a.pins = fixed_pins(sheet.pinned_vertices);
  return a;
}

enum class Churn { thresholds, forced };

// Adaptivity churn: thresholds so small that the mesh refines and coarsens on nearly every
// step (no hysteresis to speak of, no minimum lifetime, any turning rate counts as steady), or
// a random split or merge forced before every step on top of the default thresholds.
StressScene churning_sheet(Churn churn) {
  StressScene scene;
  scene.adaptive = adaptive_sheet();
  StressAdaptive& a = *scene.adaptive;
  if (churn == Churn::thresholds) {
    a.settings.refine_threshold = 2.0e-5;
    a.settings.coarsen_threshold = 1.9e-5;
    a.settings.steady_rate = 1.0e6;
    a.settings.min_lifetime = 0.0;
    a.settings.max_level = 5;
    a.start_level = 1;
  } else {
    a.forced_churn = true;
    a.churn_max_level = 5;
  }
  scene.length = kSheetSize;
  return scene;
}

std::string exponent_label(int decade) {
  return decade == 0 ? "1" : fmt::format("1e{}", decade);
}

}  // namespace

std::string step_label(double dt) {
  const double inverse = 1.0 / dt;
  if (std::abs(inverse - std::round(inverse)) < 1e-9 * inverse)
    return fmt::format("1/{}", static_cast<long>(std::round(inverse)));
  return fmt::format("{:g}", dt);
}

std::vector<StressCase> stress_matrix(bool quick) {
  std::vector<StressCase> cases;
  const auto add = [&](StressCase c) {
    c.parameters["integrator"] = sim::integrator_name(c.settings.integrator);
    c.parameters["solver"] = sim::solver_name(c.settings.solver);
    c.parameters["dt"] = c.settings.dt;
    c.parameters["duration"] = c.settings.duration;
    if (!quick || c.quick) cases.push_back(std::move(c));
  };

  // Stiffness x10^0..10^6 (stretch, shear and bending together) x step x integrator/solver.
  for (int decade = 0; decade <= 6; ++decade)
    for (double dt : {1.0 / 100, 1.0 / 24, 1.0 / 10})
      for (const Combo& combo : kCombos) {
        const double factor = std::pow(10.0, decade);
        StressCase c;
        c.family = "stiffness";
        c.id = fmt::format("stiffness-{}-h{}-{}", exponent_label(decade), step_label(dt),
                           combo_label(combo));
        c.condition = fmt::format("cotton x{} in stretch, shear and bending, step {} s",
                                  exponent_label(decade), step_label(dt));
        c.parameters["stiffness_factor"] = factor;
        c.settings = base_settings(dt, combo);
        const std::string label = combo_label(combo);
        c.quick = (dt == 1.0 / 10 && label == "ie-cholmod" && decade % 3 == 0) ||
                  (dt == 1.0 / 100 && label == "bdf2-pcg" && decade == 6) ||
                  (dt == 1.0 / 24 && label == "bdf2-cholmod" && decade == 3);
        c.build = [factor] { return hanging_sheet(scaled_stiffness(factor)); };
        add(std::move(c));
      }

  // No damping at all: the total energy can only stay or fall.
  for (double dt : {1.0 / 100, 1.0 / 24, 1.0 / 10})
    for (const Combo& combo : kCombos) {
      StressCase c;
      c.family = "undamped";
      c.id = fmt::format("undamped-h{}-{}", step_label(dt), combo_label(combo));
      c.condition =
          fmt::format("no stretch, shear or bend damping, no drag, step {} s", step_label(dt));
      c.settings = base_settings(dt, combo);
      c.quick = dt == 1.0 / 10 && combo.integrator == sim::Integrator::bdf2;
      c.build = [] {
        sim::FabricParameters fabric = sim::fabric_preset("cotton");
        fabric.damping = 0.0;
        fabric.bend_damping = 0.0;
        return hanging_sheet(fabric);
      };
      add(std::move(c));
    }

  // Near-degenerate triangles: a column of slivers with 1e-6 of the other triangles' area.
  for (double dt : {1.0 / 100, 1.0 / 10})
    for (const Combo& combo : kCombos) {
      constexpr double kRatio = 1e-6;
      StressCase c;
      c.family = "sliver";
      c.id = fmt::format("sliver-1e-6-h{}-{}", step_label(dt), combo_label(combo));
      c.condition =
          fmt::format("a column of triangles with area ratio 1e-6, step {} s", step_label(dt));
      c.parameters["area_ratio"] = kRatio;
      c.settings = base_settings(dt, combo);
      c.quick = false;  // every combination diverges today (docs/stress.md)
      c.build = [] { return sliver_sheet(kRatio); };
      add(std::move(c));
    }

  // Adaptivity churn.
  for (Churn churn : {Churn::thresholds, Churn::forced})
    for (const Combo& combo : kCombos) {
      StressCase c;
      c.family = "churn";
      const char* name = churn == Churn::thresholds ? "thresholds" : "forced";
      c.id = fmt::format("churn-{}-{}", name, combo_label(combo));
      c.condition = churn == Churn::thresholds
                        ? "adaptive, refine above 20 um and merge below 19 um of sag, no lifetime"
                        : "adaptive, a random split or merge forced before every step";
      c.parameters["churn"] = name;
      c.settings = base_settings(1.0 / 60, combo);
      c.quick = (churn == Churn::forced && combo_label(combo) == "ie-pcg") ||
                (churn == Churn::thresholds && combo_label(combo) == "bdf2-cholmod");
      c.build = [churn] { return churning_sheet(churn); };
      add(std::move(c));
    }

  // A fast body: a sphere striking the falling sheet from below.
  for (double speed : {2.5, 5.0})
    for (const Combo& combo : kCombos) {
      StressCase c;
      c.family = "body";
      c.id = fmt::format("sphere-{:g}ms-{}", speed, combo_label(combo));
      c.condition = fmt::format("a 15 cm sphere strikes the sheet from below at {:g} m/s", speed);
      c.parameters["body_speed"] = speed;
      c.settings = base_settings(1.0 / 60, combo);
      c.quick = speed == 5.0 && combo.solver == sim::LinearSolverKind::cholmod;
      c.build = [speed] { return sphere_strike(speed); };
      add(std::move(c));
    }

  // Pins moved abruptly.
  for (PinMotion motion : {PinMotion::jump_up, PinMotion::jump_apart, PinMotion::shake})
    for (const Combo& combo : kCombos) {
      StressCase c;
      c.family = "pins";
      const char* name = motion == PinMotion::jump_up      ? "jump-up"
                         : motion == PinMotion::jump_apart ? "jump-apart"
                                                           : "shake";
      c.id = fmt::format("pins-{}-{}", name, combo_label(combo));
      c.condition = motion == PinMotion::jump_up ? "both pins jump 10 cm up in one step at 0.1 s"
                    : motion == PinMotion::jump_apart
                        ? "each pin jumps 5 cm outwards at 0.1 s (20 % at once)"
                        : "pins shaken +-5 cm at 10 Hz for 0.5 s";
      c.parameters["pin_motion"] = name;
      c.settings = base_settings(1.0 / 24, combo);
      const std::string label = combo_label(combo);
      c.quick = (motion == PinMotion::jump_up && label == "ie-cholmod") ||
                (motion == PinMotion::jump_apart && label == "bdf2-pcg") ||
                (motion == PinMotion::shake && label == "ie-pcg");
      c.build = [motion] { return moving_pins(motion); };
      add(std::move(c));
    }

  // Huge gravity. At 1000 g the hanging sheet's own fall reaches ~100 m/s, so the speed limit
  // (a sanity bound for garments, 50 m/s) is raised for that case to 500 m/s.
  for (double g : {10.0, 100.0, 1000.0})
    for (const Combo& combo : kCombos) {
      StressCase c;
      c.family = "gravity";
      c.id = fmt::format("gravity-x{:g}-h1/10-{}", g, combo_label(combo));
      c.condition = fmt::format("gravity {:g} g, step 1/10 s", g);
      c.parameters["gravity_factor"] = g;
      c.settings = base_settings(1.0 / 10, combo);
      c.settings.forces.gravity *= g;
      if (g >= 1000.0) c.settings.max_speed = 500.0;
      c.parameters["max_speed"] = c.settings.max_speed;
      const std::string label = combo_label(combo);
      c.quick = (g == 100.0 && label == "ie-cholmod") || (g == 1000.0 && label == "bdf2-pcg");
      c.build = [] { return hanging_sheet(sim::fabric_preset("cotton")); };
      add(std::move(c));
    }

  // Self-contact: a crumpled start, a fast fold, a fold under 10 g (docs/collision.md).
  for (SelfFold kind : {SelfFold::crumpled, SelfFold::fast, SelfFold::heavy})
    for (const Combo& combo : {kCombos[1], kCombos[2]}) {
      StressCase c;
      c.family = "self-contact";
      const char* name = kind == SelfFold::crumpled ? "crumpled"
                         : kind == SelfFold::fast   ? "fast-fold"
                                                    : "fold-10g";
      c.id = fmt::format("self-{}-{}", name, combo_label(combo));
      c.condition = kind == SelfFold::crumpled
                        ? "starts as an accordion of six layers 8 mm apart on the floor"
                    : kind == SelfFold::fast ? "half the strip swings over the other at 20 rad/s"
                                             : "a fold 2 cm high collapses under 10 g";
      c.parameters["self_fold"] = name;
      c.settings = base_settings(1.0 / 60, combo);
      c.settings.self_contact.enabled = true;
      if (kind == SelfFold::heavy) c.settings.forces.gravity *= 10.0;
      c.quick = combo_label(combo) == "ie-cholmod";
      c.build = [kind] { return self_contact_scene(kind); };
      add(std::move(c));
    }

  // Non-finite start states: refused with a typed error before anything runs (docs/stress.md
  // says why rejecting beats repairing).
  {
    const Combo combo = kCombos[1];
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const auto nan_case = [&](std::string name, std::string condition, auto build) {
      StressCase c;
      c.family = "nan";
      c.id = "nan-" + name;
      c.condition = std::move(condition);
      c.settings = base_settings(1.0 / 60, combo);
      c.quick = true;
      c.expect_rejection = true;
      c.build = std::move(build);
      add(std::move(c));
    };
    nan_case("start-position", "one start coordinate is NaN", [nan] {
      StressScene scene = hanging_sheet(sim::fabric_preset("cotton"));
      scene.x0(3 * 40 + 1) = nan;
      return scene;
    });
    nan_case("start-velocity", "one start velocity is NaN", [nan] {
      StressScene scene = hanging_sheet(sim::fabric_preset("cotton"));
      scene.v0 = Eigen::VectorXd::Zero(scene.x0.size());
      scene.v0(3 * 40) = nan;
      return scene;
    });
    nan_case("rest-shape", "one rest-shape coordinate is NaN", [nan] {
      sim::SheetScene sheet = horizontal_sheet(kSheetQuads, kSheetSize, {"top-left", "top-right"});
      sheet.input.rest_positions(40, 2) = nan;
      StressScene scene;
      scene.model = sim::build_cloth_model(sheet.input, sim::fabric_preset("cotton"));
      scene.x0 = sim::flatten_positions(sheet.input.rest_positions);
      scene.pins = fixed_pins(sheet.pinned_vertices);
      return scene;
    });
    nan_case("adaptive-start", "one start coordinate of an adaptive cloth is infinite", [] {
      StressScene scene;
      scene.adaptive = adaptive_sheet();
      scene.x0 = sim::flatten_positions(scene.adaptive->mesh.arrays().rest_positions);
      scene.x0(3 * 7 + 1) = std::numeric_limits<double>::infinity();
      return scene;
    });
  }

  // Large start stretch, released.
  for (double factor : {1.5, 3.0})
    for (const Combo& combo : kCombos) {
      StressCase c;
      c.family = "stretch";
      c.id = fmt::format("stretch-x{:g}-{}", factor, combo_label(combo));
      c.condition = fmt::format("starts stretched x{:g} in its plane ({:g} % strain), free", factor,
                                100 * (factor - 1));
      c.parameters["start_stretch"] = factor;
      c.settings = base_settings(1.0 / 24, combo);
      const std::string label = combo_label(combo);
      c.quick = (factor == 1.5 && label == "ie-cholmod") || (factor == 3.0 && label == "bdf2-pcg");
      c.build = [factor] { return stretched_sheet(factor); };
      add(std::move(c));
    }
  return cases;
}

}  // namespace sd::app
