#include "core/eval/preview_mesh.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/nurbs/nurbs_eval.h"
#include "core/eval/quality.h"
#include "core/util/constants.h"

namespace subd2nurbs {

namespace {

double dot(const Point3& a, const Point3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/// Mean curvature of a patch point (sign: a sphere with outward normal has H = -1/R).
double mean_curvature(const SurfaceDerivs& d, const Point3& n) {
  const double E = dot(d.du, d.du), F = dot(d.du, d.dv), G = dot(d.dv, d.dv);
  const double L = dot(d.duu, n), M = dot(d.duv, n), N = dot(d.dvv, n);
  const double det = E * G - F * F;
  return det > 0 ? (E * N - 2 * F * M + G * L) / (2 * det) : 0.0;
}

void ramp(double x, float rgb[3]) {  // 0 blue -> 0.5 green-yellow -> 1 red
  x = std::clamp(x, 0.0, 1.0);
  rgb[0] = static_cast<float>(std::clamp(1.5 - std::abs(4 * x - 3), 0.0, 1.0));
  rgb[1] = static_cast<float>(std::clamp(1.5 - std::abs(4 * x - 2), 0.0, 1.0));
  rgb[2] = static_cast<float>(std::clamp(1.5 - std::abs(4 * x - 1), 0.0, 1.0));
}

void diverging(double x, float rgb[3]) {  // -1 blue, 0 white, +1 red
  x = std::clamp(x, -1.0, 1.0);
  if (x < 0) {
    rgb[0] = rgb[1] = static_cast<float>(1 + x);
    rgb[2] = 1;
  } else {
    rgb[0] = 1;
    rgb[1] = rgb[2] = static_cast<float>(1 - x);
  }
}

}  // namespace

const char* to_string(PreviewColor color) {
  switch (color) {
    case PreviewColor::Deviation: return "deviation";
    case PreviewColor::Curvature: return "curvature";
    case PreviewColor::Zebra: return "zebra";
  }
  return "?";
}

PreviewMesh build_preview(const PatchBuild& b, const LimitEvaluator* limit, PreviewColor color, int n) {
  if (n < 2) throw std::invalid_argument("build_preview: at least 2 samples per side");
  if (color == PreviewColor::Deviation && !limit)
    throw std::invalid_argument("build_preview: deviation colouring needs the limit evaluator");
  PreviewMesh m;
  const PatchSet& ps = b.set;
  const size_t nv = ps.patches.size() * static_cast<size_t>(n) * n;
  m.positions.reserve(3 * nv);
  m.normals.reserve(3 * nv);
  m.values.reserve(nv);
  for (size_t pi = 0; pi < ps.patches.size(); ++pi) {
    const uint32_t base = static_cast<uint32_t>(m.values.size());
    const PatchEvaluator eval(ps.patches[pi]);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const double s = static_cast<double>(i) / (n - 1), t = static_cast<double>(j) / (n - 1);
        const SurfaceDerivs d = eval.derivs(s, t);
        Point3 nn = unit_normal(d);
        for (int k = 0; k < 3; ++k) {
          m.positions.push_back(static_cast<float>(d.p[k]));
          m.normals.push_back(static_cast<float>(nn[k]));
        }
        double value = 0;
        switch (color) {
          case PreviewColor::Deviation:  // 0 on polar caps (not Catmull-Clark surfaces)
            value = ps.patches[pi].kind == PatchKind::PolarCap
                        ? 0.0
                        : limit_distance(b, *limit, static_cast<int>(pi), s, t);
            break;
          case PreviewColor::Curvature:
            value = mean_curvature(d, nn);
            break;
          case PreviewColor::Zebra: {
            const double angle = std::acos(std::clamp(nn[2], -1.0, 1.0));
            value = static_cast<int>(std::floor(angle / kPi * 12)) % 2 == 0 ? 1.0 : 0.0;
            break;
          }
        }
        m.values.push_back(static_cast<float>(value));
      }
    for (int i = 0; i + 1 < n; ++i)
      for (int j = 0; j + 1 < n; ++j) {
        const uint32_t a = base + static_cast<uint32_t>(i * n + j), bb = a + static_cast<uint32_t>(n);
        // (i, j) -> (i+1, j) -> (i+1, j+1): counter-clockwise in (s, t), normal X_s x X_t.
        m.indices.insert(m.indices.end(), {a, bb, bb + 1, a, bb + 1, a + 1});
      }
  }
  // Colour map.
  std::vector<float> mag(m.values.size());
  for (size_t i = 0; i < mag.size(); ++i) mag[i] = std::abs(m.values[i]);
  double hi = 0;
  if (color == PreviewColor::Curvature && !mag.empty()) {
    std::vector<float> sorted = mag;
    const size_t q = std::min(sorted.size() - 1, static_cast<size_t>(0.95 * sorted.size()));
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(q), sorted.end());
    hi = sorted[q];
  } else if (!mag.empty()) {
    hi = *std::max_element(mag.begin(), mag.end());
  }
  m.value_min = color == PreviewColor::Curvature ? -hi : 0.0;
  m.value_max = color == PreviewColor::Zebra ? 1.0 : hi;
  m.colors.reserve(3 * m.values.size());
  for (float v : m.values) {
    float rgb[3];
    if (color == PreviewColor::Curvature)
      diverging(hi > 0 ? v / hi : 0.0, rgb);
    else if (color == PreviewColor::Deviation)
      ramp(hi > 0 ? v / hi : 0.0, rgb);
    else
      rgb[0] = rgb[1] = rgb[2] = v;
    m.colors.insert(m.colors.end(), {rgb[0], rgb[1], rgb[2]});
  }
  return m;
}

}  // namespace subd2nurbs
