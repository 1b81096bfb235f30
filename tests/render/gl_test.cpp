// OSMesa is opened by the first Renderer, not when the program starts (src/render/gl.hpp):
// loading it and its LLVM was half the start-up of a run that renders nothing.

#include "src/render/gl.hpp"

#include <dlfcn.h>
#include <gtest/gtest.h>

#include "src/render/renderer.hpp"

namespace sd::render {
namespace {

bool osmesa_is_loaded() {
  // RTLD_NOLOAD: a handle only if the library is already in the process (then released again).
  void* library = dlopen(SD_OSMESA_LIBRARY, RTLD_NOW | RTLD_NOLOAD);
  if (library == nullptr) return false;
  dlclose(library);
  return true;
}

TEST(Gl, OsmesaIsLoadedByTheFirstRendererOnly) {
  // CTest runs each test in a process of its own; run alone, nothing has rendered yet, so a
  // loaded library here means the program links it again.
  if (gl::functions.OSMesaCreateContextAttribs_ != nullptr)
    GTEST_SKIP() << "another test of this process rendered first; run this one alone";
  EXPECT_FALSE(osmesa_is_loaded()) << SD_OSMESA_LIBRARY << " was loaded before any rendering";
  const Renderer renderer;
  EXPECT_TRUE(osmesa_is_loaded());
  EXPECT_NE(gl::functions.glReadPixels_, nullptr);
  EXPECT_FALSE(renderer.gl_version().empty());
}

}  // namespace
}  // namespace sd::render
