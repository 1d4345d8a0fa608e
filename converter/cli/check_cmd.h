// `subd2nurbs check MESH [--level N] [--faces packed|per-quad] [--json R.json] [--samples N] [--to TARGET] ...`: the conversion's patches
// (no B-rep) measured against the exact limit surface (core/eval/quality.h): deviation, joins
// against the class each edge should have, curvature. Summary on stderr, JSON on request
// (docs/formats.md, "Quality report"). With --to TARGET, also the two-sided distance of the
// exact limit surface to a target shape (core/eval/target_distance.h).
#pragma once

#include <ostream>
#include <string>

#include "converter/cli/commands.h"

namespace CLI {
class App;
}

namespace subd2nurbs::cli {

struct CheckOptions {
  std::string mesh;
  std::string json;  ///< output path, empty for none
  /// A target shape (io/target_reader.h), empty for none: the two-sided distance of the cage's
  /// limit surface to it is added to the summary and the report ("target").
  std::string target;
  bool quiet = false;
  /// The settings table's options of check as given (--level, --faces, --samples, --max-faces,
  /// --max-memory; converter/pipeline/settings.h): the same patches as convert with them.
  SettingValues settings;
};

CLI::App* add_check_command(CLI::App& app, CheckOptions& options);

/// \throw InputError, WriteError, UsageError
void run_check(const CheckOptions& options, std::ostream& err);

}  // namespace subd2nurbs::cli
