#include "src/app/pipeline/sha256.hpp"

#include <gtest/gtest.h>

#include <string>

#include "tests/batch/batch_test_util.hpp"

namespace sd::app {
namespace {

// Test vectors from FIPS 180-4 / NIST CSRC examples.
TEST(Sha256, KnownVectors) {
  EXPECT_EQ(sha256_hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(sha256_hex(std::string(1000000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

// Padding crosses a block boundary at 56 bytes: lengths around it must all agree with the
// one-shot digest however the input is split.
TEST(Sha256, IncrementalEqualsOneShotForEverySplit) {
  std::string text;
  for (int i = 0; i < 130; ++i) text += static_cast<char>('a' + i % 26);
  for (size_t length : {0, 1, 55, 56, 57, 63, 64, 65, 119, 120, 128, 130}) {
    const std::string part = text.substr(0, length);
    const std::string expected = sha256_hex(part);
    for (size_t split = 0; split <= length; split += 7) {
      Sha256 h;
      h.update(std::string_view(part).substr(0, split));
      h.update(std::string_view(part).substr(split));
      EXPECT_EQ(h.hex_digest(), expected) << "length " << length << " split " << split;
    }
  }
}

TEST(Sha256, DigestIsFinalAndRepeatable) {
  Sha256 h;
  h.update("abc");
  const std::string first = h.hex_digest();
  EXPECT_EQ(h.hex_digest(), first);
  EXPECT_THROW(h.update("more"), std::logic_error);
}

TEST(Sha256, FileDigestMatchesContentsAndMissingFileThrows) {
  const auto dir = test::fresh_batch_dir("sha_file");
  std::string big(200000, 'x');  // several read blocks
  big[123456] = 'y';
  test::write_text(dir / "f.bin", big);
  EXPECT_EQ(sha256_file(dir / "f.bin"), sha256_hex(big));
  EXPECT_THROW(sha256_file(dir / "missing.bin"), std::runtime_error);
}

}  // namespace
}  // namespace sd::app
