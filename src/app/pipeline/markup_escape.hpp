#pragma once
// Text for HTML and XML (SVG) documents: the five characters with a meaning in markup replaced
// by their entities, so a panel id or a job name cannot break the page it is written into.

#include <string>
#include <string_view>

namespace sd::app {

inline std::string markup_escape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

}  // namespace sd::app
