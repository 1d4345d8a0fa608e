// The body of the mesh readers' libFuzzer targets (fuzz_stl, fuzz_ply, fuzz_off): one
// parse_* function (io/mesh_reader.h) with its repairs (welding, degenerate and duplicate
// faces, orientation, quad recovery), then validation and the diagnostics' formatting. Any
// InputError is an accepted outcome; a crash, a sanitizer report, a leak or an uncaught
// exception of another type is a finding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "io/input_error.h"
#include "io/mesh_reader.h"

namespace subd2nurbs::fuzz {

using MeshParser = LoadedCage (*)(const std::string&, const std::string&, const MeshReadOptions&);

inline int run_mesh_reader(MeshParser parse, const char* name, const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
    const LoadedCage cage = parse(bytes, name, MeshReadOptions{});
    Diagnostics diagnostics;
    validate_cage(cage, &diagnostics);
    for (const Diagnostic& d : cage.diagnostics) format_diagnostic(cage, d);
    for (const Diagnostic& d : diagnostics) format_diagnostic(cage, d);
  } catch (const InputError&) {
  }
  return 0;
}

}  // namespace subd2nurbs::fuzz
