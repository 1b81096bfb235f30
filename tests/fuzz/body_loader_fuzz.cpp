// libFuzzer target: the body loader (assimp import, weld, topology, orientation, normalisation)
// on arbitrary file contents. The first byte picks the format by extension (assimp chooses its
// importer from it); the rest is the file. Any input must load or end in a BodyError.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "garment/body.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* const kExtensions[] = {".obj", ".off", ".ply", ".stl"};
  const std::string path =
      "/tmp/sd-fuzz-body-" + std::to_string(::getpid()) + kExtensions[data[0] % 4];
  if (std::FILE* file = std::fopen(path.c_str(), "wb")) {
    std::fwrite(data + 1, 1, size - 1, file);
    std::fclose(file);
  }
  try {
    (void)sd::garment::load_body(path);
  } catch (const sd::garment::BodyError&) {
  }
  std::remove(path.c_str());
  return 0;
}
