#include "core/util/number_text.h"
#include "core/mesh/validate.h"

#include "core/mesh/corner_sectors.h"

#include <cmath>
#include <cstdio>
#include <string>

namespace subd2nurbs {

namespace {
bool valid_sharpness(double s) { return std::isfinite(s) && s >= 0.0; }
std::string number_text(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", x);
  return buffer;
}
}  // namespace

PolyMesh validate_and_build(const MeshInput& input, Diagnostics* diagnostics) {
  const int nv = input.num_vertices();
  if (nv == 0 || input.num_faces() == 0)
    throw InvalidMeshError(MeshErrorCode::EmptyMesh, ElementKind::None, -1, -1,
                           "mesh is empty (" + std::to_string(nv) + " vertices, " +
                               std::to_string(input.num_faces()) + " faces)");
  for (int v = 0; v < nv; ++v)
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(input.positions[v][k]))
        throw InvalidMeshError(MeshErrorCode::NonFiniteCoordinate, ElementKind::Vertex, v, k,
                               "vertex " + std::to_string(v) + " has a non-finite coordinate (" +
                                   "xyz"[k] + " = " + std::to_string(input.positions[v][k]) + ")");

  for (int v = 0; v < nv; ++v)
    for (int k = 0; k < 3; ++k)
      if (std::fabs(input.positions[v][k]) > kMaxCoordinate)
        throw InvalidMeshError(MeshErrorCode::CoordinateOutOfRange, ElementKind::Vertex, v, k,
                               "vertex " + std::to_string(v) + " has " + "xyz"[k] + " = " +
                                   exact_number_text(input.positions[v][k]) +
                                   ", beyond the coordinate limit +-" + number_text(kMaxCoordinate));
  for (int f = 0; f < input.num_faces(); ++f)
    if (input.face_sizes[f] > kMaxFaceSize)
      throw InvalidMeshError(MeshErrorCode::FaceTooLarge, ElementKind::Face, f, input.face_sizes[f],
                             "face " + std::to_string(f) + " has " + std::to_string(input.face_sizes[f]) +
                                 " vertices; at most " + std::to_string(kMaxFaceSize) + " are supported");

  PolyMesh mesh = PolyMesh::build(nv, input.face_sizes, input.face_indices, diagnostics);

  for (int v = 0; v < nv; ++v)
    if (mesh.valence(v) > kMaxValence)
      throw InvalidMeshError(MeshErrorCode::ValenceTooHigh, ElementKind::Vertex, v, mesh.valence(v),
                             "vertex " + std::to_string(v) + " has valence " + std::to_string(mesh.valence(v)) +
                                 "; at most " + std::to_string(kMaxValence) + " is supported");

  for (size_t i = 0; i < input.creases.size(); ++i) {
    const CreaseTag& c = input.creases[i];
    if (mesh.find_edge(c.v0, c.v1) < 0)
      throw InvalidMeshError(MeshErrorCode::InvalidTag, ElementKind::Tag, static_cast<long>(i), -1,
                             "crease tag " + std::to_string(i) + " names edge (" +
                                 std::to_string(c.v0) + ", " + std::to_string(c.v1) +
                                 "), which is not an edge of the mesh");
    if (!valid_sharpness(c.sharpness))
      throw InvalidMeshError(MeshErrorCode::InvalidTag, ElementKind::Tag, static_cast<long>(i), -1,
                             "crease tag " + std::to_string(i) + " has invalid sharpness " +
                                 std::to_string(c.sharpness));
  }
  for (size_t i = 0; i < input.corners.size(); ++i) {
    const CornerTag& c = input.corners[i];
    if (c.vertex < 0 || c.vertex >= nv)
      throw InvalidMeshError(MeshErrorCode::InvalidTag, ElementKind::Tag, static_cast<long>(i), -1,
                             "corner tag " + std::to_string(i) + " names vertex " +
                                 std::to_string(c.vertex) + ", but the mesh has " +
                                 std::to_string(nv) + " vertices");
    if (!valid_sharpness(c.sharpness))
      throw InvalidMeshError(MeshErrorCode::InvalidTag, ElementKind::Tag, static_cast<long>(i), -1,
                             "corner tag " + std::to_string(i) + " has invalid sharpness " +
                                 std::to_string(c.sharpness));
  }
  for (size_t i = 0; i < input.holes.size(); ++i)
    if (input.holes[i] < 0 || input.holes[i] >= mesh.num_faces())
      throw InvalidMeshError(MeshErrorCode::InvalidTag, ElementKind::Tag, static_cast<long>(i), -1,
                             "hole tag names face " + std::to_string(input.holes[i]) +
                                 ", but the mesh has " + std::to_string(mesh.num_faces()) +
                                 " faces");
  // Corners whose sectors the corner rule folds (core/mesh/corner_sectors.h): wider than 180
  // degrees, with a margin for the cage's angles standing for the limit's.
  if (diagnostics)
    for (const CornerSector& s : wide_corner_sectors(input, kFoldingSectorDegrees))
      diagnostics->push_back({"concave-corner", ElementKind::Vertex, s.corner,
                              "vertex " + std::to_string(s.corner) + " is a corner whose " + std::to_string(s.faces) +
                                  (s.faces == 1 ? " face" : " faces") + " between two sharp edges span " +
                                  number_text(std::round(s.degrees)) +
                                  " degrees: the corner rule folds the surface over itself there (near the corner "
                                  "its faces lie on each other, facing the wrong way); infinitely sharp creases on "
                                  "edges inside that sector, from the corner, until none spans more than 180 "
                                  "degrees, keep it flat"});
  return mesh;
}

}  // namespace subd2nurbs
