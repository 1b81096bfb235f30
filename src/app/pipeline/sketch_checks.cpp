#include "src/app/pipeline/sketch_checks.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>

#include "garment/sketch_ranges.hpp"
#include "sim/fabric.hpp"
#include "sim/fabric_ranges.hpp"
#include "sim/factor_size.hpp"
#include "sim/sheet.hpp"
#include "src/app/pipeline/cloth_scene.hpp"
#include "src/render/image.hpp"

namespace sd::app {
namespace {

static_assert(garment::kMaxImageSide == render::kMaxImageSide,
              "the sketch file's image limit is the renderer's");

// Cost model of a drape. The CHOLMOD factor (and its workspace) comes from the symbolic
// analysis of the cloth's mesh (sim::predict_factor_size: 20, 103, 517 MB for sheets of 65²,
// 129², 257² vertices); the rest was fitted to the peak RSS of drapes of those sheets on the
// CHOLMOD solver (111, 265, 937 MB; docs/cli.md, "Limits"): the process before any cloth plus
// 5.8 kB per vertex (model, forces, the system matrix and its filtered and permuted copies of
// about 1.4 kB each, contacts); the fit is within 3 % of all three. Seconds per vertex and step
// grow with log2(V) like the fill of the factor (measured on the 2-core machine under a load of
// 12: 28, 38, 61 µs per vertex and step).
//
// The process before any cloth is 26 MB since OSMesa is no longer linked (it was 67 MB with the
// library mapped from the start): `run` of an 8x8 sheet (81 vertices, 0.1 s, "images": []) peaks
// at 25 MiB (/usr/bin/time's maximum resident set, 27 Nov 2026), and the 64² and 128² sheets
// above (hinges, CHOLMOD) peak 48 MiB lower than with the library linked (116 -> 68, 273 -> 224
// MiB, two runs each): the cloth's share per vertex is unchanged.
//
// The renderer, counted only when the run renders pictures (images or --frames), measured with
// `sketchdrape -v run` on that 8x8 sheet, which logs the resident memory (VmRSS) around OSMesa's
// opening and before the pictures, and /usr/bin/time's peak for one front image of 200², 600x900,
// 1500², 3000² and 4096² pixels (two runs each, identical to 0.3 MiB):
// * opening OSMesa (dlopen, its LLVM, z3 and ICU relocated) takes the process from 20-21 to 70 MB;
// * the peak over the resident memory before the pictures (72 MB) is 55, 78, 156, 458, 805 MB:
//   least squares gives 54.1 MB + 44.8 bytes per pixel, within 1.4 MB of each. 44 bytes are the
//   4-sample colour (RGBA8) and depth buffers (16 + 16), the resolved colour, the read-back and
//   the image (4 each); the 54 MB are the context, llvmpipe's threads and tiles, the shaders and
//   the 2048² shadow map. Taken as 55 MB + 45 bytes per pixel (over each measurement by 0-2 MB).
constexpr double kBaseBytes = 26e6;             // the process before any cloth (without OSMesa)
constexpr double kBytesPerVertex = 5800;        // model, forces, system matrices, contacts
constexpr double kRendererLibraryBytes = 50e6;  // OSMesa and its libraries, mapped
constexpr double kRendererContextBytes = 55e6;  // context, shaders, shadow map, llvmpipe
constexpr double kRendererBytesPerPixel = 45;   // framebuffers, read-back and image
constexpr double kSecondsPerVertexStepLog = 3e-6;
constexpr double kSecondsPerFrame = 0.05;  // one picture of the PNG sequence
// The smallest cloth a "would fit" may offer: a single quad.
constexpr double kMinVertices = 4;
// Without --max-memory, a run may use this fraction of the memory available when it starts (the
// rest for the system, other processes and the estimate's error). 0.6, not more: at 0.8 the
// 1000×1000-quad sheet (18.1 GB estimated) was started on this 24 GB machine whenever 22.6 GB
// happened to be free, a drape of hours; a user who means it gives --max-memory.
constexpr double kAvailableFraction = 0.6;

// The memory of a cloth of `vertices` vertices, scaled from an estimate of another size: the
// factor per vertex grows like log2(V), as the fill of a mesh's factor under nested dissection.
double memory_scaled(const RunEstimate& e, double vertices) {
  const double factor_per_vertex = e.factor_bytes / std::max(e.vertices, 1.0) *
                                   std::log2(std::max(vertices, 2.0)) /
                                   std::log2(std::max(e.vertices, 2.0));
  const double frames_per_vertex = 64.0 * e.frames;
  return kBaseBytes + e.renderer.total() +
         vertices * (kBytesPerVertex + factor_per_vertex + frames_per_vertex);
}

// "1.2 GB", or "74 MB" below a gigabyte (where one decimal of GB says too little: a budget of
// 60 MB read "0.1 GB").
std::string size_text(double bytes) {
  return bytes >= 1e9 ? fmt::format("{:.1f} GB", bytes / 1e9)
                      : fmt::format("{:.0f} MB", bytes / 1e6);
}

// The --max-memory to offer for a run estimated at `bytes`: a tenth more, rounded up to 10 MB
// (0.1 GB above a gigabyte). The estimate itself is not enough: trial 42's patch (base.json, 64
// vertices, three 600x900 pictures) is estimated at 156 MB and peaks at 160 MB (the body and its
// collision tree, which the 26 MB base fitted to sheets does not hold), so --max-memory 156M,
// and even 160M, stopped it before its pictures; 180M, offered now, draws them.
constexpr double kOfferedMargin = 1.1;
std::string offered_budget_text(double bytes) {
  const double offered = kOfferedMargin * bytes;
  return offered >= 1e9 ? fmt::format("{:.1f} GB", std::ceil(offered / 1e8) / 10.0)
                        : fmt::format("{:.0f} MB", 10.0 * std::ceil(offered / 1e7));
}

std::string budget_text(double budget, bool given) {
  return given
             ? fmt::format("the {} of --max-memory", size_text(budget))
             : fmt::format("the {} a run may take of the memory available now", size_text(budget));
}

// What to do about pictures that do not fit.
constexpr const char* kFewerPictures =
    "ask for smaller images or none (\"output\": {\"images\": []}, and no --frames), or give a "
    "larger --max-memory";

}  // namespace

void check_sketch(const scene::Sketch& sketch) {
  // Each fabric as build_cloth_scene reads it (scene_fabric); checking the name against the
  // presets alone refused every inline fabric not named after a preset and every fabric file.
  auto check_fabric = [&](const std::string& name, const std::string& path) {
    (void)scene_fabric(sketch, name, path);
  };
  check_fabric(sketch.fabric, "/fabric");
  for (const garment::PanelSpec& panel : sketch.panels)
    if (panel.fabric != sketch.fabric) check_fabric(panel.fabric, panel.json_path + "/fabric");
  (void)simulation_settings(sketch);
  for (const std::string& warning : fabric_warnings(sketch)) spdlog::warn("{}", warning);
  for (const std::string& warning : gather_warnings(sketch)) spdlog::warn("{}", warning);
  for (const std::string& warning : gravity_warnings(sketch)) spdlog::warn("{}", warning);
}

std::vector<std::string> gravity_warnings(const scene::Sketch& sketch) {
  const Eigen::Vector3d& g = sketch.simulate.gravity;
  if (!(g.y() > 0.0)) return {};
  const double above = std::asin(std::min(1.0, g.y() / g.norm())) * 180.0 / std::numbers::pi;
  return {fmt::format(
      "{}: /simulate/gravity: gravity [{:g}, {:g}, {:g}] m/s² points {}: +y is the body's up "
      "(docs/bodies.md), so the cloth falls off the body away from its feet, and the drape shows "
      "no fit; Earth's gravity is [0, -9.81, 0] (leave \"gravity\" out for it)",
      sketch.file, g.x(), g.y(), g.z(),
      above > 89.5 ? std::string("straight up")
                   : fmt::format("{:.0f}° above the horizontal", above))};
}

std::vector<std::string> gather_warnings(const scene::Sketch& sketch) {
  std::vector<std::string> warnings;
  if (!sketch.simulate.compression_given || sketch.simulate.compression != "linear")
    return warnings;
  for (const garment::PanelSpec& panel : sketch.panels) {
    const double ratio = gather_ratio(panel.ease);
    if (ratio <= kGatherEase) continue;
    const bool weft = panel.ease.weft > panel.ease.warp;
    const sim::FabricParameters fabric =
        scene_fabric(sketch, panel.fabric, panel.json_path + "/fabric");
    const double stiffness = weft ? fabric.stretch_weft : fabric.stretch_warp;
    const double strain = 1.0 - 1.0 / ratio;
    // The rows at the gathered seam stay squeezed by `strain` (the rest of the panel starts
    // folded into flutes: cloth_scene.cpp, gather_start), and the linear model answers that with
    // K·strain, which stretches the seam open; a panel that starts as drawn (no gathered seam)
    // is squeezed whole and springs out at about the strain times the fabric's wave speed
    // √(K/ρ) (docs/pattern.md, "A gather draped from flat cloth").
    const double speed = strain * std::sqrt(stiffness / fabric.area_density);
    warnings.push_back(fmt::format(
        "{}: {}/ease: panel '{}' is gathered {:g} : 1 along its {}, but \"simulate\": "
        "{{\"compression\": \"linear\"}} answers a gather with the fabric's tensile "
        "stiffness: the cloth at the gathered seam is {:.0f} % shorter than cut and pushes that "
        "seam open with {:.0f} N/m ({} at {:g} N/m; trial 37's flounce at 1.5 stretched its yoke "
        "45 % and was thrown about), and cloth squeezed so springs out at about {:.0f} m/s (a "
        "step fails above 50 m/s); leave \"compression\" out (a gathered drape gets "
        "\"buckling\") or gather by {:g} or less",
        sketch.file, panel.json_path, panel.id, ratio, weft ? "weft" : "warp", 100 * strain,
        stiffness * strain, fabric.name, stiffness, speed, kGatherEase));
  }
  return warnings;
}

std::vector<std::string> fabric_warnings(const scene::Sketch& sketch) {
  std::vector<std::string> warnings;
  std::vector<std::string> seen;  // each fabric once, however many panels name it
  // The same three sources as check_fabric; an inline constant at its own path
  // (/fabric/friction), a file's at the sketch's "fabric" with the file and its key named.
  auto add = [&](const std::string& name, const std::string& path) {
    if (std::find(seen.begin(), seen.end(), name) != seen.end()) return;
    seen.push_back(name);
    if (!sketch.fabric_inline.empty() && name == sketch.fabric) {
      for (const sim::FabricNote& note : sim::unusual_constants(
               sim::parse_fabric_json(sketch.fabric_inline, "the fabric given inline")))
        warnings.push_back(
            fmt::format("{}: {}{}: {}", sketch.file, "/fabric", note.pointer, note.sentence));
      return;
    }
    try {
      (void)sim::fabric_preset(name);
      return;  // the presets lie in the usual ranges (Fabric.PresetsLieInTheUsualRanges)
    } catch (const sim::UnknownFabricError&) {
    }
    const std::string file = sketch.resolve(name).lexically_normal().string();
    for (const sim::FabricNote& note :
         sim::unusual_constants(sim::load_fabric_file(sketch.resolve(name).string())))
      warnings.push_back(fmt::format("{}: {}: fabric file '{}': {}: {}", sketch.file, path, file,
                                     note.pointer, note.sentence));
  };
  add(sketch.fabric, "/fabric");
  for (const garment::PanelSpec& panel : sketch.panels)
    if (panel.fabric != sketch.fabric) add(panel.fabric, panel.json_path + "/fabric");
  return warnings;
}

double available_memory_bytes() {
  std::ifstream in("/proc/meminfo");
  std::string key;
  double kb = 0;
  std::string unit;
  while (in >> key >> kb >> unit)
    if (key == "MemAvailable:") return kb * 1024.0;
  return 0;
}

namespace {

// A field of /proc/self/status in kB ("VmRSS:", "VmHWM:"), as bytes; 0 when it is not there.
double status_bytes(std::string_view key) {
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);)
    if (line.starts_with(key)) {
      std::istringstream fields(line.substr(key.size()));
      double kb = 0;
      if (fields >> kb) return kb * 1024.0;
    }
  return 0;
}

}  // namespace

