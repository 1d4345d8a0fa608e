// Normal and curvature of a point set by an implicit quadric fit (seed 001, docs/math.md 13):
// f(x) = a x^2 + b y^2 + c z^2 + d xy + e yz + g zx + gx x + gy y + gz z = 0 through p0 (at the
// origin) and its neighbours, least squares with the largest gradient coefficient of a
// tentative normal fixed to 1; then n = grad f / |grad f|, K = n^T adj(M) n / D^2,
// H = n^T (M - tr(M) I) n / (2 D) at p0 (M the Hessian, D = |grad f|).
#pragma once

#include <vector>

#include "core/limit/limit_evaluator.h"
#include "core/refine/refiner.h"

namespace subd2nurbs {

struct QuadricFit {
  bool ok = false;      ///< false: fewer than 8 neighbours or a rank-deficient system
  Point3 normal{};      ///< unit, on the side of `tentative_normal`
  double K = 0, H = 0;  ///< Gaussian and mean curvature; a sphere with outward normal has K = 1/R^2, H = -1/R
  bool direct = false;  ///< solved by the normal equations directly (else by a QR; quadric_fit.cpp)
};

/// `tentative_normal` orients the result (and picks the fixed coefficient).
QuadricFit fit_quadric(const Point3& p0, const std::vector<Point3>& neighbours, const Point3& tentative_normal);

struct VertexCurvatureComparison {
  int vertices = 0;                   ///< interior smooth vertices compared
  double max_abs_H_error_cage = 0;    ///< fit to the cage's own 2-ring vs the exact limit H
  double mean_abs_H_error_cage = 0;
  double max_abs_H_error_limit = 0;   ///< fit to the limit points of the 2-ring vs the exact H
  double mean_abs_H_error_limit = 0;
  double max_abs_H = 0;               ///< exact, for scale
};

/// For every smooth interior vertex of the cage (all faces quads, no tags, not at a hole):
/// quadric fits to its 2-ring of cage points and of their limit points, against the exact
/// limit curvature at the vertex's limit point.
VertexCurvatureComparison compare_vertex_curvature(const LimitEvaluator& limit);

}  // namespace subd2nurbs
