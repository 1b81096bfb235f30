#pragma once
// Helpers shared by the batch tests: fresh folders and small files.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace sd::test {

// An empty folder under the system temp dir, unique per process and name.
inline std::filesystem::path fresh_batch_dir(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("sd_batch_test_" + std::to_string(::getpid())) / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline void write_text(const std::filesystem::path& path, const std::string& text) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Removes this process's test folders when every test passed (they are kept for inspection
// otherwise). Registered once per test executable that includes this header.
class RemoveBatchTestFolders : public ::testing::Environment {
 public:
  void TearDown() override {
    if (!::testing::UnitTest::GetInstance()->Passed()) return;
    std::error_code ignored;
    std::filesystem::remove_all(
        std::filesystem::temp_directory_path() / ("sd_batch_test_" + std::to_string(::getpid())),
        ignored);
  }
};
inline ::testing::Environment* const kRemoveBatchTestFolders =
    ::testing::AddGlobalTestEnvironment(new RemoveBatchTestFolders);

}  // namespace sd::test
