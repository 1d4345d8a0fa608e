#include "converter/cli/check_cmd.h"

#include <CLI/CLI.hpp>

#include <chrono>
#include <functional>

#include "converter/cli/commands.h"
#include "converter/cli/quality_json.h"
#include "converter/pipeline/conversion.h"
#include "core/eval/quality.h"
#include "io/atomic_file.h"

namespace subd2nurbs::cli {

CLI::App* add_check_command(CLI::App& app, CheckOptions& o) {
  CLI::App* c = app.add_subcommand(
      "check",
      "Measure the conversion's patches against the exact limit surface: deviation, gaps and "
      "normal jumps per edge with the class each edge should have, curvature");
  c->add_option("MESH", o.mesh, "OBJ cage (with OpenSubdiv 't' tags)")->required();
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
  using Clock = std::chrono::steady_clock;
  pipeline::ConversionSettings settings;  // the same patches as convert without options
  if (o.level_given) settings.level = o.level;
  settings.build_brep = false;
  settings.faces = pipeline::face_mode(o.faces);
  settings.limits = resource_limits(o.limits);
  pipeline::validate(settings);
  pipeline::check_samples("samples", o.samples);
  check_outputs(o.mesh, {{"--json", o.json}});
  if (!o.quiet) err << "subd2nurbs: reading " << o.mesh << "\n";
  const LoadedInput loaded = load_input(o.mesh);
  const SubdivLevel& base = loaded.level;
  const std::vector<std::string>& warnings = loaded.warnings;
  for (const std::string& w : warnings) err << w << "\n";
  const std::vector<Point3> positions = loaded.positions();

  pipeline::ConversionProgress progress;
  if (!o.quiet) progress.stage = [&](pipeline::Stage, const std::string& s) { err << "subd2nurbs: " << s << "...\n"; };
  DiagnosticPrinter diagnostics(err, o.quiet);
  progress.diagnostic = std::ref(diagnostics);
  const pipeline::ConversionResult c = pipeline::convert(base, positions, settings, progress, warnings);
  diagnostics.finish();

  if (!o.quiet) err << "subd2nurbs: measuring against the exact limit surface...\n";
  const auto t = Clock::now();
  const QualityReport q = measure_conversion_quality(base, positions, c, o.samples);
  const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t).count();
  const double size = c.build.set.model_size;

  if (!o.json.empty()) {
    std::string text = "{\n  \"format\": \"subd2nurbs-quality\",\n  \"version\": 1,\n  \"input\": " +
                       pipeline::json_string(o.mesh) + ",\n  \"model_size\": " + pipeline::json_number(size) +
                       ",\n  \"coarse_level\": " + std::to_string(c.build.info.coarse_level) +
                       ",\n  \"level\": " + std::to_string(c.build.info.level) +
                       ",\n  \"patches\": " + std::to_string(c.build.set.patches.size()) +
                       ",\n  \"faces\": {\"mode\": " + pipeline::json_string(pipeline::to_string(c.faces)) +
                       ", \"total\": " + std::to_string(c.exported.set.patches.size()) + "}" +
                       ",\n  \"quality_ms\": " + pipeline::json_number(ms) + "\n}\n";
    text = add_quality_member(text, quality_json(q, size, 2));
    write_file_atomically(o.json, [&](std::ostream& out) { out << text; });
  }
  if (!o.quiet) print_quality_summary(err, q, size);
}

}  // namespace subd2nurbs::cli
