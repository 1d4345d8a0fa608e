// The one table of the conversion's settings (docs/settings.md). Every front end loops over it:
// the command line declares its options from it (converter/cli), the Python module builds its
// Settings from convert()'s keywords by it and subd2nurbs.convert checks their types by it
// (python/), the FreeCAD workbench creates, reads and names the NURBS object's properties by it
// (freecad_plugin/), and docs/settings.md is its `subd2nurbs settings` (checked by a
// test). Adding a setting is one row here plus the code that uses its value.
//
// A row says how the setting is spelled everywhere (its name, the CLI flag, the FreeCAD
// property), what type its value has, its default and help text, and how it sets `Settings`.
// The rules of the values (ranges, what excludes what) stay in validate() (conversion.h): a row
// only converts. Named values (faces, fit, preview, ...) are checked when set, by the same
// name tables as everywhere (setting_names).
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "converter/occt/writers.h"
#include "converter/pipeline/conversion.h"
#include "converter/pipeline/mesh_path.h"

namespace subd2nurbs::pipeline {

/// Everything a front end sets for a conversion: the pipeline's settings, the preview's look
/// (whether a preview is made is the front end's: the CLI's --preview path, Python's preview=)
/// and the options of the written file.
struct Settings {
  ConversionSettings conversion;
  std::optional<PreviewColor> preview;  ///< the preview's colouring; empty: no preview asked for
  int preview_samples = 12;             ///< per patch side, 2 .. 64
  MeshPathSettings mesh;                ///< the mesh path's (a mesh input remeshed into a cage)
  /// The output's writer options.
  struct Write {
    occt::StepSchema schema = occt::StepSchema::AP214;
  } write;
};

/// A setting's value as a front end hands it over; std::monostate: not given (the default).
using SettingValue = std::variant<std::monostate, bool, long long, double, std::string>;

/// How a setting's value is spelled.
enum class SettingType {
  Flag,     ///< yes or no: a CLI flag, a Python bool, a FreeCAD PropertyBool
  OnOff,    ///< yes or no, "on" / "off" on the command line (Python: a bool or the word)
  Integer,  ///< a whole number
  Number,   ///< a real number
  Word,     ///< one of the row's `choices` (the converter's names)
  Size,     ///< a memory size in bytes: a number, or text with a K/M/G/T suffix (memory_size)
};
/// "flag", "on-off", "integer", "number", "word", "size".
const char* to_string(SettingType type);

/// The CLI subcommands that offer a setting (a bit set).
enum SettingCommand : unsigned { kConvertCommand = 1u, kCheckCommand = 2u };

/// The FreeCAD property of a setting on the workbench's NURBS object.
struct PropertySpec {
  std::string name;     ///< "Level"; empty: the workbench has none
  std::string group;    ///< the property editor's group: "Conversion", "Limits"
  std::string tooltip;  ///< empty: the row's help
  /// Enumerations whose choices are words for people: (the property's choice, the converter's
  /// name), the default first. Empty for a Word: the converter's names themselves.
  std::vector<std::pair<std::string, std::string>> choices;
  bool zero_is_default = false;  ///< a number property: 0 means "not given"
  double scale = 1;              ///< a number property: the setting's value is the property times this
};

struct SettingRow {
  std::string name;  ///< the converter's name: SettingsError::setting(), the Python keyword
  SettingType type = SettingType::Flag;
  /// The value when not given; monostate for optional settings (not given: the converter
  /// chooses, e.g. the tolerance's levels, or the stage is not run).
  SettingValue default_value;
  std::string default_text;  ///< optional settings: what not giving it means, for people ("1e-4 of the diagonal")
  std::string help;  ///< one or two sentences: the CLI's help, the docs, Python's docstring
  std::string cli;   ///< the command line's flag, e.g. "--lambda"; empty: none
  unsigned commands = kConvertCommand;  ///< with `cli`: the subcommands that offer it
  bool python = true;                   ///< a keyword of subd2nurbs.convert
  std::vector<std::string> choices;     ///< Word: the accepted names, in the rule's order
  PropertySpec property;                ///< the FreeCAD property, if any
  /// Sets a given value (never monostate) onto `settings`. \throw SettingsError for a name a
  /// Word or OnOff does not have, std::bad_variant_access for a value of another type
  std::function<void(Settings&, const SettingValue&)> set;
  /// The setting's value in `settings` (monostate: not set).
  std::function<SettingValue(const Settings&)> get;
};

/// The table, in the order of the CLI's help and the docs.
const std::vector<SettingRow>& settings_table();

/// The row named `name`, or nullptr.
const SettingRow* find_setting(const std::string& name);

/// Settings from values given by name (in any order; monostate values are skipped), applied in
/// the table's order and checked by validate() (conversion.h) and the preview's rules.
/// \throw SettingsError (a value breaking its rule), std::out_of_range (a name not in the table)
Settings make_settings(const std::vector<std::pair<std::string, SettingValue>>& given);

/// Checks `settings` as make_settings does: validate(settings.conversion), the preview samples.
/// \throw SettingsError
void validate(const Settings& settings);

/// The conversion's settings with the preview stage asked for when `preview` is set.
ConversionSettings conversion_settings(const Settings& settings);

/// A value as text for people and the docs: "" for monostate, "true"/"false", "on"/"off" for
/// OnOff, numbers in %g.
std::string value_text(const SettingRow& row, const SettingValue& value);

/// docs/settings.md: the table as Markdown (every row: name, CLI flag, Python keyword, FreeCAD
/// property, type, default, help).
std::string settings_markdown();

}  // namespace subd2nurbs::pipeline
