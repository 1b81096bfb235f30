#pragma once
// Shared helpers for the garment tests: the example files, and the sphere every test folder
// uses as its analytic body (meshing::icosphere, from meshing/tri_mesh.hpp).

#include <algorithm>
#include <filesystem>
#include <vector>

#include "meshing/tri_mesh.hpp"

namespace sd::test {

inline std::vector<std::filesystem::path> example_files() {
  std::vector<std::filesystem::path> files;
  for (const auto& entry :
       std::filesystem::directory_iterator(std::filesystem::path(SD_SOURCE_DIR) / "data/examples"))
    if (entry.path().extension() == ".json") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace sd::test
