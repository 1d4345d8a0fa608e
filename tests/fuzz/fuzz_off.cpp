// libFuzzer target: the OFF reader (io/mesh_reader.h: parse_off) with its repairs (welding,
// degenerate and duplicate faces, orientation, quad recovery), then validation. Any
// InputError is an accepted outcome; a crash, a sanitizer report, a leak or an uncaught
// exception of another type is a finding.
#include <cstddef>
#include <cstdint>
#include <string>

#include "io/input_error.h"
#include "io/mesh_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
    const subd2nurbs::LoadedCage cage = subd2nurbs::parse_off(bytes, "fuzz.off");
    subd2nurbs::Diagnostics diagnostics;
    subd2nurbs::validate_cage(cage, &diagnostics);
    for (const subd2nurbs::Diagnostic& d : cage.diagnostics) subd2nurbs::format_diagnostic(cage, d);
    for (const subd2nurbs::Diagnostic& d : diagnostics) subd2nurbs::format_diagnostic(cage, d);
  } catch (const subd2nurbs::InputError&) {
  }
  return 0;
}
