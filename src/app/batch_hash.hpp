#pragma once
// SHA-256 (FIPS 180-4) for the batch layer's done markers: a job is redone exactly when the
// digest of its inputs changes. Written here to avoid a crypto dependency for one function.

#include <filesystem>
#include <string>
#include <string_view>

namespace sd::app {

// Incremental SHA-256: feed bytes with update(), read the digest once with hex_digest().
class Sha256 {
 public:
  Sha256();
  void update(std::string_view bytes);
  // 64 lowercase hex characters. The object must not be updated afterwards.
  std::string hex_digest();

 private:
  void compress(const unsigned char* block);

  unsigned int state_[8];
  unsigned char buffer_[64];
  unsigned long long length_ = 0;  // bytes fed so far
  size_t buffered_ = 0;
  bool finished_ = false;
};

// Digest of `bytes` as 64 lowercase hex characters.
std::string sha256_hex(std::string_view bytes);

// Digest of a file's contents, read in blocks. Throws std::runtime_error when it cannot be read.
std::string sha256_file(const std::filesystem::path& path);

}  // namespace sd::app
