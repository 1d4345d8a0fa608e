// What each kind of error (core/util/error.h) means to the front ends: the command line's exit
// code and the Python module's exception class, in one table. The CLI returns the code, the
// Python module raises the class (subd2nurbs.errors), and `subd2nurbs --help` lists the codes.
#pragma once

#include <exception>
#include <string>
#include <vector>

#include "core/util/error.h"

namespace subd2nurbs::pipeline {

/// Process exit codes of the command line.
enum ExitCode : int {
  kExitOk = 0,
  kExitUsage = 1,          ///< bad command line, a setting breaking its rule, a resource limit
  kExitInvalidInput = 2,   ///< the input is unreadable, malformed or not a valid cage; a fit failed
  kExitWriteFailure = 3,   ///< an output file could not be written
  kExitInternalError = 4,  ///< a bug, an unexpected failure (e.g. out of memory), a failed export
};

struct ErrorClass {
  ErrorKind kind;
  const char* name;        ///< "settings", "input", ...
  ExitCode exit_code;
  const char* python;      ///< the class in subd2nurbs.errors
};

/// One row per ErrorKind, in the enum's order.
const std::vector<ErrorClass>& error_classes();
const ErrorClass& error_class(ErrorKind kind);

/// The exit code of any exception: its kind's, or kExitInternalError outside the family.
ExitCode exit_code(const std::exception& e);

}  // namespace subd2nurbs::pipeline
