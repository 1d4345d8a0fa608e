#include "converter/cli/quality_text.h"

#include <stdexcept>

#include "converter/cli/convert.h"
#include "converter/pipeline/conversion.h"
#include "converter/pipeline/shape_fit_report.h"
#include "core/eval/preview_mesh.h"
#include "io/gltf_preview.h"

namespace subd2nurbs::cli {

using pipeline::short_number;

StagedFile stage_preview(const ConvertOptions& o, const pipeline::ConversionResult& c, std::ostream& err) {
  if (!c.preview) throw std::logic_error("stage_preview: the conversion ran without the preview stage");
  const PreviewMesh& mesh = *c.preview;
  const std::string color = to_string(c.preview_settings.color);
  if (!o.quiet) err << "subd2nurbs: writing the preview " << o.preview << " (" << color << ")\n";
  StagedFile file = stage_preview_glb(o.preview, mesh, o.mesh + " (" + color + ")");
  if (!o.quiet)
    err << "  preview    " << mesh.indices.size() / 3 << " triangles, " << color << " from "
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

void print_target_distance(std::ostream& err, const std::string& label, const TargetDistance& d) {
  err << label << ": limit -> target " << pipeline::distance_text(d.limit_to_target) << "; target -> limit "
      << pipeline::distance_text(d.target_to_limit) << " (relative to the target's diagonal "
      << short_number(d.diagonal) << ")\n";
}

}  // namespace subd2nurbs::cli