double resident_memory_bytes() {
  return status_bytes("VmRSS:");
}

double peak_resident_memory_bytes() {
  // The peak (VmHWM), not the resident set now (statm): the kernel's proactive reclaim (DAMON
  // runs on this machine) can page a process's cold memory out, so the resident set now can fall
  // below what the drape took, and a budget is about what it took.
  return status_bytes("VmHWM:");
}

double memory_budget_bytes(const RunLimits& limits) {
  return limits.max_memory_bytes > 0 ? limits.max_memory_bytes
                                     : kAvailableFraction * available_memory_bytes();
}

std::vector<scene::ImageSpec> run_images(const scene::Sketch& sketch) {
  if (sketch.output.images_listed) return sketch.output.images;
  std::vector<scene::ImageSpec> images;
  for (const char* view : {"front", "back", "left"}) {
    scene::ImageSpec image;
    image.view = view;
    image.width = 600;
    image.height = 900;
    images.push_back(image);
  }
  return images;
}

RendererMemory renderer_memory(int width, int height) {
  RendererMemory memory;
  memory.width = width;
  memory.height = height;
  memory.library_bytes = kRendererLibraryBytes;
  memory.frame_bytes =
      kRendererContextBytes + kRendererBytesPerPixel * static_cast<double>(width) * height;
  return memory;
}

