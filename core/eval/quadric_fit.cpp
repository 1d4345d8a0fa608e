#include "core/eval/quadric_fit.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/util/eigen_point.h"
#include "core/util/parallel.h"

namespace subd2nurbs {

namespace {

/// LDL^T of a symmetric positive semidefinite 8 x 8 matrix with diagonal pivoting (the largest
/// remaining diagonal first): P S P^T = L D L^T, L unit lower triangular.
class PivotedLdlt8 {
 public:
  /// False where a pivot is not positive (S singular, to rounding). Only S's lower triangle is read.
  bool factor(const double (&S)[8][8]) {
    for (int i = 0; i < 8; ++i) {
      perm_[i] = i;
      for (int j = 0; j <= i; ++j) a_[i][j] = S[i][j];
    }
    // a_ holds the lower triangle of the permuted, partly eliminated matrix; column k becomes
    // L's column k once pivot k is taken.
    for (int k = 0; k < 8; ++k) {
      int p = k;
      for (int i = k + 1; i < 8; ++i)
        if (a_[i][i] > a_[p][p]) p = i;
      if (p != k) {  // symmetric swap of rows and columns k < p, in the lower triangle
        std::swap(perm_[k], perm_[p]);
        for (int j = 0; j < k; ++j) std::swap(a_[k][j], a_[p][j]);
        std::swap(a_[k][k], a_[p][p]);
        for (int i = k + 1; i < p; ++i) std::swap(a_[i][k], a_[p][i]);
        for (int i = p + 1; i < 8; ++i) std::swap(a_[i][k], a_[i][p]);
      }
      d_[k] = a_[k][k];
      if (!(d_[k] > 0)) return false;
      const double inv = 1 / d_[k];
      for (int i = k + 1; i < 8; ++i) {
        const double l = a_[i][k] * inv;
        for (int j = k + 1; j <= i; ++j) a_[i][j] -= l * a_[j][k];
      }
      for (int i = k + 1; i < 8; ++i) a_[i][k] *= inv;
    }
    return true;
  }
  /// D's last entry: r_88^2 of a column-pivoting QR of A where S = A^T A.
  double last_pivot() const { return d_[7]; }
  /// x = S^-1 b.
  void solve(const double (&b)[8], double (&x)[8]) const {
    double y[8];
    for (int i = 0; i < 8; ++i) {  // L y = P b
      y[i] = b[perm_[i]];
      for (int j = 0; j < i; ++j) y[i] -= a_[i][j] * y[j];
    }
    for (int i = 0; i < 8; ++i) y[i] /= d_[i];
    for (int i = 7; i >= 0; --i)  // L^T z = y
      for (int j = i + 1; j < 8; ++j) y[i] -= a_[j][i] * y[j];
    for (int i = 0; i < 8; ++i) x[perm_[i]] = y[i];
  }

