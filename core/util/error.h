// The one family of errors a user can meet: every exception that reaches a front end because of
// what the user gave (a file, a setting, a limit) or because an output or OCCT failed derives
// from subd2nurbs::Error and says which kind it is. The front ends turn a kind into an exit code
// and a Python exception by one table (converter/pipeline/errors.h). Exceptions outside the
// family (std::invalid_argument and std::logic_error from a broken precondition, std::bad_alloc)
// are internal errors, never the user's.
#pragma once

#include <stdexcept>
#include <string>

namespace subd2nurbs {

enum class ErrorKind {
  Usage,      ///< a valid command line asking for something impossible (an output that is the input)
  Settings,   ///< a setting's value breaks its rule
  Resources,  ///< the estimate exceeds a resource limit
  Input,      ///< an unreadable, malformed or invalid input (a file, a cage)
  Fit,        ///< a fit cannot be solved (it names the vertices)
  Write,      ///< an output file cannot be written
  Export,     ///< OCCT failed or refused the B-rep
};

class Error : public std::runtime_error {
 public:
  Error(ErrorKind kind, const std::string& what) : std::runtime_error(what), kind_(kind) {}
  ErrorKind kind() const { return kind_; }

 private:
  ErrorKind kind_;
};

}  // namespace subd2nurbs
