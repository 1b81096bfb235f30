#include "src/app/pipeline/atomic_file.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <pthread.h>
#include <signal.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace sd::app {
namespace {

// The temporaries and folders this process has made and not yet committed, for the SIGINT /
// SIGTERM / SIGHUP handler: it removes them (unlink and rmdir are async-signal-safe) and dies by
// the signal as it would have. Lock-free slots, since a signal may arrive in any thread at any
// time; a path string is never freed once registered (one per staged file: a few hundred KB at
// most), so the handler never reads freed memory.
constexpr size_t kTempSlots = 16384;  // above run's 10,000 frames plus the images
std::array<std::atomic<char*>, kTempSlots> g_temp_slots{};
constexpr size_t kDirSlots = 64;
std::array<std::atomic<char*>, kDirSlots> g_dir_slots{};
std::once_flag g_handlers_installed;

// The thread that stages (installs the handlers on its first stage()). A signal sent to the
// process may be delivered to any thread that does not block it, such as a renderer's worker:
// cleaning up there would race with the staging thread, which could create a temporary after
// the loop below passed its slot. The signal is passed on to the staging thread instead.
pthread_t g_staging_thread;

// Set once a file of this process has been renamed into place: an interrupted command then
// says it kept those files instead of "nothing written".
std::atomic<bool> g_any_committed{false};

extern "C" void remove_temporaries_and_reraise(int sig) {
  if (!pthread_equal(pthread_self(), g_staging_thread)) {
    pthread_kill(g_staging_thread, sig);
    return;
  }
  for (auto& slot : g_temp_slots)
    if (char* path = slot.load()) ::unlink(path);
  for (size_t i = kDirSlots; i-- > 0;)  // deepest folders were registered last
    if (char* path = g_dir_slots[i].load()) ::rmdir(path);
  // One line, so that a log that stops here says why (write(2) is async-signal-safe; the
  // result is ignored: there is nowhere else to report to).
  static constexpr std::string_view kNothing = "interrupted: nothing written\n";
  static constexpr std::string_view kKept =
      "interrupted: the files already written were kept, the unfinished ones removed\n";
  const std::string_view line = g_any_committed.load() ? kKept : kNothing;
  [[maybe_unused]] const ssize_t written = ::write(STDERR_FILENO, line.data(), line.size());
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

void install_handlers() {
  std::call_once(g_handlers_installed, [] {
    g_staging_thread = pthread_self();
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
      struct sigaction old {};
      sigaction(sig, nullptr, &old);
      // Only where nobody else handles it (batch has its own), and an ignored SIGINT (nohup)
      // stays ignored.
      if (old.sa_handler != SIG_DFL || (old.sa_flags & SA_SIGINFO) != 0) continue;
      struct sigaction action {};
      action.sa_handler = remove_temporaries_and_reraise;
      sigemptyset(&action.sa_mask);
      sigaction(sig, &action, nullptr);
    }
  });
}

}  // namespace

void install_interrupt_cleanup() {
  install_handlers();
}

