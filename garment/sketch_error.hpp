#pragma once
// The one error type for a sketch file a designer got wrong: it names the file, the JSON path of
// the offending value ("/panels/2/boundary/3") and says what is wrong in a plain sentence.

#include <cstdio>
#include <stdexcept>
#include <string>
#include <string_view>

namespace sd::garment {

// A piece of the user's file as a message quotes it: control characters (a NUL would end the
// message where the terminal prints it, an escape sequence would act on the terminal) as \xNN,
// and at most `max_chars` bytes of a longer text (a 10 MB string where a number goes was echoed
// whole), with the length it had.
inline std::string excerpt(std::string_view text, size_t max_chars = 60) {
  std::string out;
  const size_t shown = text.size() > max_chars ? max_chars : text.size();
  for (size_t i = 0; i < shown; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c < 0x20 || c == 0x7f) {
      char hex[5];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      out += hex;
    } else {
      out += static_cast<char>(c);
    }
  }
  if (shown < text.size()) out += "... (" + std::to_string(text.size()) + " characters)";
  return out;
}

// The length of the well-formed UTF-8 sequence of several bytes starting at text[i], 0 when
// there is none there (an ASCII byte, or a byte of another encoding such as Latin-1's 0xE9).
inline size_t utf8_sequence_length(std::string_view text, size_t i) {
  const auto lead = static_cast<unsigned char>(text[i]);
  const size_t length = lead >= 0xc2 && lead <= 0xdf   ? 2
                        : lead >= 0xe0 && lead <= 0xef ? 3
                        : lead >= 0xf0 && lead <= 0xf4 ? 4
                                                       : 0;
  if (length == 0 || i + length > text.size()) return 0;
  for (size_t k = 1; k < length; ++k)
    if ((static_cast<unsigned char>(text[i + k]) & 0xc0) != 0x80) return 0;
  return length;
}

class SketchError : public std::invalid_argument {
 public:
  // `json_path` may be empty (a syntax error has a line and column instead, put in the sentence).
  SketchError(std::string file, std::string json_path, std::string sentence)
      : std::invalid_argument(compose(file, json_path, sentence)),
        file_(std::move(file)),
        json_path_(std::move(json_path)),
        sentence_(std::move(sentence)) {}

  const std::string& file() const { return file_; }
  const std::string& json_path() const { return json_path_; }
  const std::string& sentence() const { return sentence_; }

 private:
  static std::string compose(const std::string& file, const std::string& path,
                             const std::string& sentence) {
    // No control character reaches the terminal (an id with a NUL byte cut the message short).
    std::string text = file + ": ";
    if (!path.empty()) text += path + ": ";
    text += sentence;
    // Nor a byte that is not UTF-8 (trial 40: a Latin-1 'é' was echoed raw).
    std::string out;
    for (size_t i = 0; i < text.size(); ++i) {
      const char c = text[i];
      const auto u = static_cast<unsigned char>(c);
      const size_t sequence = utf8_sequence_length(text, i);
      if (sequence > 1) {
        out.append(text, i, sequence);
        i += sequence - 1;
      } else if ((u < 0x20 && c != '\n' && c != '\t') || u >= 0x7f) {
        char hex[5];
        std::snprintf(hex, sizeof hex, "\\x%02x", u);
        out += hex;
      } else {
        out += c;
      }
    }
    return out;
  }

  std::string file_;
  std::string json_path_;
  std::string sentence_;
};

}  // namespace sd::garment
