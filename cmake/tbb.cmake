# oneTBB 2021 (libtbb-dev): the simulator's parallel loops (sim/parallel.hpp). Its own thread
# pool, so the one-thread limit that tames CHOLMOD's OpenMP (sim/solver_library_threads.hpp,
# docs/simulator.md, "Threads") does not cap it.
include(require)
find_package(TBB 2021 QUIET CONFIG)
sd_require_target(TBB::tbb libtbb-dev "oneTBB 2021")
