// Packed faces through OCCT, on shapes made for packing: creases across a grid, T-junctions on
// both sides of an edge, an open tube (a seam), a pack next to polar caps. Oracles: OCCT's
// checker and its own measures (free edges, solids, area and volume integrated to 1e-12), the
// per-quad B-rep of the same patches, and the crease lines packs must not cross.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "common/shapes.h"
#include "converter/occt/brep_builder.h"
#include "converter/occt/shape_check.h"
#include "core/patch/packing.h"
#include "core/patch/patch_builder.h"

using namespace subd2nurbs;
using namespace subd2nurbs::testing;

namespace {

PatchBuild build(const MeshInput& in) {
  return build_patches(SubdivLevel::from_input(in), in.positions);
}

/// Packed and per-quad B-reps of the same build: both valid, the same solids and shells, the
/// same area and volume; returns the packed one's summary.
occt::ShapeSummary expect_same_solid(const PatchBuild& b, const PackedSet& packed) {
  const occt::BrepResult q = occt::build_brep(b.set), p = occt::build_brep(packed.set);
  EXPECT_TRUE(q.valid) << q.check_message;
  EXPECT_TRUE(p.valid) << p.check_message;
  const occt::ShapeSummary sq = occt::summarize(q.shape, 8), sp = occt::summarize(p.shape, 8);
  EXPECT_EQ(sp.faces, static_cast<int>(packed.set.patches.size()));
  EXPECT_EQ(sp.solids, sq.solids);
  EXPECT_EQ(sp.shells, sq.shells);
  EXPECT_LE(sp.free_edges, sq.free_edges);
  EXPECT_EQ(sp.free_edges == 0, sq.free_edges == 0);
  EXPECT_NEAR(sp.area, sq.area, 1e-9 * sq.area);
  EXPECT_NEAR(sp.volume, sq.volume, 1e-9 * std::abs(sq.volume) + 1e-12);
  EXPECT_LE(sp.max_gap, 1e-10 * b.set.model_size);
  // The same normal jumps: none across smooth edges, the crease's own across a sharp crease.
  EXPECT_NEAR(sp.max_normal_angle_deg, sq.max_normal_angle_deg, 1e-6);
  return sp;
}

/// The cage faces (grid cells) of each output patch.
std::vector<std::set<int>> faces_of(const PackedSet& packed, const PatchBuild& b) {
  std::vector<std::set<int>> out(packed.set.patches.size());
  for (size_t p = 0; p < b.set.patches.size(); ++p) out[packed.place[p].patch].insert(b.set.patches[p].base_faces[0]);
  return out;
}

TEST(PackedBrep, CreasesAcrossAGridAreNeverCrossed) {
  const int nx = 10, ny = 8;
  MeshInput in = grid(nx, ny);
  // An infinitely sharp crease along the line x = 4 and a semi-sharp one (2.0) along y = 3.
  auto vid = [&](int i, int j) { return j * (nx + 1) + i; };
  for (int j = 0; j < ny; ++j) in.creases.push_back({vid(4, j), vid(4, j + 1), 10.0});
  for (int i = 0; i < nx; ++i) in.creases.push_back({vid(i, 3), vid(i + 1, 3), 2.0});
  const PatchBuild b = build(in);
  const PackedSet packed = pack_patches(b);
  EXPECT_EQ(packed.rejected_packs, 0);
  EXPECT_GT(packed.packs, 0);
  EXPECT_LT(packed.set.patches.size(), b.set.patches.size());
  for (const std::set<int>& cells : faces_of(packed, b)) {
    int left = 0, right = 0, below = 0, above = 0;
    for (int f : cells) {
      (f % nx < 4 ? left : right)++;
      (f / nx < 3 ? below : above)++;
    }
    EXPECT_TRUE(left == 0 || right == 0) << "a face crosses the sharp crease";
    EXPECT_TRUE(below == 0 || above == 0) << "a face crosses the semi-sharp crease";
  }
  expect_same_solid(b, packed);
}

TEST(PackedBrep, TJunctionsOnBothSidesOfAnEdge) {
  // A strip of holes cut into a grid at different places above and below a line, so that the
  // faces on both sides of that line end at different points along it.
  const int nx = 12, ny = 6;
  MeshInput in = grid(nx, ny);
  for (int f : {0 * nx + 3, 1 * nx + 3, 5 * nx + 8, 4 * nx + 8}) in.holes.push_back(f);
  const PatchBuild b = build(in);
  const PackedSet packed = pack_patches(b);
  EXPECT_EQ(packed.rejected_packs, 0);
  // A curve whose two faces both have that side split into several curves.
  int both_split = 0;
  for (const BoundaryCurve& c : packed.set.curves) {
    if (c.uses.size() != 2) continue;
    const NurbsPatch& A = packed.set.patches[c.uses[0].patch];
    const NurbsPatch& B = packed.set.patches[c.uses[1].patch];
    both_split += A.split_sides[c.uses[0].side].size() >= 2 && B.split_sides[c.uses[1].side].size() >= 2;
  }
  EXPECT_GT(both_split, 0);
  expect_same_solid(b, packed);
}

TEST(PackedBrep, OpenTubeIsOneFaceWithASeam) {
  // The torus's tube cut open: a cylinder of 16 x 6 quads with two boundary circles.
  MeshInput in = torus(16, 7);
  for (int f = 0; f < 16 * 7; ++f)
    if (f % 7 == 6) in.holes.push_back(f);  // one ring of faces removed: the tube is open
  const PatchBuild b = build(in);
  const PackedSet packed = pack_patches(b);
  EXPECT_EQ(packed.rejected_packs, 0);
  const occt::ShapeSummary s = expect_same_solid(b, packed);
  EXPECT_LE(s.faces, 3);  // the regular middle of the tube is one face around its seam
  EXPECT_EQ(s.solids, 0);
}

TEST(PackedBrep, PackNextToPolarCaps) {
  const MeshInput in = capped_cylinder(16);
  const PatchBuild b = build(in);
  ASSERT_EQ(b.info.caps.size(), 2u);
  const PackedSet packed = pack_patches(b);
  EXPECT_EQ(packed.rejected_packs, 0);
  EXPECT_GT(packed.packs, 0);
  const occt::ShapeSummary s = expect_same_solid(b, packed);
  EXPECT_EQ(s.solids, 1);
  EXPECT_EQ(s.free_edges, 0);
  EXPECT_LT(s.faces, static_cast<int>(b.set.patches.size()));
}

}  // namespace
