// The settings table (converter/pipeline/settings.h) against what the front ends and the docs
// make of it: the command line declares an option per row (a row added to a copy of the table
// reaches the help and the parsed values with no other edit), the rows' defaults are the
// settings structs' own, every row reads back what it set, and docs/settings.md is the table.
#include <gtest/gtest.h>

#include <CLI/CLI.hpp>

#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "common/run_command.h"
#include "converter/cli/commands.h"
#include "converter/occt/export_error.h"
#include "converter/pipeline/errors.h"
#include "converter/pipeline/settings.h"
#include "core/fit/interpolate.h"
#include "io/input_error.h"

using namespace subd2nurbs;
using pipeline::SettingRow;
using pipeline::SettingType;
using pipeline::SettingValue;

namespace {

std::string help_of(const std::string& command) {
  return subd2nurbs::testing::run_command(subd2nurbs::testing::quote(SUBD2NURBS_EXE) + " " + command + " --help").out;
}

/// A value of the row's type other than its default, valid by its rule (the rows of numbers
/// name theirs here: a new numeric row needs one).
SettingValue other_value(const SettingRow& row) {
  static const std::map<std::string, SettingValue> numbers = {
      {"level", 3LL},         {"tolerance", 1e-3},      {"radial_steps", 2LL}, {"polar_lambda", 0.5},
      {"fair", 0.25},         {"preview_samples", 5LL}, {"samples", 4LL},      {"max_faces", 1e5},
      {"max_memory", 2e9},    {"threads", 1LL}, {"target_faces", 500LL},  {"edge_length", 0.5},  {"feature_angle", 45.0},
      {"fit_tolerance", 2e-3}};
  switch (row.type) {
    case SettingType::Flag:
    case SettingType::OnOff: return !std::get<bool>(row.default_value);
    case SettingType::Word: return row.choices.back();
    default: break;
  }
  const auto it = numbers.find(row.name);
  if (it == numbers.end()) ADD_FAILURE() << "no test value for the numeric setting " << row.name;
  return it == numbers.end() ? SettingValue{} : it->second;
}

}  // namespace

TEST(SettingsTable, DefaultsAreTheSettingsOwn) {
  // A row's default and what the settings structs hold when nothing is given are one value.
  const pipeline::Settings defaults;
  for (const SettingRow& row : pipeline::settings_table())
    EXPECT_EQ(row.get(defaults), row.default_value) << row.name;
}

TEST(SettingsTable, EveryRowReadsBackWhatItSets) {
  for (const SettingRow& row : pipeline::settings_table()) {
    const SettingValue value = other_value(row);
    ASSERT_NE(value, row.default_value) << row.name;
    std::vector<std::pair<std::string, SettingValue>> given = {{row.name, value}};
    // Settings that need another one by the converter's rules.
    if (row.name == "fair") given.emplace_back("fit", std::string("interpolate"));
    if (row.name == "absolute") given.emplace_back("tolerance", 1e-3);
    const pipeline::Settings s = pipeline::make_settings(given);
    EXPECT_EQ(row.get(s), value) << row.name;
  }
}

TEST(SettingsTable, NamesAreUniqueAndUnknownOnesRefused) {
  std::map<std::string, int> names, flags, properties;
  for (const SettingRow& row : pipeline::settings_table()) {
    EXPECT_EQ(++names[row.name], 1) << row.name;
    if (!row.cli.empty()) EXPECT_EQ(++flags[row.cli], 1) << row.cli;
    if (!row.property.name.empty()) EXPECT_EQ(++properties[row.property.name], 1) << row.property.name;
    EXPECT_EQ(pipeline::find_setting(row.name), &row);
    EXPECT_TRUE(row.set && row.get) << row.name;
    EXPECT_FALSE(row.help.empty()) << row.name;
  }
  EXPECT_EQ(pipeline::find_setting("no_such_setting"), nullptr);
  EXPECT_THROW(pipeline::make_settings({{"no_such_setting", 1LL}}), std::out_of_range);
  // A word's names are checked when set, with the converter's rule.
  try {
    pipeline::make_settings({{"faces", std::string("all")}});
    ADD_FAILURE() << "faces=all accepted";
  } catch (const pipeline::SettingsError& e) {
    EXPECT_EQ(e.setting(), "faces");
    EXPECT_EQ(e.rule(), "must be packed or per-quad");
  }
}

TEST(SettingsTable, CommandLineHelpListsEveryRowOfItsCommand) {
  const std::string convert = help_of("convert"), check = help_of("check");
  for (const SettingRow& row : pipeline::settings_table()) {
    if (row.cli.empty()) continue;
    const std::string first_words = row.help.substr(0, 30);
    for (const auto& [command, help] : {std::pair{pipeline::kConvertCommand, &convert},
                                        std::pair{pipeline::kCheckCommand, &check}}) {
      const bool offered = (row.commands & command) != 0;
      EXPECT_EQ(help->find("  " + row.cli + " ") != std::string::npos, offered) << row.cli;
      if (offered) EXPECT_NE(help->find(first_words), std::string::npos) << row.cli;
    }
  }
}

