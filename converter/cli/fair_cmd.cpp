#include "converter/cli/fair_cmd.h"

#include <CLI/CLI.hpp>

#include <chrono>

#include "converter/cli/commands.h"
#include "converter/pipeline/conversion.h"
#include "converter/pipeline/report.h"
#include "core/fit/fairing.h"
#include "io/atomic_file.h"
#include "io/json_writer.h"
#include "io/obj_writer.h"

namespace subd2nurbs::cli {

CLI::App* add_fair_command(CLI::App& app, FairCommandOptions& o) {
  CLI::App* c = add_cage_command(
      app, "fair",
      "Fair a cage: move its free vertices to minimise the thin-plate energy of the limit surface, "
      "keeping the limit points close to where they were; write the cage as OBJ",
      o.mesh);
  c->add_option("-o,--output", o.output, "Output OBJ file (same topology and tags)")->required();
  c->add_option("--weight", o.weight, "Weight W > 0 of the energy against keeping the limit points (default 1)");
  c->add_option("--keep", o.keep, "Vertices kept fixed (repeatable): boundary, creases (ends of tagged crease "
                                  "edges) or tagged (creases and corner tags)");
  c->add_option("--levels", o.levels, "Refinement levels of the energy near extraordinary vertices (0..4, default 2)");
  c->add_option("--membrane", o.membrane, "Weight of the membrane term (>= 0, default 0; thin plate has 1)");
  c->add_option("--report", o.report, "Also write a JSON report (energies, displacement, kept vertices)");
  c->add_flag("-q,--quiet", o.quiet, "No summary on stderr (warnings are still printed)");
  return c;
}

void run_fair(const FairCommandOptions& o, std::ostream& err) {
  FairOptions fo;
  fo.weight = o.weight;
  fo.energy.levels = o.levels;
  fo.energy.membrane = o.membrane;
  pipeline::validate_fairing(fo.weight, fo.energy);
  const KeepSet keep = pipeline::keep_set(o.keep);
  check_outputs(o.mesh, {{"-o", o.output}, {"--report", o.report}});
  const LoadedInput loaded = load_input(o.mesh);
  for (const std::string& w : loaded.warnings) err << w << "\n";
  const SubdivLevel& level = loaded.level;
  const std::vector<Point3> start = loaded.positions();

  fo.keep = kept_vertices(level, keep);
  // The data term keeps the limit points where they were.
  std::vector<Point3> targets;
  limit_rows(level).rows.apply(start, targets);
  const auto t = std::chrono::steady_clock::now();
  const FairResult r = fair(level, start, targets, fo);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
  write_obj(o.output, r.positions, level);

  if (!o.report.empty()) {
    JsonWriter w(JsonWriter::Numbers::Report, JsonWriter::Spacing::Spaced);
    auto stats = [&](const char* name, const FieldStats& s) {
      pipeline::write_field_stats(w.key(name).begin_object(), s);
      w.end_object();
    };
    w.begin_object(2);
    w.members("format", "subd2nurbs-fair", "version", 1, "input", o.mesh, "output", o.output, "weight", o.weight,
              "membrane", o.membrane, "levels", o.levels);
    w.key("keep").begin_array();
    for (const std::string& k : o.keep) w.string(k);
    w.end_array();
    w.members("kept_vertices", r.kept, "free_vertices", r.free, "energy_before", r.energy_before, "energy_after",
              r.energy_after);
    stats("limit_moved", r.residual);
    stats("cage_moved", r.displacement);
    w.member("solve_ms", ms).end_object();
    write_file_atomically(o.report, [&](std::ostream& out) { out << w.text() << "\n"; });
  }
  using pipeline::short_number;
  if (!o.quiet)
    err << "subd2nurbs: wrote " << o.output << ": energy " << short_number(r.energy_before) << " -> "
        << short_number(r.energy_after) << "; limit points moved max " << short_number(r.residual.max)
        << " (vertex " << r.residual.where << "), mean " << short_number(r.residual.mean) << "; cage moved max "
        << short_number(r.displacement.max) << "; " << r.kept << " kept, " << r.free << " free vertices\n";
}

}  // namespace subd2nurbs::cli
