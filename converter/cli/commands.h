// The subd2nurbs command line: option parsing and the subcommands. Separated from main()
// so that everything except process start-up can be reused and tested.
#pragma once

#include <ostream>
#include <stdexcept>
#include <string>

namespace subd2nurbs::cli {

/// Process exit codes (also listed in `subd2nurbs --help`).
enum ExitCode : int {
  kOk = 0,
  kUsage = 1,          ///< bad command line: unknown option, missing argument, bad value
  kInvalidInput = 2,   ///< the input file is unreadable, malformed or not a valid cage
  kWriteFailure = 3,   ///< an output file could not be written
  kInternalError = 4,  ///< a bug, an unexpected failure (e.g. out of memory), a failed export
};

struct InfoOptions {
  std::string mesh;
  bool json = false;
};

struct RefineOptions {
  std::string mesh;
  int levels = 1;
  std::string output;
  std::string polar = "on";  ///< "on": BP subdivision at polar structures; "off": Catmull-Clark only
};

/// Describes a cage on `out` (text or JSON); warnings are part of the description.
/// \throw InputError for an unreadable or invalid cage
void run_info(const InfoOptions& options, std::ostream& out);

/// Refines a cage uniformly and writes the last level as OBJ. Warnings and progress go to
/// `err`. \throw InputError, WriteError, UsageError
void run_refine(const RefineOptions& options, std::ostream& err);

/// A valid command line asking for something impossible (exit code kUsage).
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Parses the command line, runs the subcommand and returns the exit code. Never throws.
int run(int argc, const char* const* argv, std::ostream& out, std::ostream& err);

}  // namespace subd2nurbs::cli
