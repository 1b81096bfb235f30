// `sketchdrape run SKETCH -o DIR`: the scene's cloth (a stitched garment or a sheet) draped by
// the implicit simulator until it is at rest or the duration is over, then the draped mesh
// (drape.glb and drape.obj), report.json, the images the file asks for and, with --trace, a
// per-step log. Only the stages the scene needs run; every output appears together or not at all.

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>

#include "garment/body_landmarks.hpp"
#include "meshing/slice_dent.hpp"
#include "scene/sketch_file.hpp"
#include "sim/adaptive_detail.hpp"
#include "sim/cantilever.hpp"
#include "sim/cloth_driver.hpp"
#include "sim/drape_coefficient.hpp"
#include "sim/sheet.hpp"
#include "sim/simulation.hpp"
#include "sim/solver_library_threads.hpp"
#include "src/app/commands/cli.hpp"
#include "src/app/pipeline/atomic_file.hpp"
#include "src/app/pipeline/cloth_scene.hpp"
#include "src/app/pipeline/drape_warnings.hpp"
#include "src/app/pipeline/mesh_export.hpp"
#include "src/app/pipeline/pattern_export.hpp"
#include "src/app/pipeline/preview_images.hpp"
#include "src/app/pipeline/progress.hpp"
#include "src/app/pipeline/quality_warnings.hpp"
#include "src/app/pipeline/run_report.hpp"
#include "src/app/pipeline/seam_ease_warnings.hpp"
#include "src/app/pipeline/self_intersections.hpp"
#include "src/app/pipeline/sketch_checks.hpp"
#include "src/render/renderer.hpp"
#include "src/render/scene.hpp"

