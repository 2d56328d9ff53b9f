// Runs the real `upd` binary as a user would, capturing its exit code and output.
#pragma once

#include <array>
#include <cstdio>
#include <string>
#include <sys/wait.h>

namespace upd::test {

struct CmdResult {
  int exit_code = -1;
  std::string output;  ///< stdout and stderr
};

/// Runs a shell command line, stdout and stderr captured.
inline CmdResult runCommand(const std::string& command_line) {
  const std::string cmd = command_line + " 2>&1";
  CmdResult r;
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf{};
  while (fgets(buf.data(), buf.size(), pipe)) r.output += buf.data();
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

#ifdef UPD_BINARY
inline CmdResult runUpd(const std::string& args) {
  return runCommand(std::string(UPD_BINARY) + " " + args);
}
#endif

}  // namespace upd::test
