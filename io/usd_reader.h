// Reading subdivision cages from USD: usda text, the binary usdc crate, and usdz packages (the
// first .usda / .usdc / .usd layer of the zip, stored uncompressed as the usdz spec requires).
// The encoding is taken from the content ("#usda", "PXR-USDC", "PK\3\4"), whatever the extension.
//
// What is read (docs/formats.md has the table of properties and units):
//  * prims `def` and `over` (a root prim that another prim of the layer references is read
//    through the reference only; `class` prims are not read), their children, variant sets (the
//    selection given in UsdReadOptions::variants, else the authored one, else the first variant)
//    and references to prims of the same layer; references to other files, payloads, inherits
//    and instancing are reported as warnings, not followed;
//  * every `Mesh` prim becomes one or more components of the cage: points, faceVertexCounts,
//    faceVertexIndices; subdivisionScheme (catmullClark, the default; bilinear / none / loop:
//    read as the cage with a warning), interpolateBoundary, triangleSubdivisionRule, creases
//    (creaseIndices / creaseLengths / creaseSharpnesses, one sharpness per crease or per edge),
//    corners, holeIndices, orientation (leftHanded faces reversed, as are faces under a
//    transform that mirrors); the default value of each attribute, else its first time sample;
//  * xformOps (translate, scale, rotateX/Y/Z, rotateXYZ and the other orders, orient,
//    transform, with !invert! and !resetXformStack!) composed down the hierarchy: the cage is
//    in the layer's world space;
//  * metersPerUnit and upAxis, reported (LoadedCage::usd), not applied.
#pragma once

#include <map>
#include <string>
#include <string_view>

#include "io/loaded_cage.h"
#include "io/usd_layer.h"

namespace subd2nurbs {

struct UsdReadOptions {
  /// Variant selections by variant set name ("geo" -> "quad_creases"), stronger than the file's.
  std::map<std::string, std::string> variants;
  usd::Limits limits;
};

/// Parses "set=name" (the CLI's --variant, Python's variant=) into `options.variants`.
/// \throw Error(ErrorKind::Usage) when the text has no '=' or an empty side.
void add_variant_selection(UsdReadOptions& options, const std::string& text);

/// True when `bytes` (a file's start) is USD: "#usda", "PXR-USDC", or a zip holding a USD layer.
bool looks_like_usd(std::string_view bytes);

/// \throw InputError naming the file (and line, in usda) when it cannot be read or is not a
/// valid USD layer with at least one mesh.
LoadedCage read_usd(const std::string& path, const UsdReadOptions& options = {});

/// The same from the file's bytes; `name` stands for the file in messages.
LoadedCage parse_usd(const std::string& bytes, const std::string& name, const UsdReadOptions& options = {});

}  // namespace subd2nurbs
