// `subd2nurbs fair MESH -o OUT.obj [--weight W] [--keep boundary|creases|tagged] [--levels K]
// [--membrane M] [--report R.json]`: moves the free cage vertices to minimise the thin-plate
// (+ membrane) energy of the limit surface while keeping its limit points close to where they
// were (core/fit/fairing.h, docs/fitting.md); kept vertices are copied bit for bit. Topology
// and tags are written unchanged.
#pragma once

#include <ostream>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace subd2nurbs::cli {

struct FairCommandOptions {
  std::string mesh;
  std::string output;            ///< OBJ
  double weight = 1.0;           ///< W > 0
  std::vector<std::string> keep; ///< boundary, creases, tagged
  int levels = 2;                ///< energy refinement levels (0..4)
  double membrane = 0.0;         ///< membrane weight (>= 0), thin plate has weight 1
  std::string report;            ///< JSON path, empty for none
  bool quiet = false;
};

CLI::App* add_fair_command(CLI::App& app, FairCommandOptions& options);

/// \throw InputError, WriteError, UsageError, pipeline::SettingsError, FitError
void run_fair(const FairCommandOptions& options, std::ostream& err);

}  // namespace subd2nurbs::cli
