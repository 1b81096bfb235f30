#include "sim/solver_threads.hpp"

#include <unistd.h>

#include <cstdlib>
#include <initializer_list>

namespace sd::sim {

void restart_with_single_threaded_solvers(char** argv) {
  bool changed = false;
  for (const char* name : {"OMP_THREAD_LIMIT", "OPENBLAS_NUM_THREADS"}) {
    if (std::getenv(name) != nullptr) continue;
    setenv(name, "1", 1);
    changed = true;
  }
  if (changed) execv("/proc/self/exe", argv);  // returns only on failure: run as we are
}

}  // namespace sd::sim
