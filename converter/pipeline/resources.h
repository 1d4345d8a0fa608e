// Resource guards: what a conversion or a refinement will need, estimated from the cage
// before any heavy work, and the limits it is checked against. One place, so that the
// estimate can follow the patch builder (adaptive refinement will make it smaller).
// Used by the CLI, the Python module and (through it) the FreeCAD workbench.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>

#include "converter/pipeline/settings_error.h"
#include "core/refine/refiner.h"
#include "core/util/error.h"

namespace subd2nurbs::pipeline {

/// Default limits. Convert / check: polynomial pieces the patch builder makes (one per regular
/// coarse quad, more at irregular vertices and along semi-sharp creases: catmark_rook makes
/// 428 000). Refine: output faces.
constexpr double kDefaultMaxConvertFaces = 4e6;
constexpr double kDefaultMaxRefineFaces = 2e7;

/// Peak memory, measured (Release build, Debian 12, x86-64, the adaptive builder): per B-rep face
/// with the B-rep and the STEP writer (OCCT's shapes and STEP model: 45 KB on a 100 000-quad
/// torus) and without (patch JSON, check); per piece (its Bezier net, the local refinement and
/// the quality report's share); a refinement per output face (all levels, stencils, the OBJ
/// text: 370-420 bytes).
constexpr double kConvertBytesPerFace = 48000;
constexpr double kConvertBytesPerFaceNoBrep = 6000;
constexpr double kConvertBytesPerPiece = 1200;
constexpr double kRefineBytesPerFace = 450;

/// Most levels a uniform refinement takes: beyond the face limit for any cage, and 4^levels
/// stays far from overflowing.
constexpr int kMaxRefineLevels = 20;

/// What the user allows; not given: the default.
struct ResourceLimits {
  std::optional<double> max_faces;   ///< > 0; default kDefaultMaxConvertFaces or kDefaultMaxRefineFaces
  std::optional<double> max_memory;  ///< bytes, > 0; default default_max_memory()
};

/// The rules of the limits (max_faces, max_memory: positive numbers) and of a refinement's
/// levels (0 .. kMaxRefineLevels). \throw SettingsError
void validate(const ResourceLimits& limits);
void check_refine_levels(int levels);
/// A memory size as parse_memory_size reads it. \throw SettingsError ("max_memory")
double memory_size(const std::string& text);

/// 3/4 of the physical memory, or of the address-space / data-size limit (ulimit -v / -d)
/// when that is lower; at least 256 MiB.
double default_max_memory();

struct ResourceEstimate {
  double faces = 0;    ///< work units: convert: polynomial pieces (bound); refine: output faces, exact
  double patches = 0;  ///< NURBS patches (convert), 0 for refine
  double poles = 0;    ///< their control points
  double bytes = 0;    ///< peak memory, roughly
};

/// Conversion with `extra_levels` beyond the minimum: from the face count (quads of the
/// coarsest all-quad mesh), the level (raised, as the patch builder does, while semi-sharp
/// creases have not decayed: up to 5 levels above the coarse mesh), and the irregular vertices (Stam's eigenbasis per
/// valence, (2n+8)^2 doubles a few times over).
ResourceEstimate estimate_conversion(const SubdivLevel& base, int extra_levels, bool build_brep = true);

/// Uniform refinement to `levels`: faces exact (corners x 4^(levels-1) after the first level).
ResourceEstimate estimate_refinement(const SubdivLevel& base, int levels);

/// A refusal: the estimate exceeds a limit. A SettingsError's sibling; the message names the
/// estimate, the limit and the overrides (--max-faces / --max-memory, Python max_faces= /
/// max_memory=).
class ResourceError : public Error {
 public:
  explicit ResourceError(const std::string& message) : Error(ErrorKind::Resources, message) {}
};

/// \throw ResourceError naming `what` ("converting at level 2", "refining to level 11")
void check_resources(const ResourceEstimate& estimate, const ResourceLimits& limits, double default_max_faces,
                     const std::string& what, const std::string& advice);

/// Human-readable byte count ("1.5 GiB").
std::string bytes_text(double bytes);

/// Parses a memory size: a number of bytes with an optional K, M, G or T suffix (powers of
/// 1024, "B" / "iB" allowed after it): "8G", "512MiB", "1e9". Returns false when malformed
/// or not positive.
bool parse_memory_size(const std::string& text, double& bytes);

}  // namespace subd2nurbs::pipeline
