#include "converter/pipeline/conversion.h"
#include "converter/pipeline/settings.h"
#include "io/input_error.h"

#include "core/nurbs/nurbs_eval.h"
#include "core/util/parallel.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <future>
#include <optional>
#include <utility>

namespace subd2nurbs::pipeline {

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

void collect_fans(ConversionResult& c) {
  const PatchBuildInfo& info = c.build.info;
  std::vector<int> measure_of_curve(c.exported.set.curves.size(), -1);
  for (size_t i = 0; i < c.continuity.curves.size(); ++i)
    measure_of_curve[c.continuity.curves[i].curve] = static_cast<int>(i);
  std::vector<int> approximate_of_fan(info.fans.size(), -1);
  for (size_t f = 0; f < info.fans.size(); ++f) {
    const IrregularFan& fan = info.fans[f];
    ++c.fans_by_mode[static_cast<int>(fan.mode)];
    if (fan.mode != FanMode::Approximate) continue;
    approximate_of_fan[f] = static_cast<int>(c.approximate.size());
    c.approximate.push_back({fan.base_vertex, fan.valence, fan.sectors, 0, -1});
  }
  for (const RayCurve& ray : info.rays) {
    if (ray.fan < 0 || approximate_of_fan[ray.fan] < 0 || ray.continuity != Continuity::C0) continue;
    ApproximateFan& a = c.approximate[approximate_of_fan[ray.fan]];
    ++a.rays;
    const int out = c.exported.curve[ray.curve];  // rays are never inside a pack
    const int m = out < 0 ? -1 : measure_of_curve[out];
    if (m >= 0) a.normal_angle_deg = std::max(a.normal_angle_deg, c.continuity.curves[m].normal_angle_deg);
  }
  for (const BoundaryCurve& bc : c.exported.set.curves) ++c.curves_by_continuity[static_cast<int>(bc.continuity)];
}

}  // namespace

/// Each cap against BP: the distance from the BP limit surface and the normal next to the
/// pole against the BP limit normal.
void measure_caps(ConversionResult& c) {
  for (const CapInfo& ci : c.build.info.caps) {
    CapMeasure m;
    m.pole_vertex = ci.structure.pole;
    m.valence = ci.structure.valence;
    const NurbsPatch& patch = c.build.set.patches[ci.patch];
    m.bp_distance = cap_distance_to_bp(ci.input, ci.cap, patch);
    m.pole = measure_cap_pole(ci.cap, patch);
    c.caps.push_back(m);
  }
}

namespace {
std::string index_list(const std::vector<int>& v) {
  std::string s;
  for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + std::to_string(v[i]);
  return s;
}
}  // namespace

const char* to_string(FaceMode mode) { return mode == FaceMode::Packed ? "packed" : "per-quad"; }

const char* to_string(PlanarMode mode) { return mode == PlanarMode::Merge ? "merge" : "keep"; }

const char* to_string(FitMode mode) { return mode == FitMode::Interpolate ? "interpolate" : "approximate"; }

const char* to_string(Stage stage) {
  static const char* const names[] = {"fit",        "patches", "deviation", "packing",
                                      "continuity", "brep",    "quality",   "preview"};  // enum order
  return names[static_cast<int>(stage)];
}

const char* to_string(Severity severity) { return severity == Severity::Note ? "note" : "warning"; }

const char* to_string(DiagnosticCode code) {
  switch (code) {
    case DiagnosticCode::InterpolationSingular: return "interpolation_singular";
    case DiagnosticCode::ToleranceCapped: return "tolerance_capped";
    case DiagnosticCode::ToleranceNotMet: return "tolerance_not_met";
    case DiagnosticCode::PacksRejected: return "packs_rejected";
    case DiagnosticCode::PoleNotPolar: return "pole_not_polar";
    case DiagnosticCode::PolesSeparated: return "poles_separated";
    case DiagnosticCode::TinyPart: return "tiny_part";
    case DiagnosticCode::FlatPart: return "flat_part";
    case DiagnosticCode::ThinPart: return "thin_part";
    case DiagnosticCode::SelfIntersection: return "self_intersection";
    case DiagnosticCode::PartsOverlap: return "parts_overlap";
  }
  return "?";
}

std::string report_text(const ConversionDiagnostic& d) {
  std::string text = std::string("subd2nurbs: ") + to_string(d.severity) + ": " + d.message;
  if (d.code == DiagnosticCode::PoleNotPolar && !d.remedy.empty())
    text += " (" + find_setting(d.remedy)->cli + " may make it a polar cap)";
  if (d.code == DiagnosticCode::ToleranceCapped && !d.remedy.empty()) text.insert(text.size() - 1, ", --max-faces / --max-memory");
  return text;
}

std::vector<std::string> warning_texts(const ConversionResult& result) {
  std::vector<std::string> texts = result.warnings;
  for (const ConversionDiagnostic& d : result.diagnostics) texts.push_back(report_text(d));
  return texts;
}

