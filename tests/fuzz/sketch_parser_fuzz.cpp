// libFuzzer target: the sketch file reader (parse_sketch) on arbitrary bytes, then the range
// checks against the built-in body's box. Any input must end in a SketchError or a Sketch; a
// crash, a sanitizer report, a hang or more than -rss_limit_mb is a bug (docs/cli.md, "Fuzzing").

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "garment/sketch_ranges.hpp"
#include "scene/sketch_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const sd::scene::Sketch sketch = sd::scene::parse_sketch(text, "fuzz.json", "/nonexistent");
    // The built-in body's normalised box (docs/bodies.md).
    sd::meshing::BoundingBox box;
    box.min = Eigen::Vector3d(-0.383, 0.0, -0.129);
    box.max = Eigen::Vector3d(0.383, 1.75, 0.129);
    sd::garment::check_against_body(sketch, box);
  } catch (const sd::garment::SketchError&) {
  }
  return 0;
}
