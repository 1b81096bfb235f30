#pragma once

// A callback for nlohmann::json::parse that refuses what JSON allows but a settings file must not
// hold: a key given twice in one object (the parser keeps the last value and drops the first
// without a word) and lists and objects nested deeper than any such file needs (a damaged or
// hostile file, costly to build and to free). It follows the parser's events to know the JSON
// Pointer of the element being read, so the refusal names its place. Shared by the sketch reader
// and the fabric reader (trial 39, P1: a fabric file's repeated key was read silently).

#include <cstddef>
#include <functional>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace sd::sim {

class StrictJsonCallback {
 public:
  // Called with the JSON Pointer of the place and a sentence for the designer; must throw.
  using Fail = std::function<void(const std::string& path, const std::string& sentence)>;

  static constexpr int kMaxNesting = 64;

  // `file_kind` ("a sketch file") and `levels_needed` finish the nesting sentence.
  StrictJsonCallback(Fail fail, std::string file_kind, int levels_needed)
      : fail_(std::move(fail)), file_kind_(std::move(file_kind)), levels_needed_(levels_needed) {}

  bool operator()(int depth, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
    using Event = nlohmann::json::parse_event_t;
    // The path is that of the element that goes too deep (its container entered first, so that
    // it reads /0 where nothing was counted yet, not /-1), shortened to its first levels: 64
    // levels of "/0" say nothing more (trial 35).
    if (depth > kMaxNesting) {
      if (event == Event::object_start || event == Event::array_start) enter_element();
      fail_(path(kShownLevels) + "/…",
            "lists and objects are nested more than " + std::to_string(kMaxNesting) +
                " levels deep here (the path shows the first " + std::to_string(kShownLevels) +
                "); " + file_kind_ + " needs fewer than " + std::to_string(levels_needed_));
    }
    switch (event) {
      case Event::object_start:
      case Event::array_start:
        enter_element();
        frames_.push_back({event == Event::array_start, -1, {}, {}});
        break;
      case Event::key: {
        Frame& f = frames_.back();
        f.key = parsed.get<std::string>();
        if (!f.keys.insert(f.key).second)
          fail_(path(), "the key '" + f.key +
                            "' is given twice in this object; JSON would keep only the last one: "
                            "remove one of them");
        break;
      }
      case Event::object_end:
      case Event::array_end:
        frames_.pop_back();
        break;
      case Event::value:
        enter_element();
        break;
    }
    return true;
  }

 private:
  struct Frame {
    bool array = false;
    long index = -1;
    std::set<std::string> keys;
    std::string key;
  };

  static constexpr std::size_t kShownLevels = 6;

  // A value or container begins: in an array it is the next element.
  void enter_element() {
    if (!frames_.empty() && frames_.back().array) ++frames_.back().index;
  }

  // "/a/0/b": keys with JSON Pointer escapes (~0 for ~, ~1 for /); the first `levels` only.
  std::string path(std::size_t levels = std::string::npos) const {
    std::string out;
    for (const Frame& f : frames_) {
      if (levels-- == 0) break;
      out += "/";
      if (f.array) {
        out += std::to_string(f.index);
        continue;
      }
      for (char c : f.key) out += c == '~' ? "~0" : c == '/' ? "~1" : std::string(1, c);
    }
    return out;
  }

  Fail fail_;
  std::string file_kind_;
  int levels_needed_;
  std::vector<Frame> frames_;
};

}  // namespace sd::sim
