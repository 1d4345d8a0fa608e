// Our exact limit evaluation against OpenSubdiv's (Far::PatchTable, isolation 10, double
// precision) wherever OpenSubdiv's patch is REGULAR, i.e. an exact piece of the limit surface
// (Gregory end caps next to extraordinary vertices are approximations and are skipped). The
// comparison covers every manifold corpus shape: boundaries, creases, semi-sharp tags, holes,
// n-gons (which also checks the ptex sub-face convention).
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <stdexcept>

#include "common/corpus.h"
#include "core/mesh/errors.h"
#include "limit_test_util.h"
#include "oracle/osd_limit_eval.h"

using namespace subd2nurbs;
using namespace subd2nurbs::testing;

namespace {

struct Tally {
  long compared = 0;
  std::map<LimitMethod, long> by_method;
  double worst_p = 0, worst_d = 0;  // relative to the diagonal
};

void compare_shape(const std::string& path, Tally& total) {
  const LoadedCage cage = read_obj(path);
  SubdivLevel level;
  try {
    level = SubdivLevel::from_input(cage.input);
  } catch (const InvalidMeshError&) {
    return;  // not a 2-manifold cage (OpenSubdiv's non-manifold tests): nothing to compare
  }
  const OsdLimitEvaluator osd(cage.input, 10);
  if (!osd.ok()) return;
  const std::vector<Point3> pos = positions_of(cage.input);
  const double diag = diagonal(pos);
  const LimitEvaluator ours(level, pos);
  ASSERT_EQ(ours.num_ptex_faces(), osd.num_ptex_faces()) << path;
  const double samples[] = {0.0, 0.07, 0.31, 0.5, 0.77, 0.96, 1.0};
  const auto t0 = std::chrono::steady_clock::now();
  Tally t;
  // At most ~300 ptex faces per shape (evenly spread) keep the test at a few seconds.
  const int stride = std::max(1, ours.num_ptex_faces() / 300);
  for (int ptex = 0; ptex < ours.num_ptex_faces(); ptex += stride)
    for (double u : samples)
      for (double v : samples) {
        OsdLimitEvaluator::Sample ref;
        try {
          ref = osd.eval(ptex, u, v);
        } catch (const std::out_of_range&) {
          continue;  // a hole: no patch
        }
        if (!ref.regular_patch) continue;
        LimitMethod method;
        const LimitSample s = ours.evaluate_ptex(ptex, u, v, &method);
        const double ep = dist(s.p, ref.p) / diag;
        // OpenSubdiv 3.5 returns derivatives twice too large on the sub-faces of n-gons (twice
        // the derivative of its own positions: OsdScalesNgonDerivativesByTwo below), so there
        // ours are compared with half of its values.
        const double k = ours.base().mesh.face_size(ours.ptex_to_face(ptex)) == 4 ? 1.0 : 0.5;
        const Point3 rdu = {k * ref.du[0], k * ref.du[1], k * ref.du[2]};
        const Point3 rdv = {k * ref.dv[0], k * ref.dv[1], k * ref.dv[2]};
        const double ed = std::max(dist(s.du, rdu), dist(s.dv, rdv)) / diag;
        // At the documented fallback points (a corner that refinement never makes regular,
        // e.g. a boundary vertex of irregular valence) the position is exact and the
        // derivatives are taken 2^-20 inside the face: compared to 1e-5 only.
        const double dtol = method == LimitMethod::Fallback ? 1e-5 : 1e-9;
        EXPECT_LT(ep, 1e-9) << path << " ptex " << ptex << " (" << u << ", " << v << ")";
        EXPECT_LT(ed, dtol) << path << " ptex " << ptex << " (" << u << ", " << v << ")";
        if (ep > 1e-9 || ed > dtol) return;  // one report per shape is enough
        if (method == LimitMethod::Fallback) {
          ++t.by_method[method];
          continue;
        }
        t.worst_p = std::max(t.worst_p, ep);
        t.worst_d = std::max(t.worst_d, ed);
        ++t.compared;
        ++t.by_method[method];  // exact paths only
      }
  std::printf("%-40s %6ld points %.2f s\n", path.substr(path.rfind('/') + 1).c_str(), t.compared,
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  std::fflush(stdout);
  total.compared += t.compared;
  for (auto& kv : t.by_method) total.by_method[kv.first] += kv.second;
  total.worst_p = std::max(total.worst_p, t.worst_p);
  total.worst_d = std::max(total.worst_d, t.worst_d);
}

}  // namespace

TEST(LimitVsOsd, RegularPatchesOfTheCorpusAgreeTo1e9OfTheDiagonal) {
  Tally total;
  for (const auto& entry : std::filesystem::directory_iterator(SUBD2NURBS_CORPUS_DIR)) {
    if (entry.path().extension() != ".obj") continue;
    const std::string stem = entry.path().stem().string();
    if (non_manifold_corpus_shapes().count(stem)) continue;
    SCOPED_TRACE(stem);
    try {
      compare_shape(entry.path().string(), total);
    } catch (const std::exception& e) {
      ADD_FAILURE() << stem << ": " << e.what();
    }
  }
  RecordProperty("compared", std::to_string(total.compared));
  RecordProperty("worst_position_rel", std::to_string(total.worst_p));
  RecordProperty("worst_derivative_rel", std::to_string(total.worst_d));
  std::printf("compared %ld points: regular %ld, stam %ld, semi-sharp %ld, refined %ld, fallback %ld; worst %.3g / %.3g\n",
              total.compared, total.by_method[LimitMethod::Regular], total.by_method[LimitMethod::Stam],
              total.by_method[LimitMethod::SemiSharp], total.by_method[LimitMethod::Refined],
              total.by_method[LimitMethod::Fallback], total.worst_p, total.worst_d);
  // Every path must have been exercised, or the test proves less than it claims.
  EXPECT_GT(total.compared, 10000);
  EXPECT_GT(total.by_method[LimitMethod::Regular], 1000);
  EXPECT_GT(total.by_method[LimitMethod::Stam], 100);
  EXPECT_GT(total.by_method[LimitMethod::SemiSharp], 1000);
  EXPECT_GT(total.by_method[LimitMethod::Refined], 1000);
}

// The closed form at semi-sharp crease lines (limit_evaluator.h case 2') against OpenSubdiv on
// a wavy 8 x 8 torus of quads crossed by crease lines: one line, two parallel lines (the faces
// between them have both sides tagged), every sharpness regime (below 1, integer, fractional,
// just below infinite), both crease methods. The samples crowd towards the lines, where the
// scheme's pieces are 2^-k wide. Every face next to a line must take the closed form, so a
// regression to refinement (or a wrong weight) fails here.
TEST(LimitVsOsd, SemiSharpCreaseLinesInClosedForm) {
  constexpr int N = 8;
  const double pi = std::acos(-1.0);
  MeshInput torus;
  auto id = [&](int i, int j) { return ((i + N) % N) * N + (j + N) % N; };
  for (int i = 0; i < N; ++i)
    for (int j = 0; j < N; ++j) {
      const double a = 2 * pi * i / N, b = 2 * pi * j / N;
      const double r = 1 + 0.1 * std::sin(3 * a + 2 * b);
      torus.positions.push_back({(3 + r * std::cos(b)) * std::cos(a), (3 + r * std::cos(b)) * std::sin(a),
                                 r * std::sin(b) + 0.05 * std::cos(5 * a)});
    }
  for (int i = 0; i < N; ++i)
    for (int j = 0; j < N; ++j) {
      torus.face_sizes.push_back(4);
      for (int v : {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)}) torus.face_indices.push_back(v);
    }
  const std::vector<Point3> pos = positions_of(torus);
  const double diag = diagonal(pos);
  const double along[] = {0.0, 0.31, 0.5, 0.77, 1.0};
  const double across[] = {0.0, 1e-3, 0.004, 0.0151, 0.06, 0.24, 0.5, 0.77, 0.97, 1.0};
  long closed_form = 0;
  for (CreaseMethod crease_method : {CreaseMethod::Uniform, CreaseMethod::Chaikin})
    for (double sharpness : {0.4, 1.0, 2.5, 7.9, 9.99})
      for (int lines : {1, 2}) {
        MeshInput in = torus;
        in.options.crease_method = crease_method;
        // Lines j = 2 (and j = 3) all around the torus in i.
        for (int l = 0; l < lines; ++l)
          for (int i = 0; i < N; ++i) in.creases.push_back({id(i, 2 + l), id(i + 1, 2 + l), sharpness});
        const SubdivLevel level = SubdivLevel::from_input(in);
        const LimitEvaluator ours(level, pos);
        const OsdLimitEvaluator osd(in, 10);
        ASSERT_TRUE(osd.ok());
        SCOPED_TRACE(std::string(to_string(crease_method)) + " sharpness " + std::to_string(sharpness) +
                     " lines " + std::to_string(lines));
        for (int i = 0; i < N; i += 3)
          for (int j = 0; j < 4 + lines; ++j) {  // rows 0 .. 3 + lines: the lines and their neighbours
            const int face = i * N + j;           // face (i, j): v runs along j, across the lines
            for (double u : along)
              for (double x : across)
                for (double v : {x, 1 - x}) {
                  LimitMethod method;
                  const LimitSample s = ours.evaluate(face, 0, u, v, &method);
                  const OsdLimitEvaluator::Sample ref = osd.eval(face, u, v);
                  ASSERT_TRUE(ref.regular_patch);
                  ASSERT_LT(dist(s.p, ref.p) / diag, 1e-12) << "face " << face << " (" << u << ", " << v << ")";
                  ASSERT_LT(std::max(dist(s.du, ref.du), dist(s.dv, ref.dv)) / diag, 1e-10)
                      << "face " << face << " (" << u << ", " << v << ")";
                  const bool next_to_line = j == 1 || j == 2 || (lines == 2 && j == 3);
                  if (next_to_line) {
                    EXPECT_EQ(method, LimitMethod::SemiSharp) << "face " << face;
                    ++closed_form;
                  }
                }
          }
      }
  EXPECT_GT(closed_form, 10000);
}

