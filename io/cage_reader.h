// Reading a cage from any supported file, chosen by the extension (case-insensitive):
//   .obj            OBJ with OpenSubdiv tags (io/obj_reader.h)
//   .gltf / .glb    glTF 2.0 with quad recovery (io/gltf_reader.h)
//   .stl / .ply / .off   meshes, welded and repaired, quads recovered from all-triangle
//                   files (io/mesh_reader.h)
//   .usd / .usda / .usdc / .usdz   USD subdivision meshes with creases, corners and holes
//                   (io/usd_reader.h); the encoding is taken from the content
//   anything else   USD when the content is ("#usda", "PXR-USDC"); refused as "not a format
//                   subd2nurbs reads" for the extensions of other 3D / CAD formats and for
//                   binary content (NUL bytes at the start); otherwise read as OBJ
#pragma once

#include <string>

#include "io/mesh_reader.h"
#include "io/obj_reader.h"
#include "io/usd_reader.h"

namespace subd2nurbs {

/// The reader a path's extension (case-insensitive) selects; Other: by content (USD, else OBJ)
/// or refused (read_cage).
enum class CageFormat { Obj, Gltf, Stl, Ply, Off, Usd, Other };
CageFormat cage_format(const std::string& path);

/// STL, PLY or OFF: the mesh formats MeshReadOptions apply to (welded, repaired, quads recovered).
inline bool is_mesh_format(CageFormat f) { return f == CageFormat::Stl || f == CageFormat::Ply || f == CageFormat::Off; }

/// Reads a cage by extension (see the file comment). `options` apply to STL, PLY and OFF,
/// `usd` to USD files.
/// \throw InputError naming the file (and line or element) if it cannot be read.
LoadedCage read_cage(const std::string& path, const MeshReadOptions& options = {}, const UsdReadOptions& usd = {});

}  // namespace subd2nurbs
