// Reading polygon meshes from STL (binary and ASCII), PLY (ASCII, binary little / big endian)
// and OFF as cages (issue #27, "Fit to a shape"). These formats carry positions and faces only:
// no creases, corners or holes.
//
// Every file goes through the same repairs (io/mesh_reader.cpp), counted in
// LoadedCage::repair:
//  1. welding: vertices closer than the weld tolerance merge into the first of them (spatial
//     hashing). STL is a triangle soup and needs it; PLY and OFF are indexed but are welded
//     too, which closes cracks narrower than the tolerance. The tolerance is
//     MeshReadOptions::weld_tolerance (default 1e-7) times the bounding-box diagonal, and never
//     more than MeshReadOptions::max_weld_edge_fraction (1/10) of the shortest non-zero edge
//     of the file, so no real edge collapses;
//  2. faces that collapse after welding (fewer than 3 distinct vertices) are dropped, as are
//     faces with the same vertex set as an earlier face; vertices no face uses are removed;
//  3. orientation: faces are made consistent per connected component (breadth-first over
//     edges with two faces, the minority of each component reversed) and closed components
//     turned to face outward (signed volume > 0). An edge of three or more faces and a
//     non-orientable component (a Moebius strip) are errors naming the face: nothing is
//     guessed;
//  4. quad recovery, only when every face of the file is a triangle: triangle pairs that form
//     reasonable quads become quads, with the rules glTF uses (core/mesh/quad_recovery.h);
//     LoadedCage::repair.triangles_only says so, so a later stage can undo it. A file with
//     quads or other polygons is taken as it is.
//
// Locations: ASCII STL, ASCII PLY and OFF give each vertex and face its source line; binary
// STL and PLY the element number (LoadedCage::Locator). Facet normals, colours, normals,
// texture coordinates and other properties or elements are ignored.
#pragma once

#include <string>

#include "io/obj_reader.h"

namespace subd2nurbs {

struct MeshReadOptions {
  /// Weld tolerance relative to the bounding-box diagonal of the file's vertices.
  /// 0 welds exactly equal positions only.
  double weld_tolerance = 1e-7;
  /// The absolute tolerance is at most this fraction of the shortest non-zero edge of the
  /// file's faces (before welding), so that no edge of the model collapses.
  double max_weld_edge_fraction = 0.1;
  /// Pair triangles into quads when every face of the file is a triangle.
  bool recover_quads = true;
  /// Most vertices and most faces a file may announce (counts beyond are refused before
  /// anything is allocated; counts are also checked against the bytes present).
  long max_elements = 100000000;
};

/// STL, binary or ASCII. Binary when the file's size is exactly 84 + 50 n, n the facet count
/// in bytes 80..83 (whatever the 80-byte header says: binary files whose header starts with
/// "solid" exist, as do "COLOR=" / "MATERIAL=" headers, which are ignored with the attribute
/// bytes); otherwise ASCII (`solid name` ... `endsolid name`, several solids, any whitespace).
/// \throw InputError naming the file and the line (ASCII) or facet (binary).
LoadedCage read_stl(const std::string& path, const MeshReadOptions& options = {});
LoadedCage parse_stl(const std::string& bytes, const std::string& name, const MeshReadOptions& options = {});

/// PLY 1.0: ascii, binary_little_endian, binary_big_endian. Element `vertex` with scalar
/// properties x, y, z (any scalar type); element `face` with the list `vertex_indices` (or
/// `vertex_index`). Other properties and elements are skipped. No faces: a point cloud
/// (LoadedCage::repair.point_cloud).
LoadedCage read_ply(const std::string& path, const MeshReadOptions& options = {});
LoadedCage parse_ply(const std::string& bytes, const std::string& name, const MeshReadOptions& options = {});

/// OFF (also COFF, NOFF, CNOFF, STOFF and combinations): the keyword alone or followed by the
/// counts, `#` comments anywhere, one vertex per line (values after x y z ignored), one face
/// per line (`n i0 ... in-1`, values after the indices ignored), polygons of any size.
LoadedCage read_off(const std::string& path, const MeshReadOptions& options = {});
LoadedCage parse_off(const std::string& bytes, const std::string& name, const MeshReadOptions& options = {});

}  // namespace subd2nurbs
