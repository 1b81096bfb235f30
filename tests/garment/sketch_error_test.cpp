#include "garment/sketch_error.hpp"

#include <gtest/gtest.h>

#include <string>

namespace sd::garment {
namespace {

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
