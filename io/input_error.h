// The error of an input file. Every message names the file and, where there is one, the line,
// in the "FILE:LINE: message" form that editors and terminals recognise. (An output's error is
// WriteError, io/write_error.h, included here for the callers that catch both.)
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/mesh/errors.h"
#include "core/util/error.h"
#include "io/input_file.h"
#include "io/write_error.h"

namespace subd2nurbs {

/// An input file could not be read, or its content is not a valid cage.
/// what() is "FILE:LINE: message", or "FILE: message" when no single line is at fault
/// (an unreadable or empty file).
class InputError : public Error {
 public:
  InputError(std::string file, int line, std::string message,
             std::optional<MeshErrorCode> code = std::nullopt)
      : Error(ErrorKind::Input, format(file, line, message)), file_(std::move(file)), line_(line),
        message_(std::move(message)), code_(code) {}

  const std::string& file() const { return file_; }
  /// 1-based line number, or 0 when the error is not about one line.
  int line() const { return line_; }
  /// "FILE:LINE" (or "FILE"), the name made printable and shortened (io/input_file.h).
  std::string location() const {
    return line_ > 0 ? printable(file_) + ":" + std::to_string(line_) : printable(file_);
  }
  /// The message without the "FILE:LINE: " prefix.
  const std::string& message() const { return message_; }
  /// Why the cage is invalid, when it is a validation problem (malformed tags count as
  /// MeshErrorCode::InvalidTag). Empty for I/O failures and OBJ syntax errors.
  std::optional<MeshErrorCode> code() const { return code_; }

 private:
  static std::string format(const std::string& file, int line, const std::string& message) {
    const std::string name = printable(file);
    return line > 0 ? name + ":" + std::to_string(line) + ": " + message : name + ": " + message;
  }

  std::string file_;
  int line_;
  std::string message_;
  std::optional<MeshErrorCode> code_;
};

}  // namespace subd2nurbs
