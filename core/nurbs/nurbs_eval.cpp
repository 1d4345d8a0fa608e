#include "core/nurbs/nurbs_eval.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace subd2nurbs {

int basis_derivatives(const std::vector<double>& U, int p, double x, int nd, double ders[3][4]) {
  if (p != 3) throw std::invalid_argument("basis_derivatives: degree 3 only");
  const int n = static_cast<int>(U.size()) - p - 2;  // last pole index
  // Span: U[span] <= x < U[span+1], with x == U.back() in the last non-empty span.
  int span;
  if (x >= U[n + 1]) span = n;
  else if (x <= U[p]) span = p;
  else span = static_cast<int>(std::upper_bound(U.begin() + p, U.begin() + n + 2, x) - U.begin()) - 1;
  double ndu[4][4], left[4], right[4];
  ndu[0][0] = 1.0;
  for (int j = 1; j <= p; ++j) {
    left[j] = x - U[span + 1 - j];
    right[j] = U[span + j] - x;
    double saved = 0.0;
    for (int r = 0; r < j; ++r) {
      ndu[j][r] = right[r + 1] + left[j - r];
      const double temp = ndu[r][j - 1] / ndu[j][r];
      ndu[r][j] = saved + right[r + 1] * temp;
      saved = left[j - r] * temp;
    }
    ndu[j][j] = saved;
  }
  for (int j = 0; j <= p; ++j) ders[0][j] = ndu[j][p];
  double a[2][4];
  for (int r = 0; r <= p; ++r) {
    int s1 = 0, s2 = 1;
    a[0][0] = 1.0;
    for (int k = 1; k <= nd; ++k) {
      double d = 0.0;
      const int rk = r - k, pk = p - k;
      if (r >= k) {
        a[s2][0] = a[s1][0] / ndu[pk + 1][rk];
        d = a[s2][0] * ndu[rk][pk];
      }
      const int j1 = rk >= -1 ? 1 : -rk;
      const int j2 = (r - 1 <= pk) ? k - 1 : p - r;
      for (int j = j1; j <= j2; ++j) {
        a[s2][j] = (a[s1][j] - a[s1][j - 1]) / ndu[pk + 1][rk + j];
        d += a[s2][j] * ndu[rk + j][pk];
      }
      if (r <= pk) {
        a[s2][k] = -a[s1][k - 1] / ndu[pk + 1][r];
        d += a[s2][k] * ndu[r][pk];
      }
      ders[k][r] = d;
      std::swap(s1, s2);
    }
  }
  double f = p;
  for (int k = 1; k <= nd; ++k) {
    for (int j = 0; j <= p; ++j) ders[k][j] *= f;
    f *= (p - k);
  }
  return span;
}

SurfaceDerivs evaluate(const NurbsPatch& patch, double u, double v) { return PatchEvaluator(patch).derivs(u, v); }

PatchEvaluator::PatchEvaluator(const NurbsPatch& patch)
    : patch_(&patch), U_(patch.knots_u.flat()), V_(patch.knots_v.flat()) {}

SurfaceDerivs PatchEvaluator::derivs(double u, double v, int order) const {
  if (order < 0 || order > 2) throw std::invalid_argument("PatchEvaluator: derivatives of order 0 to 2");
  const NurbsPatch& patch = *patch_;
  double Nu[3][4], Nv[3][4];
  const int su = basis_derivatives(U_, 3, u, order, Nu), sv = basis_derivatives(V_, 3, v, order, Nv);
  // Homogeneous sums S[k][l] = sum Nu^(k) Nv^(l) w P  and  W[k][l] = sum Nu^(k) Nv^(l) w.
  double S[3][3][3] = {}, W[3][3] = {};
  const bool rational = !patch.weights.empty();
  for (int a = 0; a <= 3; ++a)
    for (int b = 0; b <= 3; ++b) {
      const int i = su - 3 + a, j = sv - 3 + b;
      const Point3& P = patch.pole(i, j);
      const double w = rational ? patch.weights[static_cast<size_t>(i) * patch.num_poles_v + j] : 1.0;
      for (int k = 0; k <= order; ++k)
        for (int l = 0; l + k <= order; ++l) {
          const double bw = Nu[k][a] * Nv[l][b] * w;
          for (int c = 0; c < 3; ++c) S[k][l][c] += bw * P[c];
          W[k][l] += bw;
        }
    }
  // Quotient rule (Piegl & Tiller A4.4) up to the order asked.
  Point3 D[3][3] = {};
  for (int k = 0; k <= order; ++k)
    for (int l = 0; l + k <= order; ++l)
      for (int c = 0; c < 3; ++c) {
        double x = S[k][l][c];
        if (rational) {
          for (int j = 1; j <= l; ++j) x -= (l == 2 && j == 1 ? 2 : 1) * W[0][j] * D[k][l - j][c];
          for (int i = 1; i <= k; ++i) {
            const double bi = (k == 2 && i == 1) ? 2 : 1;
            x -= bi * W[i][0] * D[k - i][l][c];
            for (int j = 1; j <= l; ++j) x -= bi * W[i][j] * D[k - i][l - j][c];
          }
          x /= W[0][0];
        }
        D[k][l][c] = x;
      }
  SurfaceDerivs out;
  out.p = D[0][0];
  out.du = D[1][0];
  out.dv = D[0][1];
  out.duu = D[2][0];
  out.duv = D[1][1];
  out.dvv = D[0][2];
  return out;
}

