#include "src/solver_threads.hpp"
#include "src/app/cli.hpp"

int main(int argc, char** argv) {
  sd::restart_with_single_threaded_solvers(argv);
  return sd::app::run_cli(argc, argv);
}
