// The quality report (core/eval/quality.h) as JSON (docs/formats.md, "Quality report") and as
// a short human summary. Used by `subd2nurbs check` and by `convert --report`.
#pragma once

#include "io/atomic_file.h"

#include <ostream>
#include <string>

#include "converter/pipeline/conversion.h"
#include "core/eval/quality.h"

namespace subd2nurbs::cli {

/// The "quality" object (no trailing newline), lines indented by `indent` spaces.
/// Lengths are in model units; *_rel fields are divided by the model size.
std::string quality_json(const QualityReport& q, double model_size, int indent);

/// A copy of a JSON object text with `"quality": <quality>` added as its last member.
/// `text` (a JSON object) with the member `name`: `value` appended.
std::string add_member(const std::string& text, const std::string& name, const std::string& value);

std::string add_quality_member(const std::string& object_text, const std::string& quality);

/// measure_quality of a conversion's patches against the exact limit of its cage.
QualityReport measure_conversion_quality(const SubdivLevel& base, const std::vector<Point3>& positions,
                                         const pipeline::ConversionResult& c, int samples_per_side = 9);

/// For `convert --report`: the report text with the "quality" member added; the summary goes
/// to `err` unless quiet.
std::string report_with_quality(const std::string& report, const SubdivLevel& base,
                                const std::vector<Point3>& positions, const pipeline::ConversionResult& c,
                                std::ostream& err, bool quiet);

/// `convert --preview`: the GLB preview of the patches (core/eval/preview_mesh.h), staged
/// (io/atomic_file.h) for the caller to commit with the other outputs.
struct ConvertOptions;
StagedFile stage_preview(const ConvertOptions& options, const SubdivLevel& base, const std::vector<Point3>& positions,
                   const pipeline::ConversionResult& c, std::ostream& err);

/// Three lines for stderr.
void print_quality_summary(std::ostream& err, const QualityReport& q, double model_size);

}  // namespace subd2nurbs::cli
