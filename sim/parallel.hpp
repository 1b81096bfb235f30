#pragma once
// The simulator's parallel loops: a loop over [0, n) cut into a fixed number of chunks that
// oneTBB runs on up to thread_count() threads. The chunks depend on n alone, never on the
// thread count or on scheduling, and callers combine per-chunk results in chunk order, so a
// run gives the same bits on one thread as on many (tests/sim/parallel_test.cpp).
//
// Threads: oneTBB keeps its own pool, which OMP_THREAD_LIMIT (set to 1 to keep CHOLMOD's
// OpenMP and OpenBLAS single-threaded, docs/simulator.md "Threads") does not reach. The
// default is every core; `sketchdrape --threads N` and batch jobs (one core each) set it.

#include <algorithm>
#include <functional>

namespace sd::sim {

// Threads the parallel loops may use (≥ 1). Default: the machine's cores.
int thread_count();
// Sets it for the whole process; n < 1 means the machine's cores.
void set_thread_count(int n);

// Calls chunk(index, begin, end) for consecutive chunks covering [0, n), each at least `grain`
// items long (the last may be shorter), in parallel. chunk_count(n, grain) chunks in all.
void parallel_chunks(int n, int grain, const std::function<void(int, int, int)>& chunk);

// How many chunks parallel_chunks makes: enough to balance two to eight threads, none shorter
// than `grain`.
inline int chunk_count(int n, int grain) {
  constexpr int kMaxChunks = 32;
  if (n <= 0) return 0;
  return std::clamp(n / std::max(grain, 1), 1, kMaxChunks);
}

}  // namespace sd::sim
