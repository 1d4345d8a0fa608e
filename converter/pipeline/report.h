// The conversion's results as JSON, written with the one JSON writer (io/json_writer.h) for
// every front end: the report (subd2nurbs-report v1, docs/formats.md) of `convert --report` and
// the Python module's ConversionResult.report, with the quality stage's section when it ran,
// and the quality report of `check --json` (subd2nurbs-quality v1).
#pragma once

#include <string>

#include "converter/pipeline/conversion.h"
#include "core/eval/target_distance.h"
#include "io/json_writer.h"

namespace subd2nurbs::pipeline {

/// The report as JSON text (ending in a newline); with result.quality, its "quality" and
/// "quality_ms" members last.
std::string report_json(const ConversionResult& result);

/// `check --json`: the quality report of result.quality (which must be set), ending in a newline;
/// with `target` (`check --to`), its two-sided distance as the last member "target".
std::string quality_report_json(const ConversionResult& result, const TargetDistance* target = nullptr);

/// The members "max", "mean" and "where" (the vertex, or null) of a field's size, as the
/// report's "fit" and the fair report (`subd2nurbs fair --report`) give them.
void write_field_stats(JsonWriter& w, const FieldStats& stats);

}  // namespace subd2nurbs::pipeline
