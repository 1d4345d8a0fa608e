#include "converter/pipeline/input.h"

#include "io/cage_reader.h"

namespace subd2nurbs::pipeline {

LoadedInput load_input(const std::string& path, const UsdReadOptions& usd) {
  LoadedInput result;
  result.cage = read_cage(path, {}, usd);
  Diagnostics validation;
  result.level = SubdivLevel::from_validated(validate_cage(result.cage, &validation), result.cage.input);
  for (const Diagnostic& d : result.cage.diagnostics) result.warnings.push_back(format_diagnostic(result.cage, d));
  for (const Diagnostic& d : validation) result.warnings.push_back(format_diagnostic(result.cage, d));
  return result;
}

}  // namespace subd2nurbs::pipeline
