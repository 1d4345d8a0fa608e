// Every two-manifold shape of OpenSubdiv's regression corpus, converted at the default level
// and measured by OCCT: a valid B-rep with one face per quad of the coarsest all-quad mesh,
// one shell per connected component of the surface, each a solid without free edges when the
// cage is closed, else free edges exactly along the cage's boundary and hole edges; gaps at
// rounding level along every shared edge and no normal jump across the edges the PatchSet
// claims smooth. The expected counts come from the cage alone (corpus_brep.h).
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdio>
#include <set>
#include <string>
#include <vector>

#include "convert/corpus_brep.h"
#include "core/nurbs/nurbs_eval.h"
#include "core/patch/planar_faces.h"
#include "core/util/tolerances.h"

using namespace subd2nurbs;
using namespace subd2nurbs::testing;

namespace {

/// Gaps along shared edges, relative to the cage's bounding-box diagonal.
constexpr double kMaxRelativeGap = 1e-10;
/// Normal angle across edges claimed G1 / C1 / C2, measured by OCCT.
constexpr double kMaxSmoothNormalAngleDeg = 1e-6;

/// Shapes whose check takes more than about 2 s here (the slow label). Almost all of the time
/// is occt::summarize integrating the area (and volume) to 1e-12: the biggest cages, and those
/// whose semi-sharp creases push the build to level 5 (32 x 32 knot spans per face).
/// bishop, car and rook take about 2 minutes each.
const std::set<std::string>& slow_shapes() {
  static const std::set<std::string> s = {
      "catmark_bishop",     "catmark_car",         "catmark_chaikin0",      "catmark_chaikin1",
      "catmark_cube_creases1", "catmark_cubes_semisharp", "catmark_lefthanded", "catmark_pawn",
      "catmark_pole360",    "catmark_pole64",      "catmark_righthanded",   "catmark_rook",
      "catmark_smoothtris0", "catmark_smoothtris1", "catmark_val2_foldover"};
  return s;
}

std::vector<std::string> shapes(bool slow) {
  std::vector<std::string> r;
  for (const std::string& name : manifold_corpus_shapes())
    if ((slow_shapes().count(name) != 0) == slow) r.push_back(name);
  return r;
}

void check(const std::string& shape, bool packed = false) {
  const CorpusBrep r = corpus_brep(shape, 16, packed);
  const ExpectedBrep& e = r.expected;
  const occt::ShapeSummary& s = r.smooth;
  std::printf("%-26s faces %5d free %4d solids %2d shells %2d gap %.3g (rel %.3g) smooth-angle %.3g "
              "deg (%d edges), %.2f s (patches %.2f, brep %.2f, summary %.2f)\n",
              shape.c_str(), s.faces, s.free_edges, s.solids, s.shells, r.max_gap(),
              r.max_gap() / e.diagonal, s.max_normal_angle_deg, s.shared_edges_sampled, r.seconds,
              r.patch_seconds, r.brep_seconds, r.summary_seconds);

  EXPECT_TRUE(r.brep.valid) << r.brep.check_message;
  EXPECT_TRUE(s.valid) << s.check_message;
  // Packed: one face per output patch, never more than one per quad; the boundary edges
  // along a packed face are joined, so there are at most as many free edges as boundary edges.
  const int faces = packed ? static_cast<int>(r.packed.set.patches.size()) : e.faces;
  EXPECT_LE(faces, e.faces);
  EXPECT_EQ(r.brep.num_faces, faces);
  EXPECT_EQ(s.faces, faces);
  EXPECT_EQ(s.shells, e.components);
  if (e.closed) {  // one solid per component
    EXPECT_TRUE(r.brep.is_solid);
    EXPECT_EQ(s.solids, e.components);
    EXPECT_EQ(s.free_edges, 0);
  } else {
    EXPECT_FALSE(r.brep.is_solid);
    EXPECT_EQ(s.solids, e.closed_components);  // closed components still become solids
    if (packed) {
      EXPECT_LE(s.free_edges, e.free_edges);
      EXPECT_GT(s.free_edges, 0);
    } else {
      EXPECT_EQ(s.free_edges, e.free_edges);
    }
  }
  // Every curve between two patches is an edge between two faces, and was measured.
  EXPECT_EQ(s.shared_edges_sampled, r.smooth_edge_count);
  EXPECT_EQ(r.sharp.shared_edges_sampled, r.sharp_edge_count);
  EXPECT_LE(r.max_gap(), kMaxRelativeGap * e.diagonal);
  // catmark_val2_back2back is pairs of faces glued back to back: its limit is a doubly
  // covered flat sheet folding over at the rim, where the two sides' normals are opposite.
  // The tangent planes agree there (the exact G1 residual holds, tests/patch), the
  // orientations cannot.
  if (shape != "catmark_val2_back2back") {
    EXPECT_LE(s.max_normal_angle_deg, kMaxSmoothNormalAngleDeg);
  }
}

class CorpusBrepTest : public ::testing::TestWithParam<std::string> {};
class CorpusBrepSlowTest : public ::testing::TestWithParam<std::string> {};

TEST_P(CorpusBrepTest, ValidWatertightAndSmooth) { check(GetParam()); }
TEST_P(CorpusBrepTest, PackedValidWatertightAndSmooth) { check(GetParam(), true); }
TEST_P(CorpusBrepSlowTest, ValidWatertightAndSmooth) { check(GetParam()); }

// How much area a planar patch covers twice: the integral of the part of its area element
// dot(X_u x X_v, n) that is negative (a fold in its plane), by the midpoint rule on 32 x 32
// points per knot span (catmark_val2_back2back: 96 x 96 changes it by 8e-5 of itself).
double folded_area(const NurbsPatch& patch, const Point3& n) {
  const PatchEvaluator eval(patch);
  const auto& U = patch.knots_u.knots;
  const auto& V = patch.knots_v.knots;
  constexpr int k = 32;
  double folded = 0;
  for (size_t i = 0; i + 1 < U.size(); ++i)
    for (size_t j = 0; j + 1 < V.size(); ++j) {
      const double du = (U[i + 1] - U[i]) / k, dv = (V[j + 1] - V[j]) / k;
      for (int a = 0; a < k; ++a)
        for (int b = 0; b < k; ++b) {
          const SurfaceDerivs d = eval.derivs(U[i] + (a + 0.5) * du, V[j] + (b + 0.5) * dv, 1);
          const Eigen::Vector3d x(d.du[0], d.du[1], d.du[2]), y(d.dv[0], d.dv[1], d.dv[2]);
          folded += std::max(0.0, -x.cross(y).dot(Eigen::Vector3d(n[0], n[1], n[2]))) * du * dv;
        }
    }
  return folded;
}

// Coplanar packed faces merged into planar faces (what `convert` writes by default): the same
// solid as the faces it replaces, with as many fewer faces as were merged. The same area too,
// less twice what folded faces cover twice (core/patch/planar_faces.h: the planar face covers
// its region once; a fold's three layers count +1 -1 +1 in the faces' signed area, which is the
// region's, and three times in their area).
TEST_P(CorpusBrepTest, PlanarFacesMergedSameSolid) {
  const CorpusBrep r = corpus_brep(GetParam(), 8, true);
  occt::BrepOptions merge;
  merge.merge_planar = true;
  const occt::BrepResult m = occt::build_brep(r.packed.set, {}, merge);
  EXPECT_TRUE(m.valid) << m.check_message;
  const occt::ShapeSummary sm = occt::summarize(m.shape, 8), sp = occt::summarize(r.brep.shape, 8);
  std::printf("%-26s faces %d -> %d (%d planar faces of %d, %d rejected)\n", GetParam().c_str(), sp.faces, sm.faces,
              m.planar_faces, m.merged_patches, m.rejected_planar_faces);
  EXPECT_EQ(sm.faces, sp.faces - m.merged_patches + m.planar_faces);
  EXPECT_EQ(m.is_solid, r.brep.is_solid);
  EXPECT_EQ(sm.solids, sp.solids);
  EXPECT_EQ(sm.shells, sp.shells);
  EXPECT_LE(sm.free_edges, sp.free_edges);
  double twice = 0;
  if (m.folded_planar_patches > 0) {
    const PlanarFaces planar = find_planar_faces(r.packed.set, tolerances::kSameSurface);
    for (size_t p = 0; p < r.packed.set.patches.size(); ++p)
      if (planar.folded_patch[p]) twice += 2 * folded_area(r.packed.set.patches[p], planar.faces[planar.face_of_patch[p]].normal);
    std::printf("  %d folded faces: area %.9g -> %.9g, twice covered %.9g\n", m.folded_planar_patches, sp.area, sm.area, twice / 2);
    EXPECT_GT(twice, 0);
  }
  // (OCCT integrates a folded face's area element, which has a kink where it changes sign, to
  // about 1e-6 here: catmark_val2_back2back, 1.4e-3 less area, 1.1e-6 off the prediction.)
  EXPECT_NEAR(sm.area, sp.area - twice, 1e-9 * sp.area + 2e-3 * twice);
  EXPECT_NEAR(sm.volume, sp.volume, 1e-9 * std::abs(sp.volume) + 1e-12);
  EXPECT_LE(sm.max_gap, kMaxRelativeGap * r.expected.diagonal);
}

std::string param_name(const ::testing::TestParamInfo<std::string>& info) { return info.param; }

INSTANTIATE_TEST_SUITE_P(Corpus, CorpusBrepTest, ::testing::ValuesIn(shapes(false)), param_name);
INSTANTIATE_TEST_SUITE_P(Corpus, CorpusBrepSlowTest, ::testing::ValuesIn(shapes(true)), param_name);

TEST(CorpusBrepList, CoversEveryManifoldShape) {
  // 87 shapes, 9 rejected by validation: the two lists hold the other 78 between them.
  EXPECT_EQ(shapes(false).size() + shapes(true).size(), 78u);
  for (const std::string& name : slow_shapes())
    EXPECT_TRUE(std::filesystem::exists(corpus_file(name))) << name;
}

// --- the checks can fail ----------------------------------------------------------------------

/// The torus's patches, built and ready to be damaged.
PatchBuild torus() {
  const LoadedCage cage = read_obj(corpus_file("catmark_torus"));
  return build_patches(SubdivLevel::from_input(cage.input),
                       std::vector<Point3>(cage.input.positions.begin(), cage.input.positions.end()));
}

/// Moves pole (i, j) of patch 0 by `distance` along the normal of its side u = 0.
void push_pole(PatchSet& ps, int i, double distance) {
  NurbsPatch& p = ps.patches[0];
  const int j = p.num_poles_v / 2;
  const Eigen::Vector3d a(p.pole(0, j - 1).data()), b(p.pole(0, j + 1).data()), c(p.pole(1, j).data()),
      o(p.pole(0, j).data());
  const Eigen::Vector3d n = (b - a).cross(c - o).normalized();
  for (int k = 0; k < 3; ++k) p.pole(i, j)[k] += distance * n[k];
}

TEST(CorpusBrepChecks, SmoothNormalAngleNoticesAMovedInnerPole) {
  PatchBuild b = torus();
  ASSERT_EQ(b.set.curves[b.set.patches[0].curves[3]].continuity, Continuity::C2);
  push_pole(b.set, 1, 1e-4 * b.set.model_size);  // next to side 3, not on it
  const occt::BrepResult brep = occt::build_brep(b.set);
  EXPECT_TRUE(brep.valid) << brep.check_message;  // still watertight: only the tangent moved
  const occt::ShapeSummary s = occt::summarize(brep.shape, shared_edges(b.set, brep, true));
  EXPECT_GT(s.max_normal_angle_deg, 1e3 * kMaxSmoothNormalAngleDeg);
  EXPECT_LE(s.max_gap, kMaxRelativeGap * b.set.model_size);
}

TEST(CorpusBrepChecks, GapNoticesAMovedBoundaryPole) {
  PatchBuild b = torus();
  push_pole(b.set, 0, 1e-8 * b.set.model_size);  // on side 3: the face leaves the shared edge
  const occt::BrepResult brep = occt::build_brep(b.set);
  const occt::ShapeSummary s = occt::summarize(brep.shape, shared_edges(b.set, brep, true));
  EXPECT_GT(s.max_gap, 10 * kMaxRelativeGap * b.set.model_size);
}

TEST(CorpusBrepChecks, CountsFollowHolesAndComponents) {
  // The cube with its first face tagged as a hole: 5 faces, an open shell with 4 free edges.
  LoadedCage cage = read_obj(corpus_file("catmark_cube"));
  ASSERT_EQ(cage.input.num_faces(), 6);
  const SubdivLevel closed = SubdivLevel::from_input(cage.input);
  const ExpectedBrep e_closed = expected_brep(cage.input, closed.face_hole);
  EXPECT_EQ(e_closed.faces, 6);
  EXPECT_TRUE(e_closed.closed);
  EXPECT_EQ(e_closed.components, 1);
  cage.input.holes.push_back(0);
  const SubdivLevel holed = SubdivLevel::from_input(cage.input);
  const ExpectedBrep e = expected_brep(cage.input, holed.face_hole);
  EXPECT_EQ(e.faces, 5);
  EXPECT_EQ(e.free_edges, 4);
  EXPECT_FALSE(e.closed);
  const PatchBuild b = build_patches(holed, std::vector<Point3>(cage.input.positions.begin(), cage.input.positions.end()));
  const occt::BrepResult brep = occt::build_brep(b.set);
  const occt::ShapeSummary s = occt::summarize(brep.shape, 2);
  EXPECT_EQ(s.faces, e.faces);
  EXPECT_EQ(s.free_edges, e.free_edges);
  EXPECT_EQ(s.solids, 0);
  EXPECT_NE(s.faces, e_closed.faces);  // the closed cube's expectation would have failed

  // Two separate quads: two components; a triangle makes the level-1 counts (3 quads, 6 free edges).
  MeshInput two;
  two.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {3, 0, 0}, {4, 0, 0}, {4, 1, 0}};
  two.face_sizes = {4, 3};
  two.face_indices = {0, 1, 2, 3, 4, 5, 6};
  const ExpectedBrep e2 = expected_brep(two, std::vector<char>(2, 0));
  EXPECT_EQ(e2.components, 2);
  EXPECT_EQ(e2.faces, 7);
  EXPECT_EQ(e2.free_edges, 14);
  EXPECT_FALSE(e2.closed);
}

}  // namespace
