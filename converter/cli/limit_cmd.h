// `subd2nurbs limit MESH [QUERIES]`: exact limit surface evaluation (core/limit).
// Query lines "f u v" (quad face f) or "f s u v" (sub-face s of n-gon f), 0-based face
// indices, OpenSubdiv's ptex parametrisation; blank lines and lines starting with '#' are
// skipped. Output: one line per query, in order: "Px Py Pz Nx Ny Nz Dux Duy Duz Dvx Dvy Dvz"
// (%.17g). Every query is checked and evaluated before anything is printed.
#pragma once

#include <istream>
#include <ostream>
#include <string>

namespace CLI {
class App;
}

namespace subd2nurbs::cli {

struct LimitOptions {
  std::string mesh;
  std::string queries;  ///< file with query lines; empty or "-" for standard input
};

/// Registers the subcommand on `app`.
CLI::App* add_limit_command(CLI::App& app, LimitOptions& options);

/// \throw InputError (the cage, or a bad query line: FILE:LINE), WriteError
void run_limit(const LimitOptions& options, std::istream& in, std::ostream& out, std::ostream& err);

}  // namespace subd2nurbs::cli