namespace {

// The settings given by name: each value's name is its to_string; the rule lists them in order.
constexpr std::array kBoundaryRules{BoundaryRule::None, BoundaryRule::EdgeOnly, BoundaryRule::EdgeAndCorner};
constexpr std::array kCreaseMethods{CreaseMethod::Uniform, CreaseMethod::Chaikin};
constexpr std::array kTriangleRules{TriangleRule::Catmark, TriangleRule::Smooth};
constexpr std::array kFitModes{FitMode::Approximate, FitMode::Interpolate};
constexpr std::array kFaceModes{FaceMode::Packed, FaceMode::PerQuad};
constexpr std::array kPlanarModes{PlanarMode::Merge, PlanarMode::Keep};
constexpr std::array kPreviewColors{PreviewColor::Deviation, PreviewColor::Curvature, PreviewColor::Zebra};

template <class E, size_t N>
std::vector<std::string> names_of(const std::array<E, N>& values) {
  std::vector<std::string> names;
  for (const E v : values) names.emplace_back(to_string(v));
  return names;
}

/// The value named `name`; else SettingsError(setting, "must be a, b or c").
template <class E, size_t N>
E named(const char* setting, const std::array<E, N>& values, const std::string& name) {
  for (const E v : values)
    if (name == to_string(v)) return v;
  const std::vector<std::string> names = names_of(values);
  std::string rule = "must be " + names[0];
  for (size_t i = 1; i < N; ++i) rule += (i + 1 < N ? ", " : " or ") + names[i];
  throw SettingsError(setting, rule);
}

}  // namespace

BoundaryRule boundary_rule(const std::string& name) { return named("boundary", kBoundaryRules, name); }
CreaseMethod crease_method(const std::string& name) { return named("crease_method", kCreaseMethods, name); }
TriangleRule triangle_rule(const std::string& name) { return named("triangles", kTriangleRules, name); }
FitMode fit_mode(const std::string& name) { return named("fit", kFitModes, name); }
FaceMode face_mode(const std::string& name) { return named("faces", kFaceModes, name); }
PlanarMode planar_mode(const std::string& name) { return named("planar_faces", kPlanarModes, name); }
PreviewColor preview_color(const std::string& name) { return named("preview", kPreviewColors, name); }

std::vector<std::string> setting_names(const std::string& setting) {
  if (setting == "boundary") return names_of(kBoundaryRules);
  if (setting == "crease_method") return names_of(kCreaseMethods);
  if (setting == "triangles") return names_of(kTriangleRules);
  if (setting == "fit") return names_of(kFitModes);
  if (setting == "faces") return names_of(kFaceModes);
  if (setting == "planar_faces") return names_of(kPlanarModes);
  if (setting == "preview") return names_of(kPreviewColors);
  throw std::out_of_range("setting_names: '" + setting + "' is not a setting of named values");
}

void validate_fairing(double weight, const EnergyOptions& energy) {
  if (!(weight > 0 && std::isfinite(weight))) throw SettingsError("weight", "must be a positive number");
  if (energy.levels < 0 || energy.levels > 4) throw SettingsError("levels", "must be 0 .. 4");
  if (!(energy.membrane >= 0 && std::isfinite(energy.membrane))) throw SettingsError("membrane", "must be a number >= 0");
}

KeepSet keep_set(const std::vector<std::string>& names) {
  KeepSet keep;
  for (const std::string& k : names) {
    if (k == "boundary") keep.boundary = true;
    else if (k == "creases") keep.creases = true;
    else if (k == "tagged") keep.tagged = true;
    else throw SettingsError("keep", "must be boundary, creases or tagged");
  }
  return keep;
}

bool polar_mode(const std::string& name) {
  if (name == "on" || name == "off") return name == "on";
  throw SettingsError("polar", "must be on or off");
}

occt::StepSchema step_schema(const std::string& name) {
  if (name == "ap214") return occt::StepSchema::AP214;
  if (name == "ap242") return occt::StepSchema::AP242;
  throw SettingsError("schema", "must be ap214 or ap242");
}

void check_samples(const std::string& setting, int samples) {
  if (samples < 2 || samples > 64) throw SettingsError(setting, "must be 2 .. 64");
}

void validate(const ConversionSettings& settings) {
  auto positive = [](std::optional<double> x) { return !x || (*x > 0 && std::isfinite(*x)); };
  if (settings.level && (*settings.level < 0 || *settings.level > kMaxLevel))
    throw SettingsError("level", "must be 0 .. " + std::to_string(kMaxLevel));
  if (!positive(settings.tolerance)) throw SettingsError("tolerance", "must be a positive number");
  if (settings.level && settings.tolerance)
    throw SettingsError("tolerance", "excludes a level (the tolerance chooses the levels)");
  if (settings.absolute && !settings.tolerance) throw SettingsError("absolute", "needs a tolerance");
  const PolarCapOptions& cap = settings.patch.cap;
  if (cap.radial_steps < 1 || cap.radial_steps > kMaxRadialSteps)
    throw SettingsError("radial_steps", "must be 1 or " + std::to_string(kMaxRadialSteps));
  if (!positive(cap.lambda)) throw SettingsError("polar_lambda", "must be a positive number");
  if (settings.patch.separate_poles && !settings.patch.polar) throw SettingsError("separate_poles", "needs polar caps");
  const FitSettings& fit = settings.fit;
  if (!positive(fit.fair_weight)) throw SettingsError("fair", "must be a positive number (the weight of the fairing energy)");
  if (fit.fair_weight && fit.mode != FitMode::Interpolate) throw SettingsError("fair", "needs the interpolating fit");
  if (fit.mode == FitMode::Interpolate && settings.patch.separate_poles)
    throw SettingsError("separate_poles", "is not supported by the interpolating fit (the separating step changes "
                                          "the subdivision rule the fit solves for)");
  if (fit.energy.levels < 0 || fit.energy.levels > 4) throw SettingsError("fair_levels", "must be 0 .. 4");
  validate(settings.limits);
  if (settings.quality_samples) check_samples("samples", *settings.quality_samples);
  if (settings.preview) check_samples("preview_samples", settings.preview->samples);
}

