// libFuzzer target: the USD text reader (io/usd_reader.h, io/usda_parser.cpp) with its
// composition (variants, references, transforms) and mesh mapping, then validation and the
// diagnostics' formatting. Limits are lower than the front ends' (1e4 specs, 1e6 values, depth
// 64): the code paths are the same. InputError is an accepted outcome.
#include <cstddef>
#include <cstdint>
#include <string>

#include "io/input_error.h"
#include "io/obj_reader.h"
#include "io/usd_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // The text reader is chosen by content: make every input text (a crate or zip start would
  // send it to the other targets' code).
  std::string bytes = "#usda 1.0\n";
  bytes.append(reinterpret_cast<const char*>(data), size);
  subd2nurbs::UsdReadOptions options;
  options.limits.max_prims = 10000;
  options.limits.max_values = 1000000;
  options.limits.max_depth = 64;
  options.limits.max_expanded_prims = 20000;
  try {
    const subd2nurbs::LoadedCage cage = subd2nurbs::parse_usd(bytes, "fuzz.usda", options);
    subd2nurbs::Diagnostics diagnostics;
    subd2nurbs::validate_cage(cage, &diagnostics);
    for (const subd2nurbs::Diagnostic& d : cage.diagnostics) subd2nurbs::format_diagnostic(cage, d);
  } catch (const subd2nurbs::InputError&) {
  }
  return 0;
}
