// Extraordinary vertices of valence 3..12: our limit evaluation against uniform refinement.
//  - Exact: at the parameters of a level-L vertex the limit surface is that vertex's limit
//    position (limit masks, MATH.md 1.4, checked against OpenSubdiv in tests/oracle).
//  - Rate: the level-L control points converge to our limit values, 4x per level at a regular
//    vertex and nu_n+ per level at the extraordinary vertex itself (MATH.md 7.2, l = 0 block).
#include <gtest/gtest.h>

#include <cstdio>

#include "limit_test_util.h"

using namespace subd2nurbs;
using namespace subd2nurbs::testing;

namespace {

/// Level-L vertex at dyadic parameters (u, v) = (i, j) / 2^L of base quad f.
int vertex_at(const Refinement& r, int f, int L, int i, int j) {
  double s = std::ldexp(i, -L), t = std::ldexp(j, -L);
  for (int l = 0; l < L; ++l) {
    const PolyMesh& m = r.levels[l].mesh;
    const int k = s < 0.5 ? (t < 0.5 ? 0 : 3) : (t < 0.5 ? 1 : 2);
    double a, b;  // corner frame of corner k, as in the evaluator
    switch (k) {
      case 0: a = s; b = t; break;
      case 1: a = t; b = 1 - s; break;
      case 2: a = 1 - s; b = 1 - t; break;
      default: a = 1 - t; b = s; break;
    }
    f = m.face_begin(f) + k;  // child face index = parent corner
    s = 2 * a;
    t = 2 * b;
  }
  const PolyMesh& m = r.levels[L].mesh;
  const int corner = s == 0 ? (t == 0 ? 0 : 3) : (t == 0 ? 1 : 2);
  return m.face_vertices(f)[corner];
}

}  // namespace

TEST(LimitConvergence, ExactAtRefinedVerticesAndTheRightRatesAtValence3To12) {
  const int L = 5;
  for (int n = 3; n <= 12; ++n) {
    SCOPED_TRACE("valence " + std::to_string(n));
    const MeshInput in = ev_disc(n, 100u + n);
    const SubdivLevel base = SubdivLevel::from_input(in);
    const std::vector<Point3> pos = positions_of(in);
    const double diag = diagonal(pos);
    const LimitEvaluator ev(base, pos);
    const Refinement r = refine_uniform(base, L);
    const std::vector<std::vector<Point3>> lp = r.positions(pos);
    LimitMethod method;
    ev.evaluate(0, 0, 0.3, 0.2, &method);
    EXPECT_EQ(method, n == 4 ? LimitMethod::Regular : LimitMethod::Stam);

    // Exact: every level-L vertex of face 0 (EV at its corner (0,0)) and of a face of sector 1.
    std::vector<Point3> limit_L;
    StencilTable lim = limit_stencils(r.levels[L]);
    lim.apply(lp[L], limit_L);
    double worst = 0;
    for (int f : {0, kRings * kRings + 1})
      for (int i = 0; i <= (1 << L); ++i)
        for (int j = 0; j <= (1 << L); ++j) {
          const double u = std::ldexp(i, -L), v = std::ldexp(j, -L);
          const LimitSample s = ev.evaluate(f, 0, u, v);
          worst = std::max(worst, dist(s.p, limit_L[vertex_at(r, f, L, i, j)]) / diag);
        }
    EXPECT_LT(worst, 1e-13);

    // Rates. A point of the EV's face that is a vertex from level 2 on: ratio 1/4.
    const LimitSample q = ev.evaluate(0, 0, 0.25, 0.5);
    std::vector<double> err;
    for (int l = 2; l <= L; ++l)
      err.push_back(dist(lp[l][vertex_at(r, 0, l, 1 << (l - 2), 1 << (l - 1))], q.p));
    EXPECT_NEAR(err.back() / err[err.size() - 2], 0.25, 0.01);
    // The EV itself: ratio nu_n+.
    const LimitSample c = ev.evaluate(0, 0, 0.0, 0.0);
    const double nu = (3.0 * n - 7 + std::sqrt(5.0 * n * n - 30.0 * n + 49.0)) / (8.0 * n);
    std::vector<double> ev_err;
    for (int l = 1; l <= L; ++l) ev_err.push_back(dist(lp[l][0], c.p));
    // Asymptotic: the last ratio (the other l = 0 mode, nu_n- <= 1/6 nu_n+, has died out).
    EXPECT_NEAR(ev_err.back() / ev_err[ev_err.size() - 2], nu, 0.01 * nu);
    std::printf("n=%2d exact %.2e, rate at EV %.4f (nu_n+ %.4f)\n", n, worst,
                ev_err.back() / ev_err[ev_err.size() - 2], nu);
  }
}