PreviewMesh build_preview(const SubdivLevel& base, const ConversionResult& c, const PreviewSettings& preview) {
  check_samples("preview_samples", preview.samples);
  std::optional<LimitEvaluator> limit;  // the deviation colouring measures against the exact limit
  if (preview.color == PreviewColor::Deviation) limit.emplace(base, c.cage);
  return subd2nurbs::build_preview(c.build, limit ? &*limit : nullptr, preview.color, preview.samples);
}

namespace {

/// What the stages of a conversion share: the cage, the settings, the progress callbacks and
/// the result they fill in.
struct Run {
  const SubdivLevel& base;
  const ConversionSettings& settings;
  const ConversionProgress& progress;
  ConversionResult& c;

  void stage(Stage which, const std::string& text) const {
    if (progress.stage) progress.stage(which, text);
  }
  void report(ConversionDiagnostic d) const {
    if (progress.diagnostic) progress.diagnostic(d);
    c.diagnostics.push_back(std::move(d));
  }
  void warn(DiagnosticCode code, const std::string& message) const {
    report({Severity::Warning, code, message, -1, "", ""});
  }
  EstimateOptions estimate_options() const {
    EstimateOptions o;
    o.build_brep = settings.build_brep;
    o.packed = settings.faces == FaceMode::Packed;
    o.quality = settings.quality_samples.has_value();
    o.polar = settings.patch.polar;
    return o;
  }
  /// The resource limits allow `estimate`.
  bool fits(const ResourceEstimate& estimate) const {
    try {
      check_resources(estimate, settings.limits, kDefaultMaxConvertFaces, "", "");
      return true;
    } catch (const ResourceError&) {
      return false;
    }
  }
};

/// The fans of a build as the estimate costs them, with their levels below the coarse level.
std::vector<FanCost> fan_costs(const PatchBuild& build) {
  std::vector<FanCost> costs;
  // The irregular vertices sharing a coarse face with each fan's vertex (resources.h, nearby).
  const PolyMesh& m = build.refinement.levels[build.info.coarse_level].mesh;
  std::vector<int> valence_of(m.num_vertices(), 0);
  for (const IrregularFan& f : build.info.fans)
    if (f.vertex >= 0 && f.vertex < m.num_vertices()) valence_of[f.vertex] = f.valence;
  for (const IrregularFan& f : build.info.fans) {
    FanCost cost{f.valence, f.sectors, std::max(1, f.level - build.info.coarse_level), 0};
    if (f.vertex >= 0 && f.vertex < m.num_vertices()) cost.nearby = nearby_valence(m, f.vertex, valence_of);
    costs.push_back(cost);
  }
  return costs;
}

/// The smallest cage converted (bounding-box diagonal): the 4th powers of lengths in the
/// curvature measures stay normal doubles (1e-240), as the coordinate limit 1e15 keeps them finite.
constexpr double kMinModelSize = 1e-60;

/// A cage with a surface to convert: not every face a hole, and of a size double precision
/// resolves at its distance from the origin. \throw InvalidMeshError
void check_has_surface(const SubdivLevel& base, const std::vector<Point3>& positions) {
  bool any_surface = false;
  for (const char hole : base.face_hole) any_surface = any_surface || !hole;
  if (!any_surface)
    throw InvalidMeshError(MeshErrorCode::EmptyMesh, ElementKind::None, -1, -1,
                           "every face of the cage is a hole ('t hole' tags): there is no surface to convert");
  // A cage of zero size (all vertices at one point), or one too small for its distance from
  // the origin to be resolved in double precision, has no surface a B-rep can hold. The
  // vertices that faces use count, as for the model size (an unused one has no surface).
  const PolyMesh& m = base.mesh;
  Point3 lo = m.num_corners() == 0 ? Point3{0, 0, 0} : positions[m.corner_vertex(0)], hi = lo;
  double far = 0;
  for (int h = 0; h < m.num_corners(); ++h)
    for (int k = 0; k < 3; ++k) {
      const Point3& p = positions[m.corner_vertex(h)];
      lo[k] = std::min(lo[k], p[k]);
      hi[k] = std::max(hi[k], p[k]);
      far = std::max(far, std::fabs(p[k]));
    }
  // hypot, as `info` measures it: the squares of a denormal cage's sides underflow to 0.
  const double diagonal = std::hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  if (diagonal == 0)
    throw InvalidMeshError(MeshErrorCode::CoordinateOutOfRange, ElementKind::None, -1, -1,
                           "the cage has size 0 (bounding-box diagonal) - all its vertices coincide: there "
                           "is no surface to convert");
  if (diagonal < kMinModelSize)
    throw InvalidMeshError(MeshErrorCode::CoordinateOutOfRange, ElementKind::None, -1, -1,
                           "the cage has size " + short_number(diagonal) +
                               " (bounding-box diagonal), below the smallest size converted, " +
                               short_number(kMinModelSize) +
                               " (the squares and higher powers of its lengths would underflow): scale the model up");
  if (!(diagonal > 1e-12 * far))
    throw InvalidMeshError(MeshErrorCode::CoordinateOutOfRange, ElementKind::None, -1, -1,
                           "the cage has size " + short_number(diagonal) + " (bounding-box diagonal) at distance " +
                               short_number(far) + " from the origin, below what double precision resolves" +
                               ": there is no surface to convert");
}

/// The fit stage (FitMode::Interpolate): c.cage becomes the cage whose limit passes through the
/// input's vertices (or a fair fit of them); else it stays the input.
void fit_stage(const Run& r, const std::vector<Point3>& positions) {
  ConversionResult& c = r.c;
  const ConversionSettings& settings = r.settings;
  c.cage = positions;
  if (settings.fit.mode != FitMode::Interpolate) return;
  const auto t0 = Clock::now();
  FitReport& fr = c.fit;
  fr.mode = FitMode::Interpolate;
  fr.fair_weight = settings.fit.fair_weight.value_or(0);
  std::vector<PolarStructure> polar;
  if (settings.patch.polar) polar = detect_polar_structures(r.base).structures;
  if (settings.fit.fair_weight) {
    r.stage(Stage::Fit, "fitting the cage to its vertices (fairing weight " + short_number(fr.fair_weight) + ")");
    FairOptions fo;
    fo.weight = fr.fair_weight;
    fo.energy = settings.fit.energy;
    fo.polar = polar;
    const FairResult f = fair(r.base, positions, positions, fo);
    c.cage = f.positions;
    fr.residual = f.residual;
    fr.energy_before = f.energy_before;
    fr.energy_after = f.energy_after;
  } else {
    r.stage(Stage::Fit, "solving for the cage whose limit passes through its vertices");
    InterpolationOptions io;
    io.polar = polar;
    const InterpolationResult f = interpolate(r.base, positions, io);
    c.cage = f.positions;
    fr.residual = f.residual;
    fr.condition = f.condition;
    fr.singular = f.singular;
    fr.null_vertices = f.null_vertices;
    fr.no_surface = static_cast<int>(f.no_surface.size());
    if (f.singular)
      r.warn(DiagnosticCode::InterpolationSingular,
             "the interpolation system is singular near vertices " + index_list(f.null_vertices) +
                 ": the interpolating cage is not unique, the one nearest to the input was used");
  }
  fr.polar_vertices = 0;
  for (const PolarStructure& s : polar) fr.polar_vertices += 1 + 2 * s.valence;
  fr.displacement = field_stats(c.cage, positions);
  c.ms.fit = ms_since(t0);
}

/// The patches with `extra` levels beyond the minimum at every fan.
void patches_stage(const Run& r, int extra) {
  const auto t0 = Clock::now();
  r.stage(Stage::Patches, extra == 0 ? std::string("building patches")
                                     : "building patches (" + std::to_string(extra) + " extra levels)");
  PatchOptions po = r.settings.patch;
  po.extra_levels = extra;
  r.c.build = build_patches(r.base, r.c.cage, po);
  r.c.extra_levels = extra;
  r.c.ms.patches += ms_since(t0);
}

/// Measures the deviation at every fan, or (with `remeasure`) only at those, keeping the
/// others' last values.
void deviation_stage(const Run& r, const std::vector<char>* remeasure = nullptr) {
  ConversionResult& c = r.c;
  const auto t0 = Clock::now();
  r.stage(Stage::Deviation, "measuring the deviation from the limit surface");
  DeviationReport d = measure_deviation(c.build, kDeviationSampleLevels, remeasure ? &c.deviation : nullptr, remeasure);
  c.deviation = std::move(d);
  c.ms.deviation += ms_since(t0);
}

/// Each fan gets the extra levels its own deviation needs (per-valence rates), so a tolerance
/// deepens only the fans that miss it; measured again after each rebuild, up to
/// kToleranceRounds times. Fills c.tolerance; warns when capped or not met.
void tolerance_stage(const Run& r) {
  ConversionResult& c = r.c;
  const ConversionSettings& settings = r.settings;
  ToleranceResult& tr = c.tolerance;
  tr.requested = settings.tolerance.value_or(kDefaultTolerance);
  tr.is_default = !settings.tolerance;
  tr.absolute = settings.absolute ? tr.requested : tr.requested * c.build.set.model_size;
  deviation_stage(r);
  tr.first_max = c.deviation.max;
  std::vector<int> extra(c.build.refinement.levels.back().mesh.num_vertices(), 0);
  // The estimate with the fans as built, updated as fans deepen: each deepening is checked
  // against the limits before the deeper build (the fans of one vertex deepen together).
  // A deeper build is a rebuild (the first build held meanwhile): costed as such.
  EstimateOptions eo = r.estimate_options();
  eo.rebuilt = true;
  std::vector<FanCost> costs = fan_costs(c.build);
  ResourceEstimate total = estimate_conversion(r.base, costs, eo);
  std::vector<std::vector<int>> fans_of_vertex(extra.size());
  for (size_t fi = 0; fi < c.build.info.fans.size(); ++fi)
    fans_of_vertex[c.build.info.fans[fi].vertex].push_back(static_cast<int>(fi));
  auto deepened = [&](int vertex, int by) {
    ResourceEstimate e = total;
    for (int fi : fans_of_vertex[vertex]) {
      FanCost deeper = costs[fi];
      deeper.levels += by;
      e = e - fan_estimate(costs[fi], eo) + fan_estimate(deeper, eo);
    }
    return e;
  };
  bool by_limits = false;  // the last cap came from the face and memory limits (a setting may lift it)
  for (int round = 0; round < kToleranceRounds; ++round) {
    const std::vector<int> before = extra;
    bool deeper = false;
    for (const FanDeviation& fd : c.deviation.fans) {
      if (fd.max <= tr.absolute) continue;
      const IrregularFan& fan = c.build.info.fans[fd.fan];
      const int want = extra[fan.vertex] + std::max(1, fan_extra_levels_for_tolerance(fan, fd.max, tr.absolute));
      tr.needed = std::max(tr.needed, want);
      const int use = std::min(want, kMaxFanExtraLevels);
      if (use > extra[fan.vertex] && !r.fits(deepened(fan.vertex, use - extra[fan.vertex]))) {
        tr.capped = true;
        tr.cap_reason = "the face and memory limits";
        by_limits = true;
        continue;
      }
      if (use > extra[fan.vertex]) {
        total = deepened(fan.vertex, use - extra[fan.vertex]);
        for (int fi : fans_of_vertex[fan.vertex]) costs[fi].levels += use - extra[fan.vertex];
        extra[fan.vertex] = use;
        deeper = true;
      } else if (want > kMaxFanExtraLevels) {
        tr.capped = true;
        tr.cap_reason = "at most " + std::to_string(kMaxFanExtraLevels) + " extra levels per fan";
        by_limits = false;
      }
    }
    if (!deeper) break;
    PatchOptions po = settings.patch;
    po.vertex_extra_levels = extra;
    po.reuse = &c.build;  // only the quads at deepened vertices are rebuilt
    const auto t0 = Clock::now();
    r.stage(Stage::Patches, "building patches (deeper at " +
                                std::to_string(std::count_if(extra.begin(), extra.end(), [](int x) { return x > 0; })) +
                                " vertices for the tolerance)");
    PatchBuild deeper_build = build_patches(r.base, c.cage, po);
    c.build = std::move(deeper_build);
    c.ms.patches += ms_since(t0);
    std::vector<char> remeasure(c.build.info.fans.size(), 0);
    for (size_t fi = 0; fi < remeasure.size(); ++fi)
      remeasure[fi] = extra[c.build.info.fans[fi].vertex] != before[c.build.info.fans[fi].vertex];
    deviation_stage(r, &remeasure);
  }
  tr.used = *std::max_element(extra.begin(), extra.end());
  tr.fans_deepened = static_cast<int>(std::count_if(extra.begin(), extra.end(), [](int x) { return x > 0; }));
  tr.met = c.deviation.max <= tr.absolute;
  // The cap matters only where the tolerance is missed: the estimate of levels is pessimistic at
  // some fans (fandisk's rounded rim corners asked for 16 and met it at 12, within 1e-8).
  if (tr.capped && !tr.met)
    r.report({Severity::Warning, DiagnosticCode::ToleranceCapped,
              "the tolerance needs " + std::to_string(tr.needed) + " extra levels at some fan; using " +
                  std::to_string(tr.used) + " (" + tr.cap_reason + ")",
              -1, by_limits ? "max_faces" : "", ""});
  if (!tr.met)
    r.warn(DiagnosticCode::ToleranceNotMet, "tolerance NOT met: deviation " + short_number(c.deviation.max) +
                                                " > tolerance " + short_number(tr.absolute) +
                                                " (model units) at level " + std::to_string(c.build.info.level));
}

/// Faces: regular regions packed into one surface each, or one face per quad.
void faces_stage(const Run& r) {
  ConversionResult& c = r.c;
  const auto t = Clock::now();
  c.faces = r.settings.faces;
  if (r.settings.faces == FaceMode::Packed) {
    r.stage(Stage::Packing, "packing regular regions into faces");
    c.exported = pack_patches(c.build);
    if (c.exported.rejected_packs > 0)
      r.warn(DiagnosticCode::PacksRejected,
             std::to_string(c.exported.rejected_packs) +
                 " regular region(s) did not reproduce their quads as one surface and stay one face per quad");
  } else {
    c.exported = unpacked(c.build.set);
  }
  c.ms.packing = ms_since(t);
}

/// Notes on the poles that are not polar structures and on a separating first step.
void pole_notes(const Run& r) {
  const PatchBuildInfo& info = r.c.build.info;
  const PatchOptions& patch = r.settings.patch;
  for (const RejectedPole& p : info.rejected_poles) {
    const bool separable = p.kind != RejectedPole::Kind::Structure && !patch.separate_poles;
    if (patch.polar && (p.valence >= kMinPolarValence || separable))
      r.report({Severity::Note, DiagnosticCode::PoleNotPolar,
                "vertex " + std::to_string(p.vertex) + " (valence " + std::to_string(p.valence) +
                    ") is not a polar structure, Catmull-Clark is used there: " + p.reason,
                p.vertex, separable ? "separate_poles" : "",
                p.kind == RejectedPole::Kind::LowValence ? "valence below " + std::to_string(kMinPolarValence)
                : p.kind == RejectedPole::Kind::TooClose ? "too close to another pole"
                                                         : "their rings do not form one"});
  }
  if (!info.separated_poles.empty())
    r.report({Severity::Note, DiagnosticCode::PolesSeparated,
              "separating first step at " + std::to_string(info.separated_poles.size()) +
                  " pole(s); the patches are built from that level-1 cage",
              -1, "", ""});
}

/// Warnings about connected parts of the cage (#32 items 1 and 6):
/// - tiny_part: a part less than kMinPartTolerances B-rep tolerances across. OCCT tells no
///   distances apart below its precision (1e-7, the floor of the B-rep tolerance): such a part
///   passes the in-memory check, but OCCT's STEP and IGES readers merge its edges away
///   (measured: a 1e-12 cube beside a unit cube reads back as an invalid shape without it).
/// - flat_part: in a closed model, a part whose cage encloses no volume (|volume| at most
///   kFlatVolume x its diagonal cubed, e.g. a cube flattened onto a plane): its solid has zero
///   volume.
/// - thin_part: in a closed model, a part (not flat) thinner than kMinThicknessTolerances B-rep
///   tolerances, its thickness taken as 2 |cage volume| / cage area (a thin box's smallest side,
///   a third of a cube's side). Measured (STEP written, read back by STEPControl_Reader): boxes
///   1 x h x 1 read back as valid solids of 0.54 x their volume for h <= 1e-7 (the tolerance),
///   not at all for h = 2e-7, exactly for h >= 3e-7; cubes of size 1e-6 .. 5e-6 exactly.
/// A tiny part, and a thin or flat one of non-zero thickness, set c.exchange_refusal: such a
/// part is not written to STEP / IGES (check_exchange_output); BREP keeps it as it is.
void part_warnings(const Run& r) {
  constexpr double kMinPartTolerances = 10;
  constexpr double kMinThicknessTolerances = 4;
  constexpr double kFlatVolume = 1e-12;
  const PolyMesh& m = r.base.mesh;
  const std::vector<Point3>& x = r.c.cage;
  std::vector<int> parent(m.num_vertices());
  for (int v = 0; v < m.num_vertices(); ++v) parent[v] = v;
  const auto root = [&](int v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (int f = 0; f < m.num_faces(); ++f)
    for (int i = 1; i < m.face_size(f); ++i) parent[root(m.face_vertices(f)[i])] = root(m.face_vertices(f)[0]);
  struct Part {
    int first_face = -1, faces = 0;
    Point3 lo, hi;
    double volume = 0;  ///< six times the signed volume of the cage's faces (fans of triangles)
    double area = 0;    ///< twice the area of the cage's faces (fans of triangles)
  };
  std::vector<Part> part(m.num_vertices());
  // A part is closed when none of its edges is on a boundary and none of its faces is a hole:
  // one open part does not keep the closed ones of the same cage from their warnings.
  std::vector<char> open(m.num_vertices(), 0);
  for (int e = 0; e < m.num_edges(); ++e)
    if (m.is_boundary_edge(e)) open[root(m.edge_vertex(e, 0))] = 1;
  for (int f = 0; f < m.num_faces(); ++f)
    if (f < static_cast<int>(r.base.face_hole.size()) && r.base.face_hole[f]) open[root(m.face_vertices(f)[0])] = 1;
  for (int f = 0; f < m.num_faces(); ++f) {
    const int* fv = m.face_vertices(f);
    Part& p = part[root(fv[0])];
    if (p.faces++ == 0) {
      p.first_face = f;
      p.lo = p.hi = x[fv[0]];
    }
    for (int i = 0; i < m.face_size(f); ++i)
      for (int k = 0; k < 3; ++k) {
        p.lo[k] = std::min(p.lo[k], x[fv[i]][k]);
        p.hi[k] = std::max(p.hi[k], x[fv[i]][k]);
      }
    const Point3& a = x[fv[0]];
    for (int i = 1; i + 1 < m.face_size(f); ++i) {
      const Point3 &b = x[fv[i]], &c = x[fv[i + 1]];
      p.volume += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                  a[2] * (b[0] * c[1] - b[1] * c[0]);
      const Point3 u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      p.area += std::hypot(u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]);
    }
  }
  const double tolerance = occt::brep_tolerance(r.c.build.set.model_size);
  for (int v = 0; v < m.num_vertices(); ++v) {
    const Part& p = part[v];
    if (p.faces == 0) continue;
    double d2 = 0;
    for (int k = 0; k < 3; ++k) d2 += (p.hi[k] - p.lo[k]) * (p.hi[k] - p.lo[k]);
    const double size = std::sqrt(d2);
    const std::string which =
        "the part of the cage with face " + std::to_string(p.first_face) + " (" + std::to_string(p.faces) + " faces)";
    const double limit = kMinPartTolerances * tolerance, thin = kMinThicknessTolerances * tolerance;
    const auto below = [&](double factor) {
      return ", less than " + short_number(factor) + " x the B-rep tolerance " + short_number(tolerance);
    };
    // 2 V / A with V = volume / 6 and A = area / 2 (the fans' sums are 6 V and 2 A).
    const double thickness = p.area > 0 ? 2 * (std::fabs(p.volume) / 6) / (p.area / 2) : 0;
    const bool closed = !open[v];
    if (size < limit) {
      r.warn(DiagnosticCode::TinyPart,
             which + " is " + short_number(size) + " across" + below(kMinPartTolerances) +
                 ": OCCT's STEP / IGES readers lose it or report the shape invalid (STEP / IGES output is refused, BREP keeps it)");
      if (r.c.exchange_refusal.empty())
        r.c.exchange_refusal = which + " is " + short_number(size) + " across" + below(kMinPartTolerances);
      continue;
    }
    const bool flat = closed && std::fabs(p.volume / 6) <= kFlatVolume * size * size * size;
    if (flat)
      r.warn(DiagnosticCode::FlatPart, which + " encloses no volume (cage volume " + short_number(p.volume / 6) +
                                           ", " + short_number(thickness) + " thick across " +
                                           short_number(size) + "): its solid is flat, of zero volume");
    else if (closed && thickness < thin)
      r.warn(DiagnosticCode::ThinPart,
             which + " is " + short_number(thickness) + " thick (2 x cage volume / area)" + below(kMinThicknessTolerances) +
                 ": OCCT's STEP / IGES readers flatten it (STEP / IGES output is refused, BREP keeps it)");
    if (closed && thickness > 0 && thickness < thin && r.c.exchange_refusal.empty())
      r.c.exchange_refusal =
          which + " is " + short_number(thickness) + " thick (2 x cage volume / area)" + below(kMinThicknessTolerances);
  }
}

/// Self-intersections and overlaps of the exported faces (issue 33): found, then one warning
/// per kind with the first witness; the conversion goes on.
void intersection_warnings(const Run& r) {
  ConversionResult& c = r.c;
  const auto t = Clock::now();
  c.intersections = find_self_intersections(c.exported.set);
  c.ms.intersections = ms_since(t);
  const SelfIntersectionReport& x = c.intersections;
  auto at = [](const Point3& p) {
    return "(" + short_number(p[0]) + ", " + short_number(p[1]) + ", " + short_number(p[2]) + ")";
  };
  if (!x.self.empty()) {
    const FaceCrossing& w = x.self.front();
    // "N pair(s) of faces cross" and / or "M ... touch or lie on each other without crossing".
    const long long touching = SelfIntersectionReport::touching_count(x.self);
    const long long crossing = static_cast<long long>(x.self.size()) - touching;
    std::string pairs;
    if (crossing > 0) pairs = std::to_string(crossing) + " pair(s) of faces cross";
    if (touching > 0)
      pairs += (pairs.empty() ? "" : ", ") + std::to_string(touching) +
               " pair(s) of faces touch or lie on each other without crossing";
    r.warn(DiagnosticCode::SelfIntersection,
           std::string(crossing == 0 ? "the surface touches itself: " : "the surface intersects itself: ") + pairs +
               ", e.g. faces " + std::to_string(w.face_a) + " and " +
               std::to_string(w.face_b) + (w.touching ? " touch at " : " at ") + at(w.point) +
               "; offsets, shells and booleans of this body may fail");
  }
  if (!x.overlaps.empty()) {
    const FaceCrossing& w = x.overlaps.front();
    const std::string example =
        w.inside ? "part " + std::to_string(w.component_a) + " (face " + std::to_string(w.face_a) + ") lies inside part " +
                       std::to_string(w.component_b)
                 : "parts " + std::to_string(w.component_a) + " and " + std::to_string(w.component_b) + " (faces " +
                       std::to_string(w.face_a) + " and " + std::to_string(w.face_b) + ")" +
                       (w.touching ? " touch at " : " cross at ") + at(w.point);
    const bool touch_only =
        SelfIntersectionReport::touching_count(x.overlaps) == static_cast<long long>(x.overlaps.size());
    r.warn(DiagnosticCode::PartsOverlap,
           std::to_string(x.overlapping_components.size()) + " pair(s) of the " + std::to_string(x.components) +
               (touch_only ? " separate parts touch, e.g. " : " separate parts overlap, e.g. ") + example +
               (touch_only ? "; booleans between them and offsets may fail (fuse them in CAD if they are meant as one body)"
                           : "; their solids interpenetrate (fuse them in CAD if they are meant as one body)"));
  }
}

}  // namespace