TEST(LimitVsOsd, OsdScalesNgonDerivativesByTwo) {
  // The fact behind the factor 1/2 above, measured on OpenSubdiv alone: on a sub-face of an
  // n-gon its reported du is twice the finite difference of its own positions (on quads the
  // two agree). If a future OpenSubdiv fixes this, this test fails and the factor must go.
  const LoadedCage cage = read_obj(limit_corpus_path("catmark_nonquads"));
  const OsdLimitEvaluator osd(cage.input, 10);
  ASSERT_TRUE(osd.ok());
  const LimitEvaluator ours(SubdivLevel::from_input(cage.input), positions_of(cage.input));
  int checked[2] = {0, 0};
  for (int ptex = 0; ptex < osd.num_ptex_faces(); ++ptex) {
    const bool quad = ours.base().mesh.face_size(ours.ptex_to_face(ptex)) == 4;
    const double u = 0.6, v = 0.7, h = 1e-6;
    const auto a = osd.eval(ptex, u, v), b = osd.eval(ptex, u + h, v);
    if (!a.regular_patch) continue;
    const Point3 fd = {(b.p[0] - a.p[0]) / h, (b.p[1] - a.p[1]) / h, (b.p[2] - a.p[2]) / h};
    const double want = quad ? 1.0 : 2.0;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(a.du[c], want * fd[c], 1e-4 * (1 + std::abs(a.du[c])));
    ++checked[quad ? 1 : 0];
  }
  EXPECT_GT(checked[0], 3);
  EXPECT_GT(checked[1], 3);
}
