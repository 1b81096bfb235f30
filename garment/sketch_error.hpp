#pragma once
// The one error type for a sketch file a designer got wrong: it names the file, the JSON path of
// the offending value ("/panels/2/boundary/3") and says what is wrong in a plain sentence.

#include <stdexcept>
#include <string>
#include <string_view>

namespace sd::garment {

// The user's text (an id, a fabric name, a path) as a message may print it: nothing in it acts
// on the terminal or hides what is there. Written as escapes: C0 control characters (a NUL cut
// the message short where the terminal printed it, ESC starts a colour or cursor sequence, BEL
// beeps) and DEL as \xNN, except a line break and a tab when `keep_line_breaks`; C1 controls
// (U+0080-U+009F) and the invisible format characters that reorder or hide text (the bidi
// embeddings, overrides and isolates U+202A-U+202E and U+2066-U+2069, whose right-to-left
// override turned an id round; the marks U+061C, U+200E, U+200F; the zero-width U+200B-U+200D,
// U+2060-U+2064 and U+FEFF) as \uXXXX; bytes that are not UTF-8 as \xNN. The rest, accents
// and symbols included, as written.
inline std::string printable(std::string_view text, bool keep_line_breaks = false) {
  std::string out;
  out.reserve(text.size());
  // "\\x" and 2 hex digits, or "\\u" and 4.
  const auto hex = [&out](char kind, unsigned value) {
    static constexpr char kDigits[] = "0123456789abcdef";
    out += '\\';
    out += kind;
    for (int shift = kind == 'x' ? 4 : 12; shift >= 0; shift -= 4)
      out += kDigits[(value >> shift) & 0xfu];
  };
  for (size_t i = 0; i < text.size();) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c < 0x80) {
      if ((c < 0x20 && !(keep_line_breaks && (c == '\n' || c == '\t'))) || c == 0x7f)
        hex('x', c);
      else
        out += static_cast<char>(c);
      ++i;
      continue;
    }
    // A UTF-8 sequence: its length from the lead byte, then continuation bytes 10xxxxxx; an
    // overlong form or a surrogate is not UTF-8 either.
    size_t length = 0;
    if (c >= 0xc2 && c <= 0xdf) length = 2;
    if (c >= 0xe0 && c <= 0xef) length = 3;
    if (c >= 0xf0 && c <= 0xf4) length = 4;
    unsigned code = length == 4 ? c & 0x07u : length == 3 ? c & 0x0fu : c & 0x1fu;
    bool valid = length > 0 && i + length <= text.size();
    for (size_t k = 1; valid && k < length; ++k) {
      const auto next = static_cast<unsigned char>(text[i + k]);
      valid = (next & 0xc0) == 0x80;
      code = (code << 6) | (next & 0x3fu);
    }
    valid = valid && !(length == 3 && (code < 0x800 || (code >= 0xd800 && code <= 0xdfff))) &&
            !(length == 4 && (code < 0x10000 || code > 0x10ffff));
    if (!valid) {
      hex('x', c);
      ++i;
      continue;
    }
    const bool hidden = (code >= 0x80 && code <= 0x9f) || code == 0x61c ||
                        (code >= 0x200b && code <= 0x200f) || (code >= 0x202a && code <= 0x202e) ||
                        (code >= 0x2060 && code <= 0x2064) || (code >= 0x2066 && code <= 0x2069) ||
                        code == 0xfeff;
    if (hidden)
      hex('u', code);
    else
      out.append(text.substr(i, length));
    i += length;
  }
  return out;
}

// A piece of the user's file as a message quotes it: printable(), and at most `max_chars` bytes
// of a longer text (a 10 MB string where a number goes was echoed whole), cut between
// characters, with the length it had.
inline std::string excerpt(std::string_view text, size_t max_chars = 60) {
  size_t shown = text.size() > max_chars ? max_chars : text.size();
  // Not inside a UTF-8 sequence: back to its lead byte.
  while (shown < text.size() && shown > 0 &&
         (static_cast<unsigned char>(text[shown]) & 0xc0) == 0x80)
    --shown;
  std::string out = printable(text.substr(0, shown));
  if (shown < text.size()) out += "... (" + std::to_string(text.size()) + " characters)";
  return out;
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
    // Nothing of the user's text acts on the terminal (an id with a NUL byte cut the message
    // short); a sentence's own line breaks stay.
    std::string text = file + ": ";
    if (!path.empty()) text += path + ": ";
    text += sentence;
    return printable(text, true);
  }

  std::string file_;
  std::string json_path_;
  std::string sentence_;
};

}  // namespace sd::garment
