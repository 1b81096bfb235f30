#pragma once
// The simulator runs its linear solves on the calling thread; parallelism comes from our own
// loops (sim/parallel.hpp) and from separate processes (batch -j). Two libraries under CHOLMOD
// start threads of their own that only slow a solve down on a small machine: OpenBLAS (one per
// core in CHOLMOD's dense supernodal kernels) and CHOLMOD 3.0.14 itself (Debian's SuiteSparse
// 5), whose supernodal factorisation opens OpenMP regions with a hard-coded num_threads(4) that
// OMP_NUM_THREADS does not reach (the t-shirt drape's solve: 3.5 s with them, 0.72 s on one
// thread; docs/simulator.md, "Threads"). Both can be limited at run time, without the
// environment variables they read when they are loaded:
//  * OpenBLAS: openblas_set_num_threads(1), process-wide, and its pool (started at load, one
//    thread per further core) stopped again;
//  * OpenMP: omp_set_max_active_levels(0) makes every parallel region the calling thread opens
//    inactive (one thread), whatever its num_threads clause asks for. libgomp keeps that setting
//    per thread, so it is made on each thread that factorises (CholmodSolver::factorize).
// Both are looked up by name in the loaded libraries, so a BLAS other than OpenBLAS, or a
// CHOLMOD built without OpenMP, is simply left as it is. A user's own OMP_THREAD_LIMIT or
// OPENBLAS_NUM_THREADS passes through untouched.

namespace sd::sim {

// Limits OpenBLAS to one thread (once per process) and OpenMP regions opened on the calling
// thread to one thread, each unless the user set its environment variable. Cheap after the
// first call on a thread: call before every factorisation.
void limit_solver_library_threads();

struct SolverLibraryThreads {
  // Threads an OpenMP region opened on the calling thread with num_threads(4), as CHOLMOD's
  // supernodal loops open it, actually gets (0: no OpenMP runtime loaded).
  int openmp_region = 0;
  int openblas = 0;  // openblas_get_num_threads() (0: the BLAS is not OpenBLAS)
};

// Measures the above by opening such a region (through libgomp's GOMP_parallel, the call the
// compiler emits for the pragma) and asking OpenBLAS.
SolverLibraryThreads solver_library_threads();

}  // namespace sd::sim
