// The t-shirt's sewing pattern: flattening every panel (LSCM + ARAP with the seam lengths held),
// the layout (seam allowances by straight skeleton, nesting) and the three files (SVG, DXF,
// JSON). The garment is meshed once, outside the timed loop. Target: under 100 ms in all.
// Run: ./build/tests/bench/pattern_bench

#include <benchmark/benchmark.h>
#include <spdlog/spdlog.h>

#include <filesystem>

#include "garment/body.hpp"
#include "garment/body_surface.hpp"
#include "garment/garment_mesh.hpp"
#include "garment/panel_flattening.hpp"
#include "garment/pattern_layout.hpp"
#include "scene/sketch_file.hpp"
#include "src/app/pipeline/pattern_export.hpp"

namespace {

struct Example {
  sd::scene::Sketch sketch;
  sd::garment::Garment garment;
};

const Example& tshirt() {
  static const Example example = [] {
    const sd::garment::Body body = sd::garment::load_body("builtin");
    const sd::garment::BodySurface surface(body.mesh);
    Example e{
        sd::scene::load_sketch(std::filesystem::path(SD_SOURCE_DIR) / "data/examples/tshirt.json"),
        {}};
    e.garment = sd::garment::build_garment(e.sketch, surface);
    return e;
  }();
  return example;
}

void flatten_tshirt(benchmark::State& state) {
  const Example& e = tshirt();
  for (auto _ : state) {
    const sd::garment::FlatPattern pattern = sd::garment::flatten_garment(e.garment);
    benchmark::DoNotOptimize(pattern.panels.data());
  }
  state.counters["quads"] = static_cast<double>(e.garment.mesh.face_count());
}

void pattern_tshirt(benchmark::State& state) {
  const Example& e = tshirt();
  spdlog::set_level(spdlog::level::err);  // the back panels' stretch warnings, once per run
  size_t bytes = 0;
  for (auto _ : state) {
    const sd::app::PatternSheet sheet =
        sd::app::build_pattern_sheet(e.sketch, e.garment, sd::scene::PatternSpec{});
    bytes = sd::app::pattern_svg(sheet).size() + sd::app::pattern_dxf(sheet).size() +
            sd::app::pattern_json(sheet).dump(1).size();
    benchmark::DoNotOptimize(bytes);
  }
  state.counters["bytes"] = static_cast<double>(bytes);
}

}  // namespace

BENCHMARK(flatten_tshirt)->Unit(benchmark::kMillisecond);
BENCHMARK(pattern_tshirt)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
