#include "converter/cli/limit_cmd.h"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "converter/cli/commands.h"
#include "core/limit/limit_evaluator.h"
#include "io/input_error.h"

namespace subd2nurbs::cli {

namespace {

struct Query {
  int face = 0, sub = 0;
  double u = 0, v = 0;
  int line = 0;
};

bool parse_int(const std::string& s, int& x) {
  try {
    size_t used = 0;
    const long long v = std::stoll(s, &used);
    if (used != s.size() || v < 0 || v > 2147483647LL) return false;
    x = static_cast<int>(v);
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

bool parse_double(const std::string& s, double& x) {
  try {
    size_t used = 0;
    x = std::stod(s, &used);
    return used == s.size();
  } catch (const std::exception&) {
    return false;
  }
}

std::vector<Query> read_queries(std::istream& in, const std::string& name, const PolyMesh& mesh) {
  std::vector<Query> queries;
  std::string text;
  int line_no = 0;
  while (std::getline(in, text)) {
    ++line_no;
    std::istringstream tokens(text);
    std::vector<std::string> t;
    for (std::string w; tokens >> w;) t.push_back(w);
    if (t.empty() || t[0][0] == '#') continue;
    auto fail = [&](const std::string& why) { throw InputError(name, line_no, why); };
    if (t.size() != 3 && t.size() != 4)
      fail("expected \"f u v\" or \"f s u v\", got " + std::to_string(t.size()) + " fields");
    Query q;
    q.line = line_no;
    if (!parse_int(t[0], q.face)) fail("face index '" + t[0] + "' is not a non-negative integer");
    if (t.size() == 4 && !parse_int(t[1], q.sub))
      fail("sub-face index '" + t[1] + "' is not a non-negative integer");
    const std::string& us = t[t.size() - 2];
    const std::string& vs = t[t.size() - 1];
    if (!parse_double(us, q.u) || !parse_double(vs, q.v))
      fail("parameters '" + us + " " + vs + "' are not numbers");
    if (!(q.u >= 0 && q.u <= 1 && q.v >= 0 && q.v <= 1))
      fail("parameters (" + us + ", " + vs + ") are outside [0,1]^2");
    if (q.face >= mesh.num_faces())
      fail("no face " + t[0] + " (the mesh has " + std::to_string(mesh.num_faces()) + " faces)");
    const int size = mesh.face_size(q.face);
    if (size != 4 && t.size() == 3)
      fail("face " + t[0] + " has " + std::to_string(size) +
           " sides: give its sub-face, \"f s u v\" with s in 0.." + std::to_string(size - 1));
    if (t.size() == 4 && q.sub >= (size == 4 ? 1 : size))
      fail("face " + t[0] + " has no sub-face " + t[1] +
           (size == 4 ? " (a quad has only sub-face 0)"
                      : " (sub-faces 0.." + std::to_string(size - 1) + ")"));
    queries.push_back(q);
  }
  if (in.bad()) throw InputError(name, 0, "read error");
  return queries;
}

}  // namespace

CLI::App* add_limit_command(CLI::App& app, LimitOptions& options) {
  CLI::App* c = app.add_subcommand(
      "limit",
      "Evaluate the exact limit surface: reads query lines \"f u v\" (quad f) or \"f s u v\" "
      "(sub-face s of n-gon f) and prints \"Px Py Pz Nx Ny Nz Dux Duy Duz Dvx Dvy Dvz\" per query");
  c->add_option("MESH", options.mesh, "OBJ cage (with OpenSubdiv 't' tags)")->required();
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
    std::ifstream file(options.queries);
    if (!file) throw InputError(options.queries, 0, "cannot open the query file");
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
