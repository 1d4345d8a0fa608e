// Reading a cage from any supported file, chosen by the extension (case-insensitive):
//   .obj            OBJ with OpenSubdiv tags (io/obj_reader.h)
//   .gltf / .glb    glTF 2.0 with quad recovery (io/gltf_reader.h)
//   .stl / .ply / .off   meshes, welded and repaired, quads recovered from all-triangle
//                   files (io/mesh_reader.h)
//   anything else   read as OBJ
#pragma once

#include <string>

#include "io/mesh_reader.h"
#include "io/obj_reader.h"

namespace subd2nurbs {

/// Reads a cage by extension (see the file comment). `options` apply to STL, PLY and OFF.
/// \throw InputError naming the file (and line or element) if it cannot be read.
LoadedCage read_cage(const std::string& path, const MeshReadOptions& options = {});

}  // namespace subd2nurbs
