// The OpenSubdiv limit-surface evaluator (osd_limit_eval.h) checked against independent facts:
// a regular face is the uniform bicubic B-spline of its 4x4 control net, face corners are the
// limit positions of our limit stencils, and the derivatives are those of the positions.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "common/shapes.h"
#include "core/refine/refiner.h"
#include "io/obj_reader.h"
#include "osd_limit_eval.h"
#include "osd_reference.h"

using namespace subd2nurbs;
using namespace subd2nurbs::testing;

namespace {

/// Uniform cubic B-spline basis and its derivative on one span (MATH.md section 0).
void bspline_basis(double t, double n[4], double d[4]) {
  const double s = 1 - t;
  n[0] = s * s * s / 6;
  n[1] = (3 * t * t * t - 6 * t * t + 4) / 6;
  n[2] = (-3 * t * t * t + 3 * t * t + 3 * t + 1) / 6;
  n[3] = t * t * t / 6;
  d[0] = -s * s / 2;
  d[1] = (9 * t * t - 12 * t) / 6;
  d[2] = (-9 * t * t + 6 * t + 3) / 6;
  d[3] = t * t / 2;
}

/// (nx x ny) quads, vertex (i, j) at index j * (nx + 1) + i; face (i, j) = j * nx + i with
/// vertices (i,j), (i+1,j), (i+1,j+1), (i,j+1): its first edge runs along +i.
MeshInput grid_with(int nx, int ny, const std::function<Point3(int, int)>& pos) {
  MeshInput m;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) m.positions.push_back(pos(i, j));
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int a = j * (nx + 1) + i;
      add_face(m, {a, a + 1, a + nx + 2, a + nx + 1});
    }
  return m;
}

double max_abs_diff(const Point3& a, const Point3& b) {
  return std::max({std::abs(a[0] - b[0]), std::abs(a[1] - b[1]), std::abs(a[2] - b[2])});
}

std::string corpus_path(const std::string& name) {
  return std::string(SUBD2NURBS_CORPUS_DIR) + "/" + name + ".obj";
}

const double kSamples[] = {0.0, 0.125, 0.3, 0.5, 0.71, 0.9, 1.0};

}  // namespace

TEST(OsdLimitEval, RegularFaceIsTheUniformBSplineOfItsNet) {
  // A bumpy 8x8 grid: face (3, 3) has the 4x4 net of vertices 2..5 x 2..5, all interior
  // with interior neighbours, so its limit is the uniform bicubic B-spline of that net.
  const int n = 8;
  auto pos = [](int i, int j) -> Point3 {
    return {i + 0.2 * std::sin(1.7 * i + 0.3 * j), j + 0.15 * std::cos(0.9 * i - 1.1 * j),
            0.4 * std::sin(0.8 * i * j + 0.5)};
  };
  const MeshInput m = grid_with(n, n, pos);
  OsdLimitEvaluator osd(m);
  ASSERT_TRUE(osd.ok());
  ASSERT_EQ(osd.num_ptex_faces(), n * n);
  const int fi = 3, fj = 3;
  double worst = 0;
  for (double u : kSamples)
    for (double v : kSamples) {
      double nu[4], du[4], nv[4], dv[4];
      bspline_basis(u, nu, du);
      bspline_basis(v, nv, dv);
      Point3 p{}, pu{}, pv{};
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b) {
          const Point3 c = pos(fi - 1 + a, fj - 1 + b);
          for (int k = 0; k < 3; ++k) {
            p[k] += nu[a] * nv[b] * c[k];
            pu[k] += du[a] * nv[b] * c[k];
            pv[k] += nu[a] * dv[b] * c[k];
          }
        }
      const OsdLimitEvaluator::Sample s = osd.eval(fj * n + fi, u, v);
      EXPECT_TRUE(s.regular_patch) << u << " " << v;
      worst = std::max({worst, max_abs_diff(s.p, p), max_abs_diff(s.du, pu), max_abs_diff(s.dv, pv)});
    }
  EXPECT_LE(worst, 1e-12);
}