RendererMemory run_renderer_memory(const scene::Sketch& sketch, double frames_per_second) {
  std::vector<scene::ImageSpec> pictures = run_images(sketch);
  if (frames_per_second > 0)  // the sequence: the first image's size (run_command.cpp)
    pictures.push_back(pictures.empty() ? scene::ImageSpec{} : pictures.front());
  if (pictures.empty()) return {};
  const auto pixels = [](const scene::ImageSpec& image) {
    return static_cast<double>(image.width) * image.height;
  };
  const scene::ImageSpec& largest = *std::max_element(
      pictures.begin(), pictures.end(),
      [&](const scene::ImageSpec& a, const scene::ImageSpec& b) { return pixels(a) < pixels(b); });
  return renderer_memory(largest.width, largest.height);
}

std::optional<std::string> rendering_over_budget(double resident, const RendererMemory& renderer,
                                                 bool library_loaded, double budget, bool given) {
  const double adds = renderer.frame_bytes + (library_loaded ? 0.0 : renderer.library_bytes);
  if (budget <= 0 || resident + adds <= budget) return std::nullopt;
  return fmt::format(
      "the process holds {} and rendering {}x{} pictures takes about {} more ({}the OpenGL "
      "context and its framebuffers), {} in all, more than {}",
      size_text(resident), renderer.width, renderer.height, size_text(adds),
      library_loaded ? ""
                     : fmt::format("OSMesa's libraries {}, ", size_text(renderer.library_bytes)),
      size_text(resident + adds), budget_text(budget, given));
}

