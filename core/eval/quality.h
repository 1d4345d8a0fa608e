// Quality of a conversion measured against the exact limit surface (core/limit): how far the
// NURBS patches are from the limit, how the joins behave compared with what the limit surface
// does across the same edges, and the curvature of the limit.
#pragma once

#include <array>
#include <vector>

#include "core/eval/continuity.h"
#include "core/eval/quadric_fit.h"
#include "core/limit/limit_evaluator.h"
#include "core/patch/packing.h"
#include "core/patch/patch_builder.h"
#include "core/util/small_vector.h"

namespace subd2nurbs {

/// Where a patch point lies on the limit surface's parametrisation (ptex, docs/limit.md).
struct LimitParam {
  int face = -1, sub = 0;  ///< cage face and sub-face (0 for a quad)
  double u = 0, v = 0;
};

/// Maps patch parameters to limit parameters: patches are built on the level-a faces
/// (a = PatchBuildInfo::coarse_level); a level-1 face is a ptex sub-face of an n-gon or a
/// quarter of a quad. \throw std::out_of_range for a bad patch index.
LimitParam patch_to_limit(const PatchBuild& build, int patch, double s, double t);

struct DeviationSample {
  int patch = -1;
  double s = 0, t = 0;      ///< patch parameters
  LimitParam limit;         ///< the same point's limit parameters
  Point3 point{};           ///< on the patch
  double parametric = 0;    ///< |X(s,t) - L(u,v)|
  double distance = 0;      ///< to the closest limit point found from there (<= parametric)
};

struct EdgeQuality {
  int curve = -1;
  Continuity claimed = Continuity::Boundary;
  /// What the limit surface has across this edge: "boundary", "crease" (infinitely sharp:
  /// a normal jump is expected) or "smooth" (the limit is tangent continuous here).
  const char* expected = "smooth";
  double gap = 0;                  ///< max |X1 - X2| of the patches (from measure_continuity)
  double normal_jump_deg = 0;      ///< max angle between the patches' normals (idem)
  double limit_normal_jump_deg = 0;  ///< max angle between the limit's normals on both sides
  /// Max over the samples of |patch normal jump - limit normal jump| (degrees).
  double normal_jump_error_deg = 0;
};

struct CurvatureSummary {
  int samples = 0;                 ///< finite curvature samples
  double min_k = 0, max_k = 0;     ///< over k2 and k1 (signed, docs/limit.md)
  double max_abs_mean = 0, max_abs_gauss = 0;
  double mean_abs_mean = 0;
  double rms_mean = 0;
  DeviationSample where_max_abs_mean;  ///< where |H| is largest (its point and parameters)
};

struct QualityReport {
  int samples_per_side = 0;
  int deviation_samples = 0;
  /// Patches sampled on the kPolynomialSamples^2 grid only (sampled_as_polynomial): there the
  /// largest distance over the whole quad is at most kPolynomialBound times the sampled one.
  int polynomial_patches = 0;
  double deviation_max = 0, deviation_mean = 0;        ///< closest-point distance
  double parametric_max = 0, parametric_mean = 0;      ///< same-parameter distance
  DeviationSample worst;                               ///< largest closest-point distance
  std::vector<double> patch_max;                       ///< per patch, closest-point distance
  std::vector<EdgeQuality> edges;                      ///< one per shared curve
  double max_gap = 0;
  double max_smooth_normal_jump_deg = 0;    ///< patches, over edges expected smooth
  double max_normal_jump_error_deg = 0;     ///< over every shared curve
  int smooth_edges = 0, crease_edges = 0, boundary_edges = 0;
  /// Polar caps (PatchKind::PolarCap) follow Bi-cubic polar subdivision, not Catmull-Clark:
  /// they and the curves on their sides are not measured here (patch_max is 0 for them).
  int polar_patches = 0;
  /// Edges claimed smoother than C0 whose limit has a normal jump, or expected smooth but
  /// claimed C0 (other than sharpened semi-sharp creases): disagreements of class.
  int class_mismatches = 0;
  CurvatureSummary curvature;
  /// The cage's own curvature by implicit-quadric fits at its smooth vertices (seed 001,
  /// docs/math.md 13) against the exact limit curvature there.
  VertexCurvatureComparison quadric;
};

/// Distance from patch point (s, t) to the closest limit point found by Gauss-Newton from the
/// same parameters within the same face (an upper bound of the true distance).
double limit_distance(const PatchBuild& build, const LimitEvaluator& limit, int patch, double s, double t);

/// A tensor grid of a quad patch's parameters: the samples (s[i], t[j]), in the order i * t.size() + j.
struct SampleGrid {
  SmallVector<double, 16> s, t;  // inline up to 16 per side (no allocation per patch)
};

/// Where the measured surface and the limit are one bicubic polynomial each over a quad, their
/// difference is one too, and its values at the 4 x 4 grid {0, 1/3, 2/3, 1}^2 determine it
/// (tensor-product Lagrange interpolation): its largest norm over the quad is at most
/// Lambda^2 times the largest at the grid, Lambda = 1.63113... the Lebesgue constant of 4
/// equally spaced nodes (docs/math.md 11.2).
constexpr int kPolynomialSamples = 4;
constexpr double kPolynomialBound = 2.6606;  // 1.631130309^2, rounded up

/// True where quad patch `patch` is sampled as a polynomial: the limit over its face is one
/// bicubic (LimitEvaluator::is_polynomial) and so is the surface measured there: the patch, or
/// with `exported` the exported face's cell holding it (not rational, no knot inside the cell).
bool sampled_as_polynomial(const PatchBuild& build, const LimitEvaluator& limit, int patch,
                           const PackedSet* exported);

/// The grids measure_quality samples on a patch: the n x n grid (endpoints included; at most
/// kPolynomialSamples per side where `polynomial`, see sampled_as_polynomial), and on patches
/// at irregular vertices (PatchKind::Pccm) a 4 x 4 grid per corner and level, halving towards
/// each corner down to the level-k zone where Construction Q differs from the limit.
std::vector<SampleGrid> quality_sample_grids(const PatchBuild& build, int patch, int n, bool polynomial);
/// The same samples as a list of (s, t), grid after grid.
std::vector<std::array<double, 2>> quality_sample_parameters(const PatchBuild& build, int patch, int n,
                                                             bool polynomial);

/// Samples every patch (quality_sample_parameters) (n = samples_per_side, endpoints included;
/// polynomial patches on kPolynomialSamples per side) against the
/// exact limit, and every shared curve (from `continuity`) on both sides. With `exported`, the
/// surface measured is exported->set (packed faces): each sample of a coarse quad is taken on
/// the face holding it (PatchPlace), and `continuity` is over exported->set's curves.
QualityReport measure_quality(const PatchBuild& build, const LimitEvaluator& limit,
                              const ContinuityReport& continuity, int samples_per_side = 9,
                              const PackedSet* exported = nullptr);
/// As above, with the cage's quadric-fit comparison (QualityReport::quadric) already made: it
/// depends on the limit alone (compare_vertex_curvature(limit)), so the pipeline makes it
/// while the patches are still being packed.
QualityReport measure_quality(const PatchBuild& build, const LimitEvaluator& limit,
                              const ContinuityReport& continuity, int samples_per_side,
                              const PackedSet* exported, const VertexCurvatureComparison& quadric);

}  // namespace subd2nurbs