TEST(OsdLimitEval, QuadraticFieldIsReproducedWithItsKnownOffset) {
  // Control points on z = f(x, y) (quadratic) at integer (x, y): the uniform bicubic B-spline
  // reproduces x and y exactly and gives z = f + (f_xx + f_yy) / 6, because
  // sum_i N(t - i) i^2 = t^2 + 1/3 and sum_ij N(s - i) N(t - j) i j = s t.
  const double a = 0.3, b = -0.2, c = 0.45, d = 0.1, e = -0.7, g = 1.5;
  auto f = [&](double x, double y) { return a * x * x + b * x * y + c * y * y + d * x + e * y + g; };
  const int n = 8;
  const MeshInput m = grid_with(n, n, [&](int i, int j) -> Point3 { return {double(i), double(j), f(i, j)}; });
  OsdLimitEvaluator osd(m);
  ASSERT_TRUE(osd.ok());
  double worst = 0;
  for (int fj = 2; fj <= 5; ++fj)
    for (int fi = 2; fi <= 5; ++fi)
      for (double u : kSamples)
        for (double v : kSamples) {
          const OsdLimitEvaluator::Sample s = osd.eval(fj * n + fi, u, v);
          EXPECT_TRUE(s.regular_patch);
          const double x = fi + u, y = fj + v;
          const Point3 p{x, y, f(x, y) + (2 * a + 2 * c) / 6};
          const Point3 pu{1, 0, 2 * a * x + b * y + d}, pv{0, 1, b * x + 2 * c * y + e};
          worst = std::max({worst, max_abs_diff(s.p, p), max_abs_diff(s.du, pu), max_abs_diff(s.dv, pv)});
        }
  EXPECT_LE(worst, 1e-12);
}

namespace {

struct CornerErrors {
  double regular = -1, end_cap = -1;  ///< max |osd - ours| / diagonal, -1 if none
  int num_regular = 0, num_end_cap = 0;
};

/// eval() at every corner of every quad face against our limit stencils of the base vertex.
CornerErrors corner_errors(const MeshInput& m) {
  CornerErrors out;
  OsdLimitEvaluator osd(m);
  EXPECT_TRUE(osd.ok());
  if (!osd.ok()) return out;
  const SubdivLevel base = SubdivLevel::from_input(m);
  std::vector<Point3> pts(m.positions.begin(), m.positions.end()), lim;
  limit_stencils(base).apply(pts, lim);
  const double diag = bbox_diagonal(pts);
  EXPECT_EQ(osd.num_ptex_faces(), m.num_faces());
  const double cu[4] = {0, 1, 1, 0}, cv[4] = {0, 0, 1, 1};
  int offset = 0;
  for (int f = 0; f < m.num_faces(); offset += m.face_sizes[f], ++f) {
    EXPECT_EQ(m.face_sizes[f], 4) << "not an all-quad mesh";
    if (std::find(m.holes.begin(), m.holes.end(), f) != m.holes.end()) continue;
    for (int k = 0; k < 4; ++k) {
      const OsdLimitEvaluator::Sample s = osd.eval(f, cu[k], cv[k]);
      const double err = max_abs_diff(s.p, lim[m.face_indices[offset + k]]) / diag;
      double& slot = s.regular_patch ? out.regular : out.end_cap;
      slot = std::max(slot, err);
      ++(s.regular_patch ? out.num_regular : out.num_end_cap);
    }
  }
  return out;
}

}  // namespace

