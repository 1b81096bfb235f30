#include "garment/panel_tasks.hpp"

#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <exception>
#include <vector>

namespace sd::garment {
namespace {

std::atomic<int> requested_threads{0};  // 0: every core

}  // namespace

int panel_threads() {
  const int n = requested_threads.load();
  return n > 0 ? n : std::max(1, tbb::info::default_concurrency());
}

void set_panel_threads(int n) {
  requested_threads.store(n > 0 ? n : 0);
}

void run_panel_tasks(int n, const std::function<void(int)>& task) {
  if (n <= 0) return;
  std::vector<std::exception_ptr> failures(static_cast<size_t>(n));
  const auto run = [&](int i) {
    try {
      task(i);
    } catch (...) {
      failures[static_cast<size_t>(i)] = std::current_exception();
    }
  };
  const int threads = std::min(panel_threads(), n);
  if (threads <= 1) {
    for (int i = 0; i < n; ++i) run(i);
  } else {
    // A panel's fill takes 1-40 ms, and its size says little about it (a raglan's sleeves have
    // fewer quads than its front but fold and take five times as long): each thread takes the
    // next panel in order as it comes free (a queue, not a split of the range in halves, which
    // would leave two slow panels in one half to one thread).
    std::atomic<int> next{0};
    tbb::task_arena arena(threads);
    arena.execute([&] {
      tbb::parallel_for(0, threads, 1, [&](int) {
        for (int i = next++; i < n; i = next++) run(i);
      });
    });
  }
  for (const std::exception_ptr& failure : failures)
    if (failure) std::rethrow_exception(failure);
}

}  // namespace sd::garment
