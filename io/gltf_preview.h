// Writes a PreviewMesh (core/eval/preview_mesh.h) as glTF 2.0 binary (GLB) with tinygltf:
// one mesh, one triangle primitive with POSITION, NORMAL and COLOR_0 (float rgb), 32-bit
// indices, an unlit-looking default material (base colour white, the vertex colours carry the
// information). Written atomically (io/atomic_file.h). \throw WriteError
#pragma once

#include <string>

#include "core/eval/preview_mesh.h"
#include "io/atomic_file.h"

namespace subd2nurbs {

void write_preview_glb(const std::string& path, const PreviewMesh& mesh, const std::string& title);

/// The same, into a StagedFile the caller commits (with the other outputs of a run).
StagedFile stage_preview_glb(const std::string& path, const PreviewMesh& mesh, const std::string& title);

}  // namespace subd2nurbs
