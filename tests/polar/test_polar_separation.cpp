// The separating first step (MATH.md 3.4): its closed-form rules, that it leaves every other
// level-1 point exactly as Catmull-Clark makes it, and that low-valence and too-close poles
// then become polar caps of twice the valence with exact joins.
#include <gtest/gtest.h>

#include <set>

#include "common/shapes.h"
#include "core/eval/continuity.h"
#include "core/patch/patch_builder.h"
#include "core/polar/polar_separation.h"
#include "io/obj_reader.h"
#include "polar/polar_test_util.h"

namespace subd2nurbs::testing {
namespace {

MeshInput too_close(int n) {  // two poles sharing ring 3
  return revolved(n, {{0, 1}, {0.3, 1}, {0.7, 0.8}, {1, 0}, {0.7, -0.8}, {0.3, -1}, {0, -1}}, 0.1, 0.02);
}

TEST(PolarSeparation, ClosedFormRulesAndEverythingElseIsCatmullClark) {
  for (int n : {3, 4, 5, 8}) {
    const MeshInput in = capped_cylinder(n, 0.2, 0.03);
    const SubdivLevel base = SubdivLevel::from_input(in);
    const int top = 0, bottom = in.num_vertices() - 1;
    ASSERT_EQ(separation_obstacle(base, top), "");
    const SeparatedLevel sl = separate_poles(base, in.positions, {top, bottom});
    const RefinementStep cc = refine_once(base);
    std::vector<Point3> x;
    cc.stencils.apply(in.positions, x);
    const PolyMesh& m = base.mesh;
    // The rules of MATH.md 3.4 at the top pole, written out.
    auto p = [&](int j) { return ev(in.positions[1 + (j + n) % n]); };
    const V3 p0 = ev(in.positions[top]);
    V3 mean = V3::Zero();
    for (int j = 0; j < n; ++j) mean += p(j);
    mean /= n;
    EXPECT_LT((ev(sl.positions[top]) - (0.625 * p0 + 0.375 * mean)).norm(), 1e-15);
    std::set<int> changed{top, bottom};
    for (int pole : {top, bottom}) {
      for (int i = 0; i < m.vertex_face_count(pole); ++i) {
        const int h = m.vertex_corners(pole)[i], f = m.corner_face(h);
        changed.insert(child_of_face(m, f));
        for (int k = 0; k < 3; ++k) {
          const int hk = m.face_begin(f) + k;
          changed.insert(child_of_edge(m, m.corner_edge(hk)));
          changed.insert(child_of_vertex(m, m.corner_vertex(hk)));
        }
      }
    }
    for (int j = 0; j < n; ++j) {
      const int h = m.vertex_corners(top)[j];
      EXPECT_EQ(m.to_vertex(h), 1 + j);
      const V3 F = ev(sl.positions[child_of_face(m, m.corner_face(h))]);
      EXPECT_LT((F - (2 * p0 + p(j) + p(j + 1)) / 4).norm(), 1e-15);
      const V3 E = ev(sl.positions[child_of_edge(m, m.corner_edge(h))]);  // spoke j
      EXPECT_LT((E - (8 * p0 + p(j - 1) + 6 * p(j) + p(j + 1)) / 16).norm(), 1e-15);
    }
    // Every other point is Catmull-Clark's, bit for bit.
    for (int v = 0; v < static_cast<int>(x.size()); ++v)
      if (!changed.count(v)) EXPECT_EQ(sl.positions[v], x[v]) << "n " << n << " vertex " << v;
    // The level-1 cage has a polar structure of valence 2n at each pole.
    const PolarDetection d = detect_polar_structures(sl.level);
    ASSERT_EQ(d.structures.size(), 2u) << n;
    EXPECT_EQ(d.structures[0].pole, top);
    EXPECT_EQ(d.structures[0].valence, 2 * n);
  }
}

TEST(PolarSeparation, LowValenceAndTooClosePolesBecomeExactCaps) {
  struct Case {
    const char* name;
    MeshInput input;
    int valence;
  };
  for (const Case& c : {Case{"valence 3", capped_cylinder(3, 0.1, 0.02), 6}, Case{"valence 4", capped_cylinder(4, 0.1, 0.02), 8},
                        Case{"valence 5", mushroom(5, 0.1, 0.02), 10}, Case{"too close", too_close(8), 16}}) {
    PatchOptions o;
    const PatchBuild plain = build_patches(SubdivLevel::from_input(c.input), c.input.positions, o);
    EXPECT_TRUE(plain.info.caps.empty()) << c.name;
    ASSERT_EQ(plain.info.rejected_poles.size(), 2u) << c.name;
    o.separate_poles = true;
    const PatchBuild b = build_patches(SubdivLevel::from_input(c.input), c.input.positions, o);
    ASSERT_EQ(b.info.caps.size(), 2u) << c.name;
    EXPECT_EQ(b.info.separated_poles.size(), 2u);
    EXPECT_TRUE(b.info.rejected_poles.empty());
    for (const CapInfo& ci : b.info.caps) EXPECT_EQ(ci.structure.valence, c.valence) << c.name;
    EXPECT_TRUE(b.set.closed);
    for (const NurbsPatch& p : b.set.patches)
      for (int f : p.base_faces) EXPECT_LT(f, c.input.num_faces()) << c.name;  // cage faces
    const ContinuityReport r = measure_continuity(b.set);
    EXPECT_LT(r.max_gap, 1e-13 * b.set.model_size) << c.name;
    EXPECT_LT(r.max_normal_angle_deg, 1e-9) << c.name;
    EXPECT_EQ(b.set.model_size, plain.set.model_size);
  }
}

TEST(PolarSeparation, OnlyForLowValenceAndTooClose) {
  // catmark_pole8 lacks a 2-layer: not something the separating step is for.
  const LoadedCage cage = read_obj(std::string(SUBD2NURBS_CORPUS_DIR) + "/catmark_pole8.obj");
  PatchOptions o;
  o.separate_poles = true;
  const PatchBuild b = build_patches(SubdivLevel::from_input(cage.input),
                                     std::vector<Point3>(cage.input.positions.begin(), cage.input.positions.end()), o);
  EXPECT_TRUE(b.info.caps.empty());
  EXPECT_TRUE(b.info.separated_poles.empty());
  // A crease at a ring-1 vertex: no separation either.
  MeshInput in = capped_cylinder(5);
  in.creases.push_back({1, 2, kInfiniteSharpness});
  const SubdivLevel base = SubdivLevel::from_input(in);
  EXPECT_NE(separation_obstacle(base, 0), "");
  EXPECT_THROW(separate_poles(base, in.positions, {0}), std::invalid_argument);
}

}  // namespace
}  // namespace subd2nurbs::testing
