// Meshing a sketch, body loading excluded: sketch parse + stroke projection + curve network +
// panels + edge counts + quad fill + stitching (build_garment), for each example garment.
// The body and its AABB tree are built once, outside the timed loop (as `mesh` reports them
// apart). Run: ./build/tests/bench/garment_bench

#include <benchmark/benchmark.h>

#include <filesystem>

#include "garment/body.hpp"
#include "garment/body_surface.hpp"
#include "garment/garment_mesh.hpp"
#include "garment/sketch_inputs.hpp"
#include "scene/sketch_file.hpp"

namespace {

const sd::garment::BodySurface& surface() {
  static const sd::garment::Body body = sd::garment::load_body("builtin");
  static const sd::garment::BodySurface s(body.mesh);
  return s;
}

void mesh_file(benchmark::State& state, const std::filesystem::path& file) {
  const sd::garment::BodySurface& body = surface();
  long quads = 0;
  for (auto _ : state) {
    const sd::scene::Sketch sketch = sd::scene::load_sketch(file);
    const sd::garment::Garment g = sd::garment::build_garment(sketch, body);
    quads = static_cast<long>(g.mesh.face_count());
    benchmark::DoNotOptimize(g.mesh.vertices.data());
  }
  state.counters["quads"] = static_cast<double>(quads);
}

void mesh_example(benchmark::State& state, const char* name) {
  mesh_file(state, std::filesystem::path(SD_SOURCE_DIR) / "data/examples" / name);
}

// The design corpus on the built-in body (data/designs/): the garments' panels spanned by their
// curves ("fit": "free") cost a harmonic solve per obstacle round.
void mesh_design(benchmark::State& state, const char* name) {
  mesh_file(state, std::filesystem::path(SD_SOURCE_DIR) / "data/designs" / name);
}

// The designs on the second body, Debian's Collada human (skipped when it is not installed).
void mesh_human_design(benchmark::State& state, const char* name) {
  const std::filesystem::path file = std::filesystem::path(SD_SOURCE_DIR) / "data/designs" / name;
  const sd::scene::Sketch sketch = sd::scene::load_sketch(file);
  if (!std::filesystem::exists(sketch.resolve(sketch.body.mesh))) {
    state.SkipWithError("the Collada human (assimp-testmodels) is not installed");
    return;
  }
  static const sd::garment::Body body = sd::garment::load_sketch_body(sketch);
  static const sd::garment::BodySurface human(body.mesh);
  long quads = 0;
  for (auto _ : state) {
    const sd::scene::Sketch parsed = sd::scene::load_sketch(file);
    const sd::garment::Garment g = sd::garment::build_garment(parsed, human);
    quads = static_cast<long>(g.mesh.face_count());
    benchmark::DoNotOptimize(g.mesh.vertices.data());
  }
  state.counters["quads"] = static_cast<double>(quads);
}

void body_surface_build(benchmark::State& state) {
  static const sd::garment::Body body = sd::garment::load_body("builtin");
  for (auto _ : state) {
    sd::garment::BodySurface s(body.mesh);
    benchmark::DoNotOptimize(&s);
  }
}

}  // namespace

BENCHMARK_CAPTURE(mesh_example, tshirt, "tshirt.json")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mesh_example, a_line_skirt, "a-line-skirt.json")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mesh_example, sleeveless_dress, "sleeveless-dress.json")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mesh_example, shorts, "shorts.json")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mesh_example, godet_skirt, "godet-skirt.json")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mesh_design, pencil_skirt, "pencil-skirt.json")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mesh_design, vest, "vest.json")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mesh_design, capelet, "capelet.json")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mesh_design, one_shoulder_top, "one-shoulder-top.json")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mesh_design, wrap_skirt, "wrap-skirt.json")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mesh_design, vest_collar, "vest-collar.json")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mesh_design, long_sleeve_tee, "long-sleeve-tee.json")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mesh_design, circle_skirt, "circle-skirt.json")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mesh_design, raglan_top, "raglan-top.json")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mesh_design, cape_hood, "cape-hood.json")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mesh_human_design, trousers_human, "trousers-human.json")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mesh_human_design, jumpsuit_human, "jumpsuit-human.json")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(mesh_human_design, tee_dress_human, "tee-dress-human.json")
    ->Unit(benchmark::kMillisecond);
BENCHMARK(body_surface_build)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
