// Derivatives and curvatures of the limit evaluation against finite differences of its own
// positions and normals, on every evaluation path (regular, Stam, refined near creases,
// boundaries, semi-sharp tags and n-gons).
#include <gtest/gtest.h>

#include <random>

#include "limit_test_util.h"

using namespace subd2nurbs;
using namespace subd2nurbs::testing;

namespace {

Point3 sub(const Point3& a, const Point3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Point3 scale(const Point3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
double dot(const Point3& a, const Point3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(const Point3& a) { return std::sqrt(dot(a, a)); }

struct Case {
  const char* shape;
};

}  // namespace

TEST(LimitDerivatives, MatchCentralDifferencesOnEveryPath) {
  const char* shapes[] = {"catmark_cube",       "catmark_pyramid_creases1", "catmark_cubes_semisharp",
                          "catmark_edgecorner", "catmark_nonquads",         "catmark_helmet",
                          "catmark_chaikin1",   "catmark_tent_creases1",    "catmark_dart_edgecorner",
                          "catmark_bishop",     "catmark_pawn",             "catmark_xord_interior"};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> param(0.1, 0.9);
  std::map<LimitMethod, int> seen;
  std::vector<std::string> names(std::begin(shapes), std::end(shapes));
  for (int n : {3, 5, 6, 9, 12}) names.push_back("disc" + std::to_string(n));
  for (const std::string& name : names) {
    SCOPED_TRACE(name);
    MeshInput input;
    if (name.rfind("disc", 0) == 0) {
      input = ev_disc(std::stoi(name.substr(4)), 11);
    } else {
      input = read_obj(limit_corpus_path(name)).input;
    }
    const std::vector<Point3> pos = positions_of(input);
    const LimitEvaluator ev(SubdivLevel::from_input(input), pos);
    const double diag = diagonal(pos);
    int checked = 0;
    for (int ptex = 0; ptex < ev.num_ptex_faces() && checked < 60; ++ptex) {
      const double u = param(rng), v = param(rng);
      LimitMethod method;
      LimitSample s;
      try {
        s = ev.evaluate_ptex(ptex, u, v, &method);
      } catch (const std::domain_error&) {
        continue;  // hole
      }
      ++seen[method];
      ++checked;
      // The light entry point returns the same p, du, dv.
      const int face = ev.ptex_to_face(ptex);
      const LimitPoint lp = ev.evaluate_point(face, ptex - ev.first_ptex(face), u, v);
      EXPECT_LT(norm(sub(lp.p, s.p)) + norm(sub(lp.du, s.du)) + norm(sub(lp.dv, s.dv)), 1e-13 * diag);
      const double h = 1e-5;
      auto at = [&](double du, double dv) { return ev.evaluate_ptex(ptex, u + du, v + dv); };
      const LimitSample up = at(h, 0), um = at(-h, 0), vp = at(0, h), vm = at(0, -h);
      const Point3 fu = scale(sub(up.p, um.p), 0.5 / h), fv = scale(sub(vp.p, vm.p), 0.5 / h);
      EXPECT_LT(norm(sub(fu, s.du)), 1e-7 * diag) << "ptex " << ptex;
      EXPECT_LT(norm(sub(fv, s.dv)), 1e-7 * diag) << "ptex " << ptex;
      const Point3 fuu = scale(sub(up.du, um.du), 0.5 / h), fuv = scale(sub(vp.du, vm.du), 0.5 / h);
      const Point3 fvv = scale(sub(vp.dv, vm.dv), 0.5 / h);
      EXPECT_LT(norm(sub(fuu, s.duu)), 1e-5 * diag) << "ptex " << ptex;
      EXPECT_LT(norm(sub(fuv, s.duv)), 1e-5 * diag) << "ptex " << ptex;
      EXPECT_LT(norm(sub(fvv, s.dvv)), 1e-5 * diag) << "ptex " << ptex;
      // Weingarten: II = -(dN . dX); principal curvatures from finite differences of normals.
      const Point3 nu = scale(sub(up.normal, um.normal), 0.5 / h);
      const Point3 nv = scale(sub(vp.normal, vm.normal), 0.5 / h);
      const double E = dot(s.du, s.du), F = dot(s.du, s.dv), G = dot(s.dv, s.dv);
      const double L = -dot(nu, s.du), M = -0.5 * (dot(nu, s.dv) + dot(nv, s.du)), N = -dot(nv, s.dv);
      const double K = (L * N - M * M) / (E * G - F * F);
      const double H = (E * N - 2 * F * M + G * L) / (2 * (E * G - F * F));
      const double tol = 1e-5 * (std::abs(s.k1) + std::abs(s.k2) + 1 / diag);
      EXPECT_NEAR(H, s.mean, tol) << "ptex " << ptex;
      EXPECT_NEAR(K, s.gauss, tol * (std::abs(s.k1) + std::abs(s.k2) + 1 / diag)) << "ptex " << ptex;
      EXPECT_NEAR(s.k1 + s.k2, 2 * s.mean, 1e-12 * (std::abs(s.k1) + std::abs(s.k2) + 1));
    }
  }
  EXPECT_GT(seen[LimitMethod::Regular], 20);
  EXPECT_GT(seen[LimitMethod::Stam], 30);
  EXPECT_GT(seen[LimitMethod::Refined], 20);
}

// evaluate_grid against evaluate() at each of its points, on every kind of face: regular,
// semi-sharp lines (closed form), Stam, refined, n-gon sub-faces, boundaries.
TEST(LimitDerivatives, GridEvaluationIsPointEvaluation) {
  const double us[] = {0.0, 0.125, 0.5, 0.9, 1.0}, vs[] = {0.0, 0.3, 0.75, 1.0};
  for (const char* shape : {"catmark_torus", "catmark_pawn", "catmark_helmet", "catmark_gregory_test6",
                            "catmark_nonquads", "catmark_single_crease"}) {
    SCOPED_TRACE(shape);
    const ShapeLimit loaded = shape_limit(shape);
    const LimitEvaluator& limit = loaded.limit;
    const double diag = loaded.diag;
    const PolyMesh& m = limit.base().mesh;
    for (int f = 0; f < m.num_faces(); ++f) {
      if (limit.base().face_hole[f]) continue;
      for (int k = 0; k < (m.face_size(f) == 4 ? 1 : m.face_size(f)); ++k) {
        LimitSample grid[5 * 4];
        limit.evaluate_grid(f, k, us, 5, vs, 4, grid);
        for (int a = 0; a < 5; ++a)
          for (int b = 0; b < 4; ++b) {
            const LimitSample& g = grid[a * 4 + b];
            const LimitSample s = limit.evaluate(f, k, us[a], vs[b]);
            ASSERT_LT(norm(sub(g.p, s.p)), 1e-13 * diag) << "face " << f << " sub-face " << k;
            ASSERT_LT(norm(sub(g.du, s.du)) + norm(sub(g.dv, s.dv)), 1e-12 * diag) << "face " << f;
            ASSERT_LT(norm(sub(g.duu, s.duu)) + norm(sub(g.duv, s.duv)) + norm(sub(g.dvv, s.dvv)),
                      1e-11 * diag) << "face " << f;
            ASSERT_EQ(g.exact_derivatives, s.exact_derivatives);
            if (std::isfinite(s.mean)) {
              ASSERT_NEAR(g.mean, s.mean, 1e-9 * (1 + std::abs(s.mean)));
            }
          }
      }
    }
  }
}

// is_polynomial's claim, checked by interpolation: on every face it accepts, the bicubic
// Lagrange interpolant of the limit at the 16 nodes {0, 1/3, 2/3, 1}^2 is the limit at random
// points. On a face with an extraordinary corner it is not (the check can fail), and such faces
// are refused.
TEST(LimitEvaluator, PolynomialFacesAreOneBicubic) {
  const double nodes[4] = {0.0, 1.0 / 3, 2.0 / 3, 1.0};
  const auto lagrange = [&](double x, double l[4]) {
    for (int i = 0; i < 4; ++i) {
      l[i] = 1;
      for (int j = 0; j < 4; ++j)
        if (j != i) l[i] *= (x - nodes[j]) / (nodes[i] - nodes[j]);
    }
  };
  const auto interpolant = [&](const LimitEvaluator& limit, int f, double u, double v) {
    double lu[4], lv[4];
    lagrange(u, lu);
    lagrange(v, lv);
    Point3 x{};
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        const Point3 p = limit.evaluate(f, 0, nodes[a], nodes[b]).p;
        for (int k = 0; k < 3; ++k) x[k] += lu[a] * lv[b] * p[k];
      }
    return x;
  };
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double worst_refused = 0;
  for (const char* shape : {"catmark_torus", "catmark_pawn", "catmark_helmet", "catmark_single_crease",
                            "catmark_cube_creases0", "catmark_nonquads"}) {
    SCOPED_TRACE(shape);
    const ShapeLimit cage = shape_limit(shape);
    const PolyMesh& m = cage.limit.base().mesh;
    int accepted = 0;
    for (int f = 0; f < m.num_faces(); ++f) {
      for (int k = 1; k < m.face_size(f); ++k) EXPECT_FALSE(cage.limit.is_polynomial(f, k));
      if (!cage.limit.is_polynomial(f, 0)) {
        if (m.face_size(f) == 4 && !cage.limit.base().face_hole[f]) {
          const double u = unit(rng) * 0.3, v = unit(rng) * 0.3;  // near corner 0
          const double off = dist(interpolant(cage.limit, f, u, v), cage.limit.evaluate(f, 0, u, v).p);
          worst_refused = std::max(worst_refused, off / cage.diag);
        }
        continue;
      }
      ++accepted;
      for (int r = 0; r < 3; ++r) {
        const double u = unit(rng), v = unit(rng);
        ASSERT_LT(dist(interpolant(cage.limit, f, u, v), cage.limit.evaluate(f, 0, u, v).p), 1e-12 * cage.diag)
            << "face " << f;
      }
    }
    if (std::string(shape) == "catmark_torus") {
      EXPECT_EQ(accepted, m.num_faces());
    }
    if (std::string(shape) == "catmark_pawn") {
      EXPECT_GT(accepted, m.num_faces() / 2);
    }
  }
  EXPECT_GT(worst_refused, 1e-6) << "no refused face differs from its interpolant: the check cannot fail";
}

TEST(LimitCurvature, SphereLikeSignConvention) {
  // The limit of a cube is convex: with outward normals both principal curvatures are
  // negative everywhere (MATH.md 8.3: a sphere with outward normal has k = -1/R).
  const LoadedCage cage = read_obj(limit_corpus_path("catmark_cube"));
  const LimitEvaluator ev(SubdivLevel::from_input(cage.input), positions_of(cage.input));
  for (int f = 0; f < 6; ++f)
    for (double u : {0.1, 0.5, 0.8})
      for (double v : {0.2, 0.5, 0.9}) {
        const LimitSample s = ev.evaluate(f, 0, u, v);
        EXPECT_LT(s.k1, 0);
        EXPECT_LE(s.k2, s.k1);
        EXPECT_GT(dot(s.normal, s.p), 0);  // outward: the cube is centred at the origin
      }
}

TEST(LimitCurvature, TubeMatchesTheClosedFormOfItsBSplineCircle) {
  // A tube of 16 x 6 quads around z (open ends): exact curvatures at a vertex row.
  MeshInput m;
  const int segs = 16, rows = 6;
  const double pi = std::acos(-1.0), R = 2.0;
  for (int j = 0; j <= rows; ++j)
    for (int i = 0; i < segs; ++i)
      m.positions.push_back({R * std::cos(2 * pi * i / segs), R * std::sin(2 * pi * i / segs), 0.5 * j});
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < segs; ++i) {
      const int a = j * segs + i, b = j * segs + (i + 1) % segs;
      m.face_sizes.push_back(4);
      for (int q : {a, b, b + segs, a + segs}) m.face_indices.push_back(q);
    }
  const LimitEvaluator ev(SubdivLevel::from_input(m), positions_of(m));
  // Around z the limit is the uniform cubic B-spline of a regular 16-gon; at a vertex its
  // position and curvature follow from x' = (P1 - P-1)/2 and x'' = P-1 - 2 P0 + P1:
  // radius R (2 + cos t) / 3 and curvature 2 (1 - cos t) / (R sin^2 t), t = 2 pi / segs.
  // Along z the limit is a straight line (curvature 0).
  const double th = 2 * pi / segs;
  const double r_lim = R * (2 + std::cos(th)) / 3;
  const double kappa = 2 * (1 - std::cos(th)) / (R * std::sin(th) * std::sin(th));
  const LimitSample s = ev.evaluate(3 * segs, 0, 0.0, 0.5);
  EXPECT_NEAR(std::hypot(s.p[0], s.p[1]), r_lim, 1e-12);
  EXPECT_NEAR(s.k2, -kappa, 1e-10);
  EXPECT_NEAR(s.k1, 0, 1e-9);
}
