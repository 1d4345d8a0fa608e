// Writing a PatchSet as JSON ("subd2nurbs-patches", version 1; described in docs/formats.md).
//
// The text is deterministic: keys in a fixed order, numbers with "%.17g" (so parsing them as
// IEEE doubles gives back the exact values), one patch / curve / corner per line.
#pragma once

#include <string>

#include "core/nurbs/patch_set.h"

namespace subd2nurbs {

/// The JSON text of `patches`, ending in a newline.
/// \throw std::invalid_argument if a coordinate, weight, knot or the model size is not finite
/// (JSON has no NaN or infinity).
std::string patch_set_to_json(const PatchSet& patches);

/// Writes patch_set_to_json(patches) to `path` atomically (the file is either completely
/// written or left untouched).
/// \throw std::invalid_argument as patch_set_to_json, before anything is written
/// \throw WriteError if the file cannot be written
void write_patch_json(const std::string& path, const PatchSet& patches);

}  // namespace subd2nurbs
