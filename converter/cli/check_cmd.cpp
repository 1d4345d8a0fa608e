#include "converter/cli/check_cmd.h"

#include <CLI/CLI.hpp>

#include <functional>
#include <optional>

#include "converter/cli/commands.h"
#include "converter/cli/quality_text.h"
#include "converter/pipeline/conversion.h"
#include "converter/pipeline/report.h"
#include "core/eval/quality.h"
#include "converter/pipeline/shape_fit_report.h"
#include "core/limit/limit_evaluator.h"
#include "io/atomic_file.h"
#include "io/target_reader.h"

namespace subd2nurbs::cli {

CLI::App* add_check_command(CLI::App& app, CheckOptions& o) {
  CLI::App* c = add_cage_command(
      app, "check",
      "Measure the conversion's patches against the exact limit surface: deviation, gaps and "
      "normal jumps per edge with the class each edge should have, curvature",
      o.mesh);
  c->add_option("--json", o.json, "Write the quality report as JSON");
  c->add_option("--to", o.target,
                "Also measure the two-sided distance of the limit surface to a target shape (a triangle mesh "
                "or a point cloud, as fit --to reads it)");
  c->add_flag("-q,--quiet", o.quiet, "No progress, notes or summary (warnings are still printed)");
  add_setting_options(*c, pipeline::kCheckCommand, o.settings);
  return c;
}

void run_check(const CheckOptions& o, std::ostream& err) {
  // The same patches as convert with the same settings, no B-rep; the quality stage is what
  // check is for.
  SettingValues given = o.settings;
  given.emplace_back("brep", false);
  pipeline::ConversionSettings settings = pipeline::make_settings(given).conversion;
  if (!settings.quality_samples) settings.quality_samples = pipeline::kReportQualitySamples;
  check_outputs(o.mesh, {{"--json", o.json}});
  if (!o.quiet) err << "subd2nurbs: reading " << o.mesh << "\n";
  const LoadedInput loaded = load_input(o.mesh);
  const std::vector<std::string>& warnings = loaded.warnings;
  for (const std::string& w : warnings) err << w << "\n";

  std::optional<ShapeTarget> target;
  if (!o.target.empty()) target.emplace(pipeline::make_target(read_target(o.target), o.target));

  pipeline::ConversionProgress progress;
  if (!o.quiet) progress.stage = [&](pipeline::Stage, const std::string& s) { err << "subd2nurbs: " << s << "...\n"; };
  DiagnosticPrinter diagnostics(err, o.quiet);
  progress.diagnostic = std::ref(diagnostics);
  pipeline::ConversionResult c = pipeline::convert(loaded.level, loaded.positions(), settings, progress, warnings);
  diagnostics.finish();
  c.input = o.mesh;

  std::optional<TargetDistance> distance;
  if (target) {
    if (!o.quiet) err << "subd2nurbs: measuring the distance to " << o.target << "...\n";
    distance = measure_target_distance(LimitEvaluator(loaded.level, loaded.positions()), *target);
  }

  if (!o.json.empty()) {
    const std::string text = pipeline::quality_report_json(c, distance ? &*distance : nullptr);
    write_file_atomically(o.json, [&](std::ostream& out) { out << text; });
  }
  if (o.quiet) return;
  print_quality_summary(err, *c.quality, c.build.set.model_size);
  if (distance) print_target_distance(err, "quality: target " + o.target, *distance);
}

}  // namespace subd2nurbs::cli