namespace {

// Puts `path` in a free slot; returns the slot's string (to release it later), or null when
// every slot is taken (the file is then only removed by the destructor or a later sweep).
template <size_t N>
char* hold(std::array<std::atomic<char*>, N>& slots, const std::filesystem::path& path) {
  install_handlers();
  char* copy = ::strdup(path.c_str());
  if (copy == nullptr) return nullptr;
  for (auto& slot : slots) {
    char* expected = nullptr;
    if (slot.compare_exchange_strong(expected, copy)) return copy;
  }
  std::free(copy);
  return nullptr;
}

template <size_t N>
void release(std::array<std::atomic<char*>, N>& slots, const char* held) {
  if (held == nullptr) return;
  for (auto& slot : slots) {
    char* expected = const_cast<char*>(held);
    if (slot.compare_exchange_strong(expected, nullptr)) return;  // the string is kept (see above)
  }
}

// When this process started (static initialisation, before main): a temporary last written
// before it is not of this command.
const std::filesystem::file_time_type g_process_start =
    std::filesystem::file_time_type::clock::now();

// Removes `.NAME.tmp-PID-N` files in `dir` left by processes that are gone (killed with SIGKILL,
// or crashed): the PID is not alive on this machine and the file was last written before this
// command started, or has not changed for ten minutes; says which it removed. On a folder shared
// by a cluster the PID may be another machine's live process: its temporaries are written after
// this command started, so they stay until ten minutes old. (Only ten minutes counted before,
// so a run into the folder of one killed a minute earlier left its temporaries beside its own
// outputs without a word: trial 43, P7.) Once per folder and process.
void sweep_stale_temporaries(const std::filesystem::path& dir) {
  static std::mutex mutex;
  static std::set<std::filesystem::path> swept;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (!swept.insert(dir).second) return;
  }
  std::error_code ec;
  const auto now = std::filesystem::file_time_type::clock::now();
  std::vector<std::string> removed;
  std::set<long> gone;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    const size_t tag = name.rfind(".tmp-");
    if (name.empty() || name[0] != '.' || tag == std::string::npos) continue;
    const std::string rest = name.substr(tag + 5);  // PID-N
    const size_t dash = rest.find('-');
    if (dash == std::string::npos || dash == 0 ||
        rest.find_first_not_of("0123456789-") != std::string::npos)
      continue;
    const long pid = std::strtol(rest.substr(0, dash).c_str(), nullptr, 10);
    if (pid <= 0 || pid == ::getpid()) continue;
    if (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;  // alive, or not ours
    std::error_code time_ec;
    const auto changed = std::filesystem::last_write_time(entry.path(), time_ec);
    if (time_ec || (changed >= g_process_start && now - changed < std::chrono::minutes(10)))
      continue;
    if (std::filesystem::remove(entry.path(), time_ec)) {
      removed.push_back(name);
      gone.insert(pid);
    }
  }
  if (removed.empty()) return;
  std::sort(removed.begin(), removed.end());
  std::string pids;
  for (const long pid : gone) pids += (pids.empty() ? "" : ", ") + std::to_string(pid);
  spdlog::info(
      "removed {} temporary file{} from '{}' that {} command{} no longer running "
      "({} {}, killed or crashed before it finished) left there: {}",
      removed.size(), removed.size() == 1 ? "" : "s", dir.string(),
      gone.size() == 1 ? "a" : "earlier", gone.size() == 1 ? "" : "s",
      gone.size() == 1 ? "process" : "processes", pids,
      fmt::format("{}", fmt::join(removed, ", ")));
}

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
  char* held = hold(g_temp_slots, temp);
  write_all(temp, bytes);
  std::error_code ec;
  g_any_committed = true;
  std::filesystem::rename(temp, path, ec);
  release(g_temp_slots, held);
  if (ec) {
    std::filesystem::remove(temp);
    throw std::runtime_error("cannot write '" + path.string() + "': " + ec.message());
  }
}