// Above valence 16 a kept Stam face keeps its tiles level by level (core/limit/limit_evaluator.cpp,
// StamLevelTable), filled in whatever order the samples ask for levels: the same exact identity
// (the limit at a level-L vertex's parameters is that vertex's limit position), samples taken
// coarse-to-fine on one face and fine-to-coarse on the other, on two evaluators.
TEST(LimitConvergence, ExactAtRefinedVerticesAtHighValenceInAnyOrder) {
  const int L = 4;
  for (int n : {17, 40, kDenseValence + 3}) {  // the last above the dense eigen-structure's valences
    SCOPED_TRACE("valence " + std::to_string(n));
    const MeshInput in = ev_disc(n, 300u + n);
    const SubdivLevel base = SubdivLevel::from_input(in);
    const std::vector<Point3> pos = positions_of(in);
    const double diag = diagonal(pos);
    const Refinement r = refine_uniform(base, L);
    const std::vector<std::vector<Point3>> lp = r.positions(pos);
    std::vector<Point3> limit_L;
    StencilTable lim = limit_stencils(r.levels[L]);
    lim.apply(lp[L], limit_L);
    const int side = 1 << L;
    for (bool fine_first : {false, true}) {
      const LimitEvaluator ev(base, pos);
      LimitMethod method;
      ev.evaluate(0, 0, 0.3, 0.2, &method);
      EXPECT_EQ(method, LimitMethod::Stam);
      double worst = 0;
      for (int f : {0, kRings * kRings + 1})
        for (int k = 0; k <= side * side + 2 * side; ++k) {
          const int idx = fine_first ? k : side * side + 2 * side - k;
          const int i = idx / (side + 1), j = idx % (side + 1);
          const LimitSample s = ev.evaluate(f, 0, std::ldexp(i, -L), std::ldexp(j, -L));
          worst = std::max(worst, dist(s.p, limit_L[vertex_at(r, f, L, i, j)]) / diag);
        }
      EXPECT_LT(worst, 1e-12);
    }
  }
}

// The corners of quads beside an n-gon (a prism's sides; each corner a valence-3 vertex whose
// n-gon makes it irregular at the base level, a Stam corner one level down): the limit at a
// corner is that vertex's limit position (the exact identity above, level 1), and it is taken
// from the Stam corner of the face's kept children, not by the fallback that refines the
// n-gon's neighbourhood some 20 levels per point (a 1000-gon prism's report took 12 minutes).
TEST(LimitConvergence, CornersBesideAnNgonAreTheLimitPositionsWithoutTheFallback) {
  const int n = 12;
  MeshInput in;
  for (int z = 0; z < 2; ++z)
    for (int k = 0; k < n; ++k) {
      const double a = 2 * std::acos(-1.0) * k / n;
      in.positions.push_back({std::cos(a) * (1 + 0.1 * (k % 3)), std::sin(a), z * (1.0 + 0.05 * k)});
    }
  in.face_sizes.push_back(n);  // bottom, facing down
  for (int k = n - 1; k >= 0; --k) in.face_indices.push_back(k);
  in.face_sizes.push_back(n);  // top
  for (int k = 0; k < n; ++k) in.face_indices.push_back(n + k);
  for (int k = 0; k < n; ++k) {
    in.face_sizes.push_back(4);
    for (int q : {k, (k + 1) % n, n + (k + 1) % n, n + k}) in.face_indices.push_back(q);
  }
  const SubdivLevel base = SubdivLevel::from_input(in);
  const std::vector<Point3> pos = positions_of(in);
  const double diag = diagonal(pos);
  const LimitEvaluator ev(base, pos);
  const Refinement r = refine_uniform(base, 1);
  const std::vector<std::vector<Point3>> lp = r.positions(pos);
  std::vector<Point3> limit_1;
  limit_stencils(r.levels[1]).apply(lp[1], limit_1);
  int corners = 0;
  for (int f = 2; f < 2 + n; ++f)
    for (int i : {0, 2})
      for (int j : {0, 2}) {
        LimitMethod method;
        const LimitSample s = ev.evaluate(f, 0, i / 2.0, j / 2.0, &method);
        EXPECT_LT(dist(s.p, limit_1[vertex_at(r, f, 1, i, j)]) / diag, 1e-13) << "face " << f;
        EXPECT_EQ(method, LimitMethod::Refined) << "face " << f << " corner " << i << j;
        // The normal there is the limit of the normals inside the face (G1 at the vertex).
        const double du = i == 0 ? 1e-7 : 1 - 1e-7, dv = j == 0 ? 1e-7 : 1 - 1e-7;
        const LimitSample inside = ev.evaluate(f, 0, du, dv);
        EXPECT_LT(dist(s.normal, inside.normal), 1e-3) << "face " << f;
        ++corners;
      }
  EXPECT_EQ(corners, 4 * n);
}
