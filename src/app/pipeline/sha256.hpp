#pragma once
// SHA-256 for the batch layer's done markers and the bench's reference keys: a job is redone
// exactly when the digest of its inputs changes. The digest itself is OpenSSL's (libcrypto).

#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

namespace sd::app {

// Incremental SHA-256: feed bytes with update(), read the digest once with hex_digest().
class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;
  void update(std::string_view bytes);
  // 64 lowercase hex characters (the same on later calls). Updating afterwards throws.
  std::string hex_digest();

 private:
  struct Context;
  std::unique_ptr<Context> context_;
  bool finished_ = false;
  std::string digest_;  // once finished
};

// Digest of `bytes` as 64 lowercase hex characters.
std::string sha256_hex(std::string_view bytes);

// Digest of a file's contents, read in blocks. Throws std::runtime_error when it cannot be read.
std::string sha256_file(const std::filesystem::path& path);

}  // namespace sd::app
