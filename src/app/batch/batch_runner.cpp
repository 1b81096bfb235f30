#include "src/app/batch/batch_runner.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <spdlog/spdlog.h>
#include <sys/file.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <map>
#include <optional>

#include "sim/parallel.hpp"
#include "src/app/pipeline/atomic_file.hpp"
#include "src/app/pipeline/progress.hpp"
#include "src/app/version.hpp"

extern char** environ;

namespace sd::app {
namespace {

using Clock = std::chrono::steady_clock;

std::filesystem::path own_executable() {
  std::error_code ec;
  std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec)
    throw std::runtime_error("cannot find the sketchdrape binary (/proc/self/exe): " +
                             ec.message());
  return exe;
}

// Turns SIGCHLD, SIGINT and SIGTERM into bytes on a pipe that the loop polls. Handlers rather
// than blocked signals and sigtimedwait: libraries start threads (OpenBLAS does at load time)
// that do not block them, and a process-directed signal may be delivered to any such thread.
// A handler runs in whichever thread gets the signal, and the pipe wakes the loop either way.
int g_wake_fd = -1;
volatile sig_atomic_t g_stop_signal = 0;

extern "C" void on_batch_signal(int sig) {
  if (sig != SIGCHLD) g_stop_signal = sig;
  const int saved = errno;
  const char byte = 0;
  [[maybe_unused]] const ssize_t n = ::write(g_wake_fd, &byte, 1);
  errno = saved;
}

class SignalGate {
 public:
  SignalGate() {
    if (::pipe2(fds_, O_CLOEXEC | O_NONBLOCK) != 0)
      throw std::runtime_error(std::string("cannot create a pipe: ") + std::strerror(errno));
    g_wake_fd = fds_[1];
    g_stop_signal = 0;
    struct sigaction action {};
    action.sa_handler = on_batch_signal;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESTART | SA_NOCLDSTOP;
    for (size_t i = 0; i < kSignals.size(); ++i) {
      sigaction(kSignals[i], nullptr, &old_[i]);
      // An ignored SIGINT (a batch started with nohup or in the background) stays ignored.
      if (kSignals[i] == SIGINT && old_[i].sa_handler == SIG_IGN) continue;
      sigaction(kSignals[i], &action, nullptr);
    }
  }
  ~SignalGate() {
    for (size_t i = 0; i < kSignals.size(); ++i) sigaction(kSignals[i], &old_[i], nullptr);
    g_wake_fd = -1;
    ::close(fds_[0]);
    ::close(fds_[1]);
  }
  SignalGate(const SignalGate&) = delete;
  SignalGate& operator=(const SignalGate&) = delete;

  // Waits up to `timeout` for a signal; returns SIGINT or SIGTERM if one came, else 0.
  int wait(std::chrono::milliseconds timeout) const {
    pollfd fd{fds_[0], POLLIN, 0};
    ::poll(&fd, 1, static_cast<int>(timeout.count()));
    char buffer[64];
    while (::read(fds_[0], buffer, sizeof buffer) > 0) {
    }
    const int sig = g_stop_signal;
    g_stop_signal = 0;
    return sig;
  }