 private:
  double a_[8][8];
  double d_[8];
  int perm_[8];
};

/// fit_quadric on an A of type `Matrix` (rows x 8; fixed capacity for small rings, so that the
/// common case allocates nothing).
template <class Matrix, class Vector>
QuadricFit fit_quadric_with(const Point3& p0, const Point3* nb, int rows, const Point3& tn) {
  QuadricFit out;
  // Unknowns (a, b, c, d, e, g, gx, gy, gz); the gradient coefficient of the largest
  // component of the tentative normal is fixed to 1 and moves to the right-hand side.
  int fixed = 0;
  for (int k = 1; k < 3; ++k)
    if (std::abs(tn[k]) > std::abs(tn[fixed])) fixed = k;
  // Coordinates scaled by the RMS neighbour distance rho (conditioning); curvatures of the
  // scaled fit are rescaled at the end (K / rho^2, H / rho).
  double rho = 0;
  for (int r = 0; r < rows; ++r)
    for (int k = 0; k < 3; ++k) rho += (nb[r][k] - p0[k]) * (nb[r][k] - p0[k]);
  rho = std::sqrt(rho / rows);
  if (!(rho > 0)) return out;
  Matrix A(rows, 8);
  Vector rhs(rows);
  const double inv_rho = 1 / rho;
  for (int r = 0; r < rows; ++r) {
    const double x = (nb[r][0] - p0[0]) * inv_rho, y = (nb[r][1] - p0[1]) * inv_rho,
                 z = (nb[r][2] - p0[2]) * inv_rho;
    const double full[9] = {x * x, y * y, z * z, x * y, y * z, z * x, x, y, z};
    for (int k = 0, c = 0; k < 9; ++k)
      if (k != 6 + fixed) A(r, c++) = full[k];
    rhs(r) = -full[6 + fixed];
  }
  // Least squares: the normal equations A^T A d = A^T c of docs/math.md 13. The fit is refused
  // where A is rank-deficient (e.g. all neighbours on a few lines): smallest / largest singular
  // value <= 1e-9. A column-pivoting QR, A P = Q R, decides it: its diagonal bounds A's singular
  // values (docs/math.md 13): s_min >= 3 |r_88| / sqrt(4^8 + 47) >= 0.0117 |r_88| (Faddeev,
  // Kublanovskaya and Faddeeva) and s_max <= ||R||_F <= 6 |r_11| (every |r_ij| <= |r_ii| <=
  // |r_11|), so |r_88| > 1e-6 |r_11| already means s_min / s_max > 1.9e-9. Only below that are
  // the singular values computed (a Jacobi SVD of the 8 x 8 R).
  //
  // Most rings are well conditioned, and there the QR's cost is not needed: the normal
  // equations are solved directly, with the columns scaled to unit norm (A S, S diagonal), by a
  // diagonally pivoted LDL^T of S A^T A S. Its D is the squared diagonal of a column-pivoting QR
  // of A S in exact arithmetic (the same pivots: the largest remaining column norm), so
  // s_min(A S) >= 0.0117 sqrt(D_8), and s_min(A) >= s_min(A S) min_j |a_j|, s_max(A) <= ||A||_F.
  // The direct solution is taken where that bound on s_min / s_max of A exceeds 1e-9 (the QR
  // would accept the fit too) and where D_8 > 1e-10 (cond(A S) about 1e5 or less, so
  // cond^2 x 1e-16 < 1e-5). The normal equations lose accuracy as cond^2; one step of
  // iterative refinement (the residual c - A d recomputed from A, the correction solved with
  // the same factors) multiplies the error by about cond^2 x 1e-16 again. Anything else goes to
  // the QR. On exact quadric data both paths give the curvature to 1e-13 relative or better
  // (QuadricFit.DirectSolveIsExactOnQuadricPointsDownToFineRings).
  Eigen::Matrix<double, 8, 1> d;
  bool solved = false;
  double G[8][8], Ac[8], norm2[8];  // (A S)^T (A S) (lower triangle), (A S)^T c, |a_j|^2
  for (int i = 0; i < 8; ++i) norm2[i] = A.col(i).squaredNorm();
  const double smallest = *std::min_element(norm2, norm2 + 8);
  double frobenius2 = 0;
  for (double x : norm2) frobenius2 += x;
  if (smallest > 0) {
    double scale[8];
    for (int i = 0; i < 8; ++i) scale[i] = 1 / std::sqrt(norm2[i]);
    for (int i = 0; i < 8; ++i) {
      Ac[i] = scale[i] * A.col(i).dot(rhs);
      G[i][i] = 1;
      for (int j = 0; j < i; ++j) G[i][j] = scale[i] * scale[j] * A.col(i).dot(A.col(j));  // lower triangle
    }
    PivotedLdlt8 ldlt;
    if (ldlt.factor(G) && ldlt.last_pivot() > 1e-10 &&
        0.0117 * std::sqrt(ldlt.last_pivot() * smallest / frobenius2) > 1e-9) {
      double y[8], dy[8], Ar[8];
      ldlt.solve(Ac, y);
      for (int k = 0; k < 8; ++k) d(k) = scale[k] * y[k];
      const Vector residual = rhs - A * d;
      for (int i = 0; i < 8; ++i) Ar[i] = scale[i] * A.col(i).dot(residual);
      ldlt.solve(Ar, dy);
      for (int k = 0; k < 8; ++k) d(k) += scale[k] * dy[k];
      out.direct = true;
      solved = true;
    }
  }
  if (!solved) {
    const Eigen::ColPivHouseholderQR<Matrix> qr(A);
    const Eigen::Matrix<double, 8, 8> R =
        qr.matrixR().template topRows<8>().template triangularView<Eigen::Upper>();
    if (!(std::abs(R(7, 7)) > 1e-6 * std::abs(R(0, 0)))) {
      const Eigen::JacobiSVD<Eigen::Matrix<double, 8, 8>> svd(R);  // singular values only
      const auto& sv = svd.singularValues();
      if (!(sv(7) > 1e-9 * sv(0))) return out;
    }
    Vector qtc = rhs;
    qtc.applyOnTheLeft(qr.householderQ().adjoint());
    const Eigen::Matrix<double, 8, 1> y = R.triangularView<Eigen::Upper>().solve(qtc.template head<8>());
    d = qr.colsPermutation() * y;
  }
  double coef[9];
  for (int k = 0, c = 0; k < 9; ++k) coef[k] = k == 6 + fixed ? 1.0 : d(c++);
  Eigen::Vector3d grad(coef[6], coef[7], coef[8]);
  Eigen::Matrix3d M;
  M << 2 * coef[0], coef[3], coef[5], coef[3], 2 * coef[1], coef[4], coef[5], coef[4], 2 * coef[2];
  if (grad.dot(to_eigen(tn)) < 0) {  // orient f so that grad f is on tn's side
    grad = -grad;
    M = -M;
  }
  const double D = grad.norm();
  if (!(D > 0)) return out;
  const Eigen::Vector3d n = grad / D;
  // adj(M) for a symmetric 3x3 matrix: the cofactor matrix.
  Eigen::Matrix3d adj;
  adj(0, 0) = M(1, 1) * M(2, 2) - M(1, 2) * M(2, 1);
  adj(0, 1) = M(0, 2) * M(2, 1) - M(0, 1) * M(2, 2);
  adj(0, 2) = M(0, 1) * M(1, 2) - M(0, 2) * M(1, 1);
  adj(1, 0) = M(1, 2) * M(2, 0) - M(1, 0) * M(2, 2);
  adj(1, 1) = M(0, 0) * M(2, 2) - M(0, 2) * M(2, 0);
  adj(1, 2) = M(0, 2) * M(1, 0) - M(0, 0) * M(1, 2);
  adj(2, 0) = M(1, 0) * M(2, 1) - M(1, 1) * M(2, 0);
  adj(2, 1) = M(0, 1) * M(2, 0) - M(0, 0) * M(2, 1);
  adj(2, 2) = M(0, 0) * M(1, 1) - M(0, 1) * M(1, 0);
  out.K = n.dot(adj * n) / (D * D) / (rho * rho);
  out.H = n.dot((M - M.trace() * Eigen::Matrix3d::Identity()) * n) / (2 * D) / rho;
  out.normal = to_point(n);
  out.ok = true;
  return out;
}

}  // namespace

QuadricFit fit_quadric(const Point3& p0, const std::vector<Point3>& nb, const Point3& tn) {
  if (nb.size() < 8) return {};
  constexpr int kSmall = 48;  // a regular 2-ring has 24 points
  const int rows = static_cast<int>(nb.size());
  if (rows <= kSmall)
    return fit_quadric_with<Eigen::Matrix<double, Eigen::Dynamic, 8, 0, kSmall, 8>,
                            Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kSmall, 1>>(p0, nb.data(), rows, tn);
  return fit_quadric_with<Eigen::Matrix<double, Eigen::Dynamic, 8>, Eigen::VectorXd>(p0, nb.data(), rows, tn);
}

namespace {

/// The exact mean curvature at vertex v and the quadric fits' errors there (one vertex of
/// compare_vertex_curvature; `measured` is false where the vertex is not compared).
struct VertexFitError {
  bool measured = false;
  double exact_H = 0, cage_error = 0, limit_error = 0;
};

/// The limit at a face corner of vertex v: its first corner's face, when that is a quad with a
/// limit surface.
bool corner_limit(const LimitEvaluator& limit, int v, bool full, LimitSample& out) {
  const SubdivLevel& L = limit.base();
  const PolyMesh& m = L.mesh;
  const int h = m.vertex_corners(v)[0];
  const int f = m.corner_face(h);
  if (m.face_size(f) != 4 || L.face_hole[f]) return false;
  const int k = h - m.face_begin(f);
  const double u = (k == 1 || k == 2) ? 1.0 : 0.0, w = (k == 2 || k == 3) ? 1.0 : 0.0;
  if (full) {
    out = limit.evaluate(f, 0, u, w);
  } else {
    out.p = limit.evaluate_point(f, 0, u, w).p;
  }
  return true;
}

/// `limit_point[x]`: the limit point of every vertex x (corner_limit), NaN where there is none.
VertexFitError vertex_fit_error(const LimitEvaluator& limit, const std::vector<Point3>& limit_point, int v) {
  VertexFitError r;
  const SubdivLevel& L = limit.base();
  const PolyMesh& m = L.mesh;
  const std::vector<Point3>& P = limit.positions();
  if (m.is_unused_vertex(v) || m.is_boundary_vertex(v) || L.vertex_sharpness[v] != 0.0f) return r;
  const int n = m.vertex_face_count(v);
  const int* c = m.vertex_corners(v);
  for (int i = 0; i < n; ++i) {
    const int f = m.corner_face(c[i]);
    if (m.face_size(f) != 4 || L.face_hole[f] || L.edge_sharpness[m.corner_edge(c[i])] != 0.0f) return r;
  }
  // 2-ring: every vertex of every face touching a vertex of v's faces, v itself left out. Each
  // such face is taken once (`face_seen`), each vertex once (`seen`): the arrays hold the stamp
  // of the call that last took the element (one pair per thread, never cleared: every call has
  // a new stamp).
  thread_local std::vector<int> ring2;
  thread_local std::vector<std::uint64_t> seen, face_seen;
  thread_local std::uint64_t stamp = 0;
  ++stamp;
  ring2.clear();
  if (seen.size() < static_cast<size_t>(m.num_vertices())) seen.resize(static_cast<size_t>(m.num_vertices()), 0);
  if (face_seen.size() < static_cast<size_t>(m.num_faces())) face_seen.resize(static_cast<size_t>(m.num_faces()), 0);
  seen[v] = stamp;
  for (int i = 0; i < n; ++i) {
    const int f = m.corner_face(c[i]);
    for (int a = m.face_begin(f); a < m.face_begin(f) + 4; ++a) {
      const int w = m.corner_vertex(a);
      const int* wc = m.vertex_corners(w);
      for (int j = 0; j < m.vertex_face_count(w); ++j) {
        const int g = m.corner_face(wc[j]);
        if (face_seen[g] == stamp) continue;
        face_seen[g] = stamp;
        for (int b = m.face_begin(g); b < m.face_begin(g) + m.face_size(g); ++b) {
          const int x = m.corner_vertex(b);
          if (seen[x] != stamp) {
            seen[x] = stamp;
            ring2.push_back(x);
          }
        }
      }
    }
  }
  // Exact: the limit at v.
  LimitSample exact;
  corner_limit(limit, v, true, exact);
  if (!exact.exact_derivatives || !std::isfinite(exact.mean)) return r;  // an EV: no curvature
  thread_local std::vector<Point3> cage_pts, limit_pts;
  cage_pts.clear();
  limit_pts.clear();
  for (int x : ring2) {
    cage_pts.push_back(P[x]);
    if (!std::isnan(limit_point[x][0])) limit_pts.push_back(limit_point[x]);
  }
  const QuadricFit fc = fit_quadric(P[v], cage_pts, exact.normal);
  const QuadricFit fl = fit_quadric(exact.p, limit_pts, exact.normal);
  if (!fc.ok || !fl.ok) return r;
  r.measured = true;
  r.exact_H = exact.mean;
  r.cage_error = std::abs(fc.H - exact.mean);
  r.limit_error = std::abs(fl.H - exact.mean);
  return r;
}

}  // namespace

VertexCurvatureComparison compare_vertex_curvature(const LimitEvaluator& limit) {
  // Vertices are fitted in parallel, then summed in vertex order (the result does not depend
  // on the threads).
  const int num_vertices = limit.base().mesh.num_vertices();
  const PolyMesh& m = limit.base().mesh;
  std::vector<Point3> limit_point(static_cast<size_t>(num_vertices));
  parallel_for(num_vertices, [&](int x) {
    LimitSample s;
    limit_point[x] = !m.is_unused_vertex(x) && corner_limit(limit, x, false, s)
                         ? s.p
                         : Point3{std::nan(""), std::nan(""), std::nan("")};
  });
  std::vector<VertexFitError> fits(static_cast<size_t>(num_vertices));
  parallel_for(num_vertices, [&](int v) { fits[static_cast<size_t>(v)] = vertex_fit_error(limit, limit_point, v); });
  VertexCurvatureComparison r;
  double sum_cage = 0, sum_limit = 0;
  for (const VertexFitError& e : fits) {
    if (!e.measured) continue;
    ++r.vertices;
    r.max_abs_H_error_cage = std::max(r.max_abs_H_error_cage, e.cage_error);
    r.max_abs_H_error_limit = std::max(r.max_abs_H_error_limit, e.limit_error);
    r.max_abs_H = std::max(r.max_abs_H, std::abs(e.exact_H));
    sum_cage += e.cage_error;
    sum_limit += e.limit_error;
  }
  if (r.vertices > 0) {
    r.mean_abs_H_error_cage = sum_cage / r.vertices;
    r.mean_abs_H_error_limit = sum_limit / r.vertices;
  }
  return r;
}

}  // namespace subd2nurbs
