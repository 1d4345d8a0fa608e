// MeshInput: the plain-array form in which every front end hands a cage to the core.
// No logic lives here beyond the options' names; PolyMesh::build and validate() check it.
#pragma once

#include <array>
#include <vector>

namespace subd2nurbs {

/// Sharpness at or above this value is infinitely sharp (OpenSubdiv's convention).
constexpr double kInfiniteSharpness = 10.0;

/// How boundary vertices and edges are interpolated (OpenSubdiv `VtxBoundaryInterpolation`).
enum class BoundaryRule {
  None,           ///< boundary edges sharp, but faces touching the boundary produce no surface
  EdgeOnly,       ///< boundary edges infinitely sharp
  EdgeAndCorner,  ///< as EdgeOnly, and vertices with a single face are corners (default)
};

/// How semi-sharp crease sharpness decays under refinement.
enum class CreaseMethod { Uniform, Chaikin };

/// Edge rule next to triangles: standard Catmull-Clark, or OpenSubdiv's TRI_SUB_SMOOTH.
enum class TriangleRule { Catmark, Smooth };

/// The options' names, as `info` and the Python module give them: "none", "edge-only",
/// "edge-and-corner"; "uniform", "chaikin"; "catmark", "smooth".
const char* to_string(BoundaryRule rule);
const char* to_string(CreaseMethod method);
const char* to_string(TriangleRule rule);

struct SubdivOptions {
  BoundaryRule boundary = BoundaryRule::EdgeAndCorner;
  CreaseMethod crease_method = CreaseMethod::Uniform;
  TriangleRule triangles = TriangleRule::Catmark;
};

struct CreaseTag {
  int v0 = -1, v1 = -1;   ///< the edge's end vertices (0-based)
  double sharpness = 0;   ///< >= kInfiniteSharpness means infinitely sharp
};

struct CornerTag {
  int vertex = -1;
  double sharpness = 0;
};

/// A polygon cage as plain arrays. Faces are given as a size list plus a flat index list,
/// counter-clockwise seen from outside.
struct MeshInput {
  std::vector<std::array<double, 3>> positions;
  std::vector<int> face_sizes;
  std::vector<int> face_indices;
  std::vector<CreaseTag> creases;
  std::vector<CornerTag> corners;
  std::vector<int> holes;  ///< faces that produce no surface
  SubdivOptions options;

  int num_vertices() const { return static_cast<int>(positions.size()); }
  int num_faces() const { return static_cast<int>(face_sizes.size()); }
};

}  // namespace subd2nurbs
