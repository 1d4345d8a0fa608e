// libFuzzer target: the glTF / GLB reader (io/gltf_reader.h) with quad recovery, then
// validation. The first byte picks GLB (odd) or glTF JSON (even); external buffers are looked
// up in a directory that does not exist. InputError is an accepted outcome.
#include <cstddef>
#include <cstdint>
#include <string>

#include "io/gltf_reader.h"
#include "io/input_error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const bool binary = (data[0] & 1) != 0;
  const std::string bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
  try {
    const subd2nurbs::LoadedCage cage =
        subd2nurbs::parse_gltf(bytes, binary ? "fuzz.glb" : "fuzz.gltf", binary, "/nonexistent-fuzz-dir");
    subd2nurbs::validate_cage(cage);
  } catch (const subd2nurbs::InputError&) {
  }
  return 0;
}
