#include "sim/solver_library_threads.hpp"

#include <dlfcn.h>

#include <atomic>
#include <cstdlib>
#include <mutex>

namespace sd::sim {
namespace {

template <typename Function>
Function* find_function(const char* name) {
  // The libraries are loaded with the program (CHOLMOD links them), so their symbols are global.
  return reinterpret_cast<Function*>(dlsym(RTLD_DEFAULT, name));
}

void record_region_threads(void* data) {
  static auto* const num_threads = find_function<int()>("omp_get_num_threads");
  auto* const largest = static_cast<std::atomic<int>*>(data);
  const int n = num_threads != nullptr ? num_threads() : 1;
  int seen = largest->load();
  while (n > seen && !largest->compare_exchange_weak(seen, n)) {
  }
}

}  // namespace

void limit_solver_library_threads() {
  static std::once_flag blas_once;
  std::call_once(blas_once, [] {
    if (std::getenv("OPENBLAS_NUM_THREADS") != nullptr) return;
    auto* const set = find_function<void(int)>("openblas_set_num_threads");
    if (set == nullptr) return;
    set(1);
    // OpenBLAS started its pool (one thread per further core, each with its stack and buffers:
    // +140 MB of address space on two cores) when it was loaded. One thread never uses it, so
    // it is stopped the way OpenBLAS stops it before a fork; a later request for more threads
    // would start it again.
    if (auto* shutdown = find_function<int()>("blas_thread_shutdown_")) shutdown();
  });
  thread_local bool openmp_limited = false;
  if (openmp_limited) return;
  openmp_limited = true;
  if (std::getenv("OMP_THREAD_LIMIT") != nullptr) return;
  if (auto* set = find_function<void(int)>("omp_set_max_active_levels")) set(0);
}

SolverLibraryThreads solver_library_threads() {
  SolverLibraryThreads threads;
  // GOMP_parallel(fn, data, num_threads, flags): what `#pragma omp parallel num_threads(4)`
  // compiles to with GCC (libgomp's ABI since GCC 4.9).
  if (auto* parallel =
          find_function<void(void (*)(void*), void*, unsigned, unsigned)>("GOMP_parallel")) {
    std::atomic<int> largest{0};
    parallel(record_region_threads, &largest, 4, 0);
    threads.openmp_region = largest.load();
  }
  if (auto* get = find_function<int()>("openblas_get_num_threads")) threads.openblas = get();
  return threads;
}

}  // namespace sd::sim
