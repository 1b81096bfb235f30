#include "src/app/atomic_file.hpp"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <system_error>

namespace sd::app {
namespace {

std::filesystem::path temporary_name(const std::filesystem::path& path) {
  static std::atomic<unsigned> counter{0};
  return path.parent_path() / ("." + path.filename().string() + ".tmp-" +
                               std::to_string(::getpid()) + "-" + std::to_string(counter++));
}

void write_all(const std::filesystem::path& path, std::string_view bytes) {
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr)
    throw std::runtime_error("cannot write '" + path.string() + "': " + std::strerror(errno));
  const size_t written = std::fwrite(bytes.data(), 1, bytes.size(), file);
  const int flushed = std::fflush(file);
  const int error = errno;
  const int closed = std::fclose(file);
  if (written != bytes.size() || flushed != 0 || closed != 0) {
    std::remove(path.c_str());
    throw std::runtime_error("cannot write '" + path.string() + "': " + std::strerror(error));
  }
}

}  // namespace

void write_file_atomically(const std::filesystem::path& path, std::string_view bytes) {
  const std::filesystem::path temp = temporary_name(path);
  write_all(temp, bytes);
  std::error_code ec;
  std::filesystem::rename(temp, path, ec);
  if (ec) {
    std::filesystem::remove(temp);
    throw std::runtime_error("cannot write '" + path.string() + "': " + ec.message());
  }
}

StagedOutputs::~StagedOutputs() {
  if (committed_) return;
  std::error_code ignored;
  for (const auto& temp : temps_) std::filesystem::remove(temp, ignored);
  for (auto it = created_dirs_.rbegin(); it != created_dirs_.rend(); ++it)
    std::filesystem::remove(*it, ignored);  // only removes directories left empty
}

void StagedOutputs::stage(const std::filesystem::path& path, std::string_view bytes) {
  const std::filesystem::path dir = path.parent_path().empty() ? "." : path.parent_path();
  if (!std::filesystem::exists(dir)) {
    // Remember every level we create so an abandoned command leaves no empty folders.
    std::vector<std::filesystem::path> missing;
    for (auto d = dir; !d.empty() && !std::filesystem::exists(d); d = d.parent_path())
      missing.push_back(d);
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw std::runtime_error("cannot create folder '" + dir.string() + "': " + ec.message());
    created_dirs_.insert(created_dirs_.end(), missing.rbegin(), missing.rend());
  }
  const std::filesystem::path temp = temporary_name(path);
  write_all(temp, bytes);
  temps_.push_back(temp);
  finals_.push_back(path);
}

void StagedOutputs::commit() {
  for (size_t i = 0; i < temps_.size(); ++i) {
    std::error_code ec;
    std::filesystem::rename(temps_[i], finals_[i], ec);
    if (ec)
      throw std::runtime_error("cannot write '" + finals_[i].string() + "': " + ec.message());
  }
  committed_ = true;
}

}  // namespace sd::app
