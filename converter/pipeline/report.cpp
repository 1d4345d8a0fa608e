#include "converter/pipeline/report.h"

#include <stdexcept>
#include <utility>

#include "converter/pipeline/shape_fit_report.h"
#include "core/eval/curvature_radius.h"
#include "io/json_writer.h"

namespace subd2nurbs::pipeline {

namespace {

/// A report's writer: spaced separators, undefined measures as null.
JsonWriter report_writer() { return JsonWriter(JsonWriter::Numbers::Report, JsonWriter::Spacing::Spaced, "report"); }

/// x / size (null without a size).
void relative(JsonWriter& w, double x, double size) {
  if (size > 0) w.number(x / size);
  else w.null();
}

void optional_string(JsonWriter& w, const std::string& s) {
  if (s.empty()) w.null();
  else w.string(s);
}

void optional_number(JsonWriter& w, bool given, double x) {
  if (given) w.number(x);
  else w.null();
}

void write_sample(JsonWriter& w, const DeviationSample& d) {
  w.begin_object();
  w.members("patch", d.patch, "s", d.s, "t", d.t, "face", d.limit.face, "sub", d.limit.sub, "u", d.limit.u,
            "v", d.limit.v);
  w.key("point").point(d.point);
  w.end_object();
}

/// The "quality" member's value (docs/formats.md, "Quality report"), its members one a line
/// indented `indent` + 2. Lengths in model units; *_rel divided by the model size.
void write_quality(JsonWriter& w, const QualityReport& q, double size, int indent) {
  w.begin_object(indent + 2, indent);
  w.members("samples_per_side", q.samples_per_side, "polar_patches_skipped", q.polar_patches);
  w.key("deviation").begin_object();
  w.members("samples", q.deviation_samples, "polynomial_patches", q.polynomial_patches, "max", q.deviation_max);
  relative(w.key("max_rel"), q.deviation_max, size);
  w.members("mean", q.deviation_mean, "parametric_max", q.parametric_max, "parametric_mean", q.parametric_mean);
  write_sample(w.key("where"), q.worst);
  w.end_object();
  w.key("patch_max").numbers(q.patch_max);
  w.key("edges_summary").begin_object();
  w.members("smooth", q.smooth_edges, "crease", q.crease_edges, "boundary", q.boundary_edges, "max_gap", q.max_gap);
  relative(w.key("max_gap_rel"), q.max_gap, size);
  w.members("max_smooth_normal_jump_deg", q.max_smooth_normal_jump_deg,
            "max_normal_jump_error_deg", q.max_normal_jump_error_deg, "class_mismatches", q.class_mismatches);
  w.end_object();
  w.key("edges").begin_array(indent + 4, indent + 2);
  for (const EdgeQuality& x : q.edges) {
    w.begin_object();
    w.members("curve", x.curve, "claimed", to_string(x.claimed), "expected", x.expected, "gap", x.gap,
              "normal_jump_deg", x.normal_jump_deg, "limit_normal_jump_deg", x.limit_normal_jump_deg,
              "normal_jump_error_deg", x.normal_jump_error_deg);
    w.end_object();
  }
  w.end_array();
  const CurvatureSummary& c = q.curvature;
  w.key("curvature").begin_object();
  w.members("samples", c.samples, "min_k", c.min_k, "max_k", c.max_k, "max_abs_mean", c.max_abs_mean,
            "mean_abs_mean", c.mean_abs_mean, "rms_mean", c.rms_mean, "max_abs_gauss", c.max_abs_gauss);
  write_sample(w.key("where_max_abs_mean"), c.where_max_abs_mean);
  w.end_object();
  const VertexCurvatureComparison& v = q.quadric;
  w.key("quadric_fit").begin_object();
  w.members("vertices", v.vertices, "max_abs_H", v.max_abs_H, "cage_max_abs_H_error", v.max_abs_H_error_cage,
            "cage_mean_abs_H_error", v.mean_abs_H_error_cage,
            "limit_points_max_abs_H_error", v.max_abs_H_error_limit,
            "limit_points_mean_abs_H_error", v.mean_abs_H_error_limit);
  w.end_object();
  w.end_object();
}

void write_fans(JsonWriter& w, const ConversionResult& c) {
  const auto& fm = c.fans_by_mode;
  w.key("fans").begin_object();
  const char* const modes[] = {"smooth", "dart", "crease", "corner", "approximate"};  // FanMode order
  for (int m = 0; m < 5; ++m) w.key(modes[m]).integer(fm[m]);
  w.break_line(4).key("approximate_fans").begin_array(6, 4);
  for (const ApproximateFan& a : c.approximate) {
    w.begin_object();
    w.members("base_vertex", a.base_vertex, "valence", a.valence, "sectors", a.sectors, "rays", a.rays);
    optional_number(w.key("normal_angle_deg"), a.normal_angle_deg >= 0, a.normal_angle_deg);
    w.end_object();
  }
  w.end_array().end_object();
}

void write_polar(JsonWriter& w, const ConversionResult& c, double size) {
  const PatchBuildInfo& info = c.build.info;
  w.key("polar").begin_object();
  w.members("enabled", c.polar, "radial_steps", c.cap_options.radial_steps, "lambda", c.cap_options.lambda);
  w.break_line(4).key("caps").begin_array(6, 4);
  for (const CapMeasure& m : c.caps) {
    w.begin_object();
    w.members("pole", m.pole_vertex, "valence", m.valence, "bp_distance", m.bp_distance);
    relative(w.key("bp_distance_relative"), m.bp_distance, size);
    w.key("pole_normal_angle_deg").number(m.pole.normal_angle_deg[1]);
    w.key("pole_curvature").begin_object();
    w.key("distance").numbers({m.pole.distance[0], m.pole.distance[1]});
    w.key("max_abs_k").numbers({m.pole.max_abs_k[0], m.pole.max_abs_k[1]});
    w.key("normal_angle_deg").numbers({m.pole.normal_angle_deg[0], m.pole.normal_angle_deg[1]});
    w.end_object().end_object();
  }
  w.end_array();
  w.break_line(4).key("separated_poles").integers(info.separated_poles);
  w.break_line(4).key("not_polar").begin_array(6, 4);
  for (const RejectedPole& r : info.rejected_poles) {
    w.begin_object();
    w.members("vertex", r.vertex, "valence", r.valence, "reason", r.reason);
    w.end_object();
  }
  w.end_array().end_object();
}

void write_fit(JsonWriter& w, const FitReport& f, double size) {
  const bool on = f.mode == FitMode::Interpolate;
  auto stats = [&](const char* name, const FieldStats& st) {
    w.break_line(4).key(name);
    if (!on) {
      w.null();
      return;
    }
    w.begin_object();
    write_field_stats(w, st);
    relative(w.key("max_relative"), st.max, size);
    w.end_object();
  };
  w.key("fit").begin_object();
  w.key("mode").string(to_string(f.mode));
  optional_number(w.key("fair_weight"), on && f.fair_weight > 0, f.fair_weight);
  stats("residual", f.residual);
  stats("displacement", f.displacement);
  optional_number(w.break_line(4).key("condition"), on && f.fair_weight == 0, f.condition);
  w.key("singular").boolean(f.singular);
  w.key("null_vertices").integers(f.null_vertices);
  w.members("polar_vertices", f.polar_vertices, "no_surface", f.no_surface);
  optional_number(w.break_line(4).key("energy_before"), f.energy_before >= 0, f.energy_before);
  optional_number(w.key("energy_after"), f.energy_after >= 0, f.energy_after);
  w.break_line(4).key("to_target");
  if (f.to_target) {
    w.begin_object(6, 2);
    w.members("target", f.to_target->target, "iterations", f.to_target->iterations, "stop", f.to_target->stop);
    write_target_distance(w.key("before"), f.to_target->before);
    write_target_distance(w.key("after"), f.to_target->after);
    w.end_object();
  } else {
    w.null();
  }
  w.end_object();
}

void write_deviation(JsonWriter& w, const ConversionResult& c, double size) {
  const PatchBuildInfo& info = c.build.info;
  const DeviationReport& d = c.deviation;
  w.key("deviation").begin_object();
  w.members("max", d.max, "mean", d.mean);
  relative(w.key("relative"), d.max, size);
  w.break_line(4).key("where");
  if (d.samples > 0) w.point(d.where);
  else w.null();
  w.key("worst_fan");
  if (d.worst_fan >= 0 && d.worst_fan < static_cast<int>(info.fans.size())) {
    const IrregularFan& f = info.fans[d.worst_fan];
    w.begin_object();
    w.members("base_vertex", f.base_vertex, "valence", f.valence, "mode", to_string(f.mode));
    w.end_object();
  } else {
    w.null();
  }
  w.break_line(4).key("samples").integer(d.samples);
  w.key("sample_levels").integer(d.sample_levels);
  w.break_line(4).key("fans").begin_array(6, 4);
  for (const FanDeviation& fd : d.fans) {
    const IrregularFan& f = info.fans[fd.fan];
    w.begin_object();
    w.members("base_vertex", f.base_vertex, "valence", f.valence, "mode", to_string(f.mode), "level", f.level,
              "max", fd.max);
    w.end_object();
  }
  w.end_array();
  w.break_line(4).key("tolerance");
  if (c.tolerance_given) {
    const ToleranceResult& t = c.tolerance;
    w.begin_object();
    w.members("requested", t.requested, "default", t.is_default,
              "units", c.tolerance_absolute ? "model" : "relative", "requested_model_units", t.absolute);
    w.break_line(6).key("initial_max").number(t.first_max);
    w.members("extra_levels_needed", t.needed, "extra_levels_used", t.used, "fans_deepened", t.fans_deepened,
              "capped", t.capped);
    w.break_line(6).key("achieved").number(d.max);
    relative(w.key("achieved_relative"), d.max, size);
    w.key("met").boolean(t.met);
    w.end_object();
  } else {
    w.null();
  }
  w.end_object();
}

}  // namespace

void write_field_stats(JsonWriter& w, const FieldStats& stats) {
  w.members("max", stats.max, "mean", stats.mean).key("where");
  if (stats.where >= 0) w.integer(stats.where);
  else w.null();
}

namespace {

/// "curvature_radius" (docs/formats.md): the smallest radius of curvature of the exported
/// faces each way (core/eval/curvature_radius.h), where it is (face, u, v, point): how thick a
/// shell / inward offset (`inward`) or an outward offset (`outward`) the body can take.
void write_curvature_radius(JsonWriter& w, const PatchSet& faces) {
  const CurvatureRadii r = smallest_curvature_radii(faces, 8);
  w.key("curvature_radius").begin_object();
  w.members("samples_per_span", 8, "samples", r.samples, "normals", r.outward ? "outward" : "patch");
  for (const auto& [key, at] : {std::pair<const char*, const CurvatureRadiusAt*>{"inward", &r.inward},
                                {"outward", &r.outward_offset}}) {
    w.key(key);
    if (at->patch < 0) {  // flat or curving only the other way: no limit
      w.null();
      continue;
    }
    w.begin_object();
    w.members("radius", at->radius, "face", at->patch, "u", at->u, "v", at->v);
    w.key("point").begin_array();
    for (double x : at->point) w.number(x);
    w.end_array();
    w.end_object();
  }
  w.end_object();
}

/// "self_intersection" (docs/formats.md): where the exported faces cross themselves and where
/// separate parts overlap (core/eval/self_intersection.h), the first kMaxListed of each listed
/// with a witness point on both faces.
void write_self_intersection(JsonWriter& w, const SelfIntersectionReport& x) {
  constexpr size_t kMaxListed = 50;
  auto point = [&](const Point3& p) {
    w.key("point").begin_array();
    for (double c : p) w.number(c);
    w.end_array();
  };
  w.key("self_intersection").begin_object();
  const long long self_touching = SelfIntersectionReport::touching_count(x.self);
  const long long overlaps_touching = SelfIntersectionReport::touching_count(x.overlaps);
  w.members("components", x.components, "triangles", x.triangles, "crossing_face_pairs",
            static_cast<long long>(x.self.size()) - self_touching, "overlap_face_pairs",
            static_cast<long long>(x.overlaps.size()) - overlaps_touching, "touching_face_pairs",
            self_touching + overlaps_touching);
  w.break_line(4).key("self").begin_array();
  for (size_t k = 0; k < x.self.size() && k < kMaxListed; ++k) {
    const FaceCrossing& c = x.self[k];
    w.break_line(6).begin_object();
    w.key("faces").begin_array().integer(c.face_a).integer(c.face_b).end_array();
    w.members("component", c.component_a, "angle_deg", c.angle_deg, "touching", c.touching);
    point(c.point);
    w.end_object();
  }
  w.end_array();
  w.break_line(4).key("overlaps").begin_array();
  for (size_t k = 0; k < x.overlaps.size() && k < kMaxListed; ++k) {
    const FaceCrossing& c = x.overlaps[k];
    w.break_line(6).begin_object();
    w.key("components").begin_array().integer(c.component_a).integer(c.component_b).end_array();
    w.key("faces").begin_array().integer(c.face_a).integer(c.face_b).end_array();
    w.members("inside", c.inside, "touching", c.touching, "angle_deg", c.angle_deg);
    point(c.point);
    w.end_object();
  }
  w.end_array();
  w.break_line(4).key("overlapping_components").begin_array();
  for (const auto& [a, b] : x.overlapping_components) w.begin_array().integer(a).integer(b).end_array();
  w.end_array();
  w.end_object();
}

}  // namespace

std::string report_json(const ConversionResult& c) {
  const PatchBuildInfo& info = c.build.info;
  const PatchSet& ps = c.build.set;
  const double size = ps.model_size;
  JsonWriter w = report_writer();
  w.begin_object(2, 0);
  w.members("format", "subd2nurbs-report", "version", 1, "input", c.input);
  optional_string(w.key("output"), c.output.path);
  optional_string(w.key("output_format"), c.output.format);
  optional_string(w.key("step_schema"), c.output.step_schema);
  w.key("warnings").begin_array();
  for (const std::string& text : warning_texts(c)) w.string(text);
  w.end_array();
  w.members("model_size", size, "coarse_level", info.coarse_level, "level", info.level,
            "extra_levels", c.extra_levels);
  w.key("patches").begin_object();
  w.members("total", static_cast<long long>(ps.patches.size()), "regular", info.regular_patches,
            "pccm", info.pccm_patches, "polar_caps", static_cast<long long>(info.caps.size()),
            "poles", info.total_poles, "pieces", info.leaves, "removed_knots", info.removed_knots);
  w.end_object();
  const PackedSet& out = c.exported;
  w.key("faces").begin_object();
  w.members("mode", to_string(c.faces), "total", static_cast<long long>(out.set.patches.size()), "packed", out.packs,
            "packed_quads", out.packed_quads, "poles", out.total_poles, "removed_knot_lines", out.removed_knots);
  w.end_object();
  const auto& cc = c.curves_by_continuity;
  w.key("curves").begin_object();
  w.key("total").integer(static_cast<long long>(out.set.curves.size()));
  const char* const classes[] = {"boundary", "c0", "g1", "c1", "c2"};  // Continuity order
  for (int k = 0; k < 5; ++k) w.key(classes[k]).integer(cc[k]);
  w.end_object();
  write_fans(w, c);
  write_polar(w, c, size);
  write_fit(w, c.fit, size);
  w.members("sharpened_edges", info.sharpened_edges, "sharpened_vertices", info.sharpened_vertices);
  w.key("brep");
  if (c.has_brep) {
    const occt::BrepResult& b = c.brep;
    w.begin_object();
    w.members("faces", b.num_faces, "edges", b.num_edges, "vertices", b.num_vertices,
              "type", b.is_solid ? "solid" : "shell", "solids", b.num_solids, "shells", b.num_shells,
              "valid", b.valid, "tolerance", b.tolerance);
    w.members("planar_faces", b.planar_faces, "merged_patches", b.merged_patches, "folded_planar_patches", b.folded_planar_patches,
              "rejected_planar_faces", b.rejected_planar_faces, "split_planar_sets", b.split_planar_sets);
    w.end_object();
  } else {
    w.null();
  }
  const ContinuityReport& k = c.continuity;
  w.key("continuity").begin_object();
  w.members("samples_per_curve", kContinuitySamples, "shared_curves", static_cast<long long>(k.curves.size()));
  w.break_line(4).key("max_gap").number(k.max_gap);
  relative(w.key("max_gap_relative"), k.max_gap, size);
  w.break_line(4).key("max_normal_angle_deg").number(k.max_normal_angle_deg);
  w.key("max_coplanarity").number(k.max_coplanarity);
  w.break_line(4).key("max_c1_jump").number(k.max_c1_jump);
  w.members("max_c2_jump", k.max_c2_jump, "max_crease_normal_angle_deg", k.max_crease_normal_angle_deg);
  w.end_object();
  write_deviation(w, c, size);
  write_curvature_radius(w, c.exported.set);
  write_self_intersection(w, c.intersections);
  if (c.mesh) write_mesh_path(w.key("mesh"), *c.mesh);
  w.key("estimate").begin_object();
  for (const auto& [key, e] : {std::pair{"before_work", &c.estimate_before}, std::pair{"before_brep", &c.estimate}}) {
    w.key(key).begin_object();
    w.members("bytes", e->bytes, "cpu_seconds", e->seconds, "time_class", time_class(e->seconds));
    w.members("pieces", e->faces, "exported_faces", e->exported_faces, "exported_poles", e->exported_poles);
    w.end_object();
  }
  w.end_object();
  const Timings& ms = c.ms;
  w.key("timings_ms").begin_object();
  w.members("load", ms.load, "fit", ms.fit, "patches", ms.patches, "continuity", ms.continuity,
            "deviation", ms.deviation, "packing", ms.packing, "intersections", ms.intersections, "brep", ms.brep,
            "write", ms.write);
  w.members("threads", ms.threads);
  w.end_object();
  if (c.quality) {  // the quality stage's section and its own time, beside timings_ms
    write_quality(w.key("quality"), *c.quality, size, 2);
    w.key("quality_ms").number(ms.quality);
    w.key("quality_wait_ms").number(ms.quality_wait);
  }
  w.end_object();
  return w.take() + "\n";
}

std::string quality_report_json(const ConversionResult& c, const TargetDistance* target) {
  if (!c.quality) throw std::logic_error("quality_report_json: the conversion ran without the quality stage");
  const double size = c.build.set.model_size;
  JsonWriter w = report_writer();
  w.begin_object(2, 0);
  w.members("format", "subd2nurbs-quality", "version", 1, "input", c.input, "model_size", size,
            "coarse_level", c.build.info.coarse_level, "level", c.build.info.level,
            "patches", static_cast<long long>(c.build.set.patches.size()));
  w.key("faces").begin_object();
  w.members("mode", to_string(c.faces), "total", static_cast<long long>(c.exported.set.patches.size()));
  w.end_object();
  w.members("quality_ms", c.ms.quality, "quality_wait_ms", c.ms.quality_wait);
  write_quality(w.key("quality"), *c.quality, size, 2);
  if (target) write_target_distance(w.key("target"), *target);
  w.end_object();
  return w.take() + "\n";
}

}  // namespace subd2nurbs::pipeline
