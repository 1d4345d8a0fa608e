#include "converter/pipeline/input.h"

#include "io/cage_reader.h"

#include <utility>

namespace subd2nurbs::pipeline {

LoadedInput load_input(const std::string& path, const UsdReadOptions& usd) {
  return load_input(read_cage(path, {}, usd));
}

LoadedInput load_input(LoadedCage cage) {
  LoadedInput result;
  result.cage = std::move(cage);
  Diagnostics validation;
  result.level = SubdivLevel::from_validated(validate_cage(result.cage, &validation), result.cage.input);
  for (const Diagnostic& d : result.cage.diagnostics) result.warnings.push_back(format_diagnostic(result.cage, d));
  for (const Diagnostic& d : validation) result.warnings.push_back(format_diagnostic(result.cage, d));
  return result;
}

}  // namespace subd2nurbs::pipeline
