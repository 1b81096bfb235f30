#pragma once
// An imported garment for the CLI tests: a quad tube round the hips, as an OBJ file.

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

namespace sd::test {

// Writes a tube of radius 0.22 m from y = 0.95 m down 0.35 m, 24 quads round and 8 down
// (216 vertices, 192 quads), to `path`.
inline void write_hip_tube_obj(const std::filesystem::path& path) {
  std::ofstream obj(path);
  constexpr int kRound = 24, kDown = 8;
  for (int j = 0; j <= kDown; ++j)
    for (int i = 0; i < kRound; ++i) {
      const double a = 2 * std::numbers::pi * i / kRound;
      obj << "v " << 0.22 * std::sin(a) << " " << 0.95 - 0.35 * j / kDown << " "
          << 0.22 * std::cos(a) << "\n";
    }
  for (int j = 0; j < kDown; ++j)
    for (int i = 0; i < kRound; ++i) {
      const int a = j * kRound + i + 1, b = j * kRound + (i + 1) % kRound + 1;
      obj << "f " << a << " " << a + kRound << " " << b + kRound << " " << b << "\n";
    }
}

}  // namespace sd::test
