#pragma once
// The checks every command that reads a sketch file runs before it starts (validate, mesh, run),
// so that no command accepts what another refuses, and the estimate of a drape's memory and work
// made before any of it is done (docs/cli.md, "Limits").

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "scene/sketch_file.hpp"
#include "sim/cloth_model.hpp"
#include "sim/simulation.hpp"

namespace sd::app {

// Every panel's fabric (and the file's) is a known preset, the simulation settings work
// together, every image can be drawn. Throws garment::SketchError at the value's path.
// Logs fabric_warnings as warnings.
void check_sketch(const scene::Sketch& sketch);

// The fabrics' constants that are physically possible but unusual for apparel (friction 1.8,
// a 1 kg/m^2 cloth): one "<file>: <JSON path>: <sentence>" line each, for the terminal and
// report.json. Call after check_sketch (a bad fabric is not reported here).
std::vector<std::string> fabric_warnings(const scene::Sketch& sketch);

// A panel gathered more than kGatherEase : 1 (cloth_scene.hpp, gather_ratio) in a drape whose
// file asks for the linear compression, which cannot drape it (trial 37's flounce at weft 1.6:
// 50.7 m/s at t = 0.0004 s): one "<file>: <JSON path>: <sentence>" line per such panel, with
// what to change. Logged by check_sketch.
std::vector<std::string> gather_warnings(const scene::Sketch& sketch);

// Gravity with a part along +y, the body's up (trial 39, P13: [0, 9.81, 0] drew no word): one
// "<file>: /simulate/gravity: <sentence>" line, else none. A warning, not a refusal: a scene may
// ask for any direction (stress turns it about), but a garment falls off its body. Logged by
// check_sketch.
std::vector<std::string> gravity_warnings(const scene::Sketch& sketch);

// What a run may use: --max-memory (default: 60 % of the memory the system has available now)
// and --max-time (default: none).
struct RunLimits {
  double max_memory_bytes = 0;       // 0: the available memory (/proc/meminfo)
  std::optional<double> max_time_s;  // wall-clock seconds
};

// The memory the system can give a process now (MemAvailable), bytes; 0 when unknown.
double available_memory_bytes();

// The resident memory of this process now (VmRSS of /proc/self/status), bytes; 0 when unknown.
double resident_memory_bytes();

// The most resident memory this process has held so far (VmHWM of /proc/self/status), bytes;
// 0 when unknown.
double peak_resident_memory_bytes();

// The memory a run may use: --max-memory, else 60 % of the memory available now; 0: unknown.
double memory_budget_bytes(const RunLimits& limits);

// The pictures `run` renders after the drape: the file's images (front, back and left at
// 600x900 when it lists none).
std::vector<scene::ImageSpec> run_images(const scene::Sketch& sketch);

// The renderer's share of a run's memory (measured: sketch_checks.cpp). OSMesa is opened only
// when pictures are asked for (src/render/gl.hpp), so a run without them has none of it.
struct RendererMemory {
  double library_bytes = 0;   // OSMesa and the libraries it loads (LLVM, z3, ICU), mapped
  double frame_bytes = 0;     // an OpenGL context, shaders, shadow map and the largest framebuffer
  int width = 0, height = 0;  // the largest picture (most pixels); 0x0: none
  double total() const { return library_bytes + frame_bytes; }
};
// For pictures of at most `width` x `height` pixels.
RendererMemory renderer_memory(int width, int height);
// For the pictures a run renders: its images and, with --frames (`frames_per_second` > 0), the
// sequence, drawn at the first image's size (800x1200 without images). All zero without any.
RendererMemory run_renderer_memory(const scene::Sketch& sketch, double frames_per_second);

// Just before rendering: the process holds `resident` bytes (with OSMesa mapped when
// `library_loaded`); rendering `renderer`'s pictures adds its context and framebuffers (and the
// library when not loaded). Returns why that does not fit `budget` (bytes; 0: no budget) as a
// sentence naming both parts and the limit (`given`: --max-memory, else the share of the
// available memory), or nullopt when it fits.
std::optional<std::string> rendering_over_budget(double resident, const RendererMemory& renderer,
                                                 bool library_loaded, double budget, bool given);

// A drape's cost, estimated before it starts: the CHOLMOD factor's size from the symbolic
// analysis of the cloth's model (sim::predict_factor_size of its input and options: its bending's
// pattern and, with the diamond membrane, the diamonds' 13-vertex couplings), plus the measured
// cost per vertex of the model, the forces and the contacts (docs/cli.md, "Limits").
struct RunEstimate {
  double vertices = 0;
  double memory_bytes = 0;  // peak resident memory
  double factor_bytes = 0;  // of which the CHOLMOD factor and its workspace
  RendererMemory renderer;  // of which the renderer's, when the run renders pictures
  double steps = 0;         // duration / time_step: the most steps the run can take
  double frames = 0;        // PNG sequence pictures (--frames)
  double seconds = 0;       // wall time if it runs the whole duration
  double duration = 0;      // s, the drape's duration the estimate assumes
  double time_step = 0;     // s, its largest step
};
// `cloth`: the cloth's input (its rest positions and triangles), modelled with `model` (the
// scene's: scene_model_options); the duration and the step are the file's.
RunEstimate estimate_run(const scene::Sketch& sketch, const sim::ClothInput& cloth,
                         const sim::ClothModelOptions& model, double frames_per_second);
// The same for the duration and step the run will take (the automatic settings may change both:
// a garment without a duration of its own gets its settle time, settle_time.hpp).
RunEstimate estimate_run(const scene::Sketch& sketch, const sim::ClothInput& cloth,
                         const sim::ClothModelOptions& model, double frames_per_second,
                         double duration, double time_step);

// The estimate of a cloth whose mesh is known without building the scene (a sheet: its grid of
// triangles, without the body or the model); nullopt for a garment. A sheet whose factor alone,
// at its smallest (kMinFactorBytesPerVertexLog), would not fit `limits` is estimated from its
// vertex count without building its grid or analysing it (a 1024² disc took 11 s and 363 MB to
// be refused; now it answers at once).
std::optional<RunEstimate> estimate_before_building(const scene::Sketch& sketch,
                                                    double frames_per_second,
                                                    const RunLimits& limits = {});

// Refuses (garment::SketchError, at /sheet/resolution, /simulate/duration or the file) a run
// whose estimate does not fit `limits`, or whose PNG sequence has more than kMaxFrames pictures,
// with a sentence that says what would fit.
inline constexpr double kMaxFrames = 10000;
void check_run_fits(const scene::Sketch& sketch, const RunEstimate& estimate,
                    const RunLimits& limits, double frames_per_second);

// Parses "4G", "512M", "1.5GB", "2000000" (bytes) for --max-memory; throws
// std::invalid_argument.
double parse_memory_size(const std::string& text);

}  // namespace sd::app
