#include "scene/sketch_reader.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>

namespace sd::scene::detail {

std::string type_name(const json& value) {
  if (value.is_string())
    return fmt::format("the text \"{}\"", garment::excerpt(value.get<std::string>()));
  if (value.is_boolean()) return value.get<bool>() ? "true" : "false";
  if (value.is_number()) return fmt::format("the number {}", value.dump());
  if (value.is_null()) return "null";
  if (value.is_array()) return "a list";
  return "an object";
}

std::string mark_overflowing_numbers(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  size_t i = 0;
  while (i < text.size()) {
    const char c = text[i];
    if (c == '"') {  // copy a string literal with its escapes
      size_t j = i + 1;
      while (j < text.size() && text[j] != '"') j += text[j] == '\\' ? 2 : 1;
      j = std::min(j + 1, text.size());
      out.append(text.substr(i, j - i));
      i = j;
    } else if (c == '/' && i + 1 < text.size() && (text[i + 1] == '/' || text[i + 1] == '*')) {
      const bool line = text[i + 1] == '/';
      size_t j = line ? text.find('\n', i) : text.find("*/", i + 2);
      j = j == std::string_view::npos ? text.size() : j + (line ? 0 : 2);
      out.append(text.substr(i, j - i));
      i = j;
    } else if (c == '-' || (c >= '0' && c <= '9')) {
      size_t j = i + 1;
      while (j < text.size() &&
             (std::isdigit(static_cast<unsigned char>(text[j])) || text[j] == '.' ||
              text[j] == 'e' || text[j] == 'E' || text[j] == '+' || text[j] == '-'))
        ++j;
      const std::string token(text.substr(i, j - i));
      const double value = std::strtod(token.c_str(), nullptr);
      if (std::isinf(value))
        out +=
            fmt::format("\"\\u0001sketchdrape-overflow:{}\"", token);  // JSON escape of the marker
      else
        out += token;
      i = j;
    } else {
      out += c;
      ++i;
    }
  }
  return out;
}

std::string position_of(std::string_view text, size_t byte) {
  byte = std::min(byte, text.size());
  size_t line = 1, column = 1;
  for (size_t i = 0; i + 1 < byte; ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return fmt::format("line {}, column {}", line, column);
}

}  // namespace sd::scene::detail
