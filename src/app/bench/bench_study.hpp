#pragma once
// The work-precision study of `sketchdrape bench` (docs/benchmarks.md, "Work-precision study"):
// scenes, the grid of configurations run on each, one run of a configuration (the worker side),
// and the error of a run against the scene's reference run.
//
// Every scene starts from a 4-8 mesh (a sheet's quads or a garment's stitched quads). A fixed
// run at level L refines it uniformly to level L and drapes that mesh with the implicit
// simulator; an adaptive run starts at the scene's start level and refines and coarsens as it
// goes. The error of a run is measured at fixed material points (points of the rest surface):
// each is located once per mesh in the rest triangles (closest point, barycentric coordinates)
// and followed in the draped mesh; positions are compared with the reference's at fixed sample
// times.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "meshing/mesh48.hpp"
#include "meshing/tri_mesh.hpp"
#include "sim/adaptive_detail.hpp"
#include "sim/simulation.hpp"

namespace sd::app {

// A --scene that is neither a built-in scene nor a usable sketch file.
class BenchSceneError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// How big the study is: `full` for docs/benchmarks.md, `quick` (--quick, under two minutes),
// `tiny` (seconds: the CLI test).
enum class BenchGrid { tiny, quick, full };

// What a scene simulates, ready to be refined and run.
struct BenchScene {
  std::string name;    // "hanging-sheet", "sphere-drop", "tshirt" or the file's stem
  std::string source;  // "built-in" or the sketch file path
  std::optional<meshing::Mesh48> mesh;  // level-0 4-8 mesh, rest positions in metres (always set)
  sim::AdaptiveMaterial material;       // fabric and warp per input face
  Eigen::MatrixX3d start;               // #V by 3 start positions (rows = vertex ids of `mesh`)
  std::vector<int> pinned;              // vertex ids held where they start
  std::optional<meshing::TriMesh> body;
  sim::SimulationSettings settings;  // forces and contact; integrator, solver, dt set per run
  double duration = 2.0;             // s simulated by every run
  double sample_every = 0.1;         // s between the times positions and energies are compared
  Eigen::MatrixX3d material_points;  // #P by 3, on the rest surface
  int start_level = 0;               // level adaptive runs start from
  bool sheet = false;                // 4 by 4 level-0 quads (levels as for a sheet)
};

enum class BenchMeshKind { fixed, adaptive };

// One configuration of the grid.
struct BenchConfig {
  BenchMeshKind mesh = BenchMeshKind::fixed;
  int level = 0;           // fixed: uniform level; adaptive: finest level allowed
  double threshold = 0.0;  // adaptive: refine threshold, m (coarsen at a quarter)
  sim::Integrator integrator = sim::Integrator::implicit_euler;
  sim::LinearSolverKind solver = sim::LinearSolverKind::cholmod;
  int steps_per_second = 60;  // dt = 1 / steps_per_second
  // BDF2 only: one Newton iteration, linearised at the start of the step (the linearly implicit
  // BDF2 step, docs/simulator.md "Integration") instead of simplified Newton with fallbacks.
  bool linearized = false;
  // > 0: the PCG's relative tolerance (the automatic rule's, when it is not the default); 0: the
  // scene's.
  double pcg_tolerance = 0.0;
  // > 0: the step follows this local error (m, sim::SimulationSettings::step_error) up to dt.
  double step_error = 0.0;

  double dt() const { return 1.0 / steps_per_second; }
  std::string id() const;     // "fixed-L4-ie-cholmod-60", unique in a grid
  std::string label() const;  // "fixed L4, implicit Euler, CHOLMOD, 1/60 s"
};

// A family is one curve of the plot: configurations that differ in one parameter.
struct BenchFamily {
  std::string name;                  // "fixed, IE, CHOLMOD, 1/60 s (resolution)"
  std::vector<BenchConfig> members;  // in curve order
};

struct BenchPlan {
  BenchConfig reference;  // much finer mesh and much smaller step
  std::vector<BenchFamily> families;
  std::vector<BenchConfig> runs;  // the union of the families' members, each once
};

// The families of what the sketch defaults ("solver" and "time_step" "auto") run at each level:
// for a drape, and with `run --frames` (sim/automatic_settings.hpp).
inline const std::string kAutomaticFamily = "automatic (the sketch default): levels";
inline const std::string kAutomaticMotionFamily =
    "automatic with --frames (the motion asked for): levels";

// Names of the built-in scenes.
std::vector<std::string> builtin_bench_scenes();
// A built-in scene by name, or a sketch file (a sheet or a garment; imported garments are not
// supported). Durations depend on the grid. Throws BenchSceneError, or garment::SketchError for
// a sketch the designer can fix.
BenchScene build_bench_scene(const std::string& name_or_file, BenchGrid grid);
// The configurations of the scene for the grid.
BenchPlan bench_plan(const BenchScene& scene, BenchGrid grid);

// Digest (SHA-256, hex) of everything that decides the reference result: the scene's content
// (meshes, pins, start, fabric, forces, body, duration, sample times, material points), the
// reference configuration and `binary_digest` (the executable, so a rebuilt simulator
// recomputes its references).
std::string reference_key(const BenchScene& scene, const BenchConfig& reference,
                          const std::string& binary_digest);

// What one run produced: positions of the material points and the energy at each sample time,
// and its own figures.
struct BenchTrace {
  std::vector<double> times;                // s, the sample times reached (0 included)
  std::vector<Eigen::MatrixX3d> positions;  // per sample time, #P by 3
  std::vector<double> energy;               // J, total energy (elastic + kinetic + potential)
  bool failed = false;
  std::string failure;
  double wall_s = 0.0;         // stepping only (sampling excluded), wall time
  double cpu_s = 0.0;          // stepping only, CPU time of the process
  double rss_before_mb = 0.0;  // peak resident memory before the first step (scene, mesh, model)
  int steps = 0, retries = 0, linear_solves = 0;
  double cg_iterations_mean = 0.0;
  int vertices_max = 0, triangles_max = 0, vertices_final = 0;
  int splits = 0, merges = 0;
};

// Runs one configuration of the scene (the worker side of `bench`).
BenchTrace run_bench_config(const BenchScene& scene, const BenchConfig& config);

// Binary form of a trace (worker output and reference cache). Throws std::runtime_error when
// the bytes are not a trace.
std::string serialize_trace(const BenchTrace& trace);
BenchTrace deserialize_trace(const std::string& bytes);

// Error of a run against the reference, over the sample times both reached (t > 0).
struct BenchError {
  double rms_m = 0.0;            // RMS distance over all material points and sample times
  double max_m = 0.0;            // largest distance of any point at any sample time
  double final_rms_m = 0.0;      // RMS distance at the last sample time
  double energy_j = 0.0;         // max over sample times of |E_run − E_ref|
  double energy_relative = 0.0;  // energy_j over the range (max − min) of E_ref
  int samples = 0;               // sample times compared
};
BenchError bench_error(const BenchTrace& run, const BenchTrace& reference);

// Configuration serialised for the worker's command line, and back.
std::string config_to_json(const BenchConfig& config);
BenchConfig config_from_json(const std::string& text);

}  // namespace sd::app
