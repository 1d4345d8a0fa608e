// Sharp features of a triangle (or polygon) mesh: dihedral-angle edges, open boundaries and
// user-tagged creases, grouped into chains between corners; short isolated chains dropped as
// noise. Used by the quad remesher (core/remesh) to align and constrain the cage.
#pragma once

#include <array>
#include <vector>

#include "core/mesh/mesh_input.h"

namespace subd2nurbs {

struct FeatureOptions {
  double angle_degrees = 30.0;   ///< an edge is sharp when the angle between its faces' normals exceeds this
  int min_chain_edges = 3;       ///< open feature chains with fewer edges, not touching other features or the boundary, are dropped as noise
  double corner_angle_degrees = 60.0;  ///< a chain vertex where the chain turns more than this is a corner
};

struct FeatureSet {
  std::vector<std::array<int, 2>> edges;  ///< feature edges (vertex pairs, v0 < v1), sorted; boundary edges included
  std::vector<int> corners;               ///< vertices where the feature graph has degree != 2, or turns sharply; sorted
  int chains = 0;                         ///< feature curves (maximal chains between corners, or closed loops)
  int dropped_short_chains = 0;
};

/// Features of a triangle (or polygon) mesh. Polygons are fan-triangulated for the normals;
/// only the polygons' own edges can be features. Creases in mesh.creases with sharpness >=
/// kInfiniteSharpness are user-tagged features and always kept. The mesh must be manifold
/// (every edge on at most two faces); \throw Error(ErrorKind::Input) otherwise.
FeatureSet detect_features(const MeshInput& mesh, const FeatureOptions& options = {});

}  // namespace subd2nurbs
