#include "sim/solver_library_threads.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <thread>

#include "sim/cholmod_solver.hpp"
#include "sim/constraint_filter.hpp"

namespace sd::sim {
namespace {

// The limits are per thread for OpenMP, so each case runs on a fresh thread: what CHOLMOD's
// num_threads(4) regions get there is what a solver on that thread would get.
template <typename Body>
SolverLibraryThreads on_fresh_thread(Body body) {
  SolverLibraryThreads seen;
  std::thread worker([&] {
    body();
    seen = solver_library_threads();
  });
  worker.join();
  return seen;
}

// One thread in CHOLMOD's OpenMP regions and in OpenBLAS, unless the user set the limit (the
// test scripts set both to 1, which must give the same).
void expect_single_threaded(const SolverLibraryThreads& seen) {
  // CHOLMOD links libgomp and, on Debian, OpenBLAS: both are loaded in this test program.
  ASSERT_GT(seen.openmp_region, 0) << "no OpenMP runtime loaded";
  if (std::getenv("OMP_THREAD_LIMIT") == nullptr) {
    EXPECT_EQ(seen.openmp_region, 1);
  }
  if (std::getenv("OPENBLAS_NUM_THREADS") == nullptr) {
    EXPECT_LE(seen.openblas, 1);
  }
}

TEST(SolverLibraryThreads, LimitOnAThreadMakesItsOpenMpRegionsAndOpenBlasSingleThreaded) {
  expect_single_threaded(on_fresh_thread([] { limit_solver_library_threads(); }));
}

TEST(SolverLibraryThreads, CholmodFactorisationLimitsTheThreadItRunsOn) {
  const SolverLibraryThreads seen = on_fresh_thread([] {
    // A 2-vertex SPD system (6×6, diagonally dominant, full 3×3 blocks coupling the vertices).
    SparseMatrixR a(6, 6);
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j) a.insert(i, j) = i == j ? 4.0 : 0.1;
    CholmodSolver solver;
    EXPECT_TRUE(solver.factorize(a, ConstraintFilter(2)));
  });
  expect_single_threaded(seen);
}

}  // namespace
}  // namespace sd::sim