namespace sd::app {
namespace {

// m: a garment whose centre of mass ends more than this below where it was drawn is told it
// slid (the loose strapless peplum top: 4.6 cm; its bodice with ease 0.95, which grips: none).
constexpr double kSlidWarning = 0.03;

using Clock = std::chrono::steady_clock;

struct RunOptions {
  std::string sketch;
  std::string out = ".";
  bool trace = false;
  double frames_per_second = 0.0;  // > 0: also a PNG sequence of the drape (frames/)
  std::string max_memory;          // --max-memory, e.g. "4G"
  double max_time_s = 0;           // --max-time, seconds; 0: none
};

// --max-time passed, or the memory budget, while the drape runs: nothing is written.
class RunLimitExceeded : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One picture of the drape in progress, for the PNG sequence.
struct Frame {
  double time = 0.0;
  meshing::TriMesh cloth;
  Eigen::VectorXi triangle_group;
};

// The sketch's "simulate": {"adaptive": {...}} (the simulator's own settings), checked together
// here: a value the file gives against a default (a coarsen threshold at or above the default
// refine threshold) is refused at /simulate/adaptive.
sim::AdaptiveSettings adaptive_settings(const scene::Sketch& sketch) {
  try {
    sketch.simulate.adaptive_settings.validate();
  } catch (const sim::InvalidAdaptiveSettingsError& e) {
    sketch.fail("/simulate/adaptive", e.what());
  }
  return sketch.simulate.adaptive_settings;
}

// "1.2 GB", or "74 MB" below a gigabyte (where one decimal of GB says too little).
std::string memory_text(double bytes) {
  return bytes >= 1e9 ? fmt::format("{:.1f} GB", bytes / 1e9)
                      : fmt::format("{:.0f} MB", bytes / 1e6);
}

// The Cusick drape test's measures of a horizontal disc sheet held by a clamp "centre:R"
// (docs/fabrics.md, "Cusick drape"): DC and nodes of its shadow along the vertical.
std::optional<nlohmann::json> cusick_json(const scene::Sketch& sketch,
                                          const meshing::TriMesh& draped) {
  if (!sketch.sheet || !sketch.sheet->disc || !sketch.sheet->horizontal ||
      sketch.sheet->layers != 1)
    return std::nullopt;
  double support = 0.0;
  for (const std::string& pin : sketch.sheet->pins)
    support = std::max(support, sim::centre_clamp_radius(pin).value_or(0.0));
  if (support <= 0.0) return std::nullopt;
  sim::DrapeShadowOptions options;
  options.specimen_radius = 0.5 * sketch.sheet->size[0];
  options.support_radius = support;
  options.pixel = options.specimen_radius / 150;  // 1 mm on the standard's 30 cm disc
  const sim::DrapeShadow shadow = sim::measure_drape_shadow(
      draped.vertices, draped.faces, sketch.sheet->centre, Eigen::Vector3d::UnitY(), options);
  return nlohmann::json{{"specimen_radius", options.specimen_radius},
                        {"support_radius", support},
                        {"shadow_area", shadow.shadow_area},
                        {"drape_coefficient", shadow.drape_coefficient},
                        {"nodes", shadow.nodes}};
}

// The cantilever test's measures (docs/fabrics.md, "Cantilever"; the same as `bench --textile`)
// of a horizontal rectangle held by one clamp "top:N" of its top edge, drawn on its own grid:
// the chord angle, the overhang and Peirce's bending length from them, beside the fabric's
// c = (B/ρg)^(1/3) that the chord should give at 41.5° for an overhang of 2c.
std::optional<nlohmann::json> cantilever_json(const scene::Sketch& sketch, const ClothScene& scene,
                                              const meshing::TriMesh& draped, double gravity) {
  if (!sketch.sheet || sketch.sheet->disc || !sketch.sheet->horizontal ||
      sketch.sheet->layers != 1 || sketch.sheet->pins.size() != 1 ||
      !sketch.sheet->pins.front().starts_with("top:"))
    return std::nullopt;
  const int lines = std::atoi(sketch.sheet->pins.front().c_str() + 4);
  sim::SheetSpec spec;
  spec.columns = sketch.sheet->columns;
  spec.rows = sketch.sheet->rows;
  spec.size = sketch.sheet->size;
  spec.orientation = sim::SheetOrientation::horizontal;
  spec.centre = sketch.sheet->centre;
  const sim::SheetScene sheet = sim::build_sheet(spec);
  // The grid's own vertices, numbered as built (adaptive detail would renumber them).
  if (lines < 1 || lines > spec.rows || draped.vertices.rows() != sheet.input.rest_positions.rows())
    return std::nullopt;
  const sim::CantileverMeasure m =
      sim::measure_cantilever(sheet, sheet.input.rest_positions, draped.vertices, lines);
  const double c = std::cbrt(scene.fabric.bend / (scene.fabric.area_density * gravity));
  return nlohmann::json{{"clamp_lines", m.clamp_lines}, {"overhang_m", m.overhang},
                        {"chord_deg", m.chord_deg},     {"bending_length_m", m.bending_length},
                        {"fabric_bending_length_m", c}, {"overhang_over_2c", m.overhang / (2 * c)}};
}

// Whether the cloth can be seen to have fallen off the body (trial 41, P2): `up` against
// gravity, `body_low` the body's lowest point along it.
struct FallWatch {
  bool active = false;
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  double body_low = 0.0;
};

// Only where falling below the body is for good: a still body, nothing pinned, gravity on, and
// no wind with an upward part that could carry the cloth back.
FallWatch fall_watch(const ClothScene& scene, const sim::ForceSettings& forces) {
  FallWatch watch;
  const double g = forces.gravity.norm();
  if (!scene.body || scene.body_motion || !scene.pinned.empty() || !forces.terms.gravity ||
      !(g > 0.0) || scene.body->mesh.vertices.rows() == 0)
    return watch;
  watch.up = -forces.gravity / g;
  if (forces.terms.drag && forces.air_drag > 0.0 && forces.wind.dot(watch.up) > 0.0) return watch;
  watch.body_low = (scene.body->mesh.vertices * watch.up).minCoeff();
  watch.active = true;
  return watch;
}

// The whole cloth below the body's lowest point (by 1 cm, so that cloth lying under a foot or
// a floor slab's underside is not taken for fallen).
bool fell_below_body(const FallWatch& watch, const Eigen::MatrixX3d& positions) {
  constexpr double kBelow = 0.01;  // m
  return positions.rows() > 0 && (positions * watch.up).maxCoeff() < watch.body_low - kBelow;
}

// The refusal: what fell, when, and the two ways to hold it; nothing has been written.
[[noreturn]] void fail_fell_off(const scene::Sketch& sketch, const ClothScene& scene,
                                const FallWatch& watch, double time) {
  const double top = (scene.start * watch.up).maxCoeff();
  // A pin height that holds the top centimetre of the cloth as it was drawn.
  const double pin = std::floor((top - 0.01) * 100.0) / 100.0;
  std::string what = "the cloth";
  std::string path = "/simulate";
  if (sketch.sheet) {
    path = "/sheet";
  } else if (sketch.garment_mesh) {
    what = "the garment";
    path = "/garment_mesh";
  } else if (!sketch.panels.empty()) {
    path = "/panels";
    std::string names;
    const std::size_t shown = std::min<std::size_t>(sketch.panels.size(), 4);
    for (std::size_t i = 0; i < shown; ++i) names += (i ? ", '" : "'") + sketch.panels[i].id + "'";
    if (sketch.panels.size() > shown)
      names += fmt::format(" and {} more", sketch.panels.size() - shown);
    what = (sketch.panels.size() == 1 ? "panel " : "panels ") + names;
    if (sketch.panels.size() == 1) path = "/panels/0";
  }
  sketch.fail(path,
              fmt::format("the cloth fell off the body: nothing holds {} up (no pin, and by "
                          "t = {:.2f} s all of it was below the body's lowest point); draw it "
                          "round the body (round the torso or the waist, or over the "
                          "shoulders) or hold its top with \"simulate\": {{\"pin_above\": "
                          "{:.2f}}}; nothing was written",
                          what, time, pin));
}

void run_drape(const RunOptions& options, const GlobalOptions& global) {
  const auto start = Clock::now();
  const scene::Sketch sketch = scene::load_sketch(options.sketch);
  check_sketch(sketch);
  check_output_folder(options.out);  // before the drape's time is spent, not after it
  sim::SimulationSettings settings = simulation_settings(sketch);
  RunLimits limits;
  if (!options.max_memory.empty()) limits.max_memory_bytes = parse_memory_size(options.max_memory);
  if (options.max_time_s > 0) limits.max_time_s = options.max_time_s;
  // Refused before anything is built when the size is known from the file (a sheet), else once
  // the cloth is meshed.
  if (const auto before = estimate_before_building(sketch, options.frames_per_second, limits))
    check_run_fits(sketch, *before, limits, options.frames_per_second);
  // OSMesa is opened only by a run that renders (src/render/gl.hpp). Opened now, not after the
  // drape: a missing library is found before the drape's time is spent, and the budget checks
  // while draping count its memory, which the estimate includes.
  const RendererMemory renderer = run_renderer_memory(sketch, options.frames_per_second);
  if (renderer.total() > 0) {
    const double before = resident_memory_bytes();
    try {
      render::load_renderer_library();
    } catch (const render::RenderError& e) {
      throw render::RenderError(fmt::format(
          "{}; a run without pictures (\"output\": {{\"images\": []}}, no --frames) does not "
          "need it",
          e.what()));
    }
    spdlog::debug("OSMesa opened: resident memory {} -> {}", memory_text(before),
                  memory_text(resident_memory_bytes()));
  }
  const ClothScene scene = build_cloth_scene(sketch);
  // The pattern does not depend on the drape: laid out first, so that a piece wider than the
  // fabric is refused before the drape's time is spent, not after it.
  std::optional<PatternSheet> pattern_sheet;
  if (scene.garment && sketch.output.pattern)
    pattern_sheet = build_pattern_sheet(sketch, *scene.garment, *sketch.output.pattern,
                                        scene.flat_pattern ? &*scene.flat_pattern : nullptr,
                                        scene.flattening_ms, scene.body ? &*scene.body : nullptr);
  // The quality gate's warnings, as `validate` and `mesh` print them (trial 43, P11: `run` draped
  // a panel the gate says starts folded without a word of it): printed once here, before the
  // drape's time is spent, and counted in report.json ("quality_warnings").
  std::vector<std::string> quality;
  if (scene.garment && scene.body)
    for (const garment::QualityWarning& w : quality_warnings(*scene.garment, sketch, *scene.body))
      quality.push_back(fmt::format("{}: {}", sketch.file, w.message));
  // "solver"/"time_step": "auto" (the defaults): chosen now that the scene's size is known.
  const sim::AutomaticChoice automatic =
      apply_automatic_settings(sketch, scene, settings, options.frames_per_second > 0.0);
  spdlog::debug("settings: {}", automatic.reason);
  settings.energy_from_next_step = !options.trace;  // the trace reads each step's own sample
  const RunEstimate estimate =
      estimate_run(sketch, scene.input, scene_model_options(scene), options.frames_per_second,
                   settings.duration, settings.dt);
  check_run_fits(sketch, estimate, limits, options.frames_per_second);
  spdlog::debug(
      "estimate: {:.0f} vertices, {:.2f} GB ({:.2f} GB the factor), at most {:.0f} steps ({:.0f} "
      "s), {:.0f} frames",
      estimate.vertices, estimate.memory_bytes / 1e9, estimate.factor_bytes / 1e9, estimate.steps,
      estimate.seconds, estimate.frames);
  // A user's own OMP_THREAD_LIMIT above 1 lets CHOLMOD's OpenMP regions run on several threads,
  // which libgomp keeps spinning while they wait unless told otherwise; the policy is read when
  // libgomp is loaded, so only the user can set it (docs/benchmarks.md, "Tenth round (issue
  // 24)": the t-shirt example 33.5 s of CPU at OMP_THREAD_LIMIT=2, 1.76 s with it passive).
  if (const char* omp_limit = std::getenv("OMP_THREAD_LIMIT");
      omp_limit != nullptr && std::atoi(omp_limit) > 1 && std::getenv("OMP_WAIT_POLICY") == nullptr)
    spdlog::warn(
        "OMP_THREAD_LIMIT={} lets CHOLMOD run on several OpenMP threads, which spin while they "
        "wait (the t-shirt example took 22 times its CPU time at 2 threads on a busy machine); "
        "set OMP_WAIT_POLICY=passive as well",
        omp_limit);
  if (spdlog::should_log(spdlog::level::debug)) {  // the probe opens an OpenMP region: -v only
    const char* omp_limit = std::getenv("OMP_THREAD_LIMIT");
    const char* blas_limit = std::getenv("OPENBLAS_NUM_THREADS");
    const sim::SolverLibraryThreads library = sim::solver_library_threads();
    spdlog::debug(
        "solver libraries: OMP_THREAD_LIMIT {}, OPENBLAS_NUM_THREADS {}; an OpenMP region asking "
        "for 4 threads gets {}, OpenBLAS runs {}",
        omp_limit ? omp_limit : "unset", blas_limit ? blas_limit : "unset", library.openmp_region,
        library.openblas);
  }
  if (!limits.max_time_s && estimate.seconds > 3600)
    spdlog::warn(
        "this drape may take up to about {:.1f} h ({:.0f} steps on {:.0f} vertices, by "
        "the estimate); --max-time SECONDS stops it",
        estimate.seconds / 3600, estimate.steps, estimate.vertices);
  if (scene.pinned.empty() && !scene.body)
    spdlog::warn("nothing holds the cloth (no pins, no body): it will fall for the whole run");

  const std::filesystem::path dir(options.out);
  StagedOutputs outputs;
  outputs.keep(sketch.file);
  if (sketch.garment_mesh) outputs.keep(sketch.resolve(*sketch.garment_mesh));
  if (sketch.body.mesh != "builtin") outputs.keep(sketch.resolve(sketch.body.mesh));
  std::string trace;
  Progress progress("draping", static_cast<long>(std::ceil(settings.duration * 1000)),
                    global.quiet);
  // Called after every accepted step, by either driver.
  // Adaptive detail can grow the cloth past the estimate: the budget is also checked as it runs.
  const double memory_budget = memory_budget_bytes(limits);
  // For the trace: the body's landmarks, to say where on the body the cloth still moves.
  std::optional<garment::BodyLandmarks> landmarks;
  if (options.trace && scene.body) {
    try {
      landmarks = garment::find_landmarks(scene.body->mesh);
    } catch (const std::runtime_error&) {
      // Not a standing figure: the trace gives positions only.
    }
  }
  std::optional<Clock::time_point> drape_start;  // when the drape's first step began
  const auto on_step = [&](const sim::ClothDriver& d) {
    const sim::Simulation& s = d.simulation();
    if (const double resident = peak_resident_memory_bytes();
        memory_budget > 0 && resident > memory_budget)
      throw RunLimitExceeded(fmt::format(
          "stopped at t = {:.3f} s of the drape: it uses {} with {} vertices, more than "
          "the {} it may take (--max-memory); limit adaptive detail with "
          "simulate.adaptive.max_vertices or max_level; nothing was written",
          s.time(), memory_text(resident), s.model().vertex_count, memory_text(memory_budget)));
    // --max-time bounds the whole command (a job's wall time), set-up included: the message
    // says how much of it the set-up took, which a large body or garment makes most of it.
    if (limits.max_time_s &&
        std::chrono::duration<double>(Clock::now() - start).count() > *limits.max_time_s) {
      const double setup_s =
          std::chrono::duration<double>(drape_start.value_or(Clock::now()) - start).count();
      const double elapsed_s = std::chrono::duration<double>(Clock::now() - start).count();
      throw RunLimitExceeded(fmt::format(
          "stopped at t = {:.3f} s of the drape: --max-time {:g} s passed ({:.1f} s of wall time "
          "since the command started: {:.1f} s of set-up, reading the body and the sketch, meshing "
          "and laying out the pattern, then {:.1f} s of drape){}; nothing was written",
          s.time(), *limits.max_time_s, elapsed_s, setup_s, elapsed_s - setup_s,
          setup_s > 0.5 * *limits.max_time_s
              ? "; the set-up took most of the time: give a larger --max-time"
              : ""));
    }
    progress.update(static_cast<long>(s.time() * 1000), fmt::format("t = {:.2f} s", s.time()));
    if (!options.trace) return;
    const sim::SimulationReport& r = s.report();
    nlohmann::json line = {{"step", r.steps},
                           {"time", s.time()},
                           {"dt", s.current_dt()},
                           {"retries", r.retries},
                           {"vertices", s.model().vertex_count}};
    if (!r.energy.empty()) {
      const sim::EnergySample& e = r.energy.back();
      line["energy"] = {{"stretch", e.stretch},
                        {"shear", e.shear},
                        {"bend", e.bend},
                        {"kinetic", e.kinetic},
                        {"potential", e.potential}};
    }
    // Why a drape is not at rest: the fastest vertex (where, in which panel, near which
    // landmark, and whether a body contact holds it), how many move faster than the at-rest
    // speed, and the contact switches of the step (contacts released, body-vertex springs).
    const Eigen::VectorXd& velocity = s.velocities();
    int fastest = 0, moving = 0;
    double top = 0.0;
    for (int i = 0; i < s.model().vertex_count; ++i) {
      const double speed = velocity.segment<3>(3 * i).norm();
      if (speed > settings.rest_speed) ++moving;
      if (speed > top) {
        top = speed;
        fastest = i;
      }
    }
    const Eigen::MatrixX3i& faces = d.faces();
    const Eigen::VectorXi sources = d.source_faces();
    // A vertex as the trace names it: where, in which panel, near which landmark, and whether
    // a body contact holds it.
    const auto place = [&](int vertex) {
      const Eigen::Vector3d at = s.positions().segment<3>(3 * vertex);
      std::string panel;
      for (Eigen::Index t = 0; t < faces.rows() && panel.empty(); ++t)
        if ((faces.row(t).array() == vertex).any() && sources(t) < scene.face_group.size() &&
            scene.face_group(sources(t)) < static_cast<int>(scene.group_names.size()))
          panel = scene.group_names[static_cast<size_t>(scene.face_group(sources(t)))];
      std::string held = "free";
      if (s.contact())
        for (const sim::ActiveContact& c : s.contact()->contacts())
          if (c.contact.vertex == vertex) held = c.released ? "released" : "held";
      nlohmann::json where = {{"vertex", vertex},
                              {"at", {at.x(), at.y(), at.z()}},
                              {"panel", panel},
                              {"contact", held}};
      if (landmarks) where["near"] = landmarks->nearest(at).name;
      return where;
    };
    line["fastest"] = place(fastest);
    line["fastest"]["speed"] = top;
    line["moving"] = moving;
    // The at-rest test's view of the step: how long the cloth has been still, and otherwise
    // what ended the still stretch (with a drift, the vertex that left the anchor farthest).
    line["rest"] = {{"still_s", r.rest_still_time}, {"break", sim::rest_break_name(r.rest_break)}};
    if (r.rest_break == sim::RestBreak::drift ||
        (r.rest_break == sim::RestBreak::none && r.rest_break_vertex >= 0)) {
      line["rest"]["drift"] = place(r.rest_break_vertex);
      line["rest"]["drift"]["distance"] = r.rest_break_drift;
    }
    if (s.contact()) {
      const sim::ContactStepStats& c = s.contact()->step_stats();
      line["contacts"] = {{"held", c.contacts},
                          {"released", c.released},
                          {"stuck", c.stuck},
                          {"body_vertex_springs", c.piercings_held},
                          {"body_vertex_springs_added", c.piercings_resolved}};
    }
    line["self_contacts"] = r.self_contacts_final;
    trace += line.dump() + "\n";
  };

  // The PNG sequence: a frame at t = 0 and whenever a step reaches the next frame time (the
  // same state again for every frame time a long step passed, so that the sequence keeps its
  // rate).
  std::vector<Frame> frames;
  const auto frame_due = [&](double t) {
    return options.frames_per_second > 0.0 &&
           t >= static_cast<double>(frames.size()) / options.frames_per_second - 1e-9;
  };
  if (frame_due(0.0)) {
    frames.push_back(
        {0.0, {scene.start, scene.input.triangles}, triangle_groups(scene, scene.triangle_face)});
  }

  // One driver: the cloth's 4-8 mesh, adapting or not (a sheet that does not adapt drapes on its
  // own triangles).
  RunReport out;                           // report.json, filled as the drape goes
  out.warnings = fabric_warnings(sketch);  // logged by check_sketch, as are the gather warnings
  for (std::string& warning : gather_warnings(sketch)) out.warnings.push_back(std::move(warning));
  for (std::string& warning : gravity_warnings(sketch)) out.warnings.push_back(std::move(warning));
  if (scene.garment)  // logged as the garment was meshed (garment_stage.cpp)
    for (std::string& warning : seam_ease_warnings(sketch, *scene.garment))
      out.warnings.push_back(std::move(warning));
  if (!scene.flat_rest_differs.empty()) out.warnings.push_back(scene.flat_rest_differs);
  out.quality_warnings = static_cast<int>(quality.size());
  out.warnings.insert(out.warnings.end(), quality.begin(), quality.end());
  // The body's repairs and defects (an open body, inconsistent triangles), logged as it loaded.
  if (scene.body)
    out.warnings.insert(out.warnings.end(), scene.body->warnings.begin(),
                        scene.body->warnings.end());
  sim::SimulationReport& report = out.simulation;
  out.settings = settings;
  meshing::TriMesh draped;
  Eigen::VectorXi triangle_group;
  Eigen::VectorXd face_levels;
  const bool flat_rest = scene.input.rest_uv.rows() > 0;
  try {
    // A garment adapts unless the file says "adaptive": false; a sheet only when it asks.
    const bool adaptive =
        sketch.simulate.adaptive && (!sketch.sheet || sketch.simulate.adaptive_given);
    sim::ClothDriver driver = scene_driver(
        scene, settings, adaptive ? std::optional(adaptive_settings(sketch)) : std::nullopt);
    // Contacts and friction (through every split and merge), with the body still or moving.
    if (scene.body_motion)
      driver.set_body_motion(*scene.body_motion);
    else if (scene.body)
      driver.set_body(scene.body->mesh);
    // Each triangle keeps the group of the input face it descends from.
    const auto groups_of = [&](const sim::ClothDriver& d) {
      return triangle_groups(scene, d.source_faces());
    };
    // Cloth that nothing holds (no pin, and nothing of it caught on the body) falls: trial 41's
    // P2, the docs' 20 cm patch on the chest, fell 126 m and failed 5 s later at 50 m/s. Once
    // the whole cloth is below the body's lowest point under a constant pull it can never come
    // back (a still body, no wind lifting it), so the run stops there with the reason.
    const FallWatch fall = fall_watch(scene, settings.forces);
    std::optional<double> fell_at;
    sim::ClothObserver observer;
    observer.after_step = [&](const sim::ClothDriver& d, const sim::StepOutcome& outcome) {
      if (!outcome.accepted) return false;
      if (fall.active && fell_below_body(fall, d.positions())) {
        fell_at = d.time();
        return false;
      }
      on_step(d);
      while (frame_due(d.time()))
        frames.push_back({d.time(), {d.positions(), d.faces()}, groups_of(d)});
      return true;
    };
    drape_start = Clock::now();
    report = driver.run(observer);
    if (fell_at) {
      progress.finish();
      fail_fell_off(sketch, scene, fall, *fell_at);
    }
    draped.vertices = driver.positions();
    draped.faces = driver.faces();
    face_levels = driver.face_levels().cast<double>();
    triangle_group = groups_of(driver);
    out.strain = group_strains(driver.simulation().model(), draped.vertices, triangle_group,
                               scene.group_names);
    // Cloth the start's untangling left through itself (logged by the simulation): report.json
    // carries the sentence too, as an at_rest drape with no warnings looked clean (trial 42, P2).
    if (!report.self_untangle_warning.empty())
      out.warnings.push_back(fmt::format("{}: {}", sketch.file, report.self_untangle_warning));
    // How far the garment went down from where it was drawn: its centre of mass, from the
    // potential energy −Σ m g·x of the first and last samples (mass is conserved through
    // adaptive detail's splits and merges).
    const double weight = driver.simulation().model().total_mass() * settings.forces.gravity.norm();
    if (scene.garment && scene.body && report.energy.size() >= 2 && weight > 0.0) {
      out.settled_drop =
          (report.energy.front().potential - report.energy.back().potential) / weight;
      // Worded for the garment: the curve at its top (a skirt's waist, a top's upper edge)
      // and the panels it bounds, which are what should hold it up. Panels eased above 1
      // hang lower by design (trial 36's blouse at 1.08: 3.8 cm): that part is no slide.
      const std::optional<TopOpening> opening = top_opening(*scene.garment);
      const double eased =
          opening ? ease_drop(*opening, sketch.panels,
                              opening->centre.y() - scene.garment->mesh.vertices.col(1).mean())
                  : 0.0;
      // A failed drape did not settle: how far it fell before it broke says nothing of its fit
      // (trial 39, P13: a blow-up at t = 0.005 s was told it slid).
      if (!report.failed && *out.settled_drop > kSlidWarning + eased) {
        std::string landmark;
        if (opening) {
          try {
            landmark = garment::find_landmarks(scene.body->mesh).nearest(opening->centre).name;
          } catch (const std::runtime_error&) {
            // Not a standing figure: the height alone.
          }
        }
        out.warnings.push_back(
            settled_warning(sketch.file, *out.settled_drop, opening, landmark, eased));
        spdlog::warn("{}", out.warnings.back());
      }
    }
    // Ended without reaching at rest (the duration ran out): where it still moves and what to
    // try, so that a moving drape is not taken for a settled one.
    // (With "stop_at_rest": false the run goes on to the end; it is judged by its last window.)
    const bool still_moving = !report.failed && !report.at_rest &&
                              (settings.stop_at_rest || !driver.simulation().at_rest());
    if (still_moving) {
      const sim::Simulation& s = driver.simulation();
      StillMoving where;
      where.vertices = s.model().vertex_count;
      int fastest = 0;
      for (int i = 0; i < where.vertices; ++i) {
        const double speed = s.velocities().segment<3>(3 * i).norm();
        if (speed > settings.rest_speed) ++where.moving;
        if (speed > where.speed) where.speed = speed, fastest = i;
      }
      where.at = draped.vertices.row(fastest).transpose();
      where.flat_rest = flat_rest;
      where.rest_ramp = scene.rest_ramp;  // with the gather's default ramp
      where.still_s = report.rest_still_time;
      where.drift_m = std::isnan(report.rest_drift) ? 0.0 : report.rest_drift;
      {
        std::vector<double> time, kinetic;
        for (const sim::EnergySample& e : s.report().energy) {
          time.push_back(e.time);
          kinetic.push_back(e.kinetic);
        }
        where.kinetic_trend = kinetic_energy_trend(time, kinetic, report.sim_time);
      }
      for (Eigen::Index t = 0; t < draped.faces.rows() && where.panel.empty(); ++t)
        if ((draped.faces.row(t).array() == fastest).any() && t < triangle_group.size() &&
            triangle_group(t) >= 0 &&
            triangle_group(t) < static_cast<int>(scene.group_names.size()))
          where.panel = scene.group_names[static_cast<size_t>(triangle_group(t))];
      if (scene.body) {
        try {
          where.landmark = garment::find_landmarks(scene.body->mesh).nearest(where.at).name;
        } catch (const std::runtime_error&) {
          // Not a standing figure: the place without a landmark.
        }
      }
      out.warnings.push_back(not_at_rest_warning(sketch.file, report.sim_time, settings.rest_speed,
                                                 settings.rest_window, where));
      spdlog::warn("{}", out.warnings.back());
    }
    // A panel left stretched far beyond what cloth at rest stretches (drape_warnings.hpp): once
    // per panel, its mirror copy folded in (the worse of the two).
    if (scene.garment && !report.failed) {
      std::map<std::string, const GroupStrain*> worst;
      for (const GroupStrain& g : out.strain) {
        const std::string panel =
            g.group.ends_with(".mirror") ? g.group.substr(0, g.group.size() - 7) : g.group;
        if (g.stretch_max > kOverstretched &&
            (!worst.contains(panel) || g.stretch_max > worst[panel]->stretch_max))
          worst[panel] = &g;
      }
      for (const auto& [panel, g] : worst) {
        std::string landmark;
        if (scene.body) {
          try {
            landmark = garment::find_landmarks(scene.body->mesh).nearest(g->stretch_at).name;
          } catch (const std::runtime_error&) {
            // Not a standing figure: the place without a landmark.
          }
        }
        out.warnings.push_back(overstretched_warning(sketch.file, g->group, g->stretch_max,
                                                     g->stretch_at, landmark, !still_moving));
        spdlog::warn("{}", out.warnings.back());
      }
    }
    if (adaptive) out.adaptive = *driver.adaptive_report();
  } catch (const sim::InvalidFabricError& e) {
    sketch.fail("/fabric", e.what());
  }
  progress.finish();
  if (report.failed) {
    // Where and why, and the last accepted state to look at: drape-failed.obj and images with
    // a marker (a red octahedron 10 cm across) where it broke, seen from the
    // four sides (the place may face any way).
    const int v = report.failure_vertex;
    const bool located = v >= 0 && v < draped.vertices.rows();
    const Eigen::Vector3d where =
        located ? Eigen::Vector3d(draped.vertices.row(v).transpose())
                : Eigen::Vector3d(draped.vertices.colwise().mean().transpose());
    std::string panel = "?", landmark;
    for (Eigen::Index t = 0; t < draped.faces.rows() && located && panel == "?"; ++t)
      for (int k = 0; k < 3; ++k)
        if (draped.faces(t, k) == v && t < triangle_group.size() &&
            triangle_group(t) < static_cast<int>(scene.group_names.size()))
          panel = scene.group_names[static_cast<size_t>(triangle_group(t))];
    if (scene.body) {
      try {
        landmark = garment::find_landmarks(scene.body->mesh).nearest(where).name;
      } catch (const std::runtime_error&) {
        // Not a standing figure: the place is given without a landmark.
      }
    }
    // Red and 10 cm across, so that it shows through a sleeve or a skirt round the place.
    meshing::TriMesh marker;
    marker.vertices.resize(6, 3);
    marker.faces.resize(8, 3);
    const double r = 0.05;
    const Eigen::Vector3d axes[6] = {{r, 0, 0},  {-r, 0, 0}, {0, 0, r},
                                     {0, 0, -r}, {0, r, 0},  {0, -r, 0}};
    for (int k = 0; k < 6; ++k) marker.vertices.row(k) = (where + axes[k]).transpose();
    marker.faces << 0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5;
    StagedOutputs failed_outputs;
    failed_outputs.stage(dir / "drape-failed.obj",
                         to_obj({draped.vertices, draped.faces,
                                 std::vector<int>(triangle_group.data(),
                                                  triangle_group.data() + triangle_group.size()),
                                 scene.group_names},
                                "drape-failed"));
    const std::optional<meshing::TriMesh> body_now =
        scene.body ? std::optional(body_at(scene, report.sim_time)) : std::nullopt;
    std::vector<scene::ImageSpec> sides;
    for (const char* view : {"front", "back", "left", "right"}) {
      scene::ImageSpec image;
      image.view = view;
      image.width = 600;
      image.height = 900;
      sides.push_back(image);
    }
    // The pictures only when they fit the budget and OSMesa can be opened: drape-failed.obj and
    // the reason the drape failed come first.
    std::string pictures = " and drape-failed-<view>.png (the place marked)";
    if (const auto over = rendering_over_budget(
            resident_memory_bytes(), renderer_memory(sides.front().width, sides.front().height),
            renderer.total() > 0, memory_budget, limits.max_memory_bytes > 0))
      pictures = fmt::format(" (its pictures were not drawn: {})", *over);
    else
      try {
        stage_preview_images(sides, false, body_now ? &*body_now : nullptr,
                             {draped, triangle_group, {}, {}, marker}, "drape-failed", dir,
                             failed_outputs);
      } catch (const render::RenderError& e) {
        pictures = fmt::format(" (its pictures were not drawn: {})", e.what());
      }
    // The trace is what to read when a drape fails (trial 35 found none): its accepted steps and
    // a last line saying where and why it broke, with the other failure files.
    if (options.trace) {
      nlohmann::json failed = {{"failed", report.failure_reason},
                               {"time", report.sim_time},
                               {"vertex", located ? v : -1},
                               {"at", {where.x(), where.y(), where.z()}},
                               {"panel", panel}};
      if (!landmark.empty()) failed["near"] = landmark;
      failed_outputs.stage(dir / "trace.jsonl", trace + failed.dump() + "\n");
    }
    failed_outputs.commit();
    // Stuck after a start inside the body: the likely cause, which the start repair could not
    // undo (cloth pushed out on both sides of a leg is caught round it).
    std::string cause;
    if (report.stuck && report.start_repair_vertices > 0)
      cause = fmt::format(
          "; it started with {} vertices inside the body, the deepest {:.1f} mm: cloth drawn that "
          "deep inside the body (a curve with \"on_body\": false through it? see validate's "
          "inside_body warnings) is caught round it when pushed out: draw it outside the body",
          report.start_repair_vertices, 1e3 * report.start_repair_depth_m);
    throw std::runtime_error(fmt::format(
        "the simulation failed at t = {:.3f} s in panel '{}' at ({:.3f}, {:.3f}, {:.3f}) m{}: "
        "{}{}; the last accepted state is in {}{}{}",
        report.sim_time, panel, where.x(), where.y(), where.z(),
        landmark.empty() ? "" : fmt::format(", near the {}", landmark), report.failure_reason,
        cause, (dir / "drape-failed.obj").string(), pictures,
        options.trace ? ", the steps up to it in " + (dir / "trace.jsonl").string() : ""));
  }

  // The drape's memory is known now (adaptive detail may have grown it past the estimate):
  // the pictures are refused before the context is made, with nothing written, when they would
  // take the process over its budget.
  if (renderer.total() > 0) {
    const double resident = resident_memory_bytes();
    spdlog::debug(
        "before the pictures: resident memory {}, {} at most so far; rendering {}x{} "
        "adds about {}",
        memory_text(resident), memory_text(peak_resident_memory_bytes()), renderer.width,
        renderer.height, memory_text(renderer.frame_bytes));
    if (const auto over = rendering_over_budget(resident, renderer, true, memory_budget,
                                                limits.max_memory_bytes > 0))
      throw RunLimitExceeded(fmt::format(
          "stopped before rendering the pictures: {}; ask for smaller images or none "
          "(\"output\": {{\"images\": []}}, and no --frames), or give a larger --max-memory; "
          "nothing was written",
          *over));
  }

  // The draped cloth, one group per panel.
  const ExportMesh mesh{
      draped.vertices, draped.faces,
      std::vector<int>(triangle_group.data(), triangle_group.data() + triangle_group.size()),
      scene.group_names};
  outputs.stage(dir / "drape.glb", to_glb(mesh, "drape"));
  outputs.stage(dir / "drape.obj", to_obj(mesh, "drape"));

  const auto image_start = Clock::now();
  // The body as it stands at the end (its last pose when it moves).
  const std::optional<meshing::TriMesh> body_end =
      scene.body ? std::optional(body_at(scene, report.sim_time)) : std::nullopt;
  const PreviewCloth preview{
      draped, triangle_group, render::triangle_edges(draped), face_levels, {}};
  const std::vector<scene::ImageSpec> image_specs = run_images(sketch);
  // One context for the images and the sequence (the renderer's memory counted once).
  std::optional<render::Renderer> renderer_context;
  if (!image_specs.empty() || !frames.empty()) renderer_context.emplace();
  const std::vector<std::string> images =
      image_specs.empty()
          ? std::vector<std::string>{}
          : stage_preview_images(*renderer_context, image_specs, sketch.output.wireframe,
                                 body_end ? &*body_end : nullptr, preview, "drape", dir, outputs);
  // The sequence: the first image the file asks for (front by default), without edges.
  std::vector<scene::ImageSpec> frame_image = {image_specs.empty() ? scene::ImageSpec{}
                                                                   : image_specs.front()};
  frame_image.front().wireframe = false;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const std::optional<meshing::TriMesh> body =
        scene.body ? std::optional(body_at(scene, frames[i].time)) : std::nullopt;
    stage_preview_images(*renderer_context, frame_image, false, body ? &*body : nullptr,
                         {frames[i].cloth, frames[i].triangle_group, {}, {}, {}},
                         fmt::format("frame-{:04d}", i), dir / "frames", outputs);
  }
  const double image_s = std::chrono::duration<double>(Clock::now() - image_start).count();

