// The environment batch children get: OPENBLAS_NUM_THREADS=1 unless the user chose a value
// (one OpenBLAS thread per core in each of -j N children oversubscribes the machine), and
// everything else passed through. The child here is a shell script standing in for the binary.

#include "src/app/batch/batch_runner.hpp"

#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/stat.h>

#include <optional>
#include <string>

#include "tests/batch/batch_test_util.hpp"

namespace sd::test {
namespace {

namespace fs = std::filesystem;

// Sets (or, with nullopt, removes) an environment variable for the life of the object.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, std::optional<std::string> value) : name_(name) {
    if (const char* old = ::getenv(name)) old_ = old;
    if (value)
      ::setenv(name, value->c_str(), 1);
    else
      ::unsetenv(name);
  }
  ~ScopedEnv() {
    if (old_)
      ::setenv(name_, old_->c_str(), 1);
    else
      ::unsetenv(name_);
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  const char* name_;
  std::optional<std::string> old_;
};

// Runs a one-job batch whose child script records two variables; returns what it saw.
std::string child_sees(const fs::path& dir) {
  const fs::path script = dir / "child.sh";
  // Arguments: STAGE SKETCH -o JOB_DIR.
  write_text(script,
             "#!/bin/sh\n"
             "printf '%s %s' \"${OPENBLAS_NUM_THREADS-unset}\" \"${SD_BATCH_PROBE-unset}\" "
             "> \"$4/env.txt\"\n");
  ::chmod(script.c_str(), 0755);
  app::BatchOptions options;
  options.inputs = {(fs::path(SD_SOURCE_DIR) / "data" / "examples" / "tshirt.json").string()};
  options.out = dir / "out";
  options.stage = "mesh";
  options.quiet = true;
  options.executable = script;
  const app::BatchResult result = app::run_batch(options);
  EXPECT_TRUE(result.all_done());
  EXPECT_EQ(result.ran, 1);
  return read_text(dir / "out" / "jobs" / "tshirt" / "env.txt");
}

TEST(BatchChildren, GetOneOpenBlasThreadUnlessTheUserChoseOtherwise) {
  const ScopedEnv probe("SD_BATCH_PROBE", "passed");
  {
    const ScopedEnv unset("OPENBLAS_NUM_THREADS", std::nullopt);
    EXPECT_EQ(child_sees(fresh_batch_dir("openblas_default")), "1 passed");
    EXPECT_EQ(::getenv("OPENBLAS_NUM_THREADS"), nullptr)
        << "the batch's own environment is unchanged";
  }
  {
    const ScopedEnv chosen("OPENBLAS_NUM_THREADS", "3");
    EXPECT_EQ(child_sees(fresh_batch_dir("openblas_chosen")), "3 passed");
  }
}

}  // namespace
}  // namespace sd::test
