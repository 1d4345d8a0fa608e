#include "converter/cli/limit_cmd.h"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "converter/cli/commands.h"
#include "converter/cli/limit_queries.h"
#include "core/limit/limit_evaluator.h"
#include "io/input_error.h"
#include "io/input_file.h"

namespace subd2nurbs::cli {

CLI::App* add_limit_command(CLI::App& app, LimitOptions& options) {
  CLI::App* c = add_cage_command(
      app, "limit",
      "Evaluate the exact limit surface: reads query lines \"f u v\" (quad f) or \"f s u v\" "
      "(sub-face s of n-gon f) and prints \"Px Py Pz Nx Ny Nz Dux Duy Duz Dvx Dvy Dvz\" per query",
      options.mesh);
  c->add_option("QUERIES", options.queries, "File of query lines (default: standard input)");
  return c;
}

void run_limit(const LimitOptions& options, std::istream& in, std::ostream& out, std::ostream& err) {
  LoadedInput loaded = load_input(options.mesh);
  for (const std::string& w : loaded.warnings) err << w << "\n";
  SubdivLevel& level = loaded.level;

  std::vector<Query> queries;
  const bool from_stdin = options.queries.empty() || options.queries == "-";
  if (from_stdin) {
    queries = read_queries(in, "<stdin>", level.mesh);
  } else {
    std::istringstream file(read_input_file(options.queries, "a query file"));
    queries = read_queries(file, options.queries, level.mesh);
  }
  const std::string name = from_stdin ? "<stdin>" : options.queries;
  const LimitEvaluator evaluator(std::move(level), loaded.positions());

  const bool progress = queries.size() >= 1000000;
  std::string text;
  text.reserve(queries.size() * 220);
  char buffer[512];
  for (size_t i = 0; i < queries.size(); ++i) {
    const Query& q = queries[i];
    if (progress && i % 1000000 == 0)
      err << "subd2nurbs: limit: " << i << " / " << queries.size() << " queries\n";
    LimitSample s;
    try {
      s = evaluator.evaluate(q.face, q.sub, q.u, q.v);
    } catch (const std::domain_error& e) {
      throw InputError(name, q.line, e.what());
    }
    std::snprintf(buffer, sizeof buffer,
                  "%.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n",
                  s.p[0], s.p[1], s.p[2], s.normal[0], s.normal[1], s.normal[2], s.du[0], s.du[1],
                  s.du[2], s.dv[0], s.dv[1], s.dv[2]);
    text += buffer;
  }
  out << text;
  out.flush();
}

}  // namespace subd2nurbs::cli