void check_output_folder(const std::filesystem::path& dir_in) {
  namespace fs = std::filesystem;
  const fs::path dir = dir_in.empty() ? fs::path(".") : dir_in;
  const auto refuse = [&](const std::string& reason) {
    throw std::invalid_argument("cannot write to the output folder '" + dir.string() +
                                "': " + reason + "; choose another output folder (-o)");
  };
  // The nearest level that exists: a file there ends it; the missing levels below are made
  // (and removed again) to see that they can be.
  std::error_code ec;
  std::vector<fs::path> missing;
  fs::path base = dir;
  for (; !base.empty(); base = base.parent_path()) {
    const fs::file_status status = fs::status(base, ec);
    if (fs::exists(status)) {
      if (!fs::is_directory(status)) refuse("'" + base.string() + "' is a file, not a folder");
      break;
    }
    // A symbolic link to nowhere looks missing but cannot be made (trial 40: "File exists").
    if (fs::is_symlink(fs::symlink_status(base, ec)))
      refuse("'" + base.string() + "' is a symbolic link to '" +
             fs::read_symlink(base, ec).string() + "', which does not exist");
    missing.push_back(base);
    if (base == base.parent_path()) break;
  }
  if (base.empty()) base = ".";
  std::vector<fs::path> made;  // shallowest first
  const auto remove_made = [&] {
    std::error_code ignored;
    for (auto d = made.rbegin(); d != made.rend(); ++d) fs::remove(*d, ignored);  // if empty
  };
  for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
    if (::mkdir(it->c_str(), 0777) != 0) {
      const int error = errno;
      remove_made();
      refuse("cannot create folder '" + it->string() + "' (" + std::strerror(error) +
             (error == ENOENT ? ": its parent takes no new folders" : "") + ")");
    }
    made.push_back(*it);
  }
  // A file can be made there (as root, permission bits say nothing about /proc or a read-only
  // mount: only trying tells).
  const fs::path probe = dir / (".sketchdrape-probe-" + std::to_string(::getpid()));
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0600);
  if (fd < 0) {
    const int error = errno;
    remove_made();
    refuse(std::string("no file can be created in it (") + std::strerror(error) + ")");
  }
  ::close(fd);
  ::unlink(probe.c_str());
  remove_made();
}

StagedOutputs::~StagedOutputs() {
  if (!committed_) {
    std::error_code ignored;
    for (const auto& temp : temps_) std::filesystem::remove(temp, ignored);
    for (auto it = created_dirs_.rbegin(); it != created_dirs_.rend(); ++it)
      std::filesystem::remove(*it, ignored);  // only removes directories left empty
  }
  for (const char* held : held_) release(g_temp_slots, held);
  for (const char* held : held_dirs_) release(g_dir_slots, held);
}

namespace {

// Whether `a` and `b` name the same file: the same inode when both exist, else the same path
// once "..", "." and links of the existing part are resolved.
bool same_file(const std::filesystem::path& a, const std::filesystem::path& b) {
  std::error_code ec;
  if (std::filesystem::exists(a, ec) && std::filesystem::exists(b, ec))
    return std::filesystem::equivalent(a, b, ec);
  const auto ca = std::filesystem::weakly_canonical(a, ec);
  if (ec) return false;
  const auto cb = std::filesystem::weakly_canonical(b, ec);
  return !ec && ca == cb;
}

}  // namespace

void StagedOutputs::keep(const std::filesystem::path& input) {
  std::error_code ec;
  if (std::filesystem::is_regular_file(input, ec)) inputs_.push_back(input);
}

void StagedOutputs::stage(const std::filesystem::path& path, std::string_view bytes) {
  const std::filesystem::path dir = path.parent_path().empty() ? "." : path.parent_path();
  // Two outputs at one path (`fill --obj f.obj --png f.obj` wrote the picture over the mesh and
  // said "wrote f.obj" twice), or an output over a file the command read.
  for (const auto& staged : finals_)
    if (same_file(staged, path))
      throw std::invalid_argument("'" + path.string() + "' is named for two outputs ('" +
                                  staged.string() + "' too); give each output its own file");
  for (const auto& input : inputs_)
    if (same_file(input, path))
      throw std::invalid_argument("cannot write '" + path.string() +
                                  "': it would replace the input file '" + input.string() +
                                  "'; choose another output (-o)");
  // What the user can fix (exit code 2), found before any output is renamed into place: a
  // folder (or a device, a FIFO) where a file goes, a file where the output folder goes.
  std::error_code status_ec;
  for (auto d = dir; !d.empty() && d != d.parent_path(); d = d.parent_path()) {
    const auto status = std::filesystem::status(d, status_ec);
    if (!std::filesystem::exists(status)) continue;
    if (!std::filesystem::is_directory(status))
      throw std::invalid_argument("cannot write '" + path.string() + "': '" + d.string() +
                                  "' is a file, not a folder; remove it or choose another "
                                  "output folder (-o)");
    break;
  }
  if (const auto status = std::filesystem::status(path, status_ec);
      std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
    throw std::invalid_argument(
        "cannot write '" + path.string() + "': " +
        (std::filesystem::is_directory(status) ? "a folder" : "something that is not a file") +
        " of that name is in the way; remove it or choose another output folder (-o)");
  if (!std::filesystem::exists(dir)) {
    // Remember every level we create so an abandoned command leaves no empty folders.
    std::vector<std::filesystem::path> missing;
    for (auto d = dir; !d.empty() && !std::filesystem::exists(d); d = d.parent_path())
      missing.push_back(d);
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec)
      throw std::runtime_error("cannot create folder '" + dir.string() + "': " + ec.message());
    created_dirs_.insert(created_dirs_.end(), missing.rbegin(), missing.rend());
    for (auto it = missing.rbegin(); it != missing.rend(); ++it)
      held_dirs_.push_back(hold(g_dir_slots, *it));
  }
  sweep_stale_temporaries(dir);
  const std::filesystem::path temp = temporary_name(path);
  held_.push_back(hold(g_temp_slots, temp));  // before the file exists: a signal cannot miss it
  write_all(temp, bytes);
  temps_.push_back(temp);
  finals_.push_back(path);
}

