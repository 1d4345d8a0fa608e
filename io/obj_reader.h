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
#include "io/loaded_cage.h"

namespace subd2nurbs {

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
