#include "src/app/pipeline/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace sd::app {

Progress::Progress(std::string label, long total, bool quiet)
    : label_(std::move(label)), total_(std::max(total, 1L)), visible_(!quiet && ::isatty(2)) {}

Progress::~Progress() {
  finish();
}

void Progress::update(long done, const std::string& note) {
  if (!visible_ || finished_) return;
  const auto now = std::chrono::steady_clock::now();
  if (done < total_ && now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  constexpr int kWidth = 30;
  const double fraction = std::clamp(static_cast<double>(done) / total_, 0.0, 1.0);
  const int filled = static_cast<int>(fraction * kWidth);
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  std::fprintf(stderr, "\r%s [%s%s] %3d%% %5.1fs %s\033[K", label_.c_str(),
               std::string(filled, '#').c_str(), std::string(kWidth - filled, ' ').c_str(),
               static_cast<int>(fraction * 100), elapsed, note.c_str());
  std::fflush(stderr);
}

void Progress::finish() {
  if (!visible_ || finished_) return;
  finished_ = true;
  std::fprintf(stderr, "\r\033[K");
  std::fflush(stderr);
}

}  // namespace sd::app
