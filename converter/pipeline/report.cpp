#include "converter/pipeline/report.h"

#include <stdexcept>

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
  w.key("patch").integer(d.patch);
  w.key("s").number(d.s);
  w.key("t").number(d.t);
  w.key("face").integer(d.limit.face);
  w.key("sub").integer(d.limit.sub);
  w.key("u").number(d.limit.u);
  w.key("v").number(d.limit.v);
  w.key("point").point(d.point);
  w.end_object();
}

/// The "quality" member's value (docs/formats.md, "Quality report"), its members one a line
/// indented `indent` + 2. Lengths in model units; *_rel divided by the model size.
void write_quality(JsonWriter& w, const QualityReport& q, double size, int indent) {
  w.begin_object(indent + 2, indent);
  w.key("samples_per_side").integer(q.samples_per_side);
  w.key("polar_patches_skipped").integer(q.polar_patches);
  w.key("deviation").begin_object();
  w.key("samples").integer(q.deviation_samples);
  w.key("max").number(q.deviation_max);
  relative(w.key("max_rel"), q.deviation_max, size);
  w.key("mean").number(q.deviation_mean);
  w.key("parametric_max").number(q.parametric_max);
  w.key("parametric_mean").number(q.parametric_mean);
  write_sample(w.key("where"), q.worst);
  w.end_object();
  w.key("patch_max").numbers(q.patch_max);
  w.key("edges_summary").begin_object();
  w.key("smooth").integer(q.smooth_edges);
  w.key("crease").integer(q.crease_edges);
  w.key("boundary").integer(q.boundary_edges);
  w.key("max_gap").number(q.max_gap);
  relative(w.key("max_gap_rel"), q.max_gap, size);
  w.key("max_smooth_normal_jump_deg").number(q.max_smooth_normal_jump_deg);
  w.key("max_normal_jump_error_deg").number(q.max_normal_jump_error_deg);
  w.key("class_mismatches").integer(q.class_mismatches);
  w.end_object();
  w.key("edges").begin_array(indent + 4, indent + 2);
  for (const EdgeQuality& x : q.edges) {
    w.begin_object();
    w.key("curve").integer(x.curve);
    w.key("claimed").string(to_string(x.claimed));
    w.key("expected").string(x.expected);
    w.key("gap").number(x.gap);
    w.key("normal_jump_deg").number(x.normal_jump_deg);
    w.key("limit_normal_jump_deg").number(x.limit_normal_jump_deg);
    w.key("normal_jump_error_deg").number(x.normal_jump_error_deg);
    w.end_object();
  }
  w.end_array();
  const CurvatureSummary& c = q.curvature;
  w.key("curvature").begin_object();
  w.key("samples").integer(c.samples);
  w.key("min_k").number(c.min_k);
  w.key("max_k").number(c.max_k);
  w.key("max_abs_mean").number(c.max_abs_mean);
  w.key("mean_abs_mean").number(c.mean_abs_mean);
  w.key("rms_mean").number(c.rms_mean);
  w.key("max_abs_gauss").number(c.max_abs_gauss);
  write_sample(w.key("where_max_abs_mean"), c.where_max_abs_mean);
  w.end_object();
  const VertexCurvatureComparison& v = q.quadric;
  w.key("quadric_fit").begin_object();
  w.key("vertices").integer(v.vertices);
  w.key("max_abs_H").number(v.max_abs_H);
  w.key("cage_max_abs_H_error").number(v.max_abs_H_error_cage);
  w.key("cage_mean_abs_H_error").number(v.mean_abs_H_error_cage);
  w.key("limit_points_max_abs_H_error").number(v.max_abs_H_error_limit);
  w.key("limit_points_mean_abs_H_error").number(v.mean_abs_H_error_limit);
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
    w.key("base_vertex").integer(a.base_vertex);
    w.key("valence").integer(a.valence);
    w.key("sectors").integer(a.sectors);
    w.key("rays").integer(a.rays);
    optional_number(w.key("normal_angle_deg"), a.normal_angle_deg >= 0, a.normal_angle_deg);
    w.end_object();
  }
  w.end_array().end_object();
}

