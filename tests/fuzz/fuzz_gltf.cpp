// libFuzzer target: the glTF / GLB reader (io/gltf_reader.h) with quad recovery, then
// validation. The first byte picks GLB (odd) or glTF JSON (even); external buffers are looked
// up in a directory that does not exist. InputError is an accepted outcome.
//
// Instancing is capped lower than in the front ends (GltfLimits: 1 000 node instances, 20 000
// triangles instead of 1e5 and 2e7): the code paths are the same, but a few bytes of nodes
// no longer expand into millions of triangles whose quad recovery took most of the fuzzing time.
#include <cstddef>
#include <cstdint>
#include <string>

#include "io/gltf_reader.h"
#include "io/input_error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const bool binary = (data[0] & 1) != 0;
  const std::string bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
  subd2nurbs::GltfLimits limits;
  limits.node_instances = 1000;
  limits.instanced_triangles = 20000;
  try {
    const subd2nurbs::LoadedCage cage = subd2nurbs::parse_gltf(
        bytes, binary ? "fuzz.glb" : "fuzz.gltf", binary, "/nonexistent-fuzz-dir", limits);
    subd2nurbs::validate_cage(cage);
  } catch (const subd2nurbs::InputError&) {
  }
  return 0;
}
