#include "io/cage_reader.h"

#include "io/gltf_reader.h"
#include "io/input_file.h"

namespace subd2nurbs {

LoadedCage read_cage(const std::string& path, const MeshReadOptions& options) {
  const std::string ext = lowercase_extension(path);
  if (ext == ".glb" || ext == ".gltf") return read_gltf(path);
  if (ext == ".stl") return read_stl(path, options);
  if (ext == ".ply") return read_ply(path, options);
  if (ext == ".off") return read_off(path, options);
  return read_obj(path);
}

}  // namespace subd2nurbs