void write_polar(JsonWriter& w, const ConversionResult& c, double size) {
  const PatchBuildInfo& info = c.build.info;
  w.key("polar").begin_object();
  w.key("enabled").boolean(c.polar);
  w.key("radial_steps").integer(c.cap_options.radial_steps);
  w.key("lambda").number(c.cap_options.lambda);
  w.break_line(4).key("caps").begin_array(6, 4);
  for (const CapMeasure& m : c.caps) {
    w.begin_object();
    w.key("pole").integer(m.pole_vertex);
    w.key("valence").integer(m.valence);
    w.key("bp_distance").number(m.bp_distance);
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
    w.key("vertex").integer(r.vertex);
    w.key("valence").integer(r.valence);
    w.key("reason").string(r.reason);
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
    w.key("max").number(st.max);
    w.key("mean").number(st.mean);
    w.key("where");
    if (st.where >= 0) w.integer(st.where);
    else w.null();
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
  w.key("polar_vertices").integer(f.polar_vertices);
  w.key("no_surface").integer(f.no_surface);
  optional_number(w.break_line(4).key("energy_before"), f.energy_before >= 0, f.energy_before);
  optional_number(w.key("energy_after"), f.energy_after >= 0, f.energy_after);
  w.end_object();
}

void write_deviation(JsonWriter& w, const ConversionResult& c, double size) {
  const PatchBuildInfo& info = c.build.info;
  const DeviationReport& d = c.deviation;
  w.key("deviation").begin_object();
  w.key("max").number(d.max);
  w.key("mean").number(d.mean);
  relative(w.key("relative"), d.max, size);
  w.break_line(4).key("where");
  if (d.samples > 0) w.point(d.where);
  else w.null();
  w.key("worst_fan");
  if (d.worst_fan >= 0 && d.worst_fan < static_cast<int>(info.fans.size())) {
    const IrregularFan& f = info.fans[d.worst_fan];
    w.begin_object();
    w.key("base_vertex").integer(f.base_vertex);
    w.key("valence").integer(f.valence);
    w.key("mode").string(to_string(f.mode));
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
    w.key("base_vertex").integer(f.base_vertex);
    w.key("valence").integer(f.valence);
    w.key("mode").string(to_string(f.mode));
    w.key("level").integer(f.level);
    w.key("max").number(fd.max);
    w.end_object();
  }
  w.end_array();
  w.break_line(4).key("tolerance");
  if (c.tolerance_given) {
    const ToleranceResult& t = c.tolerance;
    w.begin_object();
    w.key("requested").number(t.requested);
    w.key("default").boolean(t.is_default);
    w.key("units").string(c.tolerance_absolute ? "model" : "relative");
    w.key("requested_model_units").number(t.absolute);
    w.break_line(6).key("initial_max").number(t.first_max);
    w.key("extra_levels_needed").integer(t.needed);
    w.key("extra_levels_used").integer(t.used);
    w.key("fans_deepened").integer(t.fans_deepened);
    w.key("capped").boolean(t.capped);
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

std::string report_json(const ConversionResult& c) {
  const PatchBuildInfo& info = c.build.info;
  const PatchSet& ps = c.build.set;
  const double size = ps.model_size;
  JsonWriter w = report_writer();
  w.begin_object(2, 0);
  w.key("format").string("subd2nurbs-report");
  w.key("version").integer(1);
  w.key("input").string(c.input);
  optional_string(w.key("output"), c.output.path);
  optional_string(w.key("output_format"), c.output.format);
  optional_string(w.key("step_schema"), c.output.step_schema);
  w.key("warnings").begin_array();
  for (const std::string& text : warning_texts(c)) w.string(text);
  w.end_array();
  w.key("model_size").number(size);
  w.key("coarse_level").integer(info.coarse_level);
  w.key("level").integer(info.level);
  w.key("extra_levels").integer(c.extra_levels);
  w.key("patches").begin_object();
  w.key("total").integer(static_cast<long long>(ps.patches.size()));
  w.key("regular").integer(info.regular_patches);
  w.key("pccm").integer(info.pccm_patches);
  w.key("polar_caps").integer(static_cast<long long>(info.caps.size()));
  w.key("poles").integer(info.total_poles);
  w.key("pieces").integer(info.leaves);
  w.key("removed_knots").integer(info.removed_knots);
  w.end_object();
  const PackedSet& out = c.exported;
  w.key("faces").begin_object();
  w.key("mode").string(to_string(c.faces));
  w.key("total").integer(static_cast<long long>(out.set.patches.size()));
  w.key("packed").integer(out.packs);
  w.key("packed_quads").integer(out.packed_quads);
  w.key("poles").integer(out.total_poles);
  w.key("removed_knot_lines").integer(out.removed_knots);
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
  w.key("sharpened_edges").integer(info.sharpened_edges);
  w.key("sharpened_vertices").integer(info.sharpened_vertices);
  w.key("brep");
  if (c.has_brep) {
    const occt::BrepResult& b = c.brep;
    w.begin_object();
    w.key("faces").integer(b.num_faces);
    w.key("edges").integer(b.num_edges);
    w.key("vertices").integer(b.num_vertices);
    w.key("type").string(b.is_solid ? "solid" : "shell");
    w.key("solids").integer(b.num_solids);
    w.key("shells").integer(b.num_shells);
    w.key("valid").boolean(b.valid);
    w.key("tolerance").number(b.tolerance);
    w.end_object();
  } else {
    w.null();
  }
  const ContinuityReport& k = c.continuity;
  w.key("continuity").begin_object();
  w.key("samples_per_curve").integer(kContinuitySamples);
  w.key("shared_curves").integer(static_cast<long long>(k.curves.size()));
  w.break_line(4).key("max_gap").number(k.max_gap);
  relative(w.key("max_gap_relative"), k.max_gap, size);
  w.break_line(4).key("max_normal_angle_deg").number(k.max_normal_angle_deg);
  w.key("max_coplanarity").number(k.max_coplanarity);
  w.break_line(4).key("max_c1_jump").number(k.max_c1_jump);
  w.key("max_c2_jump").number(k.max_c2_jump);
  w.key("max_crease_normal_angle_deg").number(k.max_crease_normal_angle_deg);
  w.end_object();
  write_deviation(w, c, size);
  const Timings& ms = c.ms;
  w.key("timings_ms").begin_object();
  w.key("load").number(ms.load);
  w.key("fit").number(ms.fit);
  w.key("patches").number(ms.patches);
  w.key("continuity").number(ms.continuity);
  w.key("deviation").number(ms.deviation);
  w.key("packing").number(ms.packing);
  w.key("brep").number(ms.brep);
  w.key("write").number(ms.write);
  w.end_object();
  if (c.quality) {  // the quality stage's section and its own time, beside timings_ms
    write_quality(w.key("quality"), *c.quality, size, 2);
    w.key("quality_ms").number(ms.quality);
  }
  w.end_object();
  return w.take() + "\n";
}

std::string quality_report_json(const ConversionResult& c) {
  if (!c.quality) throw std::logic_error("quality_report_json: the conversion ran without the quality stage");
  const double size = c.build.set.model_size;
  JsonWriter w = report_writer();
  w.begin_object(2, 0);
  w.key("format").string("subd2nurbs-quality");
  w.key("version").integer(1);
  w.key("input").string(c.input);
  w.key("model_size").number(size);
  w.key("coarse_level").integer(c.build.info.coarse_level);
  w.key("level").integer(c.build.info.level);
  w.key("patches").integer(static_cast<long long>(c.build.set.patches.size()));
  w.key("faces").begin_object();
  w.key("mode").string(to_string(c.faces));
  w.key("total").integer(static_cast<long long>(c.exported.set.patches.size()));
  w.end_object();
  w.key("quality_ms").number(c.ms.quality);
  write_quality(w.key("quality"), *c.quality, size, 2);
  w.end_object();
  return w.take() + "\n";
}

}  // namespace subd2nurbs::pipeline
