// Meshing a sketch, body loading excluded: sketch parse + stroke projection + curve network +
// panels + edge counts + quad fill + stitching (build_garment), for every example garment
// (data/examples/) and every design of the corpus (data/designs/, the Collada human's skipped
// when it is not installed). Each body and its trees are built once, outside the timed loop (as
// `mesh` reports them apart). Each garment on 1 and 2 threads (the argument: build_garment fills
// the panels side by side, garment/panel_tasks.hpp); "Time" is wall time, "CPU" the whole
// process's over every thread.
// "fine/<design>/edge_0.1mm:N": one design at edge length N/10 mm, one iteration each.
// Run: ./build/tests/bench/garment_bench (--benchmark_filter=fine for the scaling alone)

#include <benchmark/benchmark.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "garment/body.hpp"
#include "garment/body_surface.hpp"
#include "garment/garment_mesh.hpp"
#include "garment/panel_tasks.hpp"
#include "garment/sketch_inputs.hpp"
#include "scene/sketch_file.hpp"

namespace {

namespace fs = std::filesystem;

// A design's body with its closest-point and ray trees, loaded once per sketch file.
const sd::garment::BodySurface& body_of(const fs::path& file) {
  struct Loaded {
    sd::garment::Body body;
    std::unique_ptr<sd::garment::BodySurface> surface;
  };
  static std::map<fs::path, Loaded> loaded;
  auto it = loaded.find(file);
  if (it == loaded.end()) {
    Loaded l{sd::garment::load_sketch_body(sd::scene::load_sketch(file)), nullptr};
    l.surface = std::make_unique<sd::garment::BodySurface>(l.body.mesh);
    it = loaded.emplace(file, std::move(l)).first;
  }
  return *it->second.surface;
}

void mesh_file(benchmark::State& state, const fs::path& file) {
  const sd::scene::Sketch sketch = sd::scene::load_sketch(file);
  if (!fs::exists(sketch.resolve(sketch.body.mesh)) && sketch.body.mesh != "builtin") {
    state.SkipWithError("the design's body is not installed");
    return;
  }
  const sd::garment::BodySurface& body = body_of(file);
  sd::garment::set_panel_threads(static_cast<int>(state.range(0)));
  long quads = 0;
  for (auto _ : state) {
    const sd::scene::Sketch parsed = sd::scene::load_sketch(file);
    const sd::garment::Garment g = sd::garment::build_garment(parsed, body);
    quads = static_cast<long>(g.mesh.face_count());
    benchmark::DoNotOptimize(g.mesh.vertices.data());
  }
  state.counters["quads"] = static_cast<double>(quads);
}

// One design at a finer edge length than its own (state.range(0), in tenths of a millimetre; the
// panels' and curves' own edge lengths dropped): how meshing grows with the quads
// (docs/garment.md, "Meshing time and memory"). One iteration: the 0.4 cm tee takes ~30 s.
void mesh_fine(benchmark::State& state, const fs::path& file) {
  sd::scene::Sketch sketch = sd::scene::load_sketch(file);
  if (!fs::exists(sketch.resolve(sketch.body.mesh)) && sketch.body.mesh != "builtin") {
    state.SkipWithError("the design's body is not installed");
    return;
  }
  sketch.edge_length = static_cast<double>(state.range(0)) * 1e-4;
  for (sd::garment::PanelSpec& panel : sketch.panels) panel.edge_length.reset();
  for (sd::garment::CurveSpec& curve : sketch.curves) curve.edge_length.reset();
  const sd::garment::BodySurface& body = body_of(file);
  sd::garment::set_panel_threads(1);
  long quads = 0;
  for (auto _ : state) {
    const sd::garment::Garment g = sd::garment::build_garment(sketch, body);
    quads = static_cast<long>(g.mesh.face_count());
    benchmark::DoNotOptimize(g.mesh.vertices.data());
  }
  state.counters["quads"] = static_cast<double>(quads);
  state.counters["time_per_quad"] =
      benchmark::Counter(static_cast<double>(quads), benchmark::Counter::kIsIterationInvariantRate |
                                                         benchmark::Counter::kInvert);
}

void body_surface_build(benchmark::State& state) {
  static const sd::garment::Body body = sd::garment::load_body("builtin");
  for (auto _ : state) {
    sd::garment::BodySurface s(body.mesh);
    benchmark::DoNotOptimize(&s);
  }
}

// The sketch files of a folder, by name.
std::vector<fs::path> sketches_in(const char* folder) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(fs::path(SD_SOURCE_DIR) / folder))
    if (entry.path().extension() == ".json") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

int main(int argc, char** argv) {
  spdlog::set_level(spdlog::level::err);  // the shorts' merged doublet would warn every iteration
  for (const char* folder : {"data/examples", "data/designs"})
    for (const fs::path& file : sketches_in(folder))
      benchmark::RegisterBenchmark(
          (fs::path(folder).filename().string() + "/" + file.stem().string()).c_str(),
          [file](benchmark::State& state) { mesh_file(state, file); })
          ->Arg(1)
          ->Arg(2)
          ->MeasureProcessCPUTime()
          ->Unit(benchmark::kMillisecond);
  for (const char* design : {"long-sleeve-tee", "tee-dress-human"}) {
    const fs::path file =
        fs::path(SD_SOURCE_DIR) / "data/designs" / (std::string(design) + ".json");
    benchmark::RegisterBenchmark((std::string("fine/") + design).c_str(),
                                 [file](benchmark::State& state) { mesh_fine(state, file); })
        ->ArgName("edge_0.1mm")
        ->Arg(200)
        ->Arg(100)
        ->Arg(40)
        ->Iterations(1)
        ->MeasureProcessCPUTime()
        ->Unit(benchmark::kMillisecond);
  }
  benchmark::RegisterBenchmark("body_surface_build", body_surface_build)
      ->Unit(benchmark::kMillisecond);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
