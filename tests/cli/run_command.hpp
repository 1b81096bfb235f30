#pragma once
// Runs the sketchdrape binary as a user would and captures what it printed.

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace sd::test {

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

// Runs `<prefix> sketchdrape <args>` through the shell (both passed as written), e.g. with
// prefix "env -u NAME" to run it without a variable.
inline CommandResult run_sketchdrape_with_env(const std::string& prefix, const std::string& args) {
  CommandResult result;
  const std::string command = prefix + " " + std::string(SD_BINARY) + " " + args + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return result;
  std::array<char, 4096> buffer{};
  size_t n;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0)
    result.output.append(buffer.data(), n);
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

// Runs `sketchdrape <args>` through the shell (args are passed as written).
inline CommandResult run_sketchdrape(const std::string& args) {
  return run_sketchdrape_with_env("", args);
}

}  // namespace sd::test
