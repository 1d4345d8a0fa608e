// The conversion pipeline shared by the CLI (`subd2nurbs convert`), the Python module and the
// FreeCAD workbench: validated cage -> patches -> continuity and deviation measured -> B-rep
// checked by OCCT -> (optional stages) the patches measured against the exact limit (quality)
// and tessellated with colours (preview), with the quality report (subd2nurbs-report v1,
// docs/formats.md) as JSON (report.h). No files are read or written here and nothing is printed: progress and warnings go to
// callbacks, everything else comes back in a ConversionResult.
#pragma once

#include <array>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "converter/occt/brep_builder.h"
#include "converter/occt/writers.h"
#include "converter/pipeline/mesh_path.h"
#include "converter/pipeline/resources.h"
#include "converter/pipeline/settings_error.h"
#include "converter/pipeline/text.h"
#include "core/eval/continuity.h"
#include "core/eval/deviation.h"
#include "core/eval/target_distance.h"
#include "core/eval/preview_mesh.h"
#include "core/eval/quality.h"
#include "core/eval/self_intersection.h"
#include "core/fit/fairing.h"
#include "core/fit/interpolate.h"
#include "core/patch/packing.h"
#include "core/patch/patch_builder.h"
#include "core/refine/refiner.h"

namespace subd2nurbs::pipeline {

/// The deviation tolerance used when neither a level nor a tolerance is given (relative to the
/// bounding-box diagonal).
constexpr double kDefaultTolerance = 1e-4;
/// Rebuilds a tolerance may take (the per-valence rates are asymptotic, so a fan may need a
/// second look; each round rebuilds and measures only the fans it deepens).
constexpr int kToleranceRounds = 8;
/// Samples per shared curve for the continuity measures.
constexpr int kContinuitySamples = 24;
/// Extra levels of refinement for the deviation samples.
constexpr int kDeviationSampleLevels = 2;

/// Which surface the cage stands for: its own limit surface (approximate: the NURBS misses the
/// cage's vertices), or the limit surface of the cage solved so that it passes through them
/// (interpolate; core/fit, docs/fitting.md), optionally traded for fairness (fair_weight > 0:
/// least squares with the thin-plate energy as regulariser).
enum class FitMode { Approximate, Interpolate };
const char* to_string(FitMode mode);
/// "approximate" or "interpolate". \throw SettingsError (setting "fit")
FitMode fit_mode(const std::string& name);

struct FitSettings {
  FitMode mode = FitMode::Approximate;
  std::optional<double> fair_weight;  ///< given: the fair fit with this weight (> 0, Interpolate only); else exact
  EnergyOptions energy;    ///< the fairing energy of a fair fit
};

/// How the patches become B-rep faces: regular regions packed into one B-spline face each
/// (core/patch/packing.h), or one face per coarse quad.
enum class FaceMode { Packed, PerQuad };
const char* to_string(FaceMode mode);
/// "packed" or "per-quad". \throw SettingsError (setting "faces")
FaceMode face_mode(const std::string& name);

/// Whether coplanar patches become one planar B-rep face (occt::BrepOptions::merge_planar) or
/// stay one B-spline face each. Per-quad faces are never merged.
enum class PlanarMode { Merge, Keep };
const char* to_string(PlanarMode mode);
/// "merge" or "keep". \throw SettingsError (setting "planar_faces")
PlanarMode planar_mode(const std::string& name);

/// Most extra levels a level setting pins (as many as a tolerance adds at one fan).
constexpr int kMaxLevel = kMaxFanExtraLevels;
/// The radial pre-steps of a polar cap the front ends offer: the joins and the B-rep are
/// measured with 1 and 2 (docs/polar.md); the core takes any count >= 1.
constexpr int kMaxRadialSteps = 2;

/// The quality stage's samples per patch side when `convert --report` asks for it.
constexpr int kReportQualitySamples = 9;

/// The preview stage: the patches tessellated with per-vertex colours (core/eval/preview_mesh.h).
struct PreviewSettings {
  PreviewColor color = PreviewColor::Curvature;
  int samples = 12;  ///< per patch side, 2 .. 64
};

/// What to convert with, as the user gave it; validate() checks it. `patch` is handed to
/// build_patches untouched, except that its extra_levels is set from `level` or chosen by the
/// tolerance.
struct ConversionSettings {
  PatchOptions patch;
  std::optional<int> level;         ///< pin the extra levels beyond the minimum at every fan
  std::optional<double> tolerance;  ///< choose each fan's levels for this deviation; with
                                    ///< neither, kDefaultTolerance
  bool absolute = false;        ///< tolerance in model units, else relative to the bbox diagonal
  bool build_brep = true;       ///< false: patches and measures only (e.g. for patch JSON)
  FaceMode faces = FaceMode::Packed;
  PlanarMode planar = PlanarMode::Merge;
  FitSettings fit;
  /// Refused before any work when estimate_conversion exceeds them (resources.h); with a
  /// tolerance, the extra levels are capped to stay within them.
  ResourceLimits limits;
  /// Optional stages after the B-rep, their results data in ConversionResult: given, the
  /// patches measured against the exact limit with this many samples per patch side (2 .. 64;
  /// ConversionResult::quality, the report's "quality" member)...
  std::optional<int> quality_samples;
  /// ... and the coloured tessellation (ConversionResult::preview).
  std::optional<PreviewSettings> preview;
};

/// How much a diagnostic matters: a note says what the conversion did instead (Catmull-Clark at
/// a pole), a warning that the result misses what was asked (a tolerance not met).
enum class Severity { Note, Warning };
const char* to_string(Severity severity);  ///< "note", "warning"

/// What a diagnostic is about; to_string gives a stable name ("pole_not_polar").
enum class DiagnosticCode { InterpolationSingular, ToleranceCapped, ToleranceNotMet, PacksRejected, PoleNotPolar,
                            PolesSeparated, TinyPart, FlatPart, ThinPart, SelfIntersection, PartsOverlap };
const char* to_string(DiagnosticCode code);

/// Something the conversion reports besides its result, in its own words: no program name and
/// no front end's option names (a front end words `remedy` its own way).
struct ConversionDiagnostic {
  Severity severity = Severity::Warning;
  DiagnosticCode code = DiagnosticCode::ToleranceNotMet;
  std::string message;   ///< one sentence
  int element = -1;      ///< the cage vertex it is about, or -1
  std::string remedy;    ///< a setting that may mend it, named as SettingsError names settings, or empty
  std::string category;  ///< PoleNotPolar: the kind of reason ("valence below 6"), for summaries
};

/// A diagnostic as one line of subd2nurbs-report v1's "warnings" and the Python module's
/// ConversionResult.warnings: "subd2nurbs: note: ..." with the command line's option as the
/// remedy, as the command line has always printed it.
std::string report_text(const ConversionDiagnostic& diagnostic);

/// The stages of a conversion, in order (Patches and Deviation repeat for a tolerance; Quality
/// and Preview run only when the settings ask for them); to_string gives a stable name ("patches").
enum class Stage { Fit, Patches, Deviation, Packing, Continuity, Brep, Quality, Preview };
const char* to_string(Stage stage);

/// Progress reporting; every member may be empty.
struct ConversionResult;

struct ConversionProgress {
  /// A stage starts, with a line for people: "building patches (2 extra levels)", ...
  std::function<void(Stage stage, const std::string& text)> stage;
  /// Fraction (0..1] of the B-rep stage done, about every 1 %.
  std::function<void(double fraction)> brep_fraction;
  /// A diagnostic, as it is found (it is also kept in ConversionResult::diagnostics).
  std::function<void(const ConversionDiagnostic& diagnostic)> diagnostic;
  /// Called once, after the B-rep stage (whether or not it built a B-rep), on the calling
  /// thread, while the quality stage (ConversionSettings::quality_samples) may still run on a
  /// thread of its own: work for the core that OCCT's single-threaded stages leave idle, such
  /// as writing the output file. It may read the result and set `ms.write`; it must not change
  /// anything else before convert returns. An exception it throws ends the conversion.
  std::function<void(ConversionResult& result)> after_brep;
};

struct Timings {
  double load = 0, fit = 0, patches = 0, packing = 0, continuity = 0, deviation = 0, brep = 0, write = 0;
  double intersections = 0;  ///< self-intersections and overlaps (ConversionResult::intersections)
  double quality = 0, preview = 0;  ///< the optional stages (the report gives quality as "quality_ms")
  /// The quality stage runs beside the B-rep stage and ConversionProgress::after_brep: the wall
  /// time convert waited for it once those were done (what the stage added to the conversion).
  double quality_wait = 0;
  /// The threads the conversion's parallel loops used at most (the `threads` setting or the
  /// hardware threads); a run's property like the times.
  int threads = 1;
};

/// What the fit did (FitMode::Interpolate), in model units.
struct FitReport {
  FitMode mode = FitMode::Approximate;
  double fair_weight = 0;
  FieldStats residual;       ///< |limit of the fitted cage at v - input vertex v|
  FieldStats displacement;   ///< |fitted cage vertex - input vertex|
  double condition = 0;      ///< estimate for the limit operator (exact interpolation), else 0
  bool singular = false;     ///< the interpolant is not unique (InterpolationResult::singular)
  std::vector<int> null_vertices;
  int polar_vertices = 0;    ///< vertices interpolated with BP's limit
  int no_surface = 0;        ///< vertices without limit surface (left in place)
  double energy_before = -1, energy_after = -1;  ///< fairing energy of the input / fitted cage (fair fit)
  /// `convert --fit-to TARGET`: the fit to the target shape (core/fit/shape_fit.h), set by the caller.
  struct ToTarget {
    std::string target;                ///< the target's path
    int iterations = 0;
    std::string stop;                  ///< to_string(ShapeFitStop)
    TargetDistance before, after;      ///< the input and the fitted cage's limit to the target, two-sided
  };
  std::optional<ToTarget> to_target;
};

struct ToleranceResult {
  double requested = 0;  ///< as given
  bool is_default = false;  ///< kDefaultTolerance (neither a level nor a tolerance was given)
  int fans_deepened = 0;    ///< coarse vertices whose fans got extra levels
  double absolute = 0;   ///< in model units
  double first_max = 0;  ///< deviation at the minimum level
  int needed = 0;        ///< most extra levels any fan asked for
  int used = 0;          ///< most extra levels any fan got (after the cap)
  bool capped = false;
  std::string cap_reason;
  bool met = false;
};

struct ApproximateFan {
  int base_vertex = -1, valence = 0, sectors = 0, rays = 0;
  double normal_angle_deg = -1;  ///< max over its measured C0 rays, -1 if none was measured
};

/// One polar cap, measured.
struct CapMeasure {
  int pole_vertex = -1;      ///< cage vertex
  int valence = 0;
  double bp_distance = 0;    ///< max distance from the BP limit surface to the cap (model units)
  CapPoleMeasure pole;       ///< normal angle to BP's and max |k| at 1e-2 and 1e-4 from the pole
};

/// Where the result went, for the report; filled by the caller (empty strings give null).
struct OutputInfo {
  std::string path;
  std::string format;       ///< "STEP", "IGES", "BREP", "JSON"
  std::string step_schema;  ///< "AP214" / "AP242" for STEP, else empty
};

struct ConversionResult;
/// Throws InputError (exit 2) naming `input` when `result.exchange_refusal` is set and `format`
/// is STEP or IGES (the B-rep would not survive the file); nothing for BREP / JSON.
void check_exchange_output(const ConversionResult& result, const std::string& input, bool step_or_iges);

struct ConversionResult {
  std::string input;  ///< the cage's name for the report (set by the caller)
  OutputInfo output;  ///< set by the caller
  std::vector<std::string> warnings;  ///< the caller's load warnings, as given
  std::vector<ConversionDiagnostic> diagnostics;  ///< the pipeline's, in the order found
  PatchBuild build;     ///< the patches per coarse quad, with how they were built
  FaceMode faces = FaceMode::Packed;
  /// What is exported and measured for continuity: build.set packed (FaceMode::Packed) or as
  /// it is. exported.set is the PatchSet of the B-rep, the patch JSON and the Python result.
  PackedSet exported;
  int extra_levels = 0;
  ContinuityReport continuity;  ///< over output.set's curves
  /// Where the exported faces cross themselves or separate components overlap
  /// (core/eval/self_intersection.h); each kind found also gives a warning
  /// (self_intersection, parts_overlap).
  SelfIntersectionReport intersections;
  DeviationReport deviation;
  bool tolerance_given = false, tolerance_absolute = false;
  ToleranceResult tolerance;
  std::array<int, 5> fans_by_mode{};  ///< indexed by FanMode
  std::vector<ApproximateFan> approximate;
  std::array<int, 5> curves_by_continuity{};  ///< indexed by Continuity
  bool polar = true;               ///< polar structures became caps (PatchOptions::polar)
  PolarCapOptions cap_options;
  std::vector<CapMeasure> caps;    ///< one per PatchBuildInfo::caps
  bool has_brep = false;
  occt::BrepResult brep;  ///< check brep.valid: an invalid B-rep is returned, not thrown
  FitReport fit;
  std::vector<Point3> cage;  ///< the cage converted: the input's positions, or the fitted cage
  std::optional<QualityReport> quality;  ///< ConversionSettings::quality_samples given
  /// The resource estimate (resources.h): before any work, from the cage's topology (what the
  /// limits were first checked against), and with the fans as built (their levels known after
  /// the tolerance stage), before packing and the B-rep.
  ResourceEstimate estimate_before, estimate;
  std::optional<PreviewMesh> preview;    ///< ConversionSettings::preview given
  /// The input was a mesh (mesh_path.h): what made the cage from it; set by the caller.
  std::optional<MeshPathReport> mesh;
  /// Why a STEP or IGES file cannot carry this result, or empty: a part of the cage smaller or
  /// thinner than 10 B-rep tolerances (tiny_part, thin_part), which OCCT's STEP / IGES readers
  /// merge or shrink (measured: invalid shapes, half the volume). A BREP file carries it.
  /// Front ends refuse STEP / IGES output with check_exchange_output.
  std::string exchange_refusal;
  PreviewSettings preview_settings;      ///< what `preview` was made with
  Timings ms;             ///< load and write are the caller's to fill
};

/// Checks `settings` on their own: the one place of the rules of every conversion setting.
/// \throw SettingsError naming the first setting that breaks its rule
void validate(const ConversionSettings& settings);

/// The rules of a fairing (subd2nurbs fair, Python fair()): weight > 0, energy levels 0 .. 4,
/// membrane >= 0. \throw SettingsError ("weight", "levels", "membrane")
void validate_fairing(double weight, const EnergyOptions& energy);
/// The vertices a fairing keeps, by name: boundary, creases, tagged. \throw SettingsError ("keep")
KeepSet keep_set(const std::vector<std::string>& names);

/// The cage's subdivision options (core/mesh/mesh_input.h) by their names (to_string), for every
/// front end that takes them by name (the Python module's Cage and arrays, the workbench's Cage
/// properties; OBJ files give them as OpenSubdiv tags, io/obj_reader.h).
/// "none", "edge-only" or "edge-and-corner". \throw SettingsError ("boundary")
BoundaryRule boundary_rule(const std::string& name);
/// "uniform" or "chaikin". \throw SettingsError ("crease_method")
CreaseMethod crease_method(const std::string& name);
/// "catmark" or "smooth". \throw SettingsError ("triangles")
TriangleRule triangle_rule(const std::string& name);
/// The names a setting of named values accepts, in the order its rule lists them: "boundary",
/// "crease_method", "triangles", "fit", "faces", "preview". \throw std::out_of_range for others
std::vector<std::string> setting_names(const std::string& setting);

/// Polar structures as the command line's --polar names them: "on" (polar caps, true) or "off"
/// (Catmull-Clark). \throw SettingsError ("polar")
bool polar_mode(const std::string& name);
/// The STEP schema of a written file: "ap214" or "ap242". \throw SettingsError ("schema")
occt::StepSchema step_schema(const std::string& name);

/// The preview colouring: "deviation", "curvature" or "zebra". \throw SettingsError ("preview")
PreviewColor preview_color(const std::string& name);
/// Samples per patch side of a preview or a quality measure: 2 .. 64. \throw SettingsError (`setting`)
void check_samples(const std::string& setting, int samples);

/// The preview stage on its own, e.g. for a result converted without it (the FreeCAD colour map
/// of a NURBS object's last conversion). \throw SettingsError ("preview_samples")
PreviewMesh build_preview(const SubdivLevel& base, const ConversionResult& result, const PreviewSettings& preview);

/// Converts a validated cage. `warnings` (e.g. from reading and validating it) start the
/// result's warning list.
/// \throw SettingsError (see validate), ResourceError (the estimate exceeds
///        settings.limits, resources.h), InvalidMeshError (every face is a hole: no surface),
///        FitError (FitMode::Interpolate: no cage interpolates the vertices; names them),
///        std::invalid_argument (topology the patch builder does not support),
///        occt::ExportError (OCCT failed while building the B-rep)
ConversionResult convert(const SubdivLevel& base, const std::vector<Point3>& positions,
                         const ConversionSettings& settings, const ConversionProgress& progress = {},
                         std::vector<std::string> warnings = {});

/// The load warnings, then report_text of each diagnostic: the report's "warnings".
std::vector<std::string> warning_texts(const ConversionResult& result);

}  // namespace subd2nurbs::pipeline
