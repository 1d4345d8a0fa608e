// Reading a subdivision cage from glTF 2.0 (.gltf with its buffers, or binary .glb).
//
// glTF stores triangles only, so the cage is rebuilt: every triangle primitive (mode 4) of
// every mesh instanced in the scene (the default scene, else the first, else every mesh
// once), with node transforms applied; vertices welded where their transformed positions
// are identical (exporters split vertices at normal and UV seams); then triangle pairs made
// into quads where they form reasonable quads (core/mesh/quad_recovery.h), triangle fans
// around high-valence vertices kept. LoadedCage::recovery says how many quads came back.
// Attributes other than POSITION, materials and animations are ignored.
#pragma once

#include <string>

#include "io/cage_reader.h"  // read_cage, which moved there
#include "io/obj_reader.h"

namespace subd2nurbs {

/// How far node instancing may expand a scene. The defaults are the limits of every front end;
/// smaller ones serve tests and fuzzing, where they keep each input's work small.
struct GltfLimits {
  /// Node instances (one per path from the scene to a node).
  long node_instances = 100000;
  /// Triangles, and separately vertices, all instances together may bring (each is kept
  /// before quad recovery).
  long instanced_triangles = 20000000;
};

/// \throw InputError naming the file (glTF has no lines: line 0) if it cannot be read or
/// parsed, has no triangles, uses an unsupported primitive mode or accessor layout.
/// Every count is checked against the bytes present before anything is allocated, node
/// instancing is capped (GltfLimits: 1e5 node instances, 2e7 triangles), non-finite positions and
/// transforms are refused naming the accessor / node, and external buffers must be regular
/// files (io/input_file.h).
LoadedCage read_gltf(const std::string& path);

/// The same from the file's bytes in memory (`binary`: GLB, else glTF JSON); `name` stands
/// for the file in messages, `base_dir` is where external buffers are looked up.
LoadedCage parse_gltf(const std::string& bytes, const std::string& name, bool binary, const std::string& base_dir,
                      const GltfLimits& limits = {});

}  // namespace subd2nurbs
