// The error type of the OCCT front end.
#pragma once

#include <stdexcept>
#include <string>
#include <utility>

#include "core/util/error.h"

namespace subd2nurbs::occt {

/// Building or writing the B-rep failed inside OCCT (or the PatchSet could not be turned into
/// OCCT geometry). what() is "STAGE (patch P): MESSAGE", or "STAGE: MESSAGE" when no single
/// patch is at fault (patch == -1).
struct ExportError : Error {
  ExportError(std::string stage_, int patch_, std::string message_)
      : Error(ErrorKind::Export, format(stage_, patch_, message_)), stage(std::move(stage_)),
        patch(patch_), message(std::move(message_)) {}

  std::string stage;    ///< e.g. "surface", "edge", "face", "solid", "check", "step-write"
  int patch = -1;       ///< PatchSet::patches index, or -1
  std::string message;  ///< OCCT's message (Standard_Failure::GetMessageString) or ours

 private:
  static std::string format(const std::string& stage, int patch, const std::string& message) {
    return patch >= 0 ? stage + " (patch " + std::to_string(patch) + "): " + message
                      : stage + ": " + message;
  }
};

}  // namespace subd2nurbs::occt
