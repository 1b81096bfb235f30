#include "src/render/gl.hpp"

#include <dlfcn.h>
#include <fmt/format.h>

#include <cstdlib>
#include <iterator>
#include <mutex>
#include <string>
#include <vector>

#include "src/render/renderer.hpp"

namespace sd::render::gl {

Functions functions;

namespace {

// The shared library's name, found by CMake from the development package (cmake/osmesa.cmake);
// the unversioned name last, for a system where that is all there is. SKETCHDRAPE_OSMESA, when
// set, is the one library tried instead (another Mesa build; docs/rendering.md).
constexpr const char* kLibraryNames[] = {SD_OSMESA_LIBRARY, "libOSMesa.so"};
constexpr const char* kLibraryVariable = "SKETCHDRAPE_OSMESA";

std::once_flag loaded_once;

template <typename Pointer>
void look_up(void* library, const char* library_name, const char* name, Pointer& pointer) {
  pointer = reinterpret_cast<Pointer>(dlsym(library, name));
  if (pointer == nullptr)
    throw RenderError(
        fmt::format("{} has no function {} (is libosmesa6 from Mesa 20 or newer "
                    "installed?)",
                    library_name, name));
}

void load_once() {
  std::vector<const char*> names(std::begin(kLibraryNames), std::end(kLibraryNames));
  const char* chosen = std::getenv(kLibraryVariable);
  if (chosen != nullptr && *chosen != '\0') names = {chosen};
  void* library = nullptr;
  const char* library_name = names.front();
  std::string errors;
  for (const char* name : names) {
    // RTLD_LOCAL: its symbols stay out of the process's namespace (nothing else links GL).
    library = dlopen(name, RTLD_NOW | RTLD_LOCAL);
    if (library != nullptr) {
      library_name = name;
      break;
    }
    if (const char* error = dlerror())
      errors += fmt::format("{}{}", errors.empty() ? "" : "; ", error);
  }
  if (library == nullptr)
    throw RenderError(fmt::format(
        "cannot render: the OSMesa library {} could not be opened ({}){}; it is in Debian's "
        "package libosmesa6 (apt-get install libosmesa6)",
        library_name, errors,
        chosen != nullptr && *chosen != '\0'
            ? fmt::format(" (the {} environment variable named it)", kLibraryVariable)
            : ""));
  Functions loaded;
  try {
#define SD_GL_LOOK_UP(name) look_up(library, library_name, #name, loaded.name##_);
    SD_GL_FUNCTIONS(SD_GL_LOOK_UP)
#undef SD_GL_LOOK_UP
  } catch (...) {
    dlclose(library);
    throw;
  }
  functions = loaded;
  // The library stays open for the life of the process: contexts may outlive any one Renderer.
}

}  // namespace

void load_gl() {
  std::call_once(loaded_once, load_once);  // a throw leaves the flag unset: the next call retries
}

}  // namespace sd::render::gl