 private:
  static constexpr std::array<int, 3> kSignals = {SIGCHLD, SIGINT, SIGTERM};
  int fds_[2] = {-1, -1};
  std::array<struct sigaction, 3> old_{};
};

struct RunningJob {
  const PlannedJob* job;
  pid_t pid;
  Clock::time_point start;
  bool timed_out = false;
  bool stopped = false;  // sent SIGTERM because the batch is being stopped
};

// The environment children run with: this process's, plus OPENBLAS_NUM_THREADS=1 unless the
// user set it. Each child is one job on one core; OpenBLAS (under CHOLMOD) otherwise starts a
// thread per core in every child, and -j N children then oversubscribe the machine N-fold
// (docs/batch.md, "Performance").
std::vector<std::string> child_environment() {
  std::vector<std::string> env;
  bool openblas_set = false;
  for (char** e = environ; *e != nullptr; ++e) {
    env.emplace_back(*e);
    if (env.back().rfind("OPENBLAS_NUM_THREADS=", 0) == 0) openblas_set = true;
  }
  if (!openblas_set) env.emplace_back("OPENBLAS_NUM_THREADS=1");
  // The child ends when this batch process does, however it ends (follow_batch_parent).
  env.push_back(fmt::format("{}={}", kBatchParentVariable, ::getpid()));
  return env;
}

// The locks of a batch on its output folder, held for the whole batch: a second batch on the
// same folder refuses instead of running the same jobs at the same time. Each batch holds
//   .batch-lock (unsharded) or .batch-lock-shard-I-of-N  exclusive: one process per slice
//   .batch-lock-count-N (N = 1 unsharded)                  shared: the shards of one count
// and, while it starts, tests that no .batch-lock-count-M of another count is held: shards of
// different counts (or a whole batch and a shard) have overlapping slices and would run the
// same jobs at once. The test and the shared lock are made under .batch-lock-gate (exclusive,
// held for milliseconds), so two batches that start together cannot both pass it. flock is
// released by the kernel when the process ends, however it ends; O_CLOEXEC keeps the children
// from inheriting it.
class FolderLock {
 public:
  FolderLock(const std::filesystem::path& out, const std::optional<std::pair<int, int>>& shard) {
    const int count = shard ? shard->second : 1;
    const std::string mine =
        shard ? fmt::format(" as shard {}/{}", shard->first, shard->second) : std::string();
    // --shard 1/1 is the whole batch: the same lock.
    slice_fd_ = open_lock(
        out / (count > 1 ? fmt::format(".batch-lock-shard-{}-of-{}", shard->first, shard->second)
                         : std::string(".batch-lock")));
    if (::flock(slice_fd_, LOCK_EX | LOCK_NB) != 0) {
      const std::string holder = lock_holder(slice_fd_);
      close_all();
      throw std::runtime_error(
          fmt::format("another batch (process {}) is writing into '{}'{}; wait until it ends, or "
                      "give this one another -o folder",
                      holder, out.string(), mine));
    }
    const std::string pid = std::to_string(::getpid()) + "\n";
    if (::ftruncate(slice_fd_, 0) == 0 && ::pwrite(slice_fd_, pid.data(), pid.size(), 0) < 0) {
      // The pid is only for the message of a second batch.
    }

    const int gate = open_lock(out / ".batch-lock-gate");
    while (::flock(gate, LOCK_EX) != 0 && errno == EINTR) {
    }
    std::error_code ec;
    for (const auto& entry : std::filesystem::directory_iterator(out, ec)) {
      const std::string name = entry.path().filename().string();
      int other = 0;
      if (std::sscanf(name.c_str(), ".batch-lock-count-%d", &other) != 1 || other == count)
        continue;
      const int fd = ::open(entry.path().c_str(), O_RDWR | O_CLOEXEC);
      if (fd < 0) continue;
      const bool held = ::flock(fd, LOCK_EX | LOCK_NB) != 0;  // a probe, released at close
      ::close(fd);
      if (!held) continue;
      ::close(gate);
      close_all();
      const std::string running = other == 1 ? std::string("a whole batch (no --shard)")
                                             : fmt::format("a batch in {} shards", other);
      throw std::runtime_error(fmt::format(
          "{} is writing into '{}' ({}); this one{} would run some of the same jobs at the same "
          "time. Shards of one folder must all use the same count: wait until it ends, or use "
          "--shard I/{}",
          running, out.string(), holders_of(out, other),
          shard ? mine : std::string(" (without --shard)"), other));
    }
    count_fd_ = open_lock(out / fmt::format(".batch-lock-count-{}", count));
    while (::flock(count_fd_, LOCK_SH) != 0 && errno == EINTR) {
    }
    ::close(gate);
  }
  ~FolderLock() { close_all(); }
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  static int open_lock(const std::filesystem::path& path) {
    const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0)
      throw std::runtime_error(
          fmt::format("cannot open the lock '{}': {}", path.string(), std::strerror(errno)));
    return fd;
  }
  // The pid written in a lock file ("?" when there is none).
  static std::string lock_holder(int fd) {
    char text[32] = {};
    const ssize_t n = ::pread(fd, text, sizeof text - 1, 0);
    const std::string holder = n > 0 ? std::string(text, static_cast<size_t>(n)) : "?";
    return holder.substr(0, holder.find('\n'));
  }
  // "process P" (or "processes P, Q") of the slices of a `count`-shard batch that are held.
  static std::string holders_of(const std::filesystem::path& out, int count) {
    std::vector<std::string> pids;
    std::error_code ec;
    for (const auto& entry : std::filesystem::directory_iterator(out, ec)) {
      const std::string name = entry.path().filename().string();
      int index = 0, of = 0;
      const bool slice =
          count == 1 ? name == ".batch-lock"
                     : std::sscanf(name.c_str(), ".batch-lock-shard-%d-of-%d", &index, &of) == 2 &&
                           of == count;
      if (!slice) continue;
      const int fd = ::open(entry.path().c_str(), O_RDWR | O_CLOEXEC);
      if (fd < 0) continue;
      if (::flock(fd, LOCK_EX | LOCK_NB) != 0) pids.push_back(lock_holder(fd));
      ::close(fd);
    }
    if (pids.empty()) return "a process that is starting";
    std::sort(pids.begin(), pids.end());
    std::string list;
    for (const std::string& p : pids) list += (list.empty() ? "" : ", ") + p;
    return (pids.size() == 1 ? "process " : "processes ") + list;
  }
  void close_all() {
    if (slice_fd_ >= 0) ::close(slice_fd_);
    if (count_fd_ >= 0) ::close(count_fd_);
    slice_fd_ = count_fd_ = -1;
  }

