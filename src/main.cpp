#include <unistd.h>

#include <cstdlib>

#include "src/app/cli.hpp"

namespace {

// The simulator runs on one thread; parallelism comes from separate processes (batch -j).
// Two libraries start threads of their own that only slow it down on a small machine:
// OpenBLAS (one thread per core in CHOLMOD's dense kernels) and CHOLMOD 3 itself, whose
// supernodal factorisation runs loops with a hard-coded four OpenMP threads that ignore
// OMP_NUM_THREADS (their wake-ups cost more than the work: the t-shirt drape's solve time fell
// from 3.5 s to 0.72 s with one thread; docs/simulator.md). Both libraries read their limits
// from the environment when they are loaded, before main, so when the user has not chosen
// limits, set them and start this program again. A user's own settings pass through.
void start_again_single_threaded(char** argv) {
  bool changed = false;
  for (const char* name : {"OMP_THREAD_LIMIT", "OPENBLAS_NUM_THREADS"}) {
    if (std::getenv(name) != nullptr) continue;
    setenv(name, "1", 1);
    changed = true;
  }
  if (changed) execv("/proc/self/exe", argv);  // returns only on failure: run as we are
}

}  // namespace

int main(int argc, char** argv) {
  start_again_single_threaded(argv);
  return sd::app::run_cli(argc, argv);
}
