// libFuzzer target: the USD crate reader (io/usd_crate.cpp: bootstrap, table of contents,
// LZ4 and integer-coded sections, paths, specs, value reps) and the usdz package (first byte
// odd: the input is wrapped as a stored zip entry), then the composition, the mesh mapping and
// validation. Limits are lower than the front ends' (1e4 specs, 1e6 values). InputError is an
// accepted outcome.
#include <cstddef>
#include <cstdint>
#include <string>

#include "io/input_error.h"
#include "io/obj_reader.h"
#include "io/usd_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const bool zip = (data[0] & 1) != 0;
  std::string crate = "PXR-USDC";
  crate.append(reinterpret_cast<const char*>(data) + 1, size - 1);
  std::string bytes = crate;
  if (zip) {  // a local file header: stored, sizes, the name "a.usdc"
    bytes = std::string("PK\x03\x04", 4) + std::string(14, '\0');
    const std::uint32_t n = static_cast<std::uint32_t>(crate.size());
    bytes.append(reinterpret_cast<const char*>(&n), 4).append(reinterpret_cast<const char*>(&n), 4);
    bytes += std::string("\x06\0\0\0", 4) + "a.usdc" + crate;
  }
  subd2nurbs::UsdReadOptions options;
  options.limits.max_prims = 10000;
  options.limits.max_values = 1000000;
  options.limits.max_depth = 64;
  options.limits.max_expanded_prims = 20000;
  try {
    const subd2nurbs::LoadedCage cage = subd2nurbs::parse_usd(bytes, zip ? "fuzz.usdz" : "fuzz.usdc", options);
    subd2nurbs::Diagnostics diagnostics;
    subd2nurbs::validate_cage(cage, &diagnostics);
    for (const subd2nurbs::Diagnostic& d : cage.diagnostics) subd2nurbs::format_diagnostic(cage, d);
  } catch (const subd2nurbs::InputError&) {
  }
  return 0;
}
