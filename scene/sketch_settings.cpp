// The simulator's, the sheet's and the outputs' sections of a sketch file: "simulate" (the
// simulator's own settings), "sheet" and "output" (the render specs and the sewing pattern).

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <tuple>

#include "scene/sketch_sections.hpp"
#include "sim/sheet.hpp"

namespace sd::scene::detail {
namespace {

// s: the adaptive lookahead and change interval are below this (see parse_adaptive).
constexpr double kMaxAdaptiveSeconds = 1.0;

// "adaptive": true | false | {"enabled": ..., "refine_threshold": ..., ...}.
void parse_adaptive(const Reader& r, const json& a, SimulateSpec& sim) {
  const std::string path = "/simulate/adaptive";
  sim.adaptive_given = true;
  if (a.is_boolean()) {
    sim.adaptive = a.get<bool>();
    return;
  }
  if (!a.is_object())
    r.fail(path,
           "expected true, false or an object of adaptive settings {\"refine_threshold\": "
           "0.002, ...}");
  r.check_keys(a, path,
               {"enabled", "refine_threshold", "coarsen_threshold", "steady_rate", "min_lifetime",
                "min_level", "max_level", "max_vertices", "merge_batch", "even_levels",
                "target_levels", "lookahead", "change_interval"});
  sim::AdaptiveSettings& s = sim.adaptive_settings;  // the simulator's defaults where unset
  if (a.contains("enabled")) sim.adaptive = r.boolean(a["enabled"], path + "/enabled");
  if (a.contains("refine_threshold"))
    s.refine_threshold = r.positive(a["refine_threshold"], path + "/refine_threshold");
  if (a.contains("coarsen_threshold"))
    s.coarsen_threshold = r.positive(a["coarsen_threshold"], path + "/coarsen_threshold");
  // Two values the file gives are checked against each other here; a value against a default
  // is checked by run (sim::AdaptiveSettings::validate, at /simulate/adaptive).
  if (a.contains("refine_threshold") && a.contains("coarsen_threshold") &&
      !(s.coarsen_threshold < s.refine_threshold))
    r.fail(path + "/coarsen_threshold",
           fmt::format("the coarsen threshold ({} m) must be below the refine threshold ({} m): "
                       "the gap keeps a merged block from being split again at once",
                       s.coarsen_threshold, s.refine_threshold));
  if (a.contains("steady_rate"))
    s.steady_rate = r.non_negative(a["steady_rate"], path + "/steady_rate");
  if (a.contains("min_lifetime"))
    s.min_lifetime = r.non_negative(a["min_lifetime"], path + "/min_lifetime");
  for (const auto& [key, level] :
       {std::pair{"min_level", &s.min_level}, std::pair{"max_level", &s.max_level}}) {
    if (!a.contains(key)) continue;
    *level = r.integer(a[key], path + "/" + key, 0);
    if (*level > 30) r.fail(path + "/" + key, "levels go from 0 (the input's blocks) to 30");
  }
  if (a.contains("min_level") && a.contains("max_level") && s.max_level < s.min_level)
    r.fail(path + "/max_level", fmt::format("max_level ({}) must not be below min_level ({})",
                                            s.max_level, s.min_level));
  if (a.contains("max_vertices"))
    s.max_vertices = r.integer(a["max_vertices"], path + "/max_vertices", 0);
  if (a.contains("merge_batch")) {
    s.merge_batch = r.non_negative(a["merge_batch"], path + "/merge_batch");
    if (!(s.merge_batch < 1.0))
      r.fail(path + "/merge_batch",
             "the merge batch is a fraction of the particles (0.05: merges wait until 5 % of "
             "them can go at once); it must be below 1");
  }
  if (a.contains("even_levels")) s.even_levels = r.boolean(a["even_levels"], path + "/even_levels");
  if (a.contains("target_levels"))
    s.target_levels = r.boolean(a["target_levels"], path + "/target_levels");
  // Both are times of the order of a few steps: the lookahead is also the length of the trial
  // run before the first step (a copy of the whole drape), so a second or more would cost a
  // drape of its own; an interval of a second or more would leave a falling garment on its
  // first mesh.
  for (const auto& [key, seconds, what] :
       {std::tuple{"lookahead", &s.lookahead, "a refinement lookahead"},
        std::tuple{"change_interval", &s.change_interval, "an interval between mesh changes"}}) {
    if (!a.contains(key)) continue;
    *seconds = r.number(a[key], path + "/" + key);
    if (!(*seconds >= 0.0 && *seconds < kMaxAdaptiveSeconds))
      r.fail(path + "/" + key,
             fmt::format("{} of {} s is outside 0 .. {} s (below {} s; 0.1 s is usual, 0 turns "
                         "it off)",
                         what, *seconds, kMaxAdaptiveSeconds, kMaxAdaptiveSeconds));
  }
}

// "pattern": true, false, or an object of settings.
void parse_pattern(const Reader& r, const json& j, OutputSpec& out) {
  const std::string path = "/output/pattern";
  if (j.is_boolean()) {
    if (j.get<bool>()) out.pattern = PatternSpec{};
    return;
  }
  r.require_object(j, path, "true, false or an object of pattern settings");
  r.check_keys(j, path, {"fabric_width", "seam_allowance", "max_stretch"});
  PatternSpec spec;
  if (j.contains("fabric_width")) {
    spec.fabric_width = r.positive(j["fabric_width"], path + "/fabric_width");
    // Bolts are 0.9-3 m wide; 150 is centimetres typed for metres. The range is that of
    // `pattern --fabric-width`.
    if (spec.fabric_width < kMinFabricWidth || spec.fabric_width > kMaxFabricWidth)
      r.fail(path + "/fabric_width",
             out_of_range_sentence(spec.fabric_width, kMinFabricWidth, kMaxFabricWidth,
                                   "a fabric width of", kUsualFabricWidth));
  }
  if (j.contains("seam_allowance")) {
    spec.seam_allowance = r.number(j["seam_allowance"], path + "/seam_allowance");
    if (spec.seam_allowance < 0 || spec.seam_allowance > kMaxSeamAllowance)
      r.fail(path + "/seam_allowance",
             out_of_range_sentence(spec.seam_allowance, 0, kMaxSeamAllowance, "a seam allowance of",
                                   kUsualSeamAllowance));
  }
  if (j.contains("max_stretch"))
    spec.max_stretch = r.positive(j["max_stretch"], path + "/max_stretch");
  out.pattern = spec;
}

}  // namespace

void parse_simulate(const Reader& r, const json& j, SimulateSpec& sim) {
  const std::string path = "/simulate";
  r.require_object(j, path, "simulate");
  r.check_keys(j, path,
               {"duration", "adaptive", "time_step", "integrator", "solver", "bending",
                "compression", "stop_at_rest", "gravity", "pin_above", "check_body_vertices",
                "rest", "self_collision", "rest_ramp", "fade_carried_push", "gather_start"});
  if (j.contains("pin_above")) sim.pin_above = r.number(j["pin_above"], path + "/pin_above");
  if (j.contains("duration")) {
    sim.duration = r.positive(j["duration"], path + "/duration");
    sim.duration_given = true;
    if (sim.duration > kMaxDuration)
      r.fail(path + "/duration",
             fmt::format("a drape of {:.6g} s is longer than the {:g} s (one hour of simulated "
                         "time) allowed; a garment settles within seconds",
                         sim.duration, kMaxDuration));
  }
  if (j.contains("adaptive")) parse_adaptive(r, j["adaptive"], sim);
  if (j.contains("time_step") && j["time_step"].is_string()) {
    if (r.text(j["time_step"], path + "/time_step") != "auto")
      r.fail(path + "/time_step",
             "a time step is a number of seconds (1/60 s is 0.0167) or \"auto\" (the default: "
             "chosen from the scene)");
    sim.time_step_auto = true;
  } else if (j.contains("time_step")) {
    sim.time_step_auto = false;
    sim.time_step = r.positive(j["time_step"], path + "/time_step");
    if (sim.time_step < kMinTimeStep || sim.time_step > kMaxTimeStep)
      r.fail(path + "/time_step",
             fmt::format("a time step of {:.6g} s is outside {:g} .. {:g} s (the step control "
                         "shortens steps itself when it needs to; 1/60 s is the default)",
                         sim.time_step, kMinTimeStep, kMaxTimeStep));
    // Trial 40: 0.1 s steps for 1e-5 s ran one clipped step and wrote the garment as drawn.
    if (sim.duration_given && sim.duration < sim.time_step)
      r.fail(path + "/duration",
             fmt::format("a drape of {:.6g} s is shorter than one time step ({:.6g} s, "
                         "\"time_step\"): the cloth would not move; a garment settles within a "
                         "few seconds (e.g. \"duration\": 3)",
                         sim.duration, sim.time_step));
  }
  if (j.contains("integrator")) {
    sim.integrator = r.text(j["integrator"], path + "/integrator");
    if (sim.integrator != "implicit-euler" && sim.integrator != "bdf2")
      r.fail(path + "/integrator", fmt::format("unknown integrator '{}'; use \"implicit-euler\" "
                                               "or \"bdf2\"",
                                               sim.integrator));
  }
  if (j.contains("solver")) {
    sim.solver = r.text(j["solver"], path + "/solver");
    if (sim.solver != "pcg" && sim.solver != "cholmod" && sim.solver != "auto" &&
        sim.solver != "pcg-two-level")
      r.fail(path + "/solver", fmt::format("unknown solver '{}'; use \"auto\" (the default), "
                                           "\"pcg\", \"pcg-two-level\" or \"cholmod\"",
                                           sim.solver));
  }
  if (j.contains("bending")) {
    sim.bending = r.text(j["bending"], path + "/bending");
    if (sim.bending != "hinges" && sim.bending != "quadratic")
      r.fail(
          path + "/bending",
          fmt::format("unknown bending model '{}'; use \"hinges\" or \"quadratic\"", sim.bending));
  }
  if (j.contains("compression")) {
    sim.compression = r.text(j["compression"], path + "/compression");
    sim.compression_given = true;
    if (sim.compression != "linear" && sim.compression != "buckling")
      r.fail(path + "/compression",
             fmt::format("unknown compression model '{}'; use \"linear\" or \"buckling\"",
                         sim.compression));
  }
  if (j.contains("stop_at_rest"))
    sim.stop_at_rest = r.boolean(j["stop_at_rest"], path + "/stop_at_rest");
  if (j.contains("gravity")) {
    sim.gravity = r.vector<3>(j["gravity"], path + "/gravity");
    for (int k = 0; k < 3; ++k)
      if (std::abs(sim.gravity[k]) > kMaxGravity)
        r.fail(fmt::format("{}/gravity/{}", path, k),
               fmt::format("{:.6g} m/s² is outside ±{:g} m/s² (Earth's gravity is 9.81 m/s²)",
                           sim.gravity[k], kMaxGravity));
  }
  if (j.contains("check_body_vertices"))
    sim.check_body_vertices = r.boolean(j["check_body_vertices"], path + "/check_body_vertices");
  if (j.contains("gather_start"))
    sim.gather_start = r.boolean(j["gather_start"], path + "/gather_start");
  if (j.contains("fade_carried_push"))
    sim.fade_carried_push = r.boolean(j["fade_carried_push"], path + "/fade_carried_push");
  if (j.contains("rest")) {
    sim.rest = r.text(j["rest"], path + "/rest");
    if (sim.rest != "flat" && sim.rest != "shaped")
      r.fail(path + "/rest", fmt::format("unknown rest shape '{}'; use \"flat\" (the flattened "
                                         "pattern pieces) or \"shaped\" (as drawn on the body)",
                                         sim.rest));
  }
  if (j.contains("self_collision"))
    sim.self_collision = r.boolean(j["self_collision"], path + "/self_collision");
  if (j.contains("rest_ramp")) {
    sim.rest_ramp = r.number(j["rest_ramp"], path + "/rest_ramp");
    sim.rest_ramp_given = true;
    if (!(sim.rest_ramp >= 0.0 && sim.rest_ramp <= 10.0))
      r.fail(path + "/rest_ramp",
             fmt::format("a rest ramp of {:.6g} s is outside 0-10 s: the time over which cloth "
                         "draped from its flat pattern goes from its drawn shape to the "
                         "pattern's (0: at once)",
                         sim.rest_ramp));
  }
}

SheetSpec parse_sheet(const Reader& r, const json& j) {
  const std::string path = "/sheet";
  r.require_object(j, path, "sheet");
  r.check_keys(j, path,
               {"size", "resolution", "orientation", "centre", "pins", "layers", "layer_offset",
                "layer_turn", "shape"});
  SheetSpec sheet;
  if (j.contains("layers")) sheet.layers = r.integer(j["layers"], path + "/layers", 1);
  if (j.contains("layer_offset"))
    sheet.layer_offset = r.vector<3>(j["layer_offset"], path + "/layer_offset");
  if (j.contains("layer_turn")) sheet.layer_turn = r.number(j["layer_turn"], path + "/layer_turn");
  if (j.contains("size")) {
    sheet.size = r.vector<2>(j["size"], path + "/size");
    for (int k = 0; k < 2; ++k)
      if (!(sheet.size[k] > 0))
        r.fail(fmt::format("{}/size/{}", path, k), "a sheet's width and height must be positive");
    for (int k = 0; k < 2; ++k)
      if (sheet.size[k] > kMaxSheetSide)
        r.fail(fmt::format("{}/size/{}", path, k),
               out_of_range_sentence(sheet.size[k], 0, kMaxSheetSide, "a sheet side of",
                                     kUsualSheetSide));
  }
  if (j.contains("resolution")) {
    const json& res = j["resolution"];
    if (!res.is_array() || res.size() != 2)
      r.fail(path + "/resolution", "expected [columns, rows] of quads");
    sheet.columns = r.integer(res[0], path + "/resolution/0", 1);
    sheet.rows = r.integer(res[1], path + "/resolution/1", 1);
    if (sheet.columns > 1024 || sheet.rows > 1024)
      r.fail(path + "/resolution", "a sheet has at most 1024 quads along a side");
  }
  if (j.contains("orientation")) {
    const std::string o = r.text(j["orientation"], path + "/orientation");
    if (o != "vertical" && o != "horizontal")
      r.fail(path + "/orientation",
             fmt::format("unknown orientation '{}'; use \"vertical\" or \"horizontal\"", o));
    sheet.horizontal = o == "horizontal";
  }
  if (j.contains("centre")) sheet.centre = r.position<3>(j["centre"], path + "/centre");
  if (j.contains("shape")) {
    const std::string shape = r.text(j["shape"], path + "/shape");
    if (shape != "rectangle" && shape != "disc")
      r.fail(path + "/shape",
             fmt::format("unknown shape '{}'; use \"rectangle\" or \"disc\"", shape));
    sheet.disc = shape == "disc";
    if (sheet.disc && sheet.size[1] != sheet.size[0])
      r.fail(path + "/size", "a disc's size is [diameter, diameter]: give the same length twice");
    if (sheet.disc && sheet.rows != sheet.columns)
      r.fail(path + "/resolution",
             "a disc's resolution is [cells, cells] across its diameter: give the same count "
             "twice");
    if (sheet.disc && sheet.columns < 4)
      r.fail(path + "/resolution", "a disc needs at least 4 cells across its diameter");
  }
  if (j.contains("pins")) {
    const json& pins = j["pins"];
    if (!pins.is_array()) r.fail(path + "/pins", "expected a list of corner or edge names");
    static constexpr std::string_view kNames[] = {
        "top-left", "top-right", "bottom-left", "bottom-right", "top", "bottom", "left", "right"};
    for (size_t i = 0; i < pins.size(); ++i) {
      const std::string pp = fmt::format("{}/pins/{}", path, i);
      const std::string name = r.text(pins[i], pp);
      // A clamp "top:N" holds N lines of vertices from that edge (a cantilever's clamp).
      const std::size_t colon = name.find(':');
      const std::string edge = name.substr(0, colon);
      const bool clamp = colon != std::string::npos &&
                         (edge == "top" || edge == "bottom" || edge == "left" || edge == "right");
      if (edge == "centre" && colon != std::string::npos) {
        // A clamp at the centre: "centre:0.09" holds the vertices within 9 cm (Cusick's support).
        double radius = 0.0;
        try {
          radius = sim::centre_clamp_radius(name).value_or(0.0);
        } catch (const sim::InvalidSheetError&) {
          radius = 0.0;  // refused below, with the sheet's bound
        }
        const double largest = 0.5 * std::min(sheet.size[0], sheet.size[1]);
        if (!(radius > 0.0 && radius < largest))
          r.fail(pp, fmt::format("the clamp '{}' must give a radius in metres between 0 and {} "
                                 "(half the sheet), e.g. centre:0.09",
                                 name, largest));
      } else if (sheet.disc) {
        r.fail(pp, fmt::format("a disc is held only by a clamp at its centre (centre:R, R in "
                               "metres), not by '{}'",
                               name));
      } else if (colon != std::string::npos && std::find(std::begin(kNames), std::begin(kNames) + 4,
                                                         edge) != std::begin(kNames) + 4) {
        // A corner clamp: "top-left:0.02" holds the vertices within 2 cm of that corner.
        double radius = 0.0;
        try {
          radius = sim::corner_clamp(name).value_or(sim::CornerClamp{}).radius;
        } catch (const sim::InvalidSheetError&) {
          radius = 0.0;  // refused below, with the sheet's bound
        }
        const double largest = 0.5 * std::min(sheet.size[0], sheet.size[1]);
        if (!(radius > 0.0 && radius <= largest))
          r.fail(pp, fmt::format("the corner clamp '{}' must give a radius in metres above 0 and "
                                 "at most {} (half the sheet's shorter side), e.g. {}:0.02{}",
                                 name, largest, edge,
                                 radius > largest && radius / 100 <= largest
                                     ? fmt::format("; if you typed centimetres, {:g} cm is {:g} m",
                                                   radius, radius / 100)
                                     : ""));
      } else if (clamp) {
        const std::string digits = name.substr(colon + 1);
        const int lines = (edge == "top" || edge == "bottom" ? sheet.rows : sheet.columns) + 1;
        const bool number = !digits.empty() && digits.size() < 7 &&
                            std::all_of(digits.begin(), digits.end(),
                                        [](char ch) { return ch >= '0' && ch <= '9'; });
        if (!number || std::stoi(digits) < 1 || std::stoi(digits) > lines)
          r.fail(pp, fmt::format("the clamp '{}' must hold 1 to {} lines of vertices ({}:N)", name,
                                 lines, edge));
      } else if (std::find(std::begin(kNames), std::end(kNames), name) == std::end(kNames)) {
        r.fail(pp, fmt::format("unknown pin '{}'; use a corner (top-left, top-right, bottom-left, "
                               "bottom-right), an edge (top, bottom, left, right), a clamp of "
                               "several lines of vertices (top:3) or a corner clamp of a radius "
                               "in metres (top-left:0.02)",
                               name));
      }
      sheet.pins.push_back(name);
    }
  }
  return sheet;
}

void parse_output(const Reader& r, const json& j, OutputSpec& out) {
  const std::string path = "/output";
  r.require_object(j, path, "output");
  r.check_keys(j, path, {"images", "mesh", "report", "wireframe", "pattern"});
  if (j.contains("mesh")) {
    out.mesh = r.text(j["mesh"], path + "/mesh");
    if (!out.mesh.ends_with(".obj") && !out.mesh.ends_with(".glb"))
      r.fail(path + "/mesh", fmt::format("'{}' must end in .obj or .glb", out.mesh));
    if (out.mesh.find('/') != std::string::npos)
      r.fail(path + "/mesh", "give a file name only; the directory comes from -o");
    // `mesh` writes the 4-8 mesh under this name: the quads were overwritten by its triangles.
    if (out.mesh == "garment48.obj")
      r.fail(path + "/mesh",
             "'garment48.obj' is the name of the 4-8 mesh that mesh writes too; choose another "
             "name (e.g. garment.obj)");
    if (out.mesh == ".obj" || out.mesh == ".glb")
      r.fail(path + "/mesh", fmt::format("'{}' has no name before its extension (e.g. garment{})",
                                         out.mesh, out.mesh));
  }
  if (j.contains("report")) out.report = r.boolean(j["report"], path + "/report");
  if (j.contains("wireframe")) out.wireframe = r.boolean(j["wireframe"], path + "/wireframe");
  if (j.contains("pattern")) parse_pattern(r, j["pattern"], out);
  if (j.contains("images")) {
    out.images_listed = true;
    const json& images = j["images"];
    if (!images.is_array()) r.fail(path + "/images", "expected a list of images");
    r.check_count(images, path + "/images", kMaxImages, "images");
    for (size_t i = 0; i < images.size(); ++i) {
      const std::string ip = fmt::format("{}/images/{}", path, i);
      const json& im = images[i];
      r.require_object(im, ip, "an image");
      r.check_keys(im, ip, {"view", "size", "wireframe"});
      ImageSpec image;
      if (im.contains("view")) {
        const json& v = im["view"];
        // A picture may also be taken from three-quarter or above (the renderer's views; it
        // takes "three_quarter" too); a curve is drawn in front, back, left or right only.
        std::string name = v.is_string() ? v.get<std::string>() : "";
        std::replace(name.begin(), name.end(), '_', '-');
        if (name == "three-quarter" || name == "top") {
          image.view = name;
        } else if (v.is_string() && name != "front" && name != "back" && name != "left" &&
                   name != "right") {
          r.fail(ip + "/view", Reader::unknown_view_sentence(
                                   v.get<std::string>(),
                                   {"front", "back", "left", "right", "three-quarter", "top"}));
        } else {
          const ViewSpec view = r.view(v, ip + "/view");
          image.view = view.name();
          image.camera = view.camera;
        }
      }
      if (im.contains("size")) {
        const json& s = im["size"];
        if (!s.is_array() || s.size() != 2)
          r.fail(ip + "/size", "expected [width, height] in pixels");
        image.width = r.integer(s[0], ip + "/size/0", 16);
        image.height = r.integer(s[1], ip + "/size/1", 16);
        if (image.width > kMaxImageSide || image.height > kMaxImageSide)
          r.fail(ip + "/size", fmt::format("images are at most {} pixels on a side (a {}x{} "
                                           "picture takes half a gigabyte to draw)",
                                           kMaxImageSide, kMaxImageSide, kMaxImageSide));
      }
      if (im.contains("wireframe")) image.wireframe = r.boolean(im["wireframe"], ip + "/wireframe");
      out.images.push_back(image);
    }
  }
}

}  // namespace sd::scene::detail