  if (sketch.simulate.solver == "auto" || sketch.simulate.time_step_auto)
    out.automatic = automatic.reason;
  out.self_intersections_final = count_self_intersections(draped.vertices, draped.faces);
  out.sketch = sketch.file;
  out.scene = sketch.sheet ? "sheet" : (sketch.garment_mesh ? "imported garment" : "garment");
  out.fabric = scene.fabric_name;
  if (scene.body) out.body = scene.body->raw.source;
  out.pinned_vertices = scene.pinned.size();
  out.meshing = meshing_summary(scene);
  if (scene.imported)
    out.imported = nlohmann::json{{"file", sketch.resolve(*sketch.garment_mesh).string()},
                                  {"vertices", scene.imported->vertices},
                                  {"triangles", scene.imported->triangles},
                                  {"file_faces", scene.imported->faces},
                                  {"vertices_48", scene.start.rows()},
                                  {"triangles_48", scene.input.triangles.rows()}};
  out.bending = sim::bend_model_name(scene.bend_model);
  out.compression = sim::compression_name(scene.compression);
  out.cusick = cusick_json(sketch, draped);
  out.cantilever = cantilever_json(sketch, scene, draped, settings.forces.gravity.norm());
  out.rest_shape = flat_rest ? (scene.bend_rest_flat ? "flat" : "flat and shaped") : "shaped";
  if (pattern_sheet) {
    stage_pattern(*pattern_sheet, dir, outputs);
    out.pattern = pattern_summary(*pattern_sheet);
  }
  // How deep the draped cloth dents between supports (a skirt pulled between the legs): the
  // slices from 10 % of the garment's height up to 60 % of it, but not above the body's crotch
  // (cloth between the legs is below it; above it, the gap between a sleeve and the torso is a
  // "dent" too, 8.6 cm on a blouse). A garment that ends less than 5 cm below the crotch (a
  // top) has none.
  if (scene.garment && draped.vertices.rows() > 0) {
    const double low = draped.vertices.col(1).minCoeff();
    const double high = draped.vertices.col(1).maxCoeff();
    std::optional<double> crotch;
    if (scene.body) {
      try {
        crotch = garment::find_landmarks(scene.body->mesh).find("crotch")->position.y();
      } catch (const std::runtime_error&) {
        // Not a standing figure: the slices of the garment's own proportions.
      }
    }
    if (const std::optional<double> top = slice_dent_top(low, high, crotch)) {
      out.slice_dent_to = std::max(0.1, *top);
      out.slice_dent = meshing::slice_dent(draped, 0.1, out.slice_dent_to);
    }
  }
  out.images = images;
  out.frames = frames.size();
  if (sketch.body.motion && scene.body_motion) {
    const garment::BodyMotionSpec& motion = *sketch.body.motion;
    out.body_motion = {motion.type, scene.body_motion->start_time(), scene.body_motion->end_time(),
                       std::nullopt, std::nullopt};
    if (motion.type == "poses")
      out.body_motion->poses = motion.poses.size();
    else
      out.body_motion->degrees = motion.degrees;
  }
  out.images_s = image_s;
  out.total_s = std::chrono::duration<double>(Clock::now() - start).count();
  if (sketch.output.report) outputs.stage(dir / "report.json", run_report_json(out).dump(2) + "\n");
  if (options.trace) outputs.stage(dir / "trace.jsonl", trace);
  outputs.commit();
  if (const std::string notice =
          stale_outputs_notice(dir, stale_outputs(dir, outputs.paths_and_inputs()));
      !notice.empty())
    spdlog::warn("{}", notice);
  spdlog::info("draped {} → {}: {} steps, {:.2f} s simulated{}, {:.2f} s wall", sketch.file,
               dir.string(), report.steps, report.sim_time, report.at_rest ? " (at rest)" : "",
               report.wall_time_s);
}

}  // namespace

