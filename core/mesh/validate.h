// Input validation that needs more than connectivity: coordinates and tags.
#pragma once

#include "core/mesh/mesh_input.h"
#include "core/mesh/poly_mesh.h"

namespace subd2nurbs {

/// Validates a MeshInput completely and returns its connectivity.
/// Order of checks (the first failure is thrown): empty mesh, non-finite coordinates,
/// face sizes / indices / repeats, non-manifold edges, orientation, non-manifold vertices,
/// then tags (crease edges that do not exist, corner vertices / hole faces out of range,
/// negative or non-finite sharpness).
/// \throw InvalidMeshError
PolyMesh validate_and_build(const MeshInput& input, Diagnostics* diagnostics = nullptr);

}  // namespace subd2nurbs
