// A coloured triangle mesh of the patches for previews (glTF export in io/gltf_preview.h):
// every patch tessellated on an n x n grid of its parameters, with per-vertex normals and a
// colour for the deviation from the exact limit, the patches' mean curvature, or zebra stripes.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/limit/limit_evaluator.h"
#include "core/patch/patch_builder.h"

namespace subd2nurbs {

enum class PreviewColor { Deviation, Curvature, Zebra };

/// "deviation", "curvature", "zebra" (the names the front ends accept, pipeline::preview_color).
const char* to_string(PreviewColor color);

struct PreviewMesh {
  std::vector<float> positions;       ///< xyz per vertex
  std::vector<float> normals;         ///< unit normal per vertex (patch normal X_u x X_v)
  std::vector<float> colors;          ///< rgb in [0,1] per vertex
  std::vector<float> values;          ///< the coloured quantity per vertex (distance, H, stripe 0/1)
  std::vector<std::uint32_t> indices; ///< triangles, counter-clockwise seen from the normal side
  double value_min = 0, value_max = 0;  ///< the range the colour map spans
};

/// `limit` is used for PreviewColor::Deviation only (may be null otherwise).
/// Deviation: distance to the limit (limit_distance), 0 blue .. max red. Curvature: the patches'
/// mean curvature H, blue (H <= -h) .. white (0) .. red (H >= h), h = the 95th percentile of |H|.
/// Zebra: black and white stripes of the normal's angle to the z axis, 12 per half turn.
PreviewMesh build_preview(const PatchBuild& build, const LimitEvaluator* limit, PreviewColor color,
                          int samples_per_side = 16);

}  // namespace subd2nurbs
