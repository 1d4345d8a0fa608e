// `subd2nurbs convert`: cage -> bicubic NURBS patches -> STEP / IGES / BREP (or patch JSON),
// with measurements (continuity, deviation from the limit surface, the B-rep's counts) on
// stderr and optionally as a JSON report (documented in docs/formats.md).
#pragma once

#include <ostream>
#include <string>

#include "converter/cli/commands.h"
#include "converter/pipeline/conversion.h"

namespace subd2nurbs::cli {

struct ConvertOptions {
  std::string mesh;
  std::string output;         ///< .step/.stp, .iges/.igs, .brep or .json
  int level = 0;              ///< extra levels beyond the minimum (PatchOptions::extra_levels)
  bool level_given = false;
  double tolerance = 0;       ///< deviation tolerance, > 0 when given
  bool tolerance_given = false;
  bool absolute = false;      ///< tolerance in model units, else relative to the bbox diagonal
  std::string schema = "ap214";  ///< STEP schema: ap214 or ap242
  std::string faces = "packed";  ///< packed (regular regions as one face) or per-quad
  std::string report;         ///< JSON report path, empty for none
  std::string polar = "on";   ///< polar structures: "on" (singular caps) or "off" (Catmull-Clark)
  int radial_steps = 1;       ///< radial BP pre-steps of a polar cap (1 or 2)
  double lambda = 0.75;       ///< polar cap's 1-link scale (docs/math.md 4.1 (iv)), > 0
  bool separate_poles = false;  ///< the separating first step at low-valence / too-close poles
  bool quiet = false;         ///< no progress, notes or summary (warnings are still printed)
  std::string preview;        ///< GLB preview path, empty for none
  std::string preview_color = "curvature";  ///< deviation, curvature or zebra
  int preview_samples = 12;   ///< per patch side
  bool progress_tty = false;  ///< stderr is a terminal: show the B-rep percentage in place
  std::string fit = "approximate";  ///< approximate (the cage's own limit) or interpolate
  double fair = 0;            ///< > 0: fair fit with this weight (needs fit == "interpolate")
  bool fair_given = false;
  LimitOptionValues limits;   ///< --max-faces, --max-memory
};

/// Most extra levels --tolerance adds; a tolerance needing more is reported as capped.
constexpr int kMaxFanExtraLevels = pipeline::kMaxFanExtraLevels;

/// Converts a cage. Progress, warnings and the summary go to `err`.
/// Every output (-o, --report, --preview) is computed first and written only when all of
/// them are ready (io/atomic_file.h StagedFile), so a failure leaves every file as it was.
/// \throw UsageError (bad options, unknown output extension, an output that is the input),
///        pipeline::ResourceError (the estimate exceeds --max-faces / --max-memory),
///        InputError (the cage), WriteError (the output or report file),
///        occt::ExportError (OCCT failed, or the B-rep is not valid: nothing is written)
void run_convert(const ConvertOptions& options, std::ostream& err);

}  // namespace subd2nurbs::cli
