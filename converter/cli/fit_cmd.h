// `subd2nurbs fit CAGE --to TARGET -o FITTED.obj [--smoothing S] [--levels K] [--max-iterations N]
// [--tolerance T] [--exact-target] [--tag-features] [--register] [--report R.json] [-q]`: fits the cage's limit surface to a target shape (a
// triangle mesh or a point cloud: io/target_reader.h) from the cage's own positions
// (core/fit/shape_fit.h, docs/fitting.md), writes the fitted cage as OBJ with its topology and
// tags, and reports the two-sided distance to the target before and after
// (core/eval/target_distance.h).
#pragma once

#include <optional>
#include <ostream>
#include <string>

namespace CLI {
class App;
}

namespace subd2nurbs::cli {

struct FitCommandOptions {
  std::string mesh;
  std::string target;
  std::string output;             ///< OBJ
  std::optional<double> smoothing;     ///< >= 0; default 1e-4 (0 with --exact-target)
  int levels = 3;                      ///< 1 .. 4
  std::optional<int> max_iterations;   ///< >= 1; default 30 (100 with --exact-target)
  std::optional<double> tolerance;     ///< > 0, relative to the target's diagonal; default 1e-7 (1e-8)
  /// --exact-target: the target lies on a subdivision surface (a dense sampling of one): the
  /// weights that recover it (exact_target_options, core/fit/shape_fit.h)
  bool exact_target = false;
  double min_gain = 0.02;         ///< >= 0: stop when an iteration improves the distance less
  bool tag_features = false;      ///< --tag-features: crease the cage edges along the target's sharp edges
  std::string report;             ///< JSON path, empty for none
  bool quiet = false;
  bool register_first = false;    ///< --register: a similarity pre-registration onto the target
};

CLI::App* add_fit_command(CLI::App& app, FitCommandOptions& options);

/// \throw InputError, WriteError, UsageError, pipeline::SettingsError, FitError
void run_fit(const FitCommandOptions& options, std::ostream& err);

}  // namespace subd2nurbs::cli