void add_run_command(CLI::App& app, const GlobalOptions& global) {
  auto options = std::make_shared<RunOptions>();
  CLI::App* cmd = app.add_subcommand(
      "run",
      "Drape a sketch's garment (or sheet) with the cloth simulator: draped mesh, report, "
      "images");
  cmd->add_option("SKETCH", options->sketch, "Sketch file (format sketchdrape/1)")->required();
  cmd->add_option("-o,--out", options->out, "Output directory (created if needed)")
      ->check(non_empty_path());
  cmd->add_flag("--trace", options->trace, "Also write trace.jsonl: one JSON line per step");
  cmd->add_option("--frames", options->frames_per_second,
                  "Also write frames/frame-NNNN-<view>.png: this many pictures per simulated "
                  "second (the first image's view, the body at its pose)")
      ->check(finite_range(1e-3, 1000, "pictures per simulated second"));
  cmd->add_option("--max-memory", options->max_memory,
                  "Refuse a drape estimated to need more memory than this (e.g. 4G, 512M; "
                  "default: the memory available)");
  cmd->add_option("--max-time", options->max_time_s,
                  "Stop (writing nothing) once this many seconds of wall time have passed "
                  "since the command started (set-up and meshing count); refuse a drape "
                  "without stop_at_rest estimated to take longer")
      ->check(finite_range(1e-3, 1e9));
  cmd->callback([options, &global] { run_drape(*options, global); });
}

}  // namespace sd::app
