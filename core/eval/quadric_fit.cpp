#include "core/eval/quadric_fit.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/patch/local_mesh.h"
#include "core/util/eigen_point.h"
#include "core/util/parallel.h"

namespace subd2nurbs {

QuadricFit fit_quadric(const Point3& p0, const std::vector<Point3>& nb, const Point3& tn) {
  QuadricFit out;
  if (nb.size() < 8) return out;
  // Unknowns (a, b, c, d, e, g, gx, gy, gz); the gradient coefficient of the largest
  // component of the tentative normal is fixed to 1 and moves to the right-hand side.
  int fixed = 0;
  for (int k = 1; k < 3; ++k)
    if (std::abs(tn[k]) > std::abs(tn[fixed])) fixed = k;
  const int rows = static_cast<int>(nb.size());
  // Coordinates scaled by the RMS neighbour distance rho (conditioning); curvatures of the
  // scaled fit are rescaled at the end (K / rho^2, H / rho).
  double rho = 0;
  for (const Point3& q : nb)
    for (int k = 0; k < 3; ++k) rho += (q[k] - p0[k]) * (q[k] - p0[k]);
  rho = std::sqrt(rho / rows);
  if (!(rho > 0)) return out;
  Eigen::Matrix<double, Eigen::Dynamic, 8> A(rows, 8);
  Eigen::VectorXd rhs(rows);
  for (int r = 0; r < rows; ++r) {
    const double x = (nb[r][0] - p0[0]) / rho, y = (nb[r][1] - p0[1]) / rho, z = (nb[r][2] - p0[2]) / rho;
    const double full[9] = {x * x, y * y, z * z, x * y, y * z, z * x, x, y, z};
    int c = 0;
    for (int k = 0; k < 9; ++k)
      if (k != 6 + fixed) A(r, c++) = full[k];
    rhs(r) = -full[6 + fixed];
  }
  // Least squares (the normal equations A^T A d = A^T c of docs/math.md 13), solved by a
  // column-pivoting QR, A P = Q R. The fit is refused where A is rank-deficient (e.g. all
  // neighbours on a few lines): smallest / largest singular value <= 1e-9. R has A's singular
  // values, and with column pivoting its diagonal bounds them (docs/math.md 13):
  // s_min >= 3 |r_88| / sqrt(4^8 + 47) >= 0.0117 |r_88| (Faddeev, Kublanovskaya and Faddeeva)
  // and s_max <= ||R||_F <= 6 |r_11| (every |r_ij| <= |r_ii| <= |r_11|), so
  // |r_88| > 1e-6 |r_11| already means s_min / s_max > 1.9e-9. Only below that are the singular
  // values computed (a Jacobi SVD of the 8 x 8 R, most of the fit's cost when always done).
  const Eigen::ColPivHouseholderQR<Eigen::Matrix<double, Eigen::Dynamic, 8>> qr(A);
  const Eigen::Matrix<double, 8, 8> R = qr.matrixR().topRows<8>().triangularView<Eigen::Upper>();
  if (!(std::abs(R(7, 7)) > 1e-6 * std::abs(R(0, 0)))) {
    const Eigen::JacobiSVD<Eigen::Matrix<double, 8, 8>> svd(R);  // singular values only
    const auto& sv = svd.singularValues();
    if (!(sv(7) > 1e-9 * sv(0))) return out;
  }
  Eigen::VectorXd qtc = rhs;
  qtc.applyOnTheLeft(qr.householderQ().adjoint());
  const Eigen::Matrix<double, 8, 1> y = R.triangularView<Eigen::Upper>().solve(qtc.head<8>());
  const Eigen::Matrix<double, 8, 1> d = qr.colsPermutation() * y;
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

namespace {

/// The exact mean curvature at vertex v and the quadric fits' errors there (one vertex of
/// compare_vertex_curvature; `measured` is false where the vertex is not compared).
struct VertexFitError {
  bool measured = false;
  double exact_H = 0, cage_error = 0, limit_error = 0;
};

VertexFitError vertex_fit_error(const LimitEvaluator& limit, int v) {
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
  // 2-ring: every vertex of every face touching a vertex of v's faces.
  std::vector<int> ring2 = vertices_of(m, face_rings(m, {v}, 2));
  ring2.erase(std::find(ring2.begin(), ring2.end(), v));
  // Exact: the limit at v (any face corner at v).
  const int h0 = c[0];
  const int f0 = m.corner_face(h0);
  const int k = h0 - m.face_begin(f0);
  const LimitSample exact = limit.evaluate(f0, 0, (k == 1 || k == 2) ? 1.0 : 0.0, (k == 2 || k == 3) ? 1.0 : 0.0);
  if (!exact.exact_derivatives || !std::isfinite(exact.mean)) return r;  // an EV: no curvature
  std::vector<Point3> cage_pts, limit_pts;
  for (int x : ring2) cage_pts.push_back(P[x]);
  // Limit points of the 2-ring vertices: the limit at a face corner of each.
  for (int x : ring2) {
    const int hx = m.vertex_corners(x)[0];
    const int fx = m.corner_face(hx);
    if (m.face_size(fx) != 4 || L.face_hole[fx]) continue;
    const int kx = hx - m.face_begin(fx);
    limit_pts.push_back(limit.evaluate_point(fx, 0, (kx == 1 || kx == 2) ? 1.0 : 0.0, (kx == 2 || kx == 3) ? 1.0 : 0.0).p);
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
  std::vector<VertexFitError> fits(static_cast<size_t>(num_vertices));
  parallel_for(num_vertices, [&](int v) { fits[static_cast<size_t>(v)] = vertex_fit_error(limit, v); });
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
