#include "converter/pipeline/settings.h"

#include <algorithm>
#include <climits>
#include <cstdio>
#include <stdexcept>

#include "converter/pipeline/resources.h"

namespace subd2nurbs::pipeline {

namespace {

// --- reading a value of the row's type --------------------------------------------------------

bool flag(const SettingValue& v) { return std::get<bool>(v); }

/// A whole number as an int; values beyond int's range become its ends, which every rule refuses.
int integer(const SettingValue& v) {
  const long long x = std::get<long long>(v);
  return static_cast<int>(std::clamp<long long>(x, INT_MIN, INT_MAX));
}

double number(const SettingValue& v) {
  if (const auto* i = std::get_if<long long>(&v)) return static_cast<double>(*i);  // Python's 2 for 2.0
  return std::get<double>(v);
}

const std::string& word(const SettingValue& v) { return std::get<std::string>(v); }

/// OnOff: a bool, or the words "on" / "off" (checked by `named`).
bool on_off(const SettingValue& v, bool (*named)(const std::string&)) {
  if (const auto* b = std::get_if<bool>(&v)) return *b;
  return named(word(v));
}

double size(const SettingValue& v) {
  if (const auto* text = std::get_if<std::string>(&v)) return memory_size(*text);
  return number(v);
}

template <class T>
SettingValue optional_value(const std::optional<T>& x) {
  if (!x) return std::monostate{};
  if constexpr (std::is_integral_v<T>) return static_cast<long long>(*x);
  else return *x;
}

std::vector<std::string> schema_names() { return {"ap214", "ap242"}; }

std::string lowercase(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

/// Appends a row with its name, type and default; the caller fills in the rest.
SettingRow& add_row(std::vector<SettingRow>& t, std::string name, SettingType type, SettingValue default_value) {
  SettingRow& r = t.emplace_back();
  r.name = std::move(name);
  r.type = type;
  r.default_value = std::move(default_value);
  return r;
}

constexpr unsigned kBothCommands = kConvertCommand | kCheckCommand;

/// The surface's accuracy: level, tolerance, absolute.
void add_accuracy_rows(std::vector<SettingRow>& t) {

  {
    SettingRow& r = add_row(t, "level", SettingType::Integer, {});
    r.default_text = "chosen by the tolerance";
    r.help = "Pin the refinement levels beyond the minimum at every fan instead of choosing them from the "
             "tolerance: each level shrinks the deviation near extraordinary vertices (0 .. " +
             std::to_string(kMaxLevel) + ")";
    r.cli = "--level";
    r.commands = kBothCommands;
    r.property = {"Level", "Conversion",
                  "If > 0: extra refinement levels at every irregular vertex (0 with Tolerance 0: the default "
                  "tolerance, 1e-4 of the model size)",
                  {}, true};
    r.set = [](Settings& s, const SettingValue& v) { s.conversion.level = integer(v); };
    r.get = [](const Settings& s) { return optional_value(s.conversion.level); };
  }
  {
    SettingRow& r = add_row(t, "tolerance", SettingType::Number, {});
    r.default_text = "1e-4 unless a level is given";
    r.help = "Deviation from the limit surface to reach, relative to the bounding-box diagonal (unless absolute): "
             "each fan gets the levels it needs, at most " + std::to_string(kMaxFanExtraLevels) + " extra";
    r.cli = "--tolerance";
    r.property = {"Tolerance", "Conversion",
                  "If > 0: the deviation from the limit surface to reach (relative to the model size); each "
                  "irregular vertex gets the levels it needs, and Level is ignored",
                  {}, true};
    r.set = [](Settings& s, const SettingValue& v) { s.conversion.tolerance = number(v); };
    r.get = [](const Settings& s) { return optional_value(s.conversion.tolerance); };
  }
  {
    SettingRow& r = add_row(t, "absolute", SettingType::Flag, false);
    r.help = "The tolerance is in model units";
    r.cli = "--absolute";
    r.set = [](Settings& s, const SettingValue& v) { s.conversion.absolute = flag(v); };
    r.get = [](const Settings& s) -> SettingValue { return s.conversion.absolute; };
  }
}

/// Polar structures: polar, radial_steps, polar_lambda, separate_poles.
void add_polar_rows(std::vector<SettingRow>& t) {
  {
    SettingRow& r = add_row(t, "polar", SettingType::OnOff, true);
    r.help = "Polar structures (triangle fans around a pole): on (one singular polar cap each) or off "
             "(Catmull-Clark)";
    r.cli = "--polar";
    r.choices = {"on", "off"};
    r.property = {"PolarHandling", "Conversion",
                  "Polar structures (triangle fans around a pole): one singular polar cap each, or Catmull-Clark "
                  "patches like every other vertex",
                  {{"Polar caps", "on"}, {"Catmull-Clark", "off"}}};
    r.set = [](Settings& s, const SettingValue& v) { s.conversion.patch.polar = on_off(v, polar_mode); };
    r.get = [](const Settings& s) -> SettingValue { return s.conversion.patch.polar; };
  }
  {
    SettingRow& r = add_row(t, "radial_steps", SettingType::Integer, 1LL);
    r.help = "Radial BP pre-steps of a polar cap: 1 or " + std::to_string(kMaxRadialSteps) + " (elongated shapes)";
    r.cli = "--radial-steps";
    r.set = [](Settings& s, const SettingValue& v) { s.conversion.patch.cap.radial_steps = integer(v); };
    r.get = [](const Settings& s) -> SettingValue { return static_cast<long long>(s.conversion.patch.cap.radial_steps); };
  }
  {
    SettingRow& r = add_row(t, "polar_lambda", SettingType::Number, 0.75);
    r.help = "Scale of a polar cap's projected 1-link, > 0";
    r.cli = "--lambda";
    r.set = [](Settings& s, const SettingValue& v) { s.conversion.patch.cap.lambda = number(v); };
    r.get = [](const Settings& s) -> SettingValue { return s.conversion.patch.cap.lambda; };
  }
  {
    SettingRow& r = add_row(t, "separate_poles", SettingType::Flag, false);
    r.help = "Poles of valence 3..5 or too close to another: one separating Catmull-Clark step first "
             "(docs/math.md 3.7), then polar caps";
    r.cli = "--separate-poles";
    r.set = [](Settings& s, const SettingValue& v) { s.conversion.patch.separate_poles = flag(v); };
    r.get = [](const Settings& s) -> SettingValue { return s.conversion.patch.separate_poles; };
  }
}

/// The surface the cage stands for: fit, fair.
void add_fit_rows(std::vector<SettingRow>& t) {
  {
    SettingRow& r = add_row(t, "fit", SettingType::Word, std::string(to_string(FitMode::Approximate)));
    r.help = "approximate (the cage's own limit surface, which misses its vertices) or interpolate (solve for "
             "the cage whose limit passes through them)";
    r.cli = "--fit";
    r.choices = setting_names("fit");
    r.property = {"Fit", "Conversion",
                  "Approximate: the cage's own limit surface (it misses the cage's vertices); Interpolate: the "
                  "surface passes through every cage vertex (the cage is solved for first)",
                  {{"Approximate", "approximate"}, {"Interpolate", "interpolate"}}};
    r.set = [](Settings& s, const SettingValue& v) { s.conversion.fit.mode = fit_mode(word(v)); };
    r.get = [](const Settings& s) -> SettingValue { return std::string(to_string(s.conversion.fit.mode)); };
  }
  {
    SettingRow& r = add_row(t, "fair", SettingType::Number, {});
    r.default_text = "exact interpolation";
    r.help = "With fit interpolate: least squares with the thin-plate energy weighted W > 0 instead of exact "
             "interpolation (noisy points give a smooth surface)";
    r.cli = "--fair";
    r.property = {"FairWeight", "Conversion",
                  "With Fit = Interpolate: if > 0, trade exact interpolation for fairness (least squares with the "
                  "thin-plate energy weighted this much); 0: exact",
                  {}, true};
    r.set = [](Settings& s, const SettingValue& v) { s.conversion.fit.fair_weight = number(v); };
    r.get = [](const Settings& s) { return optional_value(s.conversion.fit.fair_weight); };
  }
}

/// What is made and written: faces, brep, schema, preview, preview_samples, samples.
void add_output_rows(std::vector<SettingRow>& t) {
  {
    SettingRow& r = add_row(t, "faces", SettingType::Word, std::string(to_string(FaceMode::Packed)));
    r.help = "packed (each regular region of quads is one B-spline face) or per-quad (one face per coarse quad)";
    r.cli = "--faces";
    r.commands = kBothCommands;
    r.choices = setting_names("faces");
    r.property = {"Faces", "Conversion",
                  "Packed: each regular region of quads is one B-spline face (fewer, larger faces); PerQuad: one "
                  "face per coarse quad",
                  {{"Packed", "packed"}, {"PerQuad", "per-quad"}}};
    r.set = [](Settings& s, const SettingValue& v) { s.conversion.faces = face_mode(word(v)); };
    r.get = [](const Settings& s) -> SettingValue { return std::string(to_string(s.conversion.faces)); };
  }
  {
    SettingRow& r = add_row(t, "planar_faces", SettingType::Word, std::string(to_string(PlanarMode::Merge)));
    r.help = "merge (coplanar packed faces become one planar face, exactly) or keep (one B-spline face each); "
             "per-quad faces are never merged";
    r.cli = "--planar-faces";
    r.choices = setting_names("planar_faces");
    r.property = {"PlanarFaces", "Conversion",
                  "Merge: coplanar faces become one planar face (exactly: their poles lie on the plane); Keep: one "
                  "B-spline face each",
                  {{"Merge", "merge"}, {"Keep", "keep"}}};
    r.set = [](Settings& s, const SettingValue& v) { s.conversion.planar = planar_mode(word(v)); };
    r.get = [](const Settings& s) -> SettingValue { return std::string(to_string(s.conversion.planar)); };
  }
  {
    SettingRow& r = add_row(t, "brep", SettingType::Flag, true);
    r.help = "Build the B-rep (checked by OCCT); false: the patches and their measures only";
    r.set = [](Settings& s, const SettingValue& v) { s.conversion.build_brep = flag(v); };
    r.get = [](const Settings& s) -> SettingValue { return s.conversion.build_brep; };
  }
  {
    SettingRow& r = add_row(t, "schema", SettingType::Word, std::string("ap214"));
    r.help = "STEP schema of a written STEP file: ap214 or ap242";
    r.cli = "--schema";
    r.python = false;  // an argument of ConversionResult.write
    r.choices = schema_names();
    r.set = [](Settings& s, const SettingValue& v) { s.write.schema = step_schema(word(v)); };
    r.get = [](const Settings& s) -> SettingValue { return lowercase(occt::to_string(s.write.schema)); };
  }
  {
    SettingRow& r = add_row(t, "preview", SettingType::Word, {});
    r.default_text = "curvature when a preview is asked for";
    r.help = "Preview colouring: deviation (from the exact limit), curvature (mean), zebra";
    r.cli = "--color";
    r.choices = setting_names("preview");
    r.set = [](Settings& s, const SettingValue& v) { s.preview = preview_color(word(v)); };
    r.get = [](const Settings& s) -> SettingValue {
      if (!s.preview) return std::monostate{};
      return std::string(to_string(*s.preview));
    };
  }
  {
    SettingRow& r = add_row(t, "preview_samples", SettingType::Integer, 12LL);
    r.help = "Preview vertices per patch side, 2 .. 64";
    r.cli = "--preview-samples";
    r.set = [](Settings& s, const SettingValue& v) { s.preview_samples = integer(v); };
    r.get = [](const Settings& s) -> SettingValue { return static_cast<long long>(s.preview_samples); };
  }
  {
    SettingRow& r = add_row(t, "samples", SettingType::Integer, {});
    r.default_text = std::to_string(kReportQualitySamples);
    r.help = "Quality samples per patch side, 2 .. 64";
    r.cli = "--samples";
    r.commands = kCheckCommand;
    r.python = false;
    r.set = [](Settings& s, const SettingValue& v) { s.conversion.quality_samples = integer(v); };
    r.get = [](const Settings& s) { return optional_value(s.conversion.quality_samples); };
  }
}

/// The resource limits: max_faces, max_memory, threads.
void add_limit_rows(std::vector<SettingRow>& t) {
  {
    SettingRow& r = add_row(t, "max_faces", SettingType::Number, {});
    r.default_text = "4e6";
    r.help = "Refuse when the polynomial pieces the patches are built from would exceed N, estimated";
    r.cli = "--max-faces";
    r.commands = kBothCommands;
    r.property = {"MaxFaces", "Limits",
                  "Refuse a conversion estimated to make more polynomial pieces (> 0; 0: the default, 4e6; as "
                  "--max-faces)",
                  {}, true};
    r.set = [](Settings& s, const SettingValue& v) { s.conversion.limits.max_faces = number(v); };
    r.get = [](const Settings& s) { return optional_value(s.conversion.limits.max_faces); };
  }
  {
    SettingRow& r = add_row(t, "max_memory", SettingType::Size, {});
    r.default_text = "3/4 of the memory available";
    r.help = "Refuse when the estimated memory would exceed SIZE (bytes, or with K/M/G/T)";
    r.cli = "--max-memory";
    r.commands = kBothCommands;
    r.property = {"MaxMemoryMiB", "Limits",
                  "Refuse a conversion estimated to need more memory, in MiB (> 0; 0: the default, 3/4 of the "
                  "memory available; as --max-memory)",
                  {}, true, 1024.0 * 1024.0};
    r.set = [](Settings& s, const SettingValue& v) { s.conversion.limits.max_memory = size(v); };
    r.get = [](const Settings& s) { return optional_value(s.conversion.limits.max_memory); };
  }
  {
    SettingRow& r = add_row(t, "threads", SettingType::Integer, {});
    r.default_text = "one per hardware thread (shared by the conversions running at once in one process)";
    r.help = "Threads one conversion uses, 1 .. 1024 (at most the machine's). Converting several models at once "
             "(a batch, Python threads), 1 per conversion is fastest";
    r.cli = "--threads";
    r.commands = kBothCommands;
    r.property = {"Threads", "Limits", "Threads the conversion uses (0: one per hardware thread; as --threads)", {},
                  true};
    r.set = [](Settings& s, const SettingValue& v) { s.conversion.limits.threads = integer(v); };
    r.get = [](const Settings& s) { return optional_value(s.conversion.limits.threads); };
  }
}

/// The mesh path (converter/pipeline/mesh_path.h): input, target_faces, aim_at_target, edge_length,
/// exact_spacing, fit_tolerance, feature_angle.
void add_mesh_rows(std::vector<SettingRow>& t) {
  {
    SettingRow& r = add_row(t, "input", SettingType::Word, std::string(to_string(InputKind::Auto)));
    r.help = "What the input is: auto (decided by the rule of docs/meshes.md: a triangle mesh that does not pair "
             "back into quads is a mesh), mesh (a shape to reproduce: remeshed into a quad cage, which is fitted "
             "to it) or cage (its own subdivision cage)";
    r.cli = "--input";
    r.choices = {"auto", "mesh", "cage"};
    r.property = {"InputKind", "Mesh",
                  "Auto: decided by the input (a triangle mesh that does not pair back into quads is remeshed); "
                  "Mesh: remesh into a quad cage fitted to the mesh; Cage: the input is the subdivision cage",
                  {{"Auto", "auto"}, {"Mesh", "mesh"}, {"Cage", "cage"}}};
    r.set = [](Settings& s, const SettingValue& v) { s.mesh.input = input_kind(word(v)); };
    r.get = [](const Settings& s) -> SettingValue { return std::string(to_string(s.mesh.input)); };
  }
  {
    SettingRow& r = add_row(t, "target_faces", SettingType::Integer, {});
    r.default_text = "from the mesh's area (edges of about 1/25 of the diagonal, 100 .. 1500 quads), then by fit_tolerance";
    r.help = "Mesh input: the number of quads of the cage made from the mesh (about)";
    r.cli = "--target-faces";
    r.property = {"TargetFaces", "Mesh", "Mesh input: quads of the cage (about; 0: automatic)", {}, true};
    r.set = [](Settings& s, const SettingValue& v) { s.mesh.target_faces = integer(v); };
    r.get = [](const Settings& s) -> SettingValue {
      if (s.mesh.target_faces == 0) return std::monostate{};
      return static_cast<long long>(s.mesh.target_faces);
    };
  }
  {
    SettingRow& r = add_row(t, "aim_at_target", SettingType::Flag, false);
    r.help = "Mesh input with target_faces: remesh again at corrected spacings (at most 5 runs) aiming at 0.9 .. "
             "1.0 x target_faces quads (else the nearest run, a shortfall counted 4 x an excess); where feature "
             "curves keep more vertices (small holes, lettering) the count stays above. Without it target_faces is "
             "approximate (often 10 .. 30 % over); ignored without target_faces";
    r.cli = "--aim-at-target";
    r.property = {"AimAtTarget", "Mesh", "Mesh input with TargetFaces: remesh (at most 5 runs) aiming at 0.9 .. 1 x "
                  "TargetFaces quads (feature curves may keep more)", {}, false};
    r.set = [](Settings& s, const SettingValue& v) { s.mesh.aim_at_target = flag(v); };
    r.get = [](const Settings& s) -> SettingValue { return s.mesh.aim_at_target; };
  }
  {
    SettingRow& r = add_row(t, "edge_length", SettingType::Number, {});
    r.default_text = "from target_faces";
    r.help = "Mesh input: the cage's edge length in model units, instead of target_faces";
    r.cli = "--edge-length";
    r.property = {"EdgeLength", "Mesh", "Mesh input: the cage's edge length in model units (0: from TargetFaces)",
                  {}, true};
    r.set = [](Settings& s, const SettingValue& v) { s.mesh.edge_length = number(v); };
    r.get = [](const Settings& s) -> SettingValue {
      if (s.mesh.edge_length == 0) return std::monostate{};
      return s.mesh.edge_length;
    };
  }
  {
    SettingRow& r = add_row(t, "exact_spacing", SettingType::Flag, false);
    r.help = "Mesh input with edge_length: one remesh at exactly that edge length. Without it a cage with more "
             "than 1.3 x area / edge_length^2 quads (the lattice's irregularities, feature curves) is remeshed "
             "once at a coarser spacing; ignored without edge_length";
    r.cli = "--exact-spacing";
    r.property = {"ExactSpacing", "Mesh", "Mesh input with EdgeLength: one remesh at exactly that edge length "
                  "(otherwise remeshed once coarser when the cage has over 1.3 x the quads it implies)", {}, false};
    r.set = [](Settings& s, const SettingValue& v) { s.mesh.exact_spacing = flag(v); };
    r.get = [](const Settings& s) -> SettingValue { return s.mesh.exact_spacing; };
  }
  {
    SettingRow& r = add_row(t, "fit_tolerance", SettingType::Number, 1e-3);
    r.help = "Mesh input with the automatic size: the two-sided max distance between the fitted surface and the "
             "mesh to reach, relative to the bounding-box diagonal; the cage is remeshed finer (or once coarser) at a "
             "size predicted from the distance measured (at most " + std::to_string(kMaxSizeRounds) +
             " times, up to 2.5 x the automatic size: docs/meshes.md); 0: off, one cage at the automatic size";
    r.cli = "--fit-tolerance";
    r.property = {"FitTolerance", "Mesh",
                  "Mesh input with TargetFaces and EdgeLength 0: the largest distance between the surface and the "
                  "mesh to reach, both ways, relative to the model size (the cage size is chosen for it; 0: off)",
                  {}, false};
    r.set = [](Settings& s, const SettingValue& v) { s.mesh.fit_tolerance = number(v); };
    r.get = [](const Settings& s) -> SettingValue { return s.mesh.fit_tolerance; };
  }
  {
    SettingRow& r = add_row(t, "feature_angle", SettingType::Number, 30.0);
    r.help = "Mesh input: an edge whose faces' normals differ by more than this many degrees is a sharp feature, "
             "kept as an infinitely sharp crease of the cage";
    r.cli = "--feature-angle";
    r.property = {"FeatureAngle", "Mesh", "Mesh input: degrees between the faces' normals above which an edge is "
                  "kept sharp"};
    r.set = [](Settings& s, const SettingValue& v) { s.mesh.feature_angle = number(v); };
    r.get = [](const Settings& s) -> SettingValue { return s.mesh.feature_angle; };
  }
}

std::vector<SettingRow> make_table() {
  std::vector<SettingRow> t;
  add_accuracy_rows(t);
  add_polar_rows(t);
  add_fit_rows(t);
  add_output_rows(t);
  add_limit_rows(t);
  add_mesh_rows(t);
  return t;
}

}  // namespace

const char* to_string(SettingType type) {
  switch (type) {
    case SettingType::Flag: return "flag";
    case SettingType::OnOff: return "on-off";
    case SettingType::Integer: return "integer";
    case SettingType::Number: return "number";
    case SettingType::Word: return "word";
    case SettingType::Size: return "size";
  }
  return "?";
}

const std::vector<SettingRow>& settings_table() {
  static const std::vector<SettingRow> table = make_table();
  return table;
}

const SettingRow* find_setting(const std::string& name) {
  for (const SettingRow& r : settings_table())
    if (r.name == name) return &r;
  return nullptr;
}

void validate(const Settings& settings) {
  validate(settings.conversion);
  validate(settings.mesh);
  check_samples("preview_samples", settings.preview_samples);
}

Settings make_settings(const std::vector<std::pair<std::string, SettingValue>>& given) {
  for (const auto& [name, value] : given)
    if (!find_setting(name)) throw std::out_of_range("unknown setting '" + name + "'");
  Settings s;
  for (const SettingRow& row : settings_table())
    for (const auto& [name, value] : given)
      if (name == row.name && !std::holds_alternative<std::monostate>(value)) row.set(s, value);
  validate(s);
  return s;
}

ConversionSettings conversion_settings(const Settings& settings) {
  ConversionSettings c = settings.conversion;
  if (settings.preview) c.preview = PreviewSettings{*settings.preview, settings.preview_samples};
  return c;
}

std::string value_text(const SettingRow& row, const SettingValue& value) {
  if (std::holds_alternative<std::monostate>(value)) return "";
  if (const auto* b = std::get_if<bool>(&value)) {
    if (row.type == SettingType::OnOff) return *b ? "on" : "off";
    return *b ? "true" : "false";
  }
  if (const auto* i = std::get_if<long long>(&value)) return std::to_string(*i);
  if (const auto* x = std::get_if<double>(&value)) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%g", *x);
    return buffer;
  }
  return std::get<std::string>(value);
}

std::string settings_markdown() {
  std::string md =
      "# Settings\n\n"
      "Every setting of a conversion, as the command line, the Python module (`subd2nurbs.convert`'s\n"
      "keywords) and the FreeCAD workbench (the NURBS object's properties) spell it. Generated from the\n"
      "one table of the converter (`converter/pipeline/settings.cpp`) by `subd2nurbs settings`;\n"
      "a test checks that this page is its output. Error messages name a setting as its front end spells it.\n\n"
      "| setting | command line | Python | FreeCAD | type | default | what it does |\n"
      "|---|---|---|---|---|---|---|\n";
  auto code = [](const std::string& s) { return s.empty() ? std::string("-") : "`" + s + "`"; };
  for (const SettingRow& r : settings_table()) {
    std::string cli = code(r.cli);
    if (!r.cli.empty() && r.commands != kConvertCommand)
      cli += (r.commands & kConvertCommand) ? " (convert, check)" : " (check)";
    std::string type = to_string(r.type);
    if (!r.choices.empty()) {
      type += ": ";
      for (size_t i = 0; i < r.choices.size(); ++i) type += (i ? ", " : "") + code(r.choices[i]);
    }
    std::string property = code(r.property.name);
    if (!r.property.choices.empty()) {
      property += " (";
      for (size_t i = 0; i < r.property.choices.size(); ++i)
        property += (i ? ", " : "") + r.property.choices[i].first;
      property += ")";
    }
    if (r.property.scale != 1) property += " (MiB)";
    const std::string default_text = std::holds_alternative<std::monostate>(r.default_value)
                                         ? r.default_text
                                         : code(value_text(r, r.default_value));
    md += "| `" + r.name + "` | " + cli + " | " + (r.python ? code(r.name) : std::string("-")) + " | " + property +
          " | " + type + " | " + default_text + " | " + r.help + " |\n";
  }
  return md;
}

}  // namespace subd2nurbs::pipeline