std::optional<RunEstimate> estimate_before_building(const scene::Sketch& sketch,
                                                    double frames_per_second,
                                                    const RunLimits& limits) {
  if (!sketch.sheet) return std::nullopt;
  // The options the sheet's model is built with (scene_model_options); the bending rest and the
  // compression do not change the factor's pattern.
  sim::ClothModelOptions model;
  model.bend_model = scene_bend_model(sketch);
  // A large sheet is first estimated from a proxy grid of the same shape with about 257²
  // vertices, analysed and scaled to its vertex count (memory_scaled: the factor per vertex grows
  // like log2 V), and refused at once when that does not fit, without building and analysing a
  // grid of up to a million vertices (trial 35's 1024² disc took 11 s and 363 MB to be refused).
  const double vertices = (static_cast<double>(sketch.sheet->columns) + 1) *
                          (static_cast<double>(sketch.sheet->rows) + 1);
  constexpr double kProxyVertices = 257.0 * 257.0;
  if (vertices > 4 * kProxyVertices) {
    const double shrink = std::sqrt(vertices / kProxyVertices);
    sim::SheetSpec proxy;
    proxy.columns = std::max(1, static_cast<int>(std::lround(sketch.sheet->columns / shrink)));
    proxy.rows = std::max(1, static_cast<int>(std::lround(sketch.sheet->rows / shrink)));
    const sim::SheetScene small = sim::build_sheet(proxy);
    const RunEstimate e = estimate_run(sketch, small.input, model, frames_per_second);
    RunEstimate scaled = e;
    scaled.vertices = vertices;
    scaled.memory_bytes = memory_scaled(e, vertices);
    scaled.factor_bytes = e.factor_bytes / std::max(e.vertices, 1.0) * vertices *
                          std::log2(vertices) / std::log2(std::max(e.vertices, 2.0));
    scaled.seconds = e.steps * vertices * std::log2(vertices) * kSecondsPerVertexStepLog +
                     e.frames * kSecondsPerFrame;
    if (const double budget = memory_budget_bytes(limits);
        budget > 0 && scaled.memory_bytes > budget)
      return scaled;
  }
  // The grid only (its size and place do not change the factor).
  sim::SheetSpec spec;
  spec.columns = sketch.sheet->columns;
  spec.rows = sketch.sheet->rows;
  const sim::SheetScene sheet = sim::build_sheet(spec);
  return estimate_run(sketch, sheet.input, model, frames_per_second);
}

RunEstimate estimate_run(const scene::Sketch& sketch, const sim::ClothInput& cloth,
                         const sim::ClothModelOptions& model, double frames_per_second) {
  return estimate_run(sketch, cloth, model, frames_per_second, sketch.simulate.duration,
                      sketch.simulate.time_step);
}

