#pragma once
// The panels of a garment filled side by side: each original panel's fill (panel_fill.hpp) reads
// only the sketch, its own sides and the body, and keeps its caches to itself, so the fills of
// different panels can run on different threads and give the same bits as one after the other.
//
// Threads: oneTBB's own pool in an arena of at most panel_threads() threads (the simulator's
// loops have their own count in sim/parallel.hpp, which garment/ may not include; the command
// line sets both from `--threads`).

#include <functional>

namespace sd::garment {

// Threads build_garment fills panels on (≥ 1). Default: the machine's cores.
int panel_threads();
// Sets it for the whole process; n < 1 means the machine's cores.
void set_panel_threads(int n);

// Calls task(i) once for every i in [0, n), on up to panel_threads() threads (in order on the
// calling thread when that is 1). Every task runs even when one throws; then the exception of the
// lowest index is rethrown, the one a loop in order would have met first.
void run_panel_tasks(int n, const std::function<void(int)>& task);

}  // namespace sd::garment
