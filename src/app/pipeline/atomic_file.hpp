#pragma once
// Writing outputs so that nothing partial is ever left behind: each file is written under a
// temporary name in its final directory and renamed into place only when the whole command
// has succeeded.

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace sd::app {

// Writes `bytes` to `path` through a temporary file in the same directory and a rename, so a
// reader sees either the old file or the complete new one. Throws std::runtime_error.
void write_file_atomically(const std::filesystem::path& path, std::string_view bytes);

// Installs the SIGINT / SIGTERM / SIGHUP handler that StagedOutputs otherwise installs when it
// first stages a file, at the start of a command, so that an interrupted command (a drape that
// has staged nothing yet) still says so in one line ("interrupted: nothing written") before it
// dies by the signal. Where another handler is already set (a batch), it is left alone.
void install_interrupt_cleanup();

// Checks, before any work, that files can be written in the output folder `dir`: it is a
// folder (or can be made one) and a file can be created in it. Leaves nothing behind (folders
// made for the test are removed again). Throws std::invalid_argument (exit code 2) with the
// folder, the reason and what to do: a read-only or system folder (/proc) was found only after
// a 21 s drape.
void check_output_folder(const std::filesystem::path& dir);

// A set of output files that appear together or not at all. Files are staged under temporary
// names; commit() renames them all into place; destruction without commit() removes them, and so
// does SIGINT, SIGTERM or SIGHUP (the process then dies by the signal). Staging in a folder first
// removes the temporaries that processes no longer running left there (SIGKILL, a crash) before
// this one started or ten minutes ago, and says so.
class StagedOutputs {
 public:
  StagedOutputs() = default;
  StagedOutputs(const StagedOutputs&) = delete;
  StagedOutputs& operator=(const StagedOutputs&) = delete;
  ~StagedOutputs();

  // Writes `bytes` to a temporary file that becomes `path` on commit(). Creates the parent
  // directory if needed. Throws std::runtime_error when the write fails.
  // An output at a path already staged, or at a file given to keep(), is refused with
  // std::invalid_argument (exit code 2) instead of overwriting it.
  void stage(const std::filesystem::path& path, std::string_view bytes);

  // A file the command read (the sketch, a mesh): no output may replace it (`render in.png -o
  // in.png`, `mesh report.json -o .`). Paths that do not exist are ignored.
  void keep(const std::filesystem::path& input);

  // Renames every staged file into place, in the order staged.
  void commit();

  const std::vector<std::filesystem::path>& paths() const { return finals_; }
  // The staged files and the inputs given to keep().
  std::vector<std::filesystem::path> paths_and_inputs() const {
    std::vector<std::filesystem::path> all = finals_;
    all.insert(all.end(), inputs_.begin(), inputs_.end());
    return all;
  }

 private:
  std::vector<std::filesystem::path> temps_;
  std::vector<std::filesystem::path> finals_;
  std::vector<std::filesystem::path> inputs_;
  std::vector<std::filesystem::path> created_dirs_;
  // The same paths as held by the signal handler's registry (null when it was full).
  std::vector<const char*> held_;
  std::vector<const char*> held_dirs_;
  bool committed_ = false;
};

// The files in `dir` (and its frames/ folder) named as sketchdrape names its outputs (drape*,
// garment*, frame-NNNN-*, pattern.svg/.dxf/.json, report.json, trace.jsonl) that are not among
// `written`: what an earlier command left beside this one's (trial 35: a cantilever's report
// beside a pair of shorts' images and pattern). Paths relative to `dir`, sorted. Never deletes.
std::vector<std::string> stale_outputs(const std::filesystem::path& dir,
                                       const std::vector<std::filesystem::path>& written);

// "<dir> also holds 5 output files that this command did not write: ..." for the terminal, or
// empty when `stale` is.
std::string stale_outputs_notice(const std::filesystem::path& dir,
                                 const std::vector<std::string>& stale);

}  // namespace sd::app
