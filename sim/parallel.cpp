#include "sim/parallel.hpp"

#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <memory>
#include <mutex>

namespace sd::sim {
namespace {

std::atomic<int> requested_threads{0};  // 0: every core

int machine_cores() {
  return std::max(1, tbb::info::default_concurrency());
}

}  // namespace

int thread_count() {
  const int n = requested_threads.load();
  return n > 0 ? n : machine_cores();
}

void set_thread_count(int n) {
  requested_threads.store(n > 0 ? n : 0);
}

void parallel_chunks(int n, int grain, const std::function<void(int, int, int)>& chunk) {
  const int chunks = chunk_count(n, grain);
  if (chunks == 0) return;
  const auto run = [&](int c) {
    // Chunk c covers [c·n/chunks, (c+1)·n/chunks): a function of n and grain only.
    const long long lo = static_cast<long long>(c) * n / chunks;
    const long long hi = static_cast<long long>(c + 1) * n / chunks;
    chunk(c, static_cast<int>(lo), static_cast<int>(hi));
  };
  const int threads = std::min(thread_count(), chunks);
  if (threads <= 1) {
    for (int c = 0; c < chunks; ++c) run(c);
    return;
  }
  // One arena per thread count, made once: an arena caps the concurrency of what runs in it.
  static std::mutex arenas_mutex;
  static std::unique_ptr<tbb::task_arena> arenas[65];
  tbb::task_arena* arena = nullptr;
  {
    const std::lock_guard<std::mutex> lock(arenas_mutex);
    auto& slot = arenas[std::min(threads, 64)];
    if (!slot) slot = std::make_unique<tbb::task_arena>(std::min(threads, 64));
    arena = slot.get();
  }
  arena->execute([&] { tbb::parallel_for(0, chunks, 1, [&](int c) { run(c); }); });
}

}  // namespace sd::sim
