// Evaluation of the PatchSet's B-spline patches and curves (de Boor / Cox recursion with
// derivatives, Piegl & Tiller, The NURBS Book, A2.1-A2.3). Rational patches (weights) are
// evaluated through homogeneous coordinates.
#pragma once

#include "core/nurbs/patch_set.h"

namespace subd2nurbs {

struct SurfaceDerivs {
  Point3 p{}, du{}, dv{}, duu{}, duv{}, dvv{};
};

/// Position and derivatives up to second order at (u, v) in the patch's domain ([0,1]^2, or
/// [0, mu] x [0, mv] for a packed face). Expands the knot vectors on every call: to evaluate
/// one patch many times, use a PatchEvaluator.
SurfaceDerivs evaluate(const NurbsPatch& patch, double u, double v);

/// A patch with its knot vectors expanded once (every knot repeated by its multiplicity), for
/// evaluating it many times: a packed face has hundreds of knots. The patch must outlive it.
class PatchEvaluator {
 public:
  explicit PatchEvaluator(const NurbsPatch& patch);
  /// As evaluate(patch, u, v), with the derivatives up to `order` (0, 1 or 2); the higher
  /// ones are left zero.
  SurfaceDerivs derivs(double u, double v, int order = 2) const;
  /// The position alone.
  Point3 point(double u, double v) const { return derivs(u, v, 0).p; }
  /// Positions on the tensor grid us x vs: out[a * nv + b] = point(us[a], vs[b]), with one
  /// basis evaluation per parameter instead of one per point.
  void grid(const double* us, int nu, const double* vs, int nv, Point3* out) const;
  const NurbsPatch& patch() const { return *patch_; }

 private:
  const NurbsPatch* patch_;
  std::vector<double> U_, V_;
};

/// Unit normal Xu x Xv; the zero vector where the parametrization is singular
/// (|Xu x Xv| <= 1e-12 (|Xu|^2 + |Xv|^2), e.g. the collapsed edge of a polar cap).
Point3 unit_normal(const SurfaceDerivs& d);

/// Point on a boundary curve at s in [0,1].
Point3 evaluate(const BoundaryCurve& curve, double s);

/// Parameters (u, v) of a patch side at side parameter t (counter-clockwise traversal,
/// see patch_set.h): side 0 (t,0), side 1 (1,t), side 2 (1-t,1), side 3 (0,1-t).
void side_parameters(int side, double t, double& u, double& v);

/// A patch at a side point (t in [0,1] along the whole side, whatever the patch's domain),
/// with derivatives taken along the side (counter-clockwise traversal, in the patch's own
/// parameter) and into the patch (d/dn): the frame in which two patches sharing a curve are
/// compared (docs/math.md 10.1).
struct SideDerivs {
  Point3 p{}, along{}, inward{}, inward2{};  ///< X, dX/dt, dX/dn, d2X/dn2
  Point3 normal{};                            ///< unit normal Xu x Xv
};
SideDerivs side_derivatives(const NurbsPatch& patch, int side, double t);
/// The same with an evaluator of the patch made once for many side points (it flattens the
/// knot vectors, which for a packed face are long).
SideDerivs side_derivatives(const PatchEvaluator& patch, int side, double t);

/// Basis functions and their first `nd` derivatives at x for a flat knot vector U and
/// degree p: ders[k][j] is the k-th derivative of N_{span-p+j}. Returns the span index.
int basis_derivatives(const std::vector<double>& U, int p, double x, int nd, double ders[3][4]);

}  // namespace subd2nurbs