void StagedOutputs::commit() {
  if (!temps_.empty()) g_any_committed = true;
  for (size_t i = 0; i < temps_.size(); ++i) {
    std::error_code ec;
    std::filesystem::rename(temps_[i], finals_[i], ec);
    if (ec) throw std::runtime_error("cannot write '" + finals_[i].string() + "': " + ec.message());
  }
  committed_ = true;
  for (const char* held : held_) release(g_temp_slots, held);
  for (const char* held : held_dirs_) release(g_dir_slots, held);
  held_.clear();
  held_dirs_.clear();
}

namespace {

// A name sketchdrape gives its outputs: drape.obj, drape-front.png, drape-failed.obj,
// garment48.obj, garment-left.png, frame-0007-front.png, pattern.svg, report.json, trace.jsonl.
bool output_name(const std::string& name) {
  const auto ends = [&](std::string_view suffix) { return name.ends_with(suffix); };
  for (std::string_view stem : {"drape", "garment", "frame-"})
    if (name.starts_with(stem) && (ends(".png") || ends(".obj") || ends(".glb"))) return true;
  return name == "pattern.svg" || name == "pattern.dxf" || name == "pattern.json" ||
         name == "report.json" || name == "trace.jsonl";
}

}  // namespace

std::vector<std::string> stale_outputs(const std::filesystem::path& dir,
                                       const std::vector<std::filesystem::path>& written) {
  namespace fs = std::filesystem;
  const auto ours = [&](const fs::path& file) {
    std::error_code ec;
    return std::any_of(written.begin(), written.end(),
                       [&](const fs::path& w) { return fs::equivalent(file, w, ec); });
  };
  std::vector<std::string> stale;
  for (const fs::path& folder : {dir, dir / "frames"}) {
    std::error_code ec;
    for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
      const std::string name = it->path().filename().string();
      if (it->is_regular_file(ec) && output_name(name) && !ours(it->path()))
        stale.push_back(it->path().lexically_relative(dir).string());
    }
  }
  std::sort(stale.begin(), stale.end());
  return stale;
}

std::string stale_outputs_notice(const std::filesystem::path& dir,
                                 const std::vector<std::string>& stale) {
  if (stale.empty()) return "";
  constexpr std::size_t kNamed = 8;
  std::string names;
  for (std::size_t i = 0; i < stale.size() && i < kNamed; ++i)
    names += (i == 0 ? "" : ", ") + stale[i];
  if (stale.size() > kNamed) names += fmt::format(" and {} more", stale.size() - kNamed);
  return fmt::format(
      "{} also holds {} output file{} of an earlier command that this one did not write: {}; "
      "they are left as they were, so the folder mixes two results: delete them, or give -o a "
      "new folder",
      dir.string(), stale.size(), stale.size() == 1 ? "" : "s", names);
}

}  // namespace sd::app
