// The query lines of `subd2nurbs limit` ("f u v" / "f s u v"), parsed and checked against the
// cage. Separate from the subcommand so that the parser can be fuzzed (tests/fuzz) without
// the rest of the CLI.
#pragma once

#include <istream>
#include <string>
#include <vector>

#include "core/mesh/poly_mesh.h"

namespace subd2nurbs::cli {

struct Query {
  int face = 0, sub = 0;
  double u = 0, v = 0;
  int line = 0;
};

/// Reads every query line of `in` (blank lines and '#' comments skipped).
/// \throw InputError naming `name`:LINE for the first bad line (field count, a face or
/// sub-face that does not exist, parameters that are not numbers in [0,1]).
std::vector<Query> read_queries(std::istream& in, const std::string& name, const PolyMesh& mesh);

}  // namespace subd2nurbs::cli
