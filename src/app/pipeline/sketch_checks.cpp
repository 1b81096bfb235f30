#include "src/app/pipeline/sketch_checks.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

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
constexpr double kBaseBytes = 67e6;       // the process before any cloth
constexpr double kBytesPerVertex = 5800;  // model, forces, system matrices, contacts
constexpr double kSecondsPerVertexStepLog = 3e-6;
constexpr double kSecondsPerFrame = 0.05;  // one picture of the PNG sequence
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
  return kBaseBytes + vertices * (kBytesPerVertex + factor_per_vertex + frames_per_vertex);
}

std::string gigabytes(double bytes) {
  return fmt::format("{:.1f} GB", bytes / 1e9);
}

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

double peak_resident_memory_bytes() {
  // The peak (VmHWM), not the resident set now (statm): the kernel's proactive reclaim (DAMON
  // runs on this machine) can page a process's cold memory out, so the resident set now can fall
  // below what the drape took, and a budget is about what it took.
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);)
    if (line.starts_with("VmHWM:")) {
      std::istringstream fields(line.substr(6));
      double kb = 0;
      if (fields >> kb) return kb * 1024.0;
    }
  return 0;
}

double memory_budget_bytes(const RunLimits& limits) {
  return limits.max_memory_bytes > 0 ? limits.max_memory_bytes
                                     : kAvailableFraction * available_memory_bytes();
}

std::optional<RunEstimate> estimate_before_building(const scene::Sketch& sketch,
                                                    double frames_per_second,
                                                    const RunLimits& limits) {
  if (!sketch.sheet) return std::nullopt;
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
    const RunEstimate e =
        estimate_run(sketch, small.input.triangles,
                     static_cast<int>(small.input.rest_positions.rows()), frames_per_second);
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
  // The grid's triangles only (its size and place do not change the factor).
  sim::SheetSpec spec;
  spec.columns = sketch.sheet->columns;
  spec.rows = sketch.sheet->rows;
  const sim::SheetScene sheet = sim::build_sheet(spec);
  return estimate_run(sketch, sheet.input.triangles,
                      static_cast<int>(sheet.input.rest_positions.rows()), frames_per_second);
}

RunEstimate estimate_run(const scene::Sketch& sketch, const Eigen::MatrixX3i& triangles,
                         int vertices, double frames_per_second) {
  return estimate_run(sketch, triangles, vertices, frames_per_second, sketch.simulate.duration,
                      sketch.simulate.time_step);
}

RunEstimate estimate_run(const scene::Sketch& sketch, const Eigen::MatrixX3i& triangles,
                         int vertices, double frames_per_second, double duration,
                         double time_step) {
  RunEstimate e;
  e.duration = duration;
  e.time_step = time_step;
  e.vertices = vertices;
  e.factor_bytes = sim::predict_factor_size(
                       triangles, vertices,
                       sim::parse_bend_model(sketch.simulate.bending)
                           .value_or(sketch.sheet || sketch.garment_mesh ? sim::BendModel::quadratic
                                                                         : sim::BendModel::hinges))
                       .bytes;
  e.memory_bytes = kBaseBytes + e.vertices * kBytesPerVertex + e.factor_bytes;
  e.steps = std::ceil(duration / time_step);
  e.frames = frames_per_second > 0 ? std::floor(duration * frames_per_second) + 1 : 0;
  // The PNG sequence keeps each picture's cloth until the drape ends: positions, triangles and
  // groups, about 64 bytes per vertex.
  e.memory_bytes += e.frames * 64.0 * e.vertices;
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
    // The largest vertex count that fits, by bisection on the estimate scaled to other sizes.
    double low = 4, high = estimate.vertices;
    for (int i = 0; i < 60; ++i) {
      const double mid = 0.5 * (low + high);
      (memory_scaled(estimate, mid) <= memory ? low : high) = mid;
    }
    const std::string limit =
        given ? fmt::format("the {} of --max-memory", gigabytes(memory))
              : fmt::format("the {} a run may take of the memory available now", gigabytes(memory));
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
                              "simulate ({} of it the solver's factor), more than {}; about "
                              "{:.0f}x{:.0f} quads would fit, and would take up to about {} to "
                              "drape ({:.0f} steps); the Cusick and cantilever scenes of "
                              "docs/fabrics.md use 16 to 40 cells a side",
                              sketch.sheet->columns, sketch.sheet->rows, estimate.vertices,
                              gigabytes(estimate.memory_bytes), gigabytes(estimate.factor_bytes),
                              limit, side, side, time, estimate.steps));
    }
    sketch.fail("", fmt::format("the cloth has {:.0f} vertices and needs about {} to simulate "
                                "({} of it the solver's factor), more than {}; about {:.0f} "
                                "vertices would fit (a longer edge_length)",
                                estimate.vertices, gigabytes(estimate.memory_bytes),
                                gigabytes(estimate.factor_bytes), limit, low));
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