void PatchEvaluator::grid(const double* us, int nu, const double* vs, int nv, Point3* out) const {
  if (nu < 0 || nv < 0) throw std::invalid_argument("PatchEvaluator::grid: negative size");
  const NurbsPatch& patch = *patch_;
  struct Basis {
    double N[3][4];
    int span;
  };
  // Up to 16 parameters per direction on the stack (the builder's 4 x 4, the report's n x n).
  Basis stack_u[16], stack_v[16];
  std::vector<Basis> heap_u(nu > 16 ? nu : 0), heap_v(nv > 16 ? nv : 0);
  Basis* Nu = nu > 16 ? heap_u.data() : stack_u;
  Basis* Nv = nv > 16 ? heap_v.data() : stack_v;
  for (int a = 0; a < nu; ++a) Nu[a].span = basis_derivatives(U_, 3, us[a], 0, Nu[a].N);
  for (int b = 0; b < nv; ++b) Nv[b].span = basis_derivatives(V_, 3, vs[b], 0, Nv[b].N);
  const bool rational = !patch.weights.empty();
  for (int a = 0; a < nu; ++a)
    for (int b = 0; b < nv; ++b) {
      double S[3] = {0, 0, 0}, W = 0;
      for (int i = 0; i <= 3; ++i)
        for (int j = 0; j <= 3; ++j) {
          const int pi = Nu[a].span - 3 + i, pj = Nv[b].span - 3 + j;
          const double w = rational ? patch.weights[static_cast<size_t>(pi) * patch.num_poles_v + pj] : 1.0;
          const double bw = Nu[a].N[0][i] * Nv[b].N[0][j] * w;
          const Point3& P = patch.pole(pi, pj);
          for (int c = 0; c < 3; ++c) S[c] += bw * P[c];
          W += bw;
        }
      Point3& p = out[a * nv + b];
      for (int c = 0; c < 3; ++c) p[c] = rational ? S[c] / W : S[c];
    }
}

Point3 unit_normal(const SurfaceDerivs& d) {
  const Point3& a = d.du;
  const Point3& b = d.dv;
  Point3 n{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  // Singular where Xu and Xv are parallel or one vanishes (the collapsed edge of a polar
  // cap, where rounding leaves |Xv| ~ 1e-16 |Xu|): no normal rather than a random one.
  const double scale = a[0] * a[0] + a[1] * a[1] + a[2] * a[2] + b[0] * b[0] + b[1] * b[1] + b[2] * b[2];
  if (!(len > 1e-12 * scale)) return {0, 0, 0};
  for (double& c : n) c /= len;
  return n;
}

Point3 evaluate(const BoundaryCurve& curve, double s) {
  const std::vector<double> U = curve.knots.flat();
  double N[3][4];
  const int span = basis_derivatives(U, 3, s, 0, N);
  Point3 p{0, 0, 0};
  for (int a = 0; a <= 3; ++a)
    for (int c = 0; c < 3; ++c) p[c] += N[0][a] * curve.poles[span - 3 + a][c];
  return p;
}

void side_parameters(int side, double t, double& u, double& v) {
  switch (side) {
    case 0: u = t; v = 0; break;
    case 1: u = 1; v = t; break;
    case 2: u = 1 - t; v = 1; break;
    default: u = 0; v = 1 - t; break;
  }
}

SideDerivs side_derivatives(const NurbsPatch& patch, int side, double t) {
  return side_derivatives(PatchEvaluator(patch), side, t);
}

SideDerivs side_derivatives(const PatchEvaluator& evaluator, int side, double t) {
  const NurbsPatch& patch = evaluator.patch();
  double u, v;
  side_parameters(side, t, u, v);
  // The unit square's point in the patch's domain ([0, mu] x [0, mv] for a packed face).
  const double u0 = patch.knots_u.knots.front(), u1 = patch.knots_u.knots.back();
  const double v0 = patch.knots_v.knots.front(), v1 = patch.knots_v.knots.back();
  u = u == 0 ? u0 : u == 1 ? u1 : u0 + u * (u1 - u0);
  v = v == 0 ? v0 : v == 1 ? v1 : v0 + v * (v1 - v0);
  const SurfaceDerivs d = evaluator.derivs(u, v);
  auto neg = [](const Point3& a) { return Point3{-a[0], -a[1], -a[2]}; };
  SideDerivs f;
  f.p = d.p;
  switch (side) {
    case 0: f.along = d.du; f.inward = d.dv; f.inward2 = d.dvv; break;
    case 1: f.along = d.dv; f.inward = neg(d.du); f.inward2 = d.duu; break;
    case 2: f.along = neg(d.du); f.inward = neg(d.dv); f.inward2 = d.dvv; break;
    default: f.along = neg(d.dv); f.inward = d.du; f.inward2 = d.duu; break;
  }
  f.normal = unit_normal(d);
  return f;
}

}  // namespace subd2nurbs
