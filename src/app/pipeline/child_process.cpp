#include "src/app/pipeline/child_process.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <thread>

extern char** environ;

namespace sd::app {

ChildRun run_child(const std::filesystem::path& program, const std::vector<std::string>& args,
                   const std::filesystem::path& log, double timeout_s,
                   const std::function<void(double)>& tick) {
  std::vector<std::string> argv_strings = {program.string()};
  argv_strings.insert(argv_strings.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_strings) argv.push_back(a.data());
  argv.push_back(nullptr);
  // One BLAS/OpenMP thread unless the user chose: the children's CPU times stay comparable.
  std::vector<std::string> env_strings;
  bool has_openblas = false, has_omp = false;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string entry(*e);
    has_openblas |= entry.rfind("OPENBLAS_NUM_THREADS=", 0) == 0;
    has_omp |= entry.rfind("OMP_NUM_THREADS=", 0) == 0;
    env_strings.push_back(entry);
  }
  if (!has_openblas) env_strings.push_back("OPENBLAS_NUM_THREADS=1");
  if (!has_omp) env_strings.push_back("OMP_NUM_THREADS=1");
  std::vector<char*> envp;
  for (std::string& e : env_strings) envp.push_back(e.data());
  envp.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  pid_t pid = 0;
  const int error = posix_spawn(&pid, program.c_str(), &actions, nullptr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  if (error != 0)
    throw std::runtime_error(
        fmt::format("cannot start {}: {}", program.string(), std::strerror(error)));

  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  ChildRun run;
  int status = 0;
  rusage usage{};
  while (true) {
    const pid_t r = wait4(pid, &status, WNOHANG, &usage);
    if (r == pid) break;
    if (r < 0 && errno != EINTR) throw std::runtime_error("waiting for a child process failed");
    const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    if (elapsed > timeout_s && !run.timed_out) {
      kill(pid, SIGKILL);
      run.timed_out = true;
    }
    if (tick) tick(elapsed);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  run.elapsed_s = std::chrono::duration<double>(Clock::now() - start).count();
  run.cpu_s = static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
              1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
  run.peak_rss_mb = static_cast<double>(usage.ru_maxrss) / 1024.0;  // KiB on Linux
  run.exited = WIFEXITED(status) && !run.timed_out;
  if (run.exited) run.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) run.signal = WTERMSIG(status);
  return run;
}

}  // namespace sd::app
