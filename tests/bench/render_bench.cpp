// Rendering costs for a 1024x1024 view of the built-in body, split into the parts a batch run
// pays once (context, shaders, upload) and per view (frame, PNG). Wall time is the figure that
// matters (llvmpipe draws on worker threads); process CPU time is reported alongside.

#include <benchmark/benchmark.h>

#include "garment/body.hpp"
#include "src/render/gl.hpp"
#include "src/render/renderer.hpp"

namespace sd::render {
namespace {

constexpr ImageSize kSize{1024, 1024};

const meshing::TriMesh& body() {
  static const meshing::TriMesh mesh = garment::load_body("builtin").mesh;
  return mesh;
}

Scene body_scene(bool shadows) {
  Scene scene;
  scene.meshes.emplace_back().mesh = body();
  scene.shadows = shadows;
  return scene;
}

// A bare OSMesa core context: what Renderer's constructor pays before compiling shaders.
void BM_ContextCreation(benchmark::State& state) {
  gl::load_gl();  // what the first Renderer does before its context (not timed)
  std::vector<unsigned char> buffer(16 * 16 * 4);
  for (auto _ : state) {
    const int attributes[] = {OSMESA_FORMAT,
                              OSMESA_RGBA,
                              OSMESA_DEPTH_BITS,
                              0,
                              OSMESA_PROFILE,
                              OSMESA_CORE_PROFILE,
                              OSMESA_CONTEXT_MAJOR_VERSION,
                              4,
                              OSMESA_CONTEXT_MINOR_VERSION,
                              5,
                              0};
    OSMesaContext context = OSMesaCreateContextAttribs(attributes, nullptr);
    if (context == nullptr) {
      state.SkipWithError("no OSMesa context");
      break;
    }
    OSMesaMakeCurrent(context, buffer.data(), GL_UNSIGNED_BYTE, 16, 16);
    benchmark::DoNotOptimize(glGetString(GL_VERSION));
    OSMesaDestroyContext(context);
  }
}
BENCHMARK(BM_ContextCreation)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

// Context + compiling and linking the four shader programs + the shadow map.
void BM_RendererStartup(benchmark::State& state) {
  for (auto _ : state) {
    Renderer renderer;
    benchmark::DoNotOptimize(renderer.gl_version().data());
  }
}
BENCHMARK(BM_RendererStartup)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

// Vertex normals + uploading the body (4.3k vertices, 8.6k triangles) and its face colours.
void BM_PrepareBody(benchmark::State& state) {
  Renderer renderer;
  const Scene scene = body_scene(true);
  for (auto _ : state) benchmark::DoNotOptimize(renderer.prepare(scene));
}
BENCHMARK(BM_PrepareBody)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

// One frame: shadow pass, floor, body, resolve, read back. Arg 0: none, 1: MSAA 4x,
// 2: 2x2 supersampling; arg 1: shadows on/off.
void BM_FrameBody(benchmark::State& state) {
  const auto aa = static_cast<Antialiasing>(state.range(0));
  Renderer renderer({.antialiasing = aa});
  const PreparedScene prepared = renderer.prepare(body_scene(state.range(1) != 0));
  const Camera camera = frame_view(ViewName::kThreeQuarter, prepared.bounds(), kSize.aspect());
  renderer.render(prepared, camera, kSize);  // allocate the framebuffers once, as in a batch
  for (auto _ : state) benchmark::DoNotOptimize(renderer.render(prepared, camera, kSize));
}
BENCHMARK(BM_FrameBody)
    ->ArgNames({"aa", "shadows"})
    ->Args({0, 1})
    ->Args({1, 1})
    ->Args({2, 1})
    ->Args({1, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

void BM_EncodePng(benchmark::State& state) {
  Renderer renderer;
  const Scene scene = body_scene(true);
  const Image image = renderer.render(
      scene, frame_view(ViewName::kThreeQuarter, scene_bounds(scene), kSize.aspect()), kSize);
  size_t bytes = 0;
  for (auto _ : state) bytes = encode_png(image).size();
  state.counters["png_kB"] = static_cast<double>(bytes) / 1024;
}
BENCHMARK(BM_EncodePng)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

// What each additional view costs in a batch: frame + PNG (default MSAA 4x, shadows).
void BM_ViewFrameAndPng(benchmark::State& state) {
  Renderer renderer;
  const PreparedScene prepared = renderer.prepare(body_scene(true));
  const Camera camera = frame_view(ViewName::kFront, prepared.bounds(), kSize.aspect());
  for (auto _ : state)
    benchmark::DoNotOptimize(encode_png(renderer.render(prepared, camera, kSize)));
}
BENCHMARK(BM_ViewFrameAndPng)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

// A first view from nothing: context, shaders, upload, frame, PNG.
void BM_FirstViewFromScratch(benchmark::State& state) {
  const Scene scene = body_scene(true);
  for (auto _ : state) {
    Renderer renderer;
    const PreparedScene prepared = renderer.prepare(scene);
    const Camera camera = frame_view(ViewName::kFront, prepared.bounds(), kSize.aspect());
    benchmark::DoNotOptimize(encode_png(renderer.render(prepared, camera, kSize)));
  }
}
BENCHMARK(BM_FirstViewFromScratch)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

}  // namespace
}  // namespace sd::render

BENCHMARK_MAIN();
