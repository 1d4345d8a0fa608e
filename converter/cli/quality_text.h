// The quality stage's results for people (a short summary on stderr) and the preview stage's
// mesh as a GLB file: used by `subd2nurbs check` and `convert --report` / `--preview`. Their
// JSON is the pipeline's (converter/pipeline/report.h).
#pragma once

#include "io/atomic_file.h"

#include <ostream>
#include <string>

#include "converter/pipeline/conversion.h"
#include "core/eval/quality.h"
#include "core/eval/target_distance.h"

namespace subd2nurbs::cli {

/// `convert --preview`: the GLB of the conversion's preview mesh (c.preview, which must be
/// set), staged (io/atomic_file.h) for the caller to commit with the other outputs.
struct ConvertOptions;
StagedFile stage_preview(const ConvertOptions& options, const pipeline::ConversionResult& c, std::ostream& err);

/// Three lines for stderr.
void print_quality_summary(std::ostream& err, const QualityReport& q, double model_size);

/// One line for stderr: "<label>: limit -> target max .., rms .., p95 ..; target -> limit ...
/// (relative to the target's diagonal D)" (`fit`, `check --to`).
void print_target_distance(std::ostream& err, const std::string& label, const TargetDistance& d);

}  // namespace subd2nurbs::cli
