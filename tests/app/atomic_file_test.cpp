#include "src/app/pipeline/atomic_file.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace sd::app {
namespace {

namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / "sd_atomic_test" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string read(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(AtomicFile, ReplacesContentWithoutLeavingTemporaries) {
  const fs::path dir = fresh_dir("replace");
  write_file_atomically(dir / "a.txt", "first");
  write_file_atomically(dir / "a.txt", "second");
  EXPECT_EQ(read(dir / "a.txt"), "second");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

TEST(AtomicFile, UnwritableFolderThrows) {
  EXPECT_THROW(write_file_atomically("/nonexistent-folder/a.txt", "x"), std::runtime_error);
}

// Trial 40: -o a dangling symbolic link said "cannot create folder ... (File exists)" of a folder
// the user could not see. It says where the link leads.
TEST(OutputFolder, DanglingSymbolicLinkIsSaidToBeOne) {
  const fs::path dir = fresh_dir("dangling");
  fs::create_symlink(dir / "gone" / "deeper", dir / "link");
  try {
    check_output_folder(dir / "link");
    ADD_FAILURE() << "a dangling link was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(
        std::string(e.what()).find("'" + (dir / "link").string() + "' is a symbolic link to '" +
                                   (dir / "gone" / "deeper").string() + "', which does not exist"),
        std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(fs::exists(dir / "gone"));
  // A link to a folder is written through (outtests h50).
  fs::create_directory(dir / "real");
  fs::create_directory_symlink(dir / "real", dir / "good");
  EXPECT_NO_THROW(check_output_folder(dir / "good"));
}

TEST(StagedOutputs, NothingAppearsUntilCommit) {
  const fs::path dir = fresh_dir("commit");
  StagedOutputs outputs;
  outputs.stage(dir / "out" / "a.png", "png");
  outputs.stage(dir / "out" / "report.json", "{}");
  EXPECT_FALSE(fs::exists(dir / "out" / "a.png"));
  outputs.commit();
  EXPECT_EQ(read(dir / "out" / "a.png"), "png");
  EXPECT_EQ(read(dir / "out" / "report.json"), "{}");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir / "out"), fs::directory_iterator()), 2);
}

TEST(StagedOutputs, AbandonedOutputsLeaveNothingBehind) {
  const fs::path dir = fresh_dir("abandon");
  write_file_atomically(dir / "keep.txt", "old");
  {
    StagedOutputs outputs;
    outputs.stage(dir / "keep.txt", "new");
    outputs.stage(dir / "new" / "deeper" / "b.txt", "b");
    // A command failing here: the destructor runs without commit().
  }
  EXPECT_EQ(read(dir / "keep.txt"), "old");
  EXPECT_FALSE(fs::exists(dir / "new"));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

}  // namespace
}  // namespace sd::app
