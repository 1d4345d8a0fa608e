#include "converter/cli/quality_json.h"

#include <chrono>

#include <cmath>
#include <memory>
#include <stdexcept>

#include "converter/cli/convert.h"
#include "converter/pipeline/conversion.h"
#include "core/eval/preview_mesh.h"
#include "io/gltf_preview.h"

namespace subd2nurbs::cli {

namespace {

using pipeline::short_number;

std::string sample(const DeviationSample& d) {
  return "{\"patch\": " + std::to_string(d.patch) + ", \"s\": " + json_number(d.s) +
         ", \"t\": " + json_number(d.t) + ", \"face\": " + std::to_string(d.limit.face) +
         ", \"sub\": " + std::to_string(d.limit.sub) + ", \"u\": " + json_number(d.limit.u) +
         ", \"v\": " + json_number(d.limit.v) + ", \"point\": " + json_point(d.point) + "}";
}

const char* continuity_name(Continuity c) { return to_string(c); }

}  // namespace

std::string quality_json(const QualityReport& q, double size, int indent) {
  const std::string p(static_cast<size_t>(indent), ' ');
  auto rel = [size](double x) { return size > 0 ? json_number(x / size) : std::string("null"); };
  std::string j = "{\n";
  auto line = [&](const std::string& s, bool last = false) { j += p + "  " + s + (last ? "\n" : ",\n"); };
  line("\"samples_per_side\": " + std::to_string(q.samples_per_side));
  line("\"polar_patches_skipped\": " + std::to_string(q.polar_patches));
  line("\"deviation\": {\"samples\": " + std::to_string(q.deviation_samples) +
       ", \"max\": " + json_number(q.deviation_max) + ", \"max_rel\": " + rel(q.deviation_max) +
       ", \"mean\": " + json_number(q.deviation_mean) + ", \"parametric_max\": " +
       json_number(q.parametric_max) + ", \"parametric_mean\": " + json_number(q.parametric_mean) +
       ", \"where\": " + sample(q.worst) + "}");
  std::string pm = "\"patch_max\": [";
  for (size_t i = 0; i < q.patch_max.size(); ++i) pm += (i ? ", " : "") + json_number(q.patch_max[i]);
  line(pm + "]");
  line("\"edges_summary\": {\"smooth\": " + std::to_string(q.smooth_edges) + ", \"crease\": " +
       std::to_string(q.crease_edges) + ", \"boundary\": " + std::to_string(q.boundary_edges) +
       ", \"max_gap\": " + json_number(q.max_gap) + ", \"max_gap_rel\": " + rel(q.max_gap) +
       ", \"max_smooth_normal_jump_deg\": " + json_number(q.max_smooth_normal_jump_deg) +
       ", \"max_normal_jump_error_deg\": " + json_number(q.max_normal_jump_error_deg) +
       ", \"class_mismatches\": " + std::to_string(q.class_mismatches) + "}");
  std::string e = "\"edges\": [";
  for (size_t i = 0; i < q.edges.size(); ++i) {
    const EdgeQuality& x = q.edges[i];
    e += std::string(i ? "," : "") + "\n" + p + "    {\"curve\": " + std::to_string(x.curve) +
         ", \"claimed\": " + json_string(continuity_name(x.claimed)) + ", \"expected\": " +
         json_string(x.expected) + ", \"gap\": " + json_number(x.gap) + ", \"normal_jump_deg\": " +
         json_number(x.normal_jump_deg) + ", \"limit_normal_jump_deg\": " +
         json_number(x.limit_normal_jump_deg) + ", \"normal_jump_error_deg\": " +
         json_number(x.normal_jump_error_deg) + "}";
  }
  line(e + (q.edges.empty() ? "]" : "\n" + p + "  ]"));
  const CurvatureSummary& c = q.curvature;
  line("\"curvature\": {\"samples\": " + std::to_string(c.samples) + ", \"min_k\": " +
           json_number(c.min_k) + ", \"max_k\": " + json_number(c.max_k) + ", \"max_abs_mean\": " +
           json_number(c.max_abs_mean) + ", \"mean_abs_mean\": " + json_number(c.mean_abs_mean) +
           ", \"rms_mean\": " + json_number(c.rms_mean) + ", \"max_abs_gauss\": " +
           json_number(c.max_abs_gauss) + ", \"where_max_abs_mean\": " + sample(c.where_max_abs_mean) + "}",
       false);
  const VertexCurvatureComparison& v = q.quadric;
  line("\"quadric_fit\": {\"vertices\": " + std::to_string(v.vertices) + ", \"max_abs_H\": " +
           json_number(v.max_abs_H) + ", \"cage_max_abs_H_error\": " + json_number(v.max_abs_H_error_cage) +
           ", \"cage_mean_abs_H_error\": " + json_number(v.mean_abs_H_error_cage) +
           ", \"limit_points_max_abs_H_error\": " + json_number(v.max_abs_H_error_limit) +
           ", \"limit_points_mean_abs_H_error\": " + json_number(v.mean_abs_H_error_limit) + "}",
       true);
  return j + p + "}";
}

std::string add_member(const std::string& text, const std::string& name, const std::string& value) {
  const size_t end = text.find_last_of('}');
  if (end == std::string::npos) throw std::logic_error("add_member: not a JSON object");
  size_t last = text.find_last_not_of(" \n\t", end - 1);
  std::string out = text.substr(0, last + 1);
  out += ",\n  \"" + name + "\": " + value + "\n}\n";
  return out;
}

std::string add_quality_member(const std::string& text, const std::string& quality) {
  return add_member(text, "quality", quality);
}

QualityReport measure_conversion_quality(const SubdivLevel& base, const std::vector<Point3>& positions,
                                         const pipeline::ConversionResult& c, int samples) {
  const LimitEvaluator limit(base, positions);
  return measure_quality(c.build, limit, c.continuity, samples, &c.exported);
}

std::string report_with_quality(const std::string& report, const SubdivLevel& base,
                                const std::vector<Point3>& positions, const pipeline::ConversionResult& c,
                                std::ostream& err, bool quiet) {
  if (!quiet) err << "subd2nurbs: measuring against the exact limit surface...\n";
  const auto t0 = std::chrono::steady_clock::now();
  const QualityReport q = measure_conversion_quality(base, positions, c);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const double size = c.build.set.model_size;
  if (!quiet) print_quality_summary(err, q, size);
  // The quality stage's own time, beside the conversion's timings_ms.
  return add_member(add_quality_member(report, quality_json(q, size, 2)), "quality_ms", pipeline::json_number(ms));
}

StagedFile stage_preview(const ConvertOptions& o, const SubdivLevel& base, const std::vector<Point3>& positions,
                   const pipeline::ConversionResult& c, std::ostream& err) {
  const PreviewColor color = preview_color_from_string(o.preview_color);
  if (!o.quiet) err << "subd2nurbs: writing the preview " << o.preview << " (" << o.preview_color << ")\n";
  std::unique_ptr<LimitEvaluator> limit;
  if (color == PreviewColor::Deviation) limit = std::make_unique<LimitEvaluator>(base, positions);
  const PreviewMesh mesh = build_preview(c.build, limit.get(), color, o.preview_samples);
  StagedFile file = stage_preview_glb(o.preview, mesh, o.mesh + " (" + o.preview_color + ")");
  if (!o.quiet)
    err << "  preview    " << mesh.indices.size() / 3 << " triangles, " << o.preview_color << " from "
        << short_number(mesh.value_min) << " to " << short_number(mesh.value_max) << "\n";
  return file;
}

void print_quality_summary(std::ostream& err, const QualityReport& q, double size) {
  const DeviationSample& w = q.worst;
  err << "quality: deviation from the exact limit max " << short_number(q.deviation_max) << " ("
      << short_number(size > 0 ? q.deviation_max / size : 0) << " x size), mean "
      << short_number(q.deviation_mean) << " over " << q.deviation_samples << " samples";
  if (w.patch >= 0)
    err << "; worst at patch " << w.patch << " = face " << w.limit.face
        << (w.limit.sub ? " sub-face " + std::to_string(w.limit.sub) : std::string()) << " (u "
        << short_number(w.limit.u) << ", v " << short_number(w.limit.v) << ")";
  err << "\n";
  err << "quality: edges " << q.smooth_edges << " smooth, " << q.crease_edges << " crease, "
      << q.boundary_edges << " boundary; max gap " << short_number(q.max_gap)
      << ", max normal jump on smooth edges " << short_number(q.max_smooth_normal_jump_deg)
      << " deg, max |patch - limit| normal jump " << short_number(q.max_normal_jump_error_deg) << " deg, "
      << q.class_mismatches << " class mismatches\n";
  const CurvatureSummary& c = q.curvature;
  err << "quality: limit curvature k in [" << short_number(c.min_k) << ", " << short_number(c.max_k)
      << "], max |H| " << short_number(c.max_abs_mean) << ", mean |H| " << short_number(c.mean_abs_mean)
      << ", max |K| " << short_number(c.max_abs_gauss) << "\n";
  if (q.quadric.vertices > 0)
    err << "quality: quadric-fit H at " << q.quadric.vertices << " cage vertices vs exact: mean error "
        << short_number(q.quadric.mean_abs_H_error_cage) << " (cage points), "
        << short_number(q.quadric.mean_abs_H_error_limit) << " (limit points)\n";
}

}  // namespace subd2nurbs::cli