RunEstimate estimate_run(const scene::Sketch& sketch, const sim::ClothInput& cloth,
                         const sim::ClothModelOptions& model, double frames_per_second,
                         double duration, double time_step) {
  RunEstimate e;
  e.duration = duration;
  e.time_step = time_step;
  e.vertices = static_cast<double>(cloth.rest_positions.rows());
  // The model's own pattern: with the diamond membrane its diamonds' couplings, which the
  // triangles alone under-predict by about half (sim/factor_size.hpp).
  e.factor_bytes = sim::predict_factor_size(cloth, model).bytes;
  e.memory_bytes = kBaseBytes + e.vertices * kBytesPerVertex + e.factor_bytes;
  e.steps = std::ceil(duration / time_step);
  e.frames = frames_per_second > 0 ? std::floor(duration * frames_per_second) + 1 : 0;
  // The PNG sequence keeps each picture's cloth until the drape ends: positions, triangles and
  // groups, about 64 bytes per vertex.
  e.memory_bytes += e.frames * 64.0 * e.vertices;
  e.renderer = run_renderer_memory(sketch, frames_per_second);
  e.memory_bytes += e.renderer.total();
  e.seconds =
      e.steps * e.vertices * std::log2(std::max(e.vertices, 2.0)) * kSecondsPerVertexStepLog +
      e.frames * kSecondsPerFrame;
  return e;
}

