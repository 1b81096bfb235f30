#include <cstdio>

#include "src/app/batch/batch_runner.hpp"
#include "src/app/commands/cli.hpp"
#include "src/solver_threads.hpp"

int main(int argc, char** argv) {
  // A batch's child dies with its batch (a SIGKILLed batch must not leave jobs that write into
  // its folder later); a child whose batch is already gone does not start.
  if (!sd::app::follow_batch_parent()) {
    std::fputs("error: the batch that started this job has ended; not starting\n", stderr);
    return sd::app::kExitFailure;
  }
  sd::restart_with_single_threaded_solvers(argv);
  return sd::app::run_cli(argc, argv);
}