  int slice_fd_ = -1;
  int count_fd_ = -1;
};

// Starts `exe <args>` with stdout and stderr going to `log` (truncated) and stdin from /dev/null,
// with default signal mask and dispositions and the child_environment(). Throws
// std::runtime_error.
pid_t spawn_child(const std::filesystem::path& exe, const std::vector<std::string>& args,
                  const std::filesystem::path& log) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  // Children start with no blocked signals and default SIGTERM and SIGCHLD (exec resets caught
  // signals anyway; an ignored SIGINT stays ignored, as nohup intends).
  sigset_t none, defaults;
  sigemptyset(&none);
  sigemptyset(&defaults);
  sigaddset(&defaults, SIGTERM);
  sigaddset(&defaults, SIGCHLD);
  posix_spawnattr_setsigmask(&attr, &none);
  posix_spawnattr_setsigdefault(&attr, &defaults);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);

  std::vector<std::string> argv_strings;
  argv_strings.push_back(exe.string());
  argv_strings.insert(argv_strings.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& s : argv_strings) argv.push_back(s.data());
  argv.push_back(nullptr);
  std::vector<std::string> env_strings = child_environment();
  std::vector<char*> envp;
  for (std::string& s : env_strings) envp.push_back(s.data());
  envp.push_back(nullptr);
  pid_t pid = 0;
  const int error = posix_spawn(&pid, exe.c_str(), &actions, &attr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  if (error != 0)
    throw std::runtime_error(
        fmt::format("cannot start the job (log {}): {}", log.string(), std::strerror(error)));
  return pid;
}

std::string signal_reason(int sig) {
  const char* name = strsignal(sig);
  return fmt::format("killed by signal {} ({})", sig, name != nullptr ? name : "unknown");
}

}  // namespace

bool BatchResult::all_done() const {
  return !interrupted && std::all_of(jobs.begin(), jobs.end(),
                                     [](const JobSummary& j) { return j.status == "done"; });
}

std::vector<PlannedJob> plan_batch(const BatchOptions& options, BatchPlan* plan) {
  std::vector<BatchJob> jobs = load_batch_jobs(options.inputs);
  FileDigests files;
  std::vector<PlannedJob> planned;
  planned.reserve(jobs.size());
  for (const BatchJob& job : jobs) planned.push_back(plan_job(job, options.stage, kVersion, files));
  if (plan != nullptr) {
    plan->stage = options.stage;
    plan->version = kVersion;
    plan->jobs.clear();
    for (const PlannedJob& p : planned) plan->jobs.push_back(plan_entry(p));
  }
  if (!options.shard) return planned;
  std::vector<PlannedJob> slice;
  const auto [index, count] = *options.shard;
  for (size_t i = static_cast<size_t>(index - 1); i < planned.size();
       i += static_cast<size_t>(count))
    slice.push_back(planned[i]);
  return slice;
}

bool follow_batch_parent() {
  const char* parent = std::getenv(kBatchParentVariable);
  if (parent == nullptr) return true;
  const long pid = std::strtol(parent, nullptr, 10);
  ::prctl(PR_SET_PDEATHSIG, SIGTERM);
  // The batch may have died between spawning this process and the line above: then the
  // signal never comes, and the parent is no longer the batch.
  return pid <= 0 || ::getppid() == static_cast<pid_t>(pid);
}