void check_run_fits(const scene::Sketch& sketch, const RunEstimate& estimate,
                    const RunLimits& limits, double frames_per_second) {
  const bool given = limits.max_memory_bytes > 0;
  const double memory = memory_budget_bytes(limits);
  if (memory > 0 && estimate.memory_bytes > memory) {
    const std::string limit = budget_text(memory, given);
    // The pictures are what does not fit: said as such, at the images when the file lists them,
    // not as a cloth too large.
    const RendererMemory& renderer = estimate.renderer;
    const double drape = estimate.memory_bytes - renderer.total();
    if (renderer.total() > 0 && drape <= memory)
      sketch.fail(sketch.output.images_listed ? "/output/images" : "",
                  fmt::format("the drape needs about {} and rendering its {}x{} pictures about {} "
                              "more (OSMesa's libraries {}, the OpenGL context and its "
                              "framebuffers {}), {} in all, more than {}; {}",
                              size_text(drape), renderer.width, renderer.height,
                              size_text(renderer.total()), size_text(renderer.library_bytes),
                              size_text(renderer.frame_bytes), size_text(estimate.memory_bytes),
                              limit, kFewerPictures));
    // The largest vertex count that fits, by bisection on the estimate scaled to other sizes;
    // kMinVertices when none does.
    const auto fitting_vertices = [&](const RunEstimate& e) {
      double low = kMinVertices, high = e.vertices;
      for (int i = 0; i < 60; ++i) {
        const double mid = 0.5 * (low + high);
        (memory_scaled(e, mid) <= memory ? low : high) = mid;
      }
      return low;
    };
    // What does not shrink with the cloth (the process before any cloth, the renderer) leaves no
    // room for the smallest cloth: no vertex count fits, so none is offered (trial 42, P7:
    // --max-memory 1MB answered "about 4 vertices would fit"); the budget this run needs is.
    if (memory_scaled(estimate, kMinVertices) > memory) {
      const std::string needs =
          fmt::format("give --max-memory {} or more (this run is estimated at {})",
                      offered_budget_text(estimate.memory_bytes), size_text(estimate.memory_bytes));
      if (renderer.total() > 0) {
        // Here the drape alone is over the budget too (else the pictures' sentence above).
        RunEstimate bare = estimate;
        bare.renderer = {};
        bare.memory_bytes = drape;
        const std::string without =
            memory_scaled(bare, kMinVertices) <= memory
                ? fmt::format(
                      "; without them the run still needs about {}, and about {:.0f} "
                      "vertices would fit",
                      size_text(drape), fitting_vertices(bare))
                : fmt::format("; without them the run still needs about {}", size_text(drape));
        sketch.fail(
            sketch.output.images_listed ? "/output/images" : "",
            fmt::format("the pictures alone need {} ({}x{}: OSMesa's libraries {}, the OpenGL "
                        "context and its framebuffers {}) and the process {} before any cloth, "
                        "more than {}, so no cloth fits beside them: {}, or ask for no pictures "
                        "(\"output\": {{\"images\": []}}, and no --frames){}",
                        size_text(renderer.total()), renderer.width, renderer.height,
                        size_text(renderer.library_bytes), size_text(renderer.frame_bytes),
                        size_text(kBaseBytes), limit, needs, without));
      }
      sketch.fail("", fmt::format("the process alone needs {} before any cloth, more than {}, so "
                                  "no cloth fits: {}",
                                  size_text(kBaseBytes), limit, needs));
    }
    const double low = fitting_vertices(estimate);
    const std::string pictures =
        renderer.total() > 0
            ? fmt::format(", {} the renderer of its {}x{} pictures", size_text(renderer.total()),
                          renderer.width, renderer.height)
            : "";
    if (sketch.sheet) {
      const double side = std::floor(std::sqrt(low)) - 1;
      // Fitting in memory is not being quick: the time of a drape at that size, every step of
      // the duration (a drape at rest stops earlier).
      const double seconds =
          estimate.steps * low * std::log2(std::max(low, 2.0)) * kSecondsPerVertexStepLog;
      const std::string time = seconds < 120    ? fmt::format("{:.0f} s", seconds)
                               : seconds < 7200 ? fmt::format("{:.0f} min", seconds / 60)
                                                : fmt::format("{:.1f} h", seconds / 3600);
      sketch.fail("/sheet/resolution",
                  fmt::format("a sheet of {}x{} quads ({:.0f} vertices) needs about {} to "
                              "simulate ({} of it the solver's factor{}), more than {}; about "
                              "{:.0f}x{:.0f} quads would fit, and would take up to about {} to "
                              "drape ({:.0f} steps); the Cusick and cantilever scenes of "
                              "docs/fabrics.md use 16 to 40 cells a side",
                              sketch.sheet->columns, sketch.sheet->rows, estimate.vertices,
                              size_text(estimate.memory_bytes), size_text(estimate.factor_bytes),
                              pictures, limit, side, side, time, estimate.steps));
    }
    sketch.fail("", fmt::format("the cloth has {:.0f} vertices and needs about {} to simulate "
                                "({} of it the solver's factor{}), more than {}; about {:.0f} "
                                "vertices would fit (a longer edge_length)",
                                estimate.vertices, size_text(estimate.memory_bytes),
                                size_text(estimate.factor_bytes), pictures, limit, low));
  }
  if (estimate.frames > kMaxFrames)
    throw std::invalid_argument(fmt::format(
        "--frames {:g} over a drape of {:g} s makes {:.0f} pictures, more than the {:.0f} "
        "allowed; at most {:.4g} per second fit this duration",
        frames_per_second, estimate.duration, estimate.frames, kMaxFrames,
        (kMaxFrames - 1) / estimate.duration));
  // Without stop_at_rest the run takes every step up to the duration: its time is known.
  if (limits.max_time_s && !sketch.simulate.stop_at_rest && estimate.seconds > *limits.max_time_s) {
    const double fits = *limits.max_time_s / estimate.seconds * estimate.duration;
    sketch.fail("/simulate/duration",
                fmt::format("{:.0f} steps of {:.3g} s on {:.0f} vertices take about {:.0f} s, more "
                            "than --max-time {:g} s; a duration of about {:.3g} s would fit (or "
                            "\"stop_at_rest\": true)",
                            estimate.steps, estimate.time_step, estimate.vertices, estimate.seconds,
                            *limits.max_time_s, fits));
  }
}

double parse_memory_size(const std::string& text) {
  size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    throw std::invalid_argument(
        fmt::format("--max-memory '{}' is not a size like 4G or 512M", text));
  }
  std::string unit = text.substr(used);
  if (!unit.empty() && (unit.back() == 'B' || unit.back() == 'b')) unit.pop_back();
  double scale = 1;
  if (unit == "K" || unit == "k")
    scale = 1e3;
  else if (unit == "M" || unit == "m")
    scale = 1e6;
  else if (unit == "G" || unit == "g")
    scale = 1e9;
  else if (unit == "T" || unit == "t")
    scale = 1e12;
  else if (!unit.empty())
    throw std::invalid_argument(
        fmt::format("--max-memory '{}': unknown unit '{}' (use K, M, G or T)", text, unit));
  const double bytes = value * scale;
  if (!std::isfinite(bytes) || bytes < 1e6 || bytes > 1e15)
    throw std::invalid_argument(fmt::format("--max-memory '{}' is outside 1M .. 1000T", text));
  return bytes;
}

}  // namespace sd::app