TEST(SettingsTable, RowAddedToTheTableReachesTheCommandLine) {
  // The command line's options come from the table: a copy with one more row declares one
  // more option, with its help, whose value arrives under the row's name.
  std::vector<SettingRow> table = pipeline::settings_table();
  SettingRow& dummy = table.emplace_back();
  dummy.name = "dummy_setting";
  dummy.type = SettingType::Integer;
  dummy.default_value = 5LL;
  dummy.help = "A setting only this test has";
  dummy.cli = "--dummy-setting";
  CLI::App app{"test"};
  cli::SettingValues values;
  cli::add_setting_options(app, pipeline::kConvertCommand, values, table);
  const std::string help = app.help();
  EXPECT_NE(help.find("--dummy-setting"), std::string::npos) << help;
  EXPECT_NE(help.find("A setting only this test has (default: 5)"), std::string::npos) << help;
  app.parse(std::vector<std::string>{"7", "--dummy-setting", "per-quad", "--faces"});  // reversed, as CLI11 takes it
  ASSERT_EQ(values.size(), 2u);
  EXPECT_EQ(values[0], (std::pair<std::string, SettingValue>{"faces", std::string("per-quad")}));
  EXPECT_EQ(values[1], (std::pair<std::string, SettingValue>{"dummy_setting", 7LL}));
}

TEST(SettingsTable, OptionNamesComeFromTheTable) {
  EXPECT_EQ(cli::option_name("polar_lambda"), "--lambda");
  EXPECT_EQ(cli::option_name("preview"), "--color");
  EXPECT_EQ(cli::option_name("radial_steps"), "--radial-steps");
  EXPECT_EQ(cli::option_name("weight"), "--weight");  // fair's own settings are not in the table
}

TEST(SettingsTable, DocsPageIsTheTable) {
  std::ifstream in(std::string(SUBD2NURBS_SOURCE_DIR) + "/docs/settings.md");
  ASSERT_TRUE(in) << "docs/settings.md missing";
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), pipeline::settings_markdown())
      << "docs/settings.md is out of date: regenerate it with `subd2nurbs settings > docs/settings.md`";
  EXPECT_EQ(subd2nurbs::testing::run_command(subd2nurbs::testing::quote(SUBD2NURBS_EXE) + " settings").out, pipeline::settings_markdown());
}

// --- the error family (core/util/error.h, converter/pipeline/errors.h) -----------------------

TEST(ErrorFamily, EveryKindHasItsRowAndTheDocumentedExitCode) {
  // The codes `subd2nurbs --help` documents (kExitCodeHelp): 1 usage and settings, 2 invalid
  // input, 3 write failure, 4 export failure and internal errors.
  const std::map<ErrorKind, int> documented = {{ErrorKind::Usage, 1}, {ErrorKind::Settings, 1},
                                               {ErrorKind::Resources, 1}, {ErrorKind::Input, 2},
                                               {ErrorKind::Fit, 2}, {ErrorKind::Write, 3},
                                               {ErrorKind::Export, 4}};
  ASSERT_EQ(pipeline::error_classes().size(), documented.size());
  for (const auto& [kind, code] : documented) {
    EXPECT_EQ(pipeline::error_class(kind).kind, kind);
    EXPECT_EQ(pipeline::error_class(kind).exit_code, code) << pipeline::error_class(kind).name;
  }
  // Each concrete class is of its kind; anything outside the family is internal.
  EXPECT_EQ(pipeline::exit_code(pipeline::SettingsError("level", "must be 0 .. 12")), 1);
  EXPECT_EQ(pipeline::exit_code(pipeline::ResourceError("too big")), 1);
  EXPECT_EQ(pipeline::exit_code(cli::UsageError("same file")), 1);
  EXPECT_EQ(pipeline::exit_code(InputError("a.obj", 3, "bad face")), 2);
  EXPECT_EQ(pipeline::exit_code(InvalidMeshError(MeshErrorCode::NonManifoldEdge, ElementKind::Edge, 1, 2, "x")), 2);
  EXPECT_EQ(pipeline::exit_code(FitError("singular", {1})), 2);
  EXPECT_EQ(pipeline::exit_code(WriteError("a.step", "read-only")), 3);
  EXPECT_EQ(pipeline::exit_code(occt::ExportError("face", 2, "failed")), 4);
  EXPECT_EQ(pipeline::exit_code(std::invalid_argument("a broken precondition")), 4);
}
