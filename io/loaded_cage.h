// A cage as every reader returns it (OBJ, glTF, STL, PLY, OFF, USD: io/cage_reader.h): the mesh input
// with the file position of each element, the reader's warnings and what it repaired or recovered.
#pragma once

#include <string>
#include <vector>

#include "core/mesh/errors.h"
#include "core/mesh/mesh_input.h"

namespace subd2nurbs {

/// A cage as read from a file, with the source line (1-based) of every element so that
/// later errors can point back into the file.
struct LoadedCage {
  MeshInput input;
  std::string path;
  std::vector<int> vertex_line;  ///< per vertex
  std::vector<int> face_line;    ///< per face
  std::vector<int> crease_line;  ///< per entry of input.creases (a chain gives several)
  std::vector<int> corner_line;  ///< per entry of input.corners
  std::vector<int> hole_line;    ///< per entry of input.holes
  /// Warnings found while reading. They concern a line of the file rather than a mesh
  /// element, so their `element` is ElementKind::None and their `index` is the line number.
  Diagnostics diagnostics;
  /// What vertex_line / face_line hold. Line: 1-based source lines (OBJ, ASCII STL, ASCII PLY,
  /// OFF). Element: binary STL and binary PLY have no lines; there they hold the 1-based number
  /// of the file's element (binary STL: the facet, for a vertex the first facet that used it;
  /// binary PLY: the vertex or face element), and messages name "facet N" / "face N" /
  /// "vertex N" with the file's own 0-based N instead of a line.
  enum class Locator { Line, Element } locator = Locator::Line;
  /// Element names in messages for Locator::Element: "facet" for STL's faces and vertices (a
  /// vertex is named by the first facet that used it), "face" and "vertex" for PLY's.
  std::string face_unit = "face", vertex_unit = "vertex";
  /// Set when the file holds triangles only (glTF, io/gltf_reader.h) and quads were recovered
  /// from triangle pairs (core/mesh/quad_recovery.h).
  struct QuadRecovery {
    bool applied = false;
    int source_triangles = 0;  ///< triangles in the file (after welding)
    int quads = 0;             ///< quads recovered from two triangles each
    int triangles_kept = 0;    ///< triangles left as they were
    int fan_vertices = 0;      ///< fan (polar candidate) vertices whose triangles were kept
    int fan_triangles = 0;     ///< of triangles_kept, those kept because they belong to a fan
  } recovery;
  /// What the mesh readers (STL, PLY, OFF: io/mesh_reader.h) repaired; `applied` is false for
  /// OBJ and glTF, which are taken as they are (glTF welds exact duplicates only).
  struct MeshRepair {
    bool applied = false;
    int file_vertices = 0;        ///< vertices in the file (STL: 3 per facet)
    int file_faces = 0;           ///< faces (facets) in the file
    double weld_tolerance = 0;    ///< the absolute tolerance used (model units)
    int vertices_merged = 0;      ///< file vertices welded onto an earlier one
    int vertices_merged_near = 0; ///< of those, the ones at a different position (cracks closed)
    int unused_vertices = 0;      ///< vertices (after welding) no kept face uses: removed
    int degenerate_faces = 0;     ///< faces that collapsed to fewer than 3 vertices: dropped
    int duplicate_faces = 0;      ///< faces with the vertex set of an earlier face: dropped
    int faces_flipped = 0;        ///< faces reversed to agree with their neighbours
    int components = 0;           ///< connected components (through edges)
    int closed_components = 0;    ///< components without boundary edges
    int components_reversed = 0;  ///< closed components turned inside out to face outward
    /// The file's faces were all triangles. With recovery.applied, every quad of the cage
    /// is then two of the file's triangles, (q0, q1, q2) and (q2, q3, q0), so a later stage
    /// may split them back (mesh path) instead of taking the quads as a cage.
    bool triangles_only = false;
    /// Vertices and no faces (a PLY or OFF point cloud): the cage has the points, no faces,
    /// and validate_cage refuses it as empty.
    bool point_cloud = false;
  } repair;
  /// What the USD reader (io/usd_reader.h) read; `applied` is false for the other formats.
  struct UsdInfo {
    bool applied = false;
    std::string encoding;        ///< "usda", "usdc", "usdz/usda", "usdz/usdc"
    std::string version;         ///< "1.0" (text) or the crate's "0.8.0"
    double meters_per_unit = 0;  ///< 0: not authored (USD's fallback is 0.01)
    std::string up_axis;         ///< "Y", "Z", or "" when not authored (USD's fallback is Y)
    struct Mesh {
      std::string path;    ///< the prim path, "/Pyramid/geo/shape"
      std::string scheme;  ///< "catmullClark", "bilinear", "none", "loop"
      int vertices = 0, faces = 0, creases = 0, corners = 0, holes = 0;
    };
    std::vector<Mesh> meshes;  ///< in the cage's order: each mesh's vertices and faces follow the previous one's
    struct VariantSet {
      std::string prim;                   ///< the prim path
      std::string name;                   ///< the variant set
      std::string selection;              ///< the variant used ("" when the selection names none)
      std::vector<std::string> variants;  ///< every variant the set offers
    };
    std::vector<VariantSet> variant_sets;
  } usd;
};

}  // namespace subd2nurbs
