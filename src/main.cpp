#include <cstdio>

#include "sim/solver_library_threads.hpp"
#include "src/app/batch/batch_runner.hpp"
#include "src/app/commands/cli.hpp"
#include "src/app/pipeline/atomic_file.hpp"

int main(int argc, char** argv) {
  // A batch's child dies with its batch (a SIGKILLed batch must not leave jobs that write into
  // its folder later); a child whose batch is already gone does not start.
  if (!sd::app::follow_batch_parent()) {
    std::fputs("error: the batch that started this job has ended; not starting\n", stderr);
    return sd::app::kExitFailure;
  }
  // CHOLMOD's OpenMP loops and OpenBLAS on one thread unless the user chose (the program starts
  // once: the limits are set at run time, sim/solver_library_threads.hpp).
  sd::sim::limit_solver_library_threads();
  sd::app::install_interrupt_cleanup();
  return sd::app::run_cli(argc, argv);
}