BatchResult run_batch(const BatchOptions& options) {
  if (options.parallel < 1) throw std::invalid_argument("-j must be at least 1");
  if (options.timeout_s < 0) throw std::invalid_argument("--timeout must not be negative");
  BatchPlan plan;
  const std::vector<PlannedJob> mine = plan_batch(options, &plan);
  const std::filesystem::path exe =
      options.executable.empty() ? own_executable() : options.executable;
  const std::filesystem::path jobs_dir = options.out / kJobsFolder;
  std::error_code ec;
  std::filesystem::create_directories(jobs_dir, ec);
  if (ec)
    throw std::runtime_error(
        fmt::format("cannot create '{}': {}", jobs_dir.string(), ec.message()));
  const FolderLock lock(options.out, options.shard);
  write_plan(options.out, plan);

  BatchResult result;
  std::map<std::string, KnownRecord> records;  // this run's outcome per job id
  std::deque<const PlannedJob*> queue;
  const Progress* bar = nullptr;  // cleared before a warning so the two do not share a line
  auto finish = [&](const PlannedJob& p, JobRecord record, bool write_marker) {
    record.inputs_hash = p.inputs_hash;
    record.stage = options.stage;
    record.version = kVersion;
    record.finished_at = utc_timestamp();
    if (write_marker) {
      try {
        // The marker binds the outputs as they are now to the inputs' digest.
        if (record.status == "done") record.outputs = digest_job_outputs(jobs_dir / p.job.id);
        write_job_record(jobs_dir / p.job.id, record);
      } catch (const std::exception& e) {
        if (record.status == "done") {
          record.status = "failed";
          record.reason =
              fmt::format("the job finished but its done marker cannot be written: {}", e.what());
        }
        spdlog::warn("{}: {}", p.job.id, e.what());
      }
    }
    if (record.status != "done") {
      if (bar != nullptr && bar->visible()) std::fputs("\r\033[K", stderr);
      spdlog::warn("{} {}: {}", p.job.id, record.status, record.reason);
    }
    records[p.job.id] = {record, false};
  };

  for (const PlannedJob& p : mine) {
    const std::filesystem::path dir = jobs_dir / p.job.id;
    if (!p.input_error.empty()) {
      // The sketch is not a JSON object: no child can do anything with it.
      JobRecord record;
      record.status = "bad-input";
      record.reason = p.input_error;
      try {
        clean_job_folder(dir);
        write_file_atomically(dir / kJobLog, "error: " + p.input_error + "\n");
      } catch (const std::exception& e) {
        spdlog::warn("{}: {}", p.job.id, e.what());
      }
      finish(p, record, true);
      continue;
    }
    if (!options.force && job_is_done(dir, p.inputs_hash)) {
      records[p.job.id] = {*read_job_record(dir), true};
      ++result.reused;
      continue;
    }
    queue.push_back(&p);
  }

  const long total = static_cast<long>(queue.size());
  Progress progress(options.shard
                        ? fmt::format("batch {}/{}", options.shard->first, options.shard->second)
                        : "batch",
                    total, options.quiet);
  bar = &progress;
  const auto batch_start = Clock::now();
  int finished = 0, failed = 0;
  auto update_progress = [&] {
    const double elapsed = std::chrono::duration<double>(Clock::now() - batch_start).count();
    const long remaining = total - finished;
    std::string eta = "?";
    if (finished > 0) {
      const double per_job = elapsed / finished;
      eta = fmt::format("{:.0f}s", per_job * static_cast<double>(remaining));
    }
    progress.update(finished, fmt::format("{} done, {} failed, {} left, ETA {}", finished - failed,
                                          failed, remaining, eta));
  };

  SignalGate gate;
  std::vector<RunningJob> running;
  const int child_threads = std::max(1, sim::thread_count() / std::max(1, options.parallel));
  bool stopping = false;
  while (!queue.empty() || !running.empty()) {
    while (!stopping && !queue.empty() && static_cast<int>(running.size()) < options.parallel) {
      const PlannedJob& p = *queue.front();
      queue.pop_front();
      const std::filesystem::path dir = jobs_dir / p.job.id;
      try {
        clean_job_folder(dir);
        write_file_atomically(dir / kJobSketch, p.document->dump(2) + "\n");
        std::vector<std::string> args;
        if (options.verbose) args.push_back("-v");
        args.insert(args.end(), {options.stage, (dir / kJobSketch).string(), "-o", dir.string()});
        // The cores shared out between the jobs running side by side (a global option; last, so
        // the job's own arguments keep their places).
        args.insert(args.end(), {"--threads", std::to_string(child_threads)});
        running.push_back({&p, spawn_child(exe, args, dir / kJobLog), Clock::now()});
        ++result.ran;
      } catch (const std::exception& e) {
        JobRecord record;
        record.status = "failed";
        record.reason = e.what();
        finish(p, record, true);
        ++finished, ++failed;
        update_progress();
      }
    }
    if (running.empty()) break;
    update_progress();

    const int sig = gate.wait(std::chrono::milliseconds(200));
    if ((sig == SIGINT || sig == SIGTERM) && !stopping) {
      stopping = true;
      result.interrupted = true;
      spdlog::warn("stopping: {} received; ending {} running jobs", strsignal(sig), running.size());
      for (RunningJob& r : running) {
        r.stopped = true;
        kill(r.pid, SIGTERM);
      }
    }
    if (options.timeout_s > 0) {
      for (RunningJob& r : running) {
        const double age = std::chrono::duration<double>(Clock::now() - r.start).count();
        if (!r.timed_out && age > options.timeout_s) {
          r.timed_out = true;
          kill(r.pid, SIGKILL);
        }
      }
    }
    // Reap every child that has ended.
    for (;;) {
      int status = 0;
      const pid_t pid = waitpid(-1, &status, WNOHANG);
      if (pid <= 0) break;
      auto it = std::find_if(running.begin(), running.end(),
                             [&](const RunningJob& r) { return r.pid == pid; });
      if (it == running.end()) continue;
      const RunningJob r = *it;
      running.erase(it);
      const PlannedJob& p = *r.job;
      JobRecord record;
      record.wall_time_s = std::chrono::duration<double>(Clock::now() - r.start).count();
      const std::filesystem::path log = jobs_dir / p.job.id / kJobLog;
      bool write_marker = true;
      if (WIFEXITED(status)) {
        record.exit_code = WEXITSTATUS(status);
        record.status = record.exit_code == 0   ? "done"
                        : record.exit_code == 2 ? "bad-input"
                                                : "failed";
        if (record.exit_code != 0) {
          // Paths inside the job's own folder read better relative to it ("sketch.json: /fabric").
          record.reason = failure_reason_from_log(log);
          const std::string prefix = (jobs_dir / p.job.id).string() + "/";
          for (size_t at = record.reason.find(prefix); at != std::string::npos;
               at = record.reason.find(prefix, at))
            record.reason.erase(at, prefix.size());
          if (record.reason.empty())
            record.reason = fmt::format("exited with code {}", record.exit_code);
        }
      } else {
        record.status = "failed";
        const int s = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
        if (r.timed_out) {
          record.reason = fmt::format("timed out after {:g} s (--timeout)", options.timeout_s);
        } else if (r.stopped) {
          record.reason = "interrupted: the batch was stopped";
          write_marker = false;  // an interrupted job is simply not finished
        } else {
          record.reason = signal_reason(s);
        }
      }
      finish(p, record, write_marker);
      ++finished;
      if (record.status != "done") ++failed;
    }
  }
  progress.finish();
  if (stopping)
    for (const PlannedJob* p : queue)
      spdlog::warn("{}: not started (the batch was stopped)", p->job.id);

  // This run's jobs, as the summary and the shard file see them.
  if (options.shard) {
    BatchPlan mine_plan = plan;
    mine_plan.jobs.clear();
    for (const PlannedJob& p : mine) mine_plan.jobs.push_back(plan_entry(p));
    result.jobs = summarise_jobs(mine_plan, options.out, records, {});
    const auto [index, count] = *options.shard;
    std::filesystem::create_directories(options.out / kShardsFolder, ec);
    write_file_atomically(options.out / kShardsFolder / shard_file_name(index, count),
                          shard_json(index, count, records).dump(2) + "\n");
  } else {
    result.jobs = summarise_jobs(plan, options.out, records, {});
    write_summary(options.out, plan, result.jobs);
  }
  const std::map<std::string, int> counts = count_statuses(result.jobs);
  std::vector<std::string> parts;
  for (const auto& [status, n] : counts) parts.push_back(fmt::format("{} {}", n, status));
  spdlog::info(
      "batch{}: {} ({} ran, {} reused) in {:.1f} s{}",
      options.shard ? fmt::format(" shard {}/{}", options.shard->first, options.shard->second) : "",
      fmt::join(parts, ", "), result.ran, result.reused,
      std::chrono::duration<double>(Clock::now() - batch_start).count(),
      options.shard ? "" : " → " + (options.out / kContactSheetFile).string());
  return result;
}

}  // namespace sd::app
