#include "converter/cli/check_cmd.h"

#include <CLI/CLI.hpp>

#include <functional>

#include "converter/cli/commands.h"
#include "converter/cli/quality_text.h"
#include "converter/pipeline/conversion.h"
#include "converter/pipeline/report.h"
#include "core/eval/quality.h"
#include "io/atomic_file.h"

namespace subd2nurbs::cli {

CLI::App* add_check_command(CLI::App& app, CheckOptions& o) {
  CLI::App* c = add_cage_command(
      app, "check",
      "Measure the conversion's patches against the exact limit surface: deviation, gaps and "
      "normal jumps per edge with the class each edge should have, curvature",
      o.mesh);
  c->add_option("--level", o.level,
                "Pin the refinement levels beyond the minimum (as convert --level; default: the "
                "levels convert's default tolerance chooses)")
      ->each([&o](const std::string&) { o.level_given = true; });
  c->add_option("--faces", o.faces,
                "The faces measured: packed (default, as convert exports them) or per-quad; every sample "
                "of a coarse quad is taken on the face that holds it");
  c->add_option("--json", o.json, "Write the quality report as JSON");
  c->add_option("--samples", o.samples, "Samples per patch side (default 9)");
  c->add_flag("-q,--quiet", o.quiet, "No progress, notes or summary (warnings are still printed)");
  add_limit_options(*c, o.limits, "the faces of the refined mesh the patches are built from (as convert)");
  return c;
}

void run_check(const CheckOptions& o, std::ostream& err) {
  pipeline::ConversionSettings settings;  // the same patches as convert without options
  if (o.level_given) settings.level = o.level;
  settings.build_brep = false;
  settings.faces = pipeline::face_mode(o.faces);
  settings.limits = resource_limits(o.limits);
  settings.quality_samples = o.samples;  // the quality stage is what check is for
  pipeline::validate(settings);
  check_outputs(o.mesh, {{"--json", o.json}});
  if (!o.quiet) err << "subd2nurbs: reading " << o.mesh << "\n";
  const LoadedInput loaded = load_input(o.mesh);
  const std::vector<std::string>& warnings = loaded.warnings;
  for (const std::string& w : warnings) err << w << "\n";

  pipeline::ConversionProgress progress;
  if (!o.quiet) progress.stage = [&](pipeline::Stage, const std::string& s) { err << "subd2nurbs: " << s << "...\n"; };
  DiagnosticPrinter diagnostics(err, o.quiet);
  progress.diagnostic = std::ref(diagnostics);
  pipeline::ConversionResult c = pipeline::convert(loaded.level, loaded.positions(), settings, progress, warnings);
  diagnostics.finish();
  c.input = o.mesh;

  if (!o.json.empty()) {
    const std::string text = pipeline::quality_report_json(c);
    write_file_atomically(o.json, [&](std::ostream& out) { out << text; });
  }
  if (!o.quiet) print_quality_summary(err, *c.quality, c.build.set.model_size);
}

}  // namespace subd2nurbs::cli
