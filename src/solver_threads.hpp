#pragma once
// The simulator runs on one thread; parallelism comes from separate processes (batch -j). Two
// libraries under the linear solve start threads of their own that only slow it down on a small
// machine: OpenBLAS (one thread per core in CHOLMOD's dense kernels) and CHOLMOD 3 itself, whose
// supernodal factorisation runs loops with a hard-coded four OpenMP threads that ignore
// OMP_NUM_THREADS (their wake-ups cost more than the work: the t-shirt drape's solve time fell
// from 3.5 s to 0.72 s with one thread, and a fixed level-6 sheet from 5.1 s to 1.3 s of CPU;
// docs/simulator.md). Both read their limits from the environment when they are loaded, before
// main, so a program has to set them and start again. Starting a process again is the
// program's business, not a library's: this is called by the programs' main() (sketchdrape and
// the simulator's benchmarks), never by sd_sim.

#include <unistd.h>

#include <cstdlib>
#include <initializer_list>

namespace sd {

// When the environment does not set OMP_THREAD_LIMIT and OPENBLAS_NUM_THREADS, sets them to 1
// and starts this program again with the same arguments (call first thing in main). A user's
// own settings pass through. Returns only when nothing had to change (or the restart failed:
// then the program runs as it is).
inline void restart_with_single_threaded_solvers(char** argv) {
  bool changed = false;
  for (const char* name : {"OMP_THREAD_LIMIT", "OPENBLAS_NUM_THREADS"}) {
    if (std::getenv(name) != nullptr) continue;
    setenv(name, "1", 1);
    changed = true;
  }
  if (changed) execv("/proc/self/exe", argv);  // returns only on failure: run as we are
}

}  // namespace sd
