// What a message may print of the user's text (garment/sketch_error.hpp): printable() and
// excerpt(), and a SketchError built from them.

#include "garment/sketch_error.hpp"

#include <gtest/gtest.h>

#include <string>

namespace sd::garment {
namespace {

// Trial 39, P7: a fabric name with BEL and ANSI colour escapes rang the terminal and turned it
// red, and U+202E (right-to-left override) in an id reordered the line; every one is written
// as an escape, and nothing else changes.
TEST(Printable, ControlAndBidiCharactersBecomeEscapes) {
  EXPECT_EQ(printable("lin\x07\x1b[31mRED\x1b[0m"), "lin\\x07\\x1b[31mRED\\x1b[0m");
  EXPECT_EQ(printable("side\xe2\x80\xae"
                      "edis"),
            "side\\u202eedis");  // U+202E
  EXPECT_EQ(printable("a\xe2\x80\x8d"
                      "b"),
            "a\\u200db");  // U+200D, zero-width joiner
  EXPECT_EQ(printable("a\xe2\x81\xa6"
                      "b\xe2\x81\xa9"),
            "a\\u2066b\\u2069");  // an isolate
  EXPECT_EQ(printable("\xef\xbb\xbf"
                      "x"),
            "\\ufeffx");  // a byte-order mark
  EXPECT_EQ(printable("a\xc2\x9b"
                      "b"),
            "a\\u009bb");  // C1 CSI, an escape too
  EXPECT_EQ(printable("del\x7f"), "del\\x7f");
  // Accents, symbols and emoji are text: as written.
  EXPECT_EQ(printable("vorderteil_ä → ✂ 🧵 ±5 °"), "vorderteil_ä → ✂ 🧵 ±5 °");
  // Bytes that are not UTF-8: a lone continuation byte, a cut sequence, an overlong '/', a
  // surrogate.
  EXPECT_EQ(printable("a\x80z"), "a\\x80z");
  EXPECT_EQ(printable("a\xe2\x80"), "a\\xe2\\x80");
  EXPECT_EQ(printable("\xc0\xaf"), "\\xc0\\xaf");
  EXPECT_EQ(printable("\xed\xa0\x80"), "\\xed\\xa0\\x80");
  // Line breaks and tabs only where a message keeps its own.
  EXPECT_EQ(printable("a\nb\tc"), "a\\x0ab\\x09c");
  EXPECT_EQ(printable("a\nb\tc", true), "a\nb\tc");
}

// A long value is cut between characters, never inside one (a cut sequence would print as
// bytes), with its length.
TEST(Printable, ExcerptCutsBetweenCharacters) {
  EXPECT_EQ(excerpt(std::string(100, 'p'), 20), std::string(20, 'p') + "... (100 characters)");
  // 'ä' is two bytes: at 3 bytes the second 'ä' would be cut, so two bytes are shown.
  EXPECT_EQ(excerpt("ääää", 3), "ä... (8 characters)");
  EXPECT_EQ(excerpt("a\xe2\x80\xae"
                    "b",
                    60),
            "a\\u202eb");
}

// The error's whole text, file name included, is printable; its own line breaks stay.
TEST(Printable, SketchErrorsArePrintable) {
  const SketchError e("sk\x1b[2Jetch.json", "/curves/0/id",
                      "id 'a\xe2\x80\xae' is wrong\nsee the docs");
  EXPECT_EQ(std::string(e.what()),
            "sk\\x1b[2Jetch.json: /curves/0/id: id 'a\\u202e' is wrong\nsee the docs");
}

// Trial 40: a Latin-1 'é' (the byte 0xE9, not UTF-8) in an id was echoed raw into the message.
// Bytes that are not UTF-8 are shown as \xNN like control characters; UTF-8 text is kept.
TEST(SketchError, BytesThatAreNotUtf8AreEscaped) {
  const SketchError e("f.json", "/curves/0/id", "id 'caf\xe9' or 'caf\xc3\xa9' \x1b[2J");
  EXPECT_EQ(std::string(e.what()), "f.json: /curves/0/id: id 'caf\\xe9' or 'caf\xc3\xa9' \\x1b[2J");
  // A sequence cut short and a lone continuation byte.
  EXPECT_EQ(std::string(SketchError("f.json", "", "\xc3 \x80").what()), "f.json: \\xc3 \\x80");
}

}  // namespace
}  // namespace sd::garment
