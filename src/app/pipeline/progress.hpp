#pragma once
// A progress bar on stderr for long work. It draws only when stderr is a terminal and the user
// did not ask for --quiet, so logs and CI output stay clean.

#include <chrono>
#include <string>

namespace sd::app {

class Progress {
 public:
  // `total` units of work, described by `label` ("rendering views").
  Progress(std::string label, long total, bool quiet);
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  ~Progress();

  // Sets the completed amount (0..total) with an optional short note ("front").
  void update(long done, const std::string& note = {});
  // Clears the bar; safe to call twice.
  void finish();

  bool visible() const { return visible_; }

 private:
  std::string label_;
  long total_;
  bool visible_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point last_draw_{};
};

}  // namespace sd::app
