// libFuzzer target: the STL reader (parse_stl, io/mesh_reader.h); see mesh_reader_target.h.
#include "mesh_reader_target.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return subd2nurbs::fuzz::run_mesh_reader(&subd2nurbs::parse_stl, "fuzz.stl", data, size);
}
