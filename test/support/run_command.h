#pragma once

// Runs a program through the shell as a user would, for tests of the package's executables.

#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace sdf_tracker::test {

/// How a command ended: its exit code (-1 when it did not exit by itself) and what it printed on
/// stdout and stderr.
struct CommandResult {
  int exit_code = -1;
  std::string output;
};

/// Runs `command` (already quoted for the shell) and waits for it.
inline CommandResult runCommand(const std::string& command) {
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  CommandResult result;
  char buffer[4096];
  while (pipe && fgets(buffer, sizeof(buffer), pipe)) result.output += buffer;
  const int status = pipe ? pclose(pipe) : -1;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

}  // namespace sdf_tracker::test
