// The error of an output file that cannot be written: the file front end's other error, beside
// InputError (io/input_error.h).
#pragma once

#include <string>
#include <utility>

#include "core/util/error.h"
#include "io/input_file.h"

namespace subd2nurbs {

/// An output file could not be written. what() is "FILE: message".
class WriteError : public Error {
 public:
  WriteError(std::string file, std::string message)
      : Error(ErrorKind::Write, printable(file) + ": " + message), file_(std::move(file)),
        message_(std::move(message)) {}

  const std::string& file() const { return file_; }
  const std::string& message() const { return message_; }

 private:
  std::string file_;
  std::string message_;
};

}  // namespace subd2nurbs
