// Reading a subdivision cage from a Wavefront OBJ file with OpenSubdiv-style tags.
//
// Statements used: `v x y z` (vertex; extra values such as w or colours are ignored),
// `f a b c ...` (face; a/t/n and a//n forms and negative relative indices are accepted; texture
// and normal indices are ignored) and `t name nint/nfloat/nstring ints... floats... strings...`
// (tags, indices in tags are 0-based as in OpenSubdiv's regression shapes):
//
//   t crease 2/1/0 a b s           edge a-b gets sharpness s; with k > 2 ints the tag is a
//                                  chain a-b, b-c, ... and takes 1 sharpness or k-1 of them
//                                  (as RenderMan's crease; OpenSubdiv's regression loader
//                                  reads k > 2 ints as separate pairs instead)
//   t corner k/1/0 v... s          vertices get sharpness s (1 shared value or k values)
//   t interpolateboundary 1/0/0 i  0 none, 1 edge-and-corner (the default), 2 edge-only
//   t creasemethod 0/0/1 m         normal | chaikin
//   t smoothtriangles 0/0/1 r      catmark | smooth
//   t hole k/0/0 f...              faces that produce no surface
//
// Other tags (vertexedit, edgeedit, faceedit, facevaryinginterpolateboundary, ...) are
// ignored with a warning. Texture coordinates, normals, groups, materials and smoothing
// groups are ignored silently; unknown statements and line / point elements with a warning.
#pragma once

#include <string>
#include <vector>

#include "core/mesh/errors.h"
#include "core/mesh/mesh_input.h"
#include "core/mesh/poly_mesh.h"
#include "io/input_error.h"

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
};

/// Sets cage.input to the result of a quad recovery (core/mesh/quad_recovery.h) and
/// cage.recovery to its counts (glTF and the mesh readers; defined in io/mesh_reader.cpp).
struct QuadRecoveryResult;
void take_recovered_quads(LoadedCage& cage, QuadRecoveryResult&& result);

/// Reads an OBJ file. Topology is not validated yet (see validate_cage).
/// \throw InputError (naming the file and line) if the file cannot be read, a statement is
/// malformed, a face has fewer than 3 vertices or uses vertex index 0, or a tag is malformed
/// (code MeshErrorCode::InvalidTag).
/// Regular files only (io/input_file.h: a FIFO, directory or device is refused unread); a
/// UTF-8 byte-order mark is skipped, UTF-16 / UTF-32 text refused.
LoadedCage read_obj(const std::string& path);

/// The same from OBJ text in memory; `name` stands for the file in messages.
LoadedCage parse_obj(const std::string& text, const std::string& name);

/// Validates the cage (validate_and_build, core/mesh/validate.h) and returns its connectivity;
/// SubdivLevel::from_validated(mesh, cage.input) (core/refine/refiner.h) makes the base level.
/// Validation warnings (e.g. unused vertices) are appended to `diagnostics` if given; they
/// name mesh elements, use source_line() or format_diagnostic() to locate them.
/// \throw InputError with the MeshErrorCode of the problem and the line of the offending
/// face, vertex or tag: for an edge, the face that made it non-manifold; for inconsistent
/// orientation, the later of the two faces.
PolyMesh validate_cage(const LoadedCage& cage, Diagnostics* diagnostics = nullptr);

/// The source line a diagnostic refers to, or 0 if it cannot be located.
int source_line(const LoadedCage& cage, const Diagnostic& diagnostic);

/// "FILE:LINE: warning: message" (or "FILE: warning: message").
std::string format_diagnostic(const LoadedCage& cage, const Diagnostic& diagnostic);

}  // namespace subd2nurbs
