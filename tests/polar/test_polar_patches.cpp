// Polar caps inside the patch set (core only): one cap per polar structure, the rest
// Catmull-Clark; the cap's boundary is split into its neighbours' curves, its seam is C2,
// and it meets its neighbours with the same surface (gap and normal angle at rounding level).
#include <gtest/gtest.h>

#include <string>

#include "common/shapes.h"
#include "core/eval/continuity.h"
#include "core/patch/patch_builder.h"
#include "polar/polar_test_util.h"

namespace subd2nurbs::testing {
namespace {

PatchBuild build(const MeshInput& in, bool polar = true, int radial_steps = 1) {
  PatchOptions o;
  o.polar = polar;
  o.cap.radial_steps = radial_steps;
  return build_patches(SubdivLevel::from_input(in), in.positions, o);
}

int count_kind(const PatchSet& ps, PatchKind k) {
  int c = 0;
  for (const NurbsPatch& p : ps.patches) c += p.kind == k;
  return c;
}

struct Shape {
  std::string name;
  MeshInput input;
  int quads;  // quads of the cage
};

std::vector<Shape> shapes() {
  std::vector<Shape> out;
  for (int n : {6, 7, 8, 12, 16, 32, 64}) {
    out.push_back({"cylinder" + std::to_string(n), capped_cylinder(n, 0.05, 0.02), 7 * n});
    out.push_back({"mushroom" + std::to_string(n), mushroom(n, 0.1, 0.02), 10 * n});
  }
  return out;
}

TEST(PolarPatches, OneCapPerStructureAndTheJoinsAreExact) {
  for (const Shape& s : shapes()) {
    for (int steps : {1, 2}) {
      const PatchBuild b = build(s.input, true, steps);
      const PatchSet& ps = b.set;
      const int n = b.info.caps.at(0).structure.valence;
      ASSERT_EQ(b.info.caps.size(), 2u) << s.name;
      EXPECT_EQ(b.info.coarse_level, 0) << s.name;  // the triangles are all inside caps
      EXPECT_EQ(count_kind(ps, PatchKind::PolarCap), 2) << s.name;
      EXPECT_EQ(static_cast<int>(ps.patches.size()), s.quads - 2 * n + 2) << s.name;  // 1-layer quads go into caps
      EXPECT_TRUE(ps.closed) << s.name;
      for (const CapInfo& ci : b.info.caps) {
        const NurbsPatch& cap = ps.patches[ci.patch];
        EXPECT_EQ(cap.split_sides[1].size(), static_cast<size_t>(n)) << s.name;
        EXPECT_EQ(cap.curves[3], -1);
        EXPECT_EQ(cap.corners[0], cap.corners[3]);
        EXPECT_EQ(cap.corners[1], cap.corners[2]);
        EXPECT_EQ(ps.curves[cap.curves[0]].continuity, Continuity::C2);
      }
      const ContinuityReport r = measure_continuity(ps);
      EXPECT_LT(r.max_gap, 1e-13 * ps.model_size) << s.name;
      EXPECT_LT(r.max_normal_angle_deg, 1e-9) << s.name;
      EXPECT_LT(r.max_c2_jump, 1e-10) << s.name;  // seams and regular joins: rounding (seen up to 1.25e-11)
      // Every shared curve was measured, the cap's split boundary included.
      int shared = 0;
      for (const BoundaryCurve& c : ps.curves) shared += c.uses.size() == 2;
      EXPECT_EQ(static_cast<int>(r.curves.size()), shared);
    }
  }
}

// With a Catmull-Clark level a = 1 (an n-gon elsewhere) each boundary span of the cap is
// split in two: 2n pieces, still exact. The hexagon's valence-3 corners sit on ring 3 (the
// structure's Catmull-Clark ring, right next to the 2-layer) or one ring further out.
TEST(PolarPatches, CapBoundaryFollowsLevelOneNeighboursAndEvsOnRingThree) {
  for (int band : {3, 4}) {
    MeshInput in = capped_cylinder(8, 0.1, 0.02);
    // Merge two quads of the band between rings `band` and `band` + 1 into a hexagon.
    const int r0 = 1 + (band - 1) * 8, r1 = 1 + band * 8;
    std::vector<int> sizes, idx;
    int off = 0, merged = 0;
    for (size_t f = 0; f < in.face_sizes.size(); ++f) {
      const int sz = in.face_sizes[f];
      std::vector<int> face(in.face_indices.begin() + off, in.face_indices.begin() + off + sz);
      off += sz;
      const bool a = sz == 4 && face[1] == r0 + 0 && face[2] == r1 + 0;  // (r0[1], r0[0], r1[0], r1[1])
      const bool b = sz == 4 && face[1] == r0 + 1 && face[2] == r1 + 1;
      if (a) continue;
      if (b) {
        face = {r0 + 2, r0 + 1, r0 + 0, r1 + 0, r1 + 1, r1 + 2};
        ++merged;
      }
      sizes.push_back(static_cast<int>(face.size()));
      idx.insert(idx.end(), face.begin(), face.end());
    }
    ASSERT_EQ(merged, 1);
    in.face_sizes = sizes;
    in.face_indices = idx;
    const PatchBuild b = build(in);
    ASSERT_EQ(b.info.caps.size(), 2u) << band;
    EXPECT_EQ(b.info.coarse_level, 1);
    EXPECT_EQ(b.set.patches[b.info.caps[0].patch].split_sides[1].size(), 16u);
    const ContinuityReport r = measure_continuity(b.set);
    EXPECT_LT(r.max_gap, 1e-13 * b.set.model_size) << band;
    // G1 across the rays of the hexagon's valence-3 vertices is exact up to Construction Q's
    // residual; everything at the caps is rounding.
    EXPECT_LT(r.max_normal_angle_deg, 1e-6) << band;
    EXPECT_LT(r.max_c1_jump, 1e-9) << band;
  }
}

TEST(PolarPatches, PolarOffIsPlainCatmullClark) {
  const MeshInput in = capped_cylinder(8);
  const PatchBuild on = build(in), off = build(in, false);
  EXPECT_EQ(off.info.caps.size(), 0u);
  EXPECT_EQ(off.info.coarse_level, 1);  // triangles: one Catmull-Clark step first
  EXPECT_EQ(count_kind(off.set, PatchKind::PolarCap), 0);
  EXPECT_EQ(static_cast<int>(off.set.patches.size()), 4 * 7 * 8 + 3 * 2 * 8);
  EXPECT_EQ(count_kind(on.set, PatchKind::PolarCap), 2);
}

}  // namespace
}  // namespace subd2nurbs::testing
