// Running a command line from a test: shell quoting, and the exit code, stdout and stderr of
// a command (header-only; POSIX sh).
#pragma once

#include <sys/wait.h>

#include <cstdlib>
#include <string>

#include "io/temp_dir.h"

namespace subd2nurbs::testing {

/// `s` as one single-quoted sh word.
inline std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

struct CommandResult {
  int exit_code = -1;  ///< -1 if the command did not exit normally
  std::string out, err;
};

/// Runs `command` (an sh command line, arguments already quoted; it may redirect stdin) with
/// its stdout and stderr captured.
inline CommandResult run_command(const std::string& command) {
  TempDir dir;
  const int status =
      std::system((command + " >" + quote(dir.file("out")) + " 2>" + quote(dir.file("err"))).c_str());
  CommandResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = read_text(dir.file("out"));
  r.err = read_text(dir.file("err"));
  return r;
}

}  // namespace subd2nurbs::testing
