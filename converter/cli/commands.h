// The subd2nurbs command line: option parsing and the subcommands. Separated from main()
// so that everything except process start-up can be reused and tested.
#pragma once

#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "converter/pipeline/conversion.h"
#include "converter/pipeline/errors.h"
#include "converter/pipeline/input.h"
#include "converter/pipeline/resources.h"
#include "converter/pipeline/settings.h"
#include "core/refine/refiner.h"
#include "core/util/error.h"
#include "io/obj_reader.h"

namespace CLI {
class App;
}

namespace subd2nurbs::cli {

/// Process exit codes (also listed in `subd2nurbs --help`): one per kind of error, by the
/// pipeline's table (converter/pipeline/errors.h).
constexpr int kOk = pipeline::kExitOk;
constexpr int kUsage = pipeline::kExitUsage;
constexpr int kInternalError = pipeline::kExitInternalError;

/// The command line's words for an error of the family (core/util/error.h): the setting as
/// its flag, an input error at FILE:LINE, an invalid cage found after validation at `input`.
std::string error_message(const Error& e, const std::string& input);

/// A cage read and validated, with its warnings: the pipeline's (converter/pipeline/input.h), the
/// same for every front end.
using pipeline::LoadedInput;
/// pipeline::load_input with the --variant selections the command was given (add_cage_command).
LoadedInput load_input(const std::string& path);
/// The --variant selections of the command being run (one command per process).
UsdReadOptions& usd_read_options();

/// Checks the outputs before any work (io/atomic_file.h resolve_output_path): each must be
/// a regular file or not exist yet (a symbolic link is followed: its target is replaced),
/// in a writable directory, and must be neither the input file (same inode) nor another of
/// the outputs. `outputs` holds (option, path) pairs; empty paths are skipped.
/// \throw WriteError (special file, missing or read-only directory, dangling link),
///        UsageError (an output is the input, or two outputs are the same file)
void check_outputs(const std::string& input, const std::vector<std::pair<std::string, std::string>>& outputs);

/// A subcommand that reads a cage: `name` with its description and the required MESH argument
/// (OBJ, glTF / GLB, STL, PLY, OFF, USD: load_input) stored in `mesh`, and --variant SET=NAME
/// (USD variant selections, for load_input).
CLI::App* add_cage_command(CLI::App& app, const std::string& name, const std::string& description,
                           std::string& mesh);

/// The settings a subcommand was given, by the names of the settings table
/// (converter/pipeline/settings.h), in the order given.
using SettingValues = std::vector<std::pair<std::string, pipeline::SettingValue>>;
/// Declares an option for every row of the settings table that `command` offers (its flag, its
/// help, a value of its type), each storing what it is given in `values`.
/// `table`: the settings table (a test passes its own copy with a row added).
void add_setting_options(CLI::App& app, pipeline::SettingCommand command, SettingValues& values,
                         const std::vector<pipeline::SettingRow>& table = pipeline::settings_table());

/// The --max-faces / --max-memory options of refine (its own meaning of faces: output faces).
struct LimitOptionValues {
  std::optional<double> max_faces;  ///< not given: the default
  std::string max_memory;  ///< empty: the default; else bytes with an optional K/M/G/T suffix
};
/// Registers --max-faces and --max-memory on `command`.
void add_limit_options(CLI::App& command, LimitOptionValues& values, const std::string& faces_meaning);
/// \throw pipeline::SettingsError (pipeline::validate's rules, a malformed --max-memory)
pipeline::ResourceLimits resource_limits(const LimitOptionValues& values);

/// Prints the pipeline's diagnostics on stderr in the command line's words: warnings as they
/// come; notes (none with --quiet) too, except that poles which are not polar structures are
/// kept for finish(): up to kListedPoles one line each, more in one line with counts by reason.
class DiagnosticPrinter {
 public:
  static constexpr size_t kListedPoles = 3;
  DiagnosticPrinter(std::ostream& err, bool quiet) : err_(err), quiet_(quiet) {}
  void operator()(const pipeline::ConversionDiagnostic& d);
  void finish();

 private:
  std::ostream& err_;
  bool quiet_;
  std::vector<pipeline::ConversionDiagnostic> poles_;
};

/// The command-line spelling of a pipeline setting (pipeline::SettingsError::setting): the
/// settings table's flag ("polar_lambda" -> "--lambda"), else "--" and the name with dashes
/// ("weight" -> "--weight", fair's own settings).
std::string option_name(const std::string& setting);

struct InfoOptions {
  std::string mesh;
  bool json = false;
  std::string input = "auto";  ///< which path convert would take: auto, mesh, cage
};

struct RefineOptions {
  std::string mesh;
  LimitOptionValues limits;
  int levels = 1;
  std::string output;
  std::string polar = "on";  ///< "on": BP subdivision at polar structures; "off": Catmull-Clark only
};

/// Describes a cage on `out` (text or JSON); warnings are part of the description.
/// \throw InputError for an unreadable or invalid cage
void run_info(const InfoOptions& options, std::ostream& out);

/// Refines a cage uniformly and writes the last level as OBJ. Warnings and progress go to
/// `err`. \throw InputError, WriteError, UsageError
void run_refine(const RefineOptions& options, std::ostream& err);

/// A valid command line asking for something impossible (exit code kUsage).
class UsageError : public Error {
 public:
  explicit UsageError(const std::string& message) : Error(ErrorKind::Usage, message) {}
};

/// Parses the command line, runs the subcommand and returns the exit code. Never throws.
int run(int argc, const char* const* argv, std::ostream& out, std::ostream& err);

}  // namespace subd2nurbs::cli
