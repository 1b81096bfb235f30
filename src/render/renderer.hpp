#pragma once
// Offscreen OpenGL rendering with OSMesa (Mesa's llvmpipe, on the CPU, no display needed).
//
//   sd::render::Renderer renderer;                      // one context, reused for every frame
//   sd::render::PreparedScene prepared = renderer.prepare(scene);   // upload once
//   for (const Camera& c : cameras) images.push_back(renderer.render(prepared, c, {800, 1200}));
//
// A Renderer owns one OSMesa core-profile context (OpenGL 4.5) and the compiled shaders; make
// one per thread and keep it for the whole run (creating a context costs ~10 ms, compiling the
// shaders more). Lights follow the camera: a key light above and to the camera's left that
// casts soft shadows, and a weaker fill light from the right.

#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "src/render/camera.hpp"
#include "src/render/image.hpp"
#include "src/render/scene.hpp"

namespace sd::render {

// OpenGL could not do what was asked (no context, shader compile failure, out of memory).
class RenderError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class Antialiasing {
  kNone,
  kMsaa4,         // 4 samples per pixel, resolved by the GPU (the default: see docs/rendering.md)
  kSupersample2,  // render at twice the width and height, average 2x2 blocks on the CPU
};

struct RendererOptions {
  Antialiasing antialiasing = Antialiasing::kMsaa4;
  int shadow_map_size = 2048;  // texels per side of the key light's depth map
};

class Renderer;

// Opens OSMesa now, as the first Renderer would (once per process; later calls return at once):
// a program that will render after a long computation finds a missing library before it.
// Throws RenderError naming the library and its Debian package.
void load_renderer_library();

// A scene uploaded to the renderer's context. Keeps that context alive; use it only with the
// Renderer that made it. Move-only.
class PreparedScene {
 public:
  PreparedScene(PreparedScene&&) noexcept;
  PreparedScene& operator=(PreparedScene&&) noexcept;
  ~PreparedScene();

  const meshing::BoundingBox& bounds() const;  // of the meshes, without the ground

  struct Data;  // GPU objects; defined in renderer.cpp

 private:
  friend class Renderer;
  explicit PreparedScene(std::unique_ptr<Data> data);
  std::unique_ptr<Data> data_;
};

class Renderer {
 public:
  // Creates the context and compiles the shaders. Throws RenderError.
  explicit Renderer(const RendererOptions& options = {});
  ~Renderer();
  Renderer(Renderer&&) noexcept;
  Renderer& operator=(Renderer&&) noexcept;
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Uploads meshes, normals, colours and wireframes. Throws std::invalid_argument for a
  // malformed scene (see validate_scene).
  PreparedScene prepare(const Scene& scene);

  // Draws one frame. The image is `size` pixels, rows top to bottom, alpha 255.
  Image render(const PreparedScene& scene, const Camera& camera, ImageSize size);

  // prepare() then render() for one camera.
  Image render(const Scene& scene, const Camera& camera, ImageSize size);

  const std::string& gl_version() const;   // e.g. "4.5 (Core Profile) Mesa 22.3.6"
  const std::string& gl_renderer() const;  // e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
  const RendererOptions& options() const;

  struct Impl;  // the context and shaders; defined in renderer.cpp

 private:
  std::shared_ptr<Impl> impl_;
};

}  // namespace sd::render
