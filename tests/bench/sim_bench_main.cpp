// main() of the simulator's benchmarks: the solvers on one thread, as the program runs them
// (src/solver_threads.hpp), then Google Benchmark.
#include <benchmark/benchmark.h>

#include "src/solver_threads.hpp"

int main(int argc, char** argv) {
  sd::restart_with_single_threaded_solvers(argv);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