TEST(OsdLimitEval, FaceCornersAreOurLimitPositions) {
  // catmark_cube has only valence-3 vertices: every corner lies on a Gregory end cap, whose
  // corner point OpenSubdiv computes with the exact limit mask.
  {
    LoadedCage cube = read_obj(corpus_path("catmark_cube"));
    CornerErrors e = corner_errors(cube.input);
    EXPECT_EQ(e.num_regular, 0);
    EXPECT_EQ(e.num_end_cap, 24);
    EXPECT_LE(e.end_cap, 1e-12);
  }
  // Shapes with regular vertices (interior, boundary, corners, semi-sharp and infinitely sharp
  // creases, Chaikin) next to extraordinary ones. REGULAR patches must be exact. OpenSubdiv's
  // Gregory end caps put their corner at the exact limit position too, except at darts
  // (catmark_cubes_infsharp has some), where it uses the smooth mask.
  struct Shape {
    const char* name;
    bool end_caps_exact;
  };
  for (const Shape& shape : {Shape{"catmark_torus", true}, Shape{"catmark_xord_interior", true},
                             Shape{"catmark_xord_boundary", true}, Shape{"catmark_edgecorner", true},
                             Shape{"catmark_edgeonly", true}, Shape{"catmark_torus_creases0", true},
                             Shape{"catmark_single_crease", true}, Shape{"catmark_chaikin0", true},
                             Shape{"catmark_tent_creases0", true}, Shape{"catmark_cubes_infsharp", false}}) {
    SCOPED_TRACE(shape.name);
    LoadedCage cage = read_obj(corpus_path(shape.name));
    CornerErrors e = corner_errors(cage.input);
    EXPECT_GT(e.num_regular, 0);
    EXPECT_LE(e.regular, 1e-12);
    if (shape.end_caps_exact) EXPECT_LE(e.end_cap, 1e-12);  // -1 if there is none
  }
}

TEST(OsdLimitEval, DerivativesAreThoseOfThePositions) {
  const double h = 1e-5;
  for (const char* name : {"catmark_cube", "catmark_torus", "catmark_xord_interior", "catmark_edgecorner"}) {
    SCOPED_TRACE(name);
    LoadedCage cage = read_obj(corpus_path(name));
    OsdLimitEvaluator osd(cage.input);
    ASSERT_TRUE(osd.ok());
    std::vector<Point3> pts(cage.input.positions.begin(), cage.input.positions.end());
    const double diag = bbox_diagonal(pts);
    double worst = 0;
    for (int f = 0; f < osd.num_ptex_faces(); ++f)
      for (double u : {0.2, 0.5, 0.77})
        for (double v : {0.35, 0.6}) {
          const OsdLimitEvaluator::Sample s = osd.eval(f, u, v);
          const Point3 up = osd.eval(f, u + h, v).p, um = osd.eval(f, u - h, v).p;
          const Point3 vp = osd.eval(f, u, v + h).p, vm = osd.eval(f, u, v - h).p;
          for (int k = 0; k < 3; ++k) {
            worst = std::max(worst, std::abs(s.du[k] - (up[k] - um[k]) / (2 * h)) / diag);
            worst = std::max(worst, std::abs(s.dv[k] - (vp[k] - vm[k]) / (2 * h)) / diag);
          }
        }
    EXPECT_LE(worst, 1e-8);  // O(h^2) truncation + O(eps / h) rounding, about 1e-11 here
  }
}

TEST(OsdLimitEval, PtexFacesOfNGonsAndRejectedQueries) {
  const MeshInput m = star(5);  // 5 quads and one 10-gon
  OsdLimitEvaluator osd(m);
  ASSERT_TRUE(osd.ok());
  EXPECT_EQ(osd.num_ptex_faces(), 5 + 10);
  EXPECT_NO_THROW(osd.eval(14, 0.5, 0.5));
  EXPECT_THROW(osd.eval(15, 0.5, 0.5), std::out_of_range);
  EXPECT_THROW(osd.eval(-1, 0.5, 0.5), std::out_of_range);
  MeshInput holed = grid(3, 3);
  holed.holes = {4};
  OsdLimitEvaluator h(holed);
  ASSERT_TRUE(h.ok());
  EXPECT_THROW(h.eval(4, 0.5, 0.5), std::out_of_range);
  EXPECT_NO_THROW(h.eval(3, 0.5, 0.5));
}
