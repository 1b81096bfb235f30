#pragma once
// Runs this binary (or another program) as a child process and measures it: exit status, wall
// time, CPU time and peak memory from the kernel (wait4), with a time limit. What the bench
// studies use so that each run's figures are its own.

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace sd::app {

struct ChildRun {
  bool exited = false;     // ended by exit() (not a signal, not the time limit)
  int exit_code = -1;      // when exited
  int signal = 0;          // when killed by a signal
  bool timed_out = false;  // killed because it passed the limit
  double elapsed_s = 0.0;  // wall
  double cpu_s = 0.0;      // user + system, the child alone
  double peak_rss_mb = 0.0;
};

// Starts `program` with `args` (argv[1..]), stdout and stderr to `log`; adds
// `OPENBLAS_NUM_THREADS=1` and `OMP_NUM_THREADS=1` to the environment unless set. Waits, calling
// `tick(elapsed_s)` about every 20 ms, and kills the child after `timeout_s`. Throws
// std::runtime_error when the child cannot be started.
ChildRun run_child(const std::filesystem::path& program, const std::vector<std::string>& args,
                   const std::filesystem::path& log, double timeout_s,
                   const std::function<void(double)>& tick = {});

}  // namespace sd::app
