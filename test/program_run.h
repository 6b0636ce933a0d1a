// Runs the point-detail program as a user would, for the tests that need it.
#ifndef CGAL_EXT_TEST_PROGRAM_RUN_H
#define CGAL_EXT_TEST_PROGRAM_RUN_H

#include <cstdio>
#include <string>
#include <sys/wait.h>

struct Program_run
{
  int exit_code; ///< -1 when the program did not exit normally (a crash or a signal)
  std::string output; ///< stdout and stderr
};

/// Runs a shell command and collects what it prints on stdout and stderr.
inline Program_run run_command(const std::string& command_line)
{
  const std::string command = command_line + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  Program_run r{-1, {}};
  if(pipe == nullptr) return r;
  char buffer[4096];
  while(std::size_t got = std::fread(buffer, 1, sizeof buffer, pipe)) r.output.append(buffer, got);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

/// Runs `point-detail --quiet <arguments>` through the shell and collects what it prints. `shell_prefix`
/// runs first in the same shell (for instance `ulimit -v N;`).
inline Program_run run(const std::string& arguments, const std::string& shell_prefix = "")
{
  return run_command(shell_prefix + std::string(POINT_DETAIL_EXE) + " --quiet " + arguments);
}

#endif
