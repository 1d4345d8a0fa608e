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
  std::string report;         ///< JSON report path, empty for none
  std::string preview;        ///< GLB preview path, empty for none
  std::string fit_to;         ///< a target shape: the cage is fitted to it first (subd2nurbs fit), empty for none
  std::string keep_cage;      ///< mesh input: the cage made from it, written as OBJ (fitted), empty for none
  bool quiet = false;         ///< no progress, notes or summary (warnings are still printed)
  bool progress_tty = false;  ///< stderr is a terminal: show the B-rep percentage in place
  SettingValues settings;     ///< the settings table's options as given (converter/pipeline/settings.h)
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
