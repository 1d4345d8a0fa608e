#include "converter/pipeline/errors.h"

namespace subd2nurbs::pipeline {

const std::vector<ErrorClass>& error_classes() {
  static const std::vector<ErrorClass> table = {
      {ErrorKind::Usage, "usage", kExitUsage, "SettingsError"},
      {ErrorKind::Settings, "settings", kExitUsage, "SettingsError"},
      {ErrorKind::Resources, "resources", kExitUsage, "SettingsError"},
      {ErrorKind::Input, "input", kExitInvalidInput, "CageError"},
      {ErrorKind::Fit, "fit", kExitInvalidInput, "FitError"},
      {ErrorKind::Write, "write", kExitWriteFailure, "WriteError"},
      {ErrorKind::Export, "export", kExitInternalError, "ConversionError"},
  };
  return table;
}

const ErrorClass& error_class(ErrorKind kind) { return error_classes()[static_cast<size_t>(kind)]; }

ExitCode exit_code(const std::exception& e) {
  if (const auto* error = dynamic_cast<const Error*>(&e)) return error_class(error->kind()).exit_code;
  return kExitInternalError;
}

}  // namespace subd2nurbs::pipeline