void check_exchange_output(const ConversionResult& result, const std::string& input, bool step_or_iges) {
  if (!step_or_iges || result.exchange_refusal.empty()) return;
  throw InputError(input, 0,
                   result.exchange_refusal +
                       ": a STEP or IGES file cannot carry it (OCCT's readers merge or flatten what is within "
                       "their precision; nothing was written); scale the model up, remove the part, or write "
                       "a .brep file");
}

ConversionResult convert(const SubdivLevel& base, const std::vector<Point3>& positions,
                         const ConversionSettings& settings, const ConversionProgress& progress,
                         std::vector<std::string> warnings) {
  validate(settings);
  const ThreadLimit thread_scope(settings.limits.threads.value_or(0));
  const JobShare job;  // conversions side by side in this process share the cores
  ConversionResult c;
  c.ms.threads = loop_threads();
  const Run run{base, settings, progress, c};
  c.warnings = std::move(warnings);
  // A level pins the levels; else a tolerance (the user's or the default) chooses them.
  const bool tolerance_given = !settings.level;
  c.tolerance_given = tolerance_given;
  c.tolerance_absolute = settings.absolute;
  const int level = settings.level.value_or(0);
  check_has_surface(base, positions);
  EstimateOptions before = run.estimate_options();
  if (tolerance_given) {  // predict the deepening of curved high-valence fans (resources.h)
    // An absolute tolerance is taken relative to the model size (check_has_surface: not 0).
    double tolerance = settings.tolerance.value_or(kDefaultTolerance);
    if (settings.absolute) tolerance /= bounding_diagonal(base.mesh, positions);
    before.tolerance = tolerance;
    before.positions = &positions;
  }
  c.estimate_before = estimate_conversion(base, level, before);
  check_resources(c.estimate_before, settings.limits, kDefaultMaxConvertFaces,
                  "converting " + std::to_string(base.mesh.num_faces()) + " cage faces at level " +
                      std::to_string(level),
                  level > 0 ? "use a lower level" : "simplify the cage");

  fit_stage(run, positions);
  // Patches, at the level asked for or at the minimum level first for a tolerance.
  patches_stage(run, level);
  if (tolerance_given) tolerance_stage(run);
  // The estimate with the fans as built (their levels known now), before the B-rep.
  EstimateOptions built = run.estimate_options();
  built.rebuilt = std::any_of(c.build.vertex_extra.begin(), c.build.vertex_extra.end(), [](int x) { return x > 0; });
  c.estimate = estimate_conversion(base, fan_costs(c.build), built);

  // The optional quality stage runs on a thread of its own from here on, beside the other
  // stages: first what depends on the cage alone (the exact limit, the quadric fits at the
  // cage's vertices) while the patches are packed and measured, then, once `surfaces_ready`
  // says the patches, the exported faces and the continuity are final (nothing changes them
  // after that), the patches against the limit while OCCT builds the B-rep and the caller
  // writes the file (after_brep). Packing, the B-rep and writing use one core; this thread
  // holds a ThreadReservation meanwhile, so that every parallel loop (the stage's, and this
  // thread's own) uses one thread fewer and the two never share a core.
  //
  // Declared in this order so that an exception unwinds safely: the reservation goes first,
  // then the promise (broken, it ends the stage's wait with an exception), then the future,
  // whose destructor waits for the stage's thread, all before `c`.
  std::future<std::pair<QualityReport, double>> quality;
  std::promise<void> surfaces_ready;
  std::optional<ThreadReservation> main_core;
  if (settings.quality_samples) {
    run.stage(Stage::Quality, "measuring against the exact limit surface (beside the next stages)");
    // Under a ThreadLimit of 1 the measure runs on this thread when its result is asked for.
    const bool beside = loop_threads() > 1;
    quality = std::async(beside ? std::launch::async : std::launch::deferred,
                         [&base, &c, samples = *settings.quality_samples, ready = surfaces_ready.get_future(),
                          caller_limit = thread_limit()]() mutable {
                           const ThreadLimit threads(caller_limit);
                           const auto t0 = Clock::now();
                           const LimitEvaluator limit(base, c.cage);
                           const VertexCurvatureComparison quadric = compare_vertex_curvature(limit);
                           ready.get();
                           QualityReport q = measure_quality(c.build, limit, c.continuity, samples, &c.exported, quadric);
                           return std::make_pair(std::move(q), ms_since(t0));
                         });
    if (beside) main_core.emplace();
  }

  faces_stage(run);
  auto t = Clock::now();
  run.stage(Stage::Continuity, "measuring continuity");
  c.continuity = measure_continuity(c.exported.set, kContinuitySamples);
  c.ms.continuity = ms_since(t);
  surfaces_ready.set_value();
  if (!tolerance_given) deviation_stage(run);
  collect_fans(c);
  measure_caps(c);
  c.polar = settings.patch.polar;
  c.cap_options = settings.patch.cap;
  pole_notes(run);
  part_warnings(run);
  intersection_warnings(run);

  if (settings.build_brep) {
    t = Clock::now();
    run.stage(Stage::Brep, "building the B-rep");
    occt::BrepOptions brep_options;
    brep_options.merge_planar = settings.planar == PlanarMode::Merge && settings.faces == FaceMode::Packed;
    c.brep = occt::build_brep(c.exported.set, progress.brep_fraction, brep_options);
    c.has_brep = true;
    c.ms.brep = ms_since(t);
  }
  if (progress.after_brep) progress.after_brep(c);
  main_core.reset();  // from here this thread waits: the stage's loops may take every core
  if (quality.valid()) {
    t = Clock::now();
    std::pair<QualityReport, double> measured = quality.get();
    c.ms.quality_wait = ms_since(t);
    c.quality = std::move(measured.first);
    c.ms.quality = measured.second;
  }
  if (settings.preview) {
    t = Clock::now();
    run.stage(Stage::Preview, std::string("tessellating the preview (") + to_string(settings.preview->color) + ")");
    c.preview_settings = *settings.preview;
    c.preview = build_preview(base, c, *settings.preview);
    c.ms.preview = ms_since(t);
  }
  return c;
}

}  // namespace subd2nurbs::pipeline
