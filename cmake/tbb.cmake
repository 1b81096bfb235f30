# oneTBB 2021 (libtbb-dev): the simulator's parallel loops (sim/parallel.hpp). Its own thread
# pool, so the OMP_THREAD_LIMIT=1 that tames CHOLMOD's OpenMP (docs/simulator.md, "Threads")
# does not cap it.
include(require)
find_package(TBB 2021 QUIET CONFIG)
sd_require_target(TBB::tbb libtbb-dev "oneTBB 2021")
