// libFuzzer target: the quad filler's input, as `sketchdrape fill --sides` gives it: up to 12
// side counts of 1..64 edges (one byte each). Counts the filler accepts must give a valid quad
// mesh whose boundary has exactly those counts; others must end in a FillError.

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "meshing/patch_fill.hpp"
#include "meshing/quad_mesh.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<int> counts;
  for (size_t i = 0; i < size && i < 12; ++i) counts.push_back(1 + data[i] % 64);
  try {
    const sd::meshing::PatchTopology patch = sd::meshing::fill_region(counts);
    if (!sd::meshing::validate(patch.mesh).ok()) std::abort();
    if (patch.side_vertices.size() != counts.size()) std::abort();
    for (size_t s = 0; s < counts.size(); ++s)
      if (static_cast<int>(patch.side_vertices[s].size()) != counts[s] + 1) std::abort();
  } catch (const sd::meshing::FillError&) {
  }
  return 0;
}
