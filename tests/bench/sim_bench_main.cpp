// main() of the simulator's benchmarks: the solvers on one thread, as the program runs them
// (sim/solver_library_threads.hpp), then Google Benchmark.
#include <benchmark/benchmark.h>

#include "sim/solver_library_threads.hpp"

int main(int argc, char** argv) {
  sd::sim::limit_solver_library_threads();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
