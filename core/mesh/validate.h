// Input validation that needs more than connectivity: coordinates and tags.
#pragma once

#include "core/mesh/mesh_input.h"
#include "core/mesh/poly_mesh.h"

namespace subd2nurbs {

/// Largest |coordinate| accepted. Beyond it the B-rep cannot be built reliably: OCCT treats
/// values near 1e100 as infinite (Precision::Infinite) and its absolute tolerances
/// (1e-7) fall below the spacing of doubles (see README, "Limits"); and every later
/// computation (squared distances, curvatures, which raise coordinates to the 4th power)
/// stays finite.
constexpr double kMaxCoordinate = 1e15;
/// Most vertices of one face. An n-gon becomes a level-1 vertex of valence n, so this is
/// the valence limit as well.
constexpr int kMaxFaceSize = 1024;
/// Most edges around one vertex. Stam's eigenbases (core/limit) exist up to 1024; the patch
/// builder's work per extraordinary vertex grows with the cube of the valence.
constexpr int kMaxValence = 1024;

/// A corner's sector (core/mesh/corner_sectors.h) wider than this, measured on the cage, gets a
/// "concave-corner" diagnostic: above 180 degrees the corner rule folds it; the margin keeps a
/// T-junction's 180 (a crease ending on another) quiet.
constexpr double kFoldingSectorDegrees = 190;

/// Validates a MeshInput completely and returns its connectivity.
/// Order of checks (the first failure is thrown): empty mesh, non-finite coordinates,
/// coordinates beyond +-kMaxCoordinate, faces larger than kMaxFaceSize, face sizes /
/// indices / repeats, vertices of valence above kMaxValence, non-manifold edges, orientation, non-manifold vertices,
/// then tags (crease edges that do not exist, corner vertices / hole faces out of range,
/// negative or non-finite sharpness). Diagnostics (when asked for): unused vertices, corners
/// with a sector wider than kFoldingSectorDegrees.
/// \throw InvalidMeshError
PolyMesh validate_and_build(const MeshInput& input, Diagnostics* diagnostics = nullptr);

}  // namespace subd2nurbs
