// Packed faces (core/patch/packing.h, docs/patches.md "Packed faces").
//
// Oracles: the per-quad patches (a pack must be the same surface: at every per-quad sample
// point within 1e-12 x diagonal), the continuity identities across the packed set's curves,
// shapes whose answer is known (a regular torus or open grid is one face, a flat grid one
// Bezier patch), and on grids with holes a brute-force search of the largest free rectangle
// (greedy largest-first: after taking away every rectangle larger than A, the largest free
// rectangle has area A, for every area A chosen).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>
#include <string>

#include "common/corpus.h"
#include "common/shapes.h"
#include "core/eval/continuity.h"
#include "core/nurbs/nurbs_eval.h"
#include "core/patch/packing.h"
#include "io/cage_reader.h"
#include "io/obj_reader.h"
#include "patch/patch_test_util.h"

namespace subd2nurbs::testing {
namespace {

/// Largest |per-quad patch - packed face| over a 5 x 5 grid of every quad (sides included).
double max_packed_difference(const PatchBuild& b, const PackedSet& out) {
  double worst = 0;
  for (size_t p = 0; p < b.set.patches.size(); ++p)
    for (int i = 0; i <= 4; ++i)
      for (int j = 0; j <= 4; ++j) {
        const double s = i / 4.0, t = j / 4.0;
        double u, v;
        place_parameters(out.place[p], s, t, u, v);
        const Point3 a = evaluate(b.set.patches[p], s, t).p;
        const Point3 c = evaluate(out.set.patches[out.place[p].patch], u, v).p;
        worst = std::max(worst, (ev(a) - ev(c)).norm());
      }
  return worst;
}

/// Structural checks of a packed set against its per-quad source.
void expect_consistent(const PatchBuild& b, const PackedSet& out) {
  const PatchSet& q = b.set;
  const PatchSet& ps = out.set;
  EXPECT_EQ(out.rejected_packs, 0);
  ASSERT_EQ(out.place.size(), q.patches.size());
  ASSERT_EQ(out.curve.size(), q.curves.size());
  ASSERT_EQ(out.source_curves.size(), ps.curves.size());
  EXPECT_EQ(ps.closed, q.closed);
  // Every quad is in exactly one output patch: packs list their quads as cells.
  std::vector<int> quads_of(ps.patches.size(), 0);
  for (const PatchPlace& pl : out.place) ++quads_of[pl.patch];
  int packs = 0, packed = 0;
  long long poles = 0;
  for (size_t i = 0; i < ps.patches.size(); ++i) {
    const NurbsPatch& p = ps.patches[i];
    poles += static_cast<long long>(p.poles.size());
    if (p.cells.empty()) {
      EXPECT_EQ(quads_of[i], 1);
      continue;
    }
    ++packs;
    packed += static_cast<int>(p.cells.size());
    EXPECT_EQ(quads_of[i], static_cast<int>(p.cells.size()));
    EXPECT_EQ(p.knots_u.knots.back(), 1 + std::max_element(p.cells.begin(), p.cells.end(), [](auto& a, auto& c) { return a.u < c.u; })->u);
    EXPECT_EQ(p.knots_v.knots.back(), 1 + std::max_element(p.cells.begin(), p.cells.end(), [](auto& a, auto& c) { return a.v < c.v; })->v);
  }
  EXPECT_EQ(packs, out.packs);
  EXPECT_EQ(packed, out.packed_quads);
  EXPECT_EQ(poles, out.total_poles);
  // A curve goes only when both its uses are inside one pack; the others keep their uses.
  for (size_t k = 0; k < q.curves.size(); ++k) {
    const BoundaryCurve& c = q.curves[k];
    if (out.curve[k] < 0) {
      ASSERT_EQ(c.uses.size(), 2u);
      EXPECT_EQ(out.place[c.uses[0].patch].patch, out.place[c.uses[1].patch].patch);
      EXPECT_FALSE(ps.patches[out.place[c.uses[0].patch].patch].cells.empty());
    } else {
      EXPECT_EQ(ps.curves[out.curve[k]].uses.size(), c.uses.size());
      const std::vector<int>& sources = out.source_curves[out.curve[k]];
      EXPECT_NE(std::find(sources.begin(), sources.end(), static_cast<int>(k)), sources.end());
    }
  }
  // Each use's piece of its side is where the curve lies on the face.
  const double tol = 1e-12 * ps.model_size;
  double worst = 0;
  for (const BoundaryCurve& c : ps.curves)
    for (const CurveUse& use : c.uses)
      for (double s : {0.0, 0.3, 1.0}) {
        const SideDerivs d = side_derivatives(ps.patches[use.patch], use.side, use.side_parameter(s));
        worst = std::max(worst, (ev(d.p) - ev(evaluate(c, s))).norm());
      }
  EXPECT_LT(worst, tol);
}

PatchBuild build_with(MeshInput in, int extra_levels = 0) { return build_from_input(in, extra_levels); }

TEST(Packing, RegularTorusIsOneFaceWithSeamCurves) {
  const PatchBuild b = build_with(torus(12, 8));
  const PackedSet out = pack_patches(b);
  expect_consistent(b, out);
  ASSERT_EQ(out.set.patches.size(), 1u);
  const NurbsPatch& p = out.set.patches[0];
  EXPECT_EQ(p.cells.size(), 96u);
  // One span per quad in both directions (a torus is nowhere one polynomial across a line).
  EXPECT_EQ(p.num_poles_u * p.num_poles_v, 15 * 11);
  EXPECT_EQ(p.knots_u.knots.size() + p.knots_v.knots.size(), 13u + 9u);
  // The cut: two closed curves (the 12 and the 8 coarse edges along it, joined: no other face
  // meets them), each used by opposite sides of the one face, like a torus face in OCCT.
  ASSERT_EQ(out.set.curves.size(), 2u);
  for (const BoundaryCurve& c : out.set.curves) {
    ASSERT_EQ(c.uses.size(), 2u);
    EXPECT_EQ(c.uses[0].patch, 0);
    EXPECT_EQ(c.uses[1].patch, 0);
    EXPECT_EQ((c.uses[0].side + 2) % 4, c.uses[1].side);
    EXPECT_EQ(c.corner0, c.corner1);
  }
  EXPECT_EQ(out.source_curves[0].size() + out.source_curves[1].size(), 20u);
  EXPECT_EQ(out.set.corners.size(), 1u);
  EXPECT_LT(max_packed_difference(b, out), 1e-12 * b.set.model_size);
  const ContinuityReport r = measure_continuity(out.set);
  EXPECT_LT(r.max_gap, 1e-12 * b.set.model_size);
  EXPECT_LT(r.max_normal_angle_deg, 1e-9);
  EXPECT_LT(r.max_c1_jump, 1e-11);  // the seam is C2 in the face's own parameters
  EXPECT_LT(r.max_c2_jump, 1e-9);
}

TEST(Packing, OpenGridIsOneFaceAndAFlatGridOneBezierPatch) {
  const PatchBuild b = build_with(grid(7, 5));
  const PackedSet out = pack_patches(b);
  expect_consistent(b, out);
  ASSERT_EQ(out.set.patches.size(), 1u);
  EXPECT_EQ(out.set.patches[0].num_poles_u, 7 + 3);
  EXPECT_EQ(out.set.patches[0].num_poles_v, 5 + 3);
  EXPECT_EQ(out.set.curves.size(), 4u);  // the boundary: one curve per side, the edges along it joined
  EXPECT_LT(max_packed_difference(b, out), 1e-12 * b.set.model_size);

  // A flat, evenly spaced grid has a linear limit: every knot line is removable.
  MeshInput flat = grid(6, 4);
  for (Point3& p : flat.positions) p[2] = 0;
  const PatchBuild bf = build_with(flat);
  const PackedSet of = pack_patches(bf);
  expect_consistent(bf, of);
  ASSERT_EQ(of.set.patches.size(), 1u);
  EXPECT_EQ(of.set.patches[0].num_poles_u, 4);
  EXPECT_EQ(of.set.patches[0].num_poles_v, 4);
  EXPECT_EQ(of.removed_knots, 5 + 3);
  EXPECT_LT(max_packed_difference(bf, of), 1e-12 * bf.set.model_size);
}

TEST(Packing, PerQuadIsTheSourceUnchanged) {
  const PatchBuild b = build_with(torus(6, 5));
  const PackedSet out = unpacked(b.set);
  EXPECT_EQ(out.set.patches.size(), b.set.patches.size());
  EXPECT_EQ(out.packs, 0);
  EXPECT_EQ(max_packed_difference(b, out), 0.0);
}

/// Edges on the boundary of each packed face (a seam counted twice): per side its pieces, or one.
std::vector<int> pack_edge_counts(const PackedSet& out) {
  std::vector<int> counts;
  for (const NurbsPatch& p : out.set.patches) {
    if (p.cells.empty()) continue;
    int e = 0;
    for (int s = 0; s < 4; ++s) e += p.split_sides[s].empty() ? (p.curves[s] >= 0 ? 1 : 0) : static_cast<int>(p.split_sides[s].size());
    counts.push_back(e);
  }
  return counts;
}

// A capsule (docs/patches.md "Packed faces"): the side ring meets every fan quad of both caps
// one by one, so the one pack of the ring has 2 x 2n edges. With a cap of K edges it is cut
// into strips of at most K edges, which are still exactly the per-quad surface and cover the
// same quads; a torus (2 seams) is one face at any cap of at least 4.
TEST(Packing, PacksWithManyEdgesAreCutIntoStrips) {
  const int n = 24;
  const PatchBuild b = build_with(revolved(n, {{0, 1.7}, {0.7, 1.4}, {1, 1}, {1, -1}, {0.7, -1.4}, {0, -1.7}}));
  const PackedSet whole = pack_patches(b, 1 << 30);
  expect_consistent(b, whole);
  // The side ring, and pairs of the caps' fan quads (across the C2 edges between two of the
  // cage's triangles), which have at most 8 edges each.
  std::vector<int> whole_edges = pack_edge_counts(whole);
  ASSERT_EQ(whole_edges.size(), static_cast<size_t>(whole.packs));
  std::sort(whole_edges.begin(), whole_edges.end());
  EXPECT_GE(whole_edges.back(), 2 * n);  // the case is present: the ring meets n faces or more on each side
  EXPECT_LE(whole_edges[whole_edges.size() - 2], 8);
  for (int cap : {64, 16, 8}) {
    SCOPED_TRACE("cap " + std::to_string(cap));
    const PackedSet out = pack_patches(b, cap);
    expect_consistent(b, out);
    EXPECT_LT(max_packed_difference(b, out), 1e-12 * b.set.model_size);
    EXPECT_EQ(out.packed_quads, whole.packed_quads);  // the same quads, the ring in strips
    EXPECT_GE(out.packs, whole.packs - 1 + (whole_edges.back() + cap - 1) / cap);
    for (int e : pack_edge_counts(out)) EXPECT_LE(e, cap);
    const ContinuityReport r = measure_continuity(out.set);
    EXPECT_LT(r.max_gap, 1e-12 * b.set.model_size);
    EXPECT_LT(r.max_normal_angle_deg, 1e-6);
  }
  const PatchBuild t = build_with(torus(12, 8));
  for (int cap : {4, 64}) {
    const PackedSet out = pack_patches(t, cap);
    EXPECT_EQ(out.set.patches.size(), 1u);
    EXPECT_EQ(pack_edge_counts(out), std::vector<int>{4});
  }
}

// Quads at extraordinary vertices (docs/patches.md "Packed faces"): a torus with two rotated
// edges (two valence-3 and two valence-5 vertices each). A quad at an extraordinary vertex
// joins a pack across its sides claimed C2, never across a fan ray (G1): every curve inside a
// pack was claimed C2, the pack is the per-quad surface (1e-12), and the greedy choice leaves
// no two quads alone that share a C2 curve (it takes every rectangle of two or more).
TEST(Packing, QuadsAtExtraordinaryVerticesJoinAcrossTheirC2Sides) {
  MeshInput m = torus(24, 16);
  rotate_torus_edge(m, 24, 16, 5, 3);
  rotate_torus_edge(m, 24, 16, 17, 11);
  for (int extra : {0, 3}) {
    SCOPED_TRACE("extra levels " + std::to_string(extra));
    const PatchBuild b = build_with(m, extra);
    const PackedSet out = pack_patches(b);
    expect_consistent(b, out);
    const double size = b.set.model_size;
    EXPECT_LT(max_packed_difference(b, out), 1e-12 * size);
    int ev_quads = 0, ev_packed = 0;
    for (size_t p = 0; p < b.set.patches.size(); ++p) {
      if (b.set.patches[p].kind != PatchKind::Pccm) continue;
      ++ev_quads;
      ev_packed += !out.set.patches[out.place[p].patch].cells.empty();
    }
    EXPECT_GT(ev_quads, 0);
    EXPECT_GT(ev_packed, 0);
    for (size_t k = 0; k < b.set.curves.size(); ++k) {
      const BoundaryCurve& c = b.set.curves[k];
      if (out.curve[k] < 0) EXPECT_EQ(c.continuity, Continuity::C2) << "curve " << k << " inside a pack";
      if (c.continuity != Continuity::C2 || c.uses.size() != 2) continue;
      const int a = c.uses[0].patch, d = c.uses[1].patch;
      EXPECT_FALSE(out.set.patches[out.place[a].patch].cells.empty() && out.set.patches[out.place[d].patch].cells.empty())
          << "quads " << a << " and " << d << " share C2 curve " << k << " and are both alone";
    }
    const ContinuityReport r = measure_continuity(out.set);
    EXPECT_LT(r.max_gap, 1e-12 * size);
    EXPECT_LT(r.max_normal_angle_deg, 1e-6);  // over curves claimed G1 or smoother
    EXPECT_LT(r.max_coplanarity, 1e-8);
    EXPECT_LT(r.max_c1_jump, 1e-9);
    RecordProperty("faces_per_quad_extra_" + std::to_string(extra), static_cast<int>(b.set.patches.size()));
    RecordProperty("faces_packed_extra_" + std::to_string(extra), static_cast<int>(out.set.patches.size()));
    std::printf("extra %d: %zu quads (%d at extraordinary vertices, %d of them packed) -> %zu faces, max c2 jump %.2g\n",
                extra, b.set.patches.size(), ev_quads, ev_packed, out.set.patches.size(), r.max_c2_jump);
  }
}

/// The largest rectangle of free cells (brute force).
int largest_free_rectangle(const std::vector<std::vector<char>>& free) {
  const int nx = static_cast<int>(free.size()), ny = static_cast<int>(free[0].size());
  int best = 0;
  for (int x0 = 0; x0 < nx; ++x0)
    for (int y0 = 0; y0 < ny; ++y0)
      for (int x1 = x0; x1 < nx; ++x1)
        for (int y1 = y0; y1 < ny; ++y1) {
          bool all = true;
          for (int x = x0; x <= x1 && all; ++x)
            for (int y = y0; y <= y1 && all; ++y) all = free[x][y];
          if (all) best = std::max(best, (x1 - x0 + 1) * (y1 - y0 + 1));
        }
  return best;
}

TEST(Packing, GreedyLargestFirstOnGridsWithHoles) {
  const int nx = 9, ny = 7;
  unsigned seed = 12345;
  auto next = [&] { return seed = seed * 1103515245u + 12345u, (seed >> 16) & 0x7fff; };
  for (int trial = 0; trial < 6; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    MeshInput in = grid(nx, ny);
    for (int f = 0; f < nx * ny; ++f)
      if (next() % 9 == 0) in.holes.push_back(f);
    const PatchBuild b = build_with(in);
    const PackedSet out = pack_patches(b);
    expect_consistent(b, out);
    EXPECT_LT(max_packed_difference(b, out), 1e-12 * b.set.model_size);
    // Cells that may be packed: the regular quads (no creases in a grid, so every edge between
    // two of them is C2).
    std::vector<std::vector<char>> free(nx, std::vector<char>(ny, 0));
    std::map<int, std::vector<int>> rect_of_face;  // output patch -> its cage faces
    for (size_t p = 0; p < b.set.patches.size(); ++p) {
      const NurbsPatch& q = b.set.patches[p];
      const int f = q.base_faces.at(0);
      const bool ok = q.kind == PatchKind::RegularBSpline;
      if (ok) free[f % nx][f / nx] = 1;
      if (ok) rect_of_face[out.place[p].patch].push_back(f);
      else EXPECT_TRUE(out.set.patches[out.place[p].patch].cells.empty());
    }
    // Every output patch of free cells is an axis-aligned rectangle of them.
    std::map<int, std::vector<std::array<int, 4>>> by_area;  // area -> rectangles (x0, y0, x1, y1)
    for (const auto& [patch, faces] : rect_of_face) {
      int x0 = nx, y0 = ny, x1 = -1, y1 = -1;
      for (int f : faces) {
        x0 = std::min(x0, f % nx);
        x1 = std::max(x1, f % nx);
        y0 = std::min(y0, f / nx);
        y1 = std::max(y1, f / nx);
      }
      ASSERT_EQ(static_cast<int>(faces.size()), (x1 - x0 + 1) * (y1 - y0 + 1)) << "patch " << patch << " is not a rectangle";
      by_area[static_cast<int>(faces.size())].push_back({x0, y0, x1, y1});
    }
    // Greedy largest first: with the rectangles larger than A taken away, the largest free
    // rectangle has area A.
    std::vector<std::vector<char>> left = free;
    for (auto it = by_area.rbegin(); it != by_area.rend(); ++it) {
      EXPECT_EQ(largest_free_rectangle(left), it->first);
      for (const auto& r : it->second)
        for (int x = r[0]; x <= r[2]; ++x)
          for (int y = r[1]; y <= r[3]; ++y) left[x][y] = 0;
    }
    EXPECT_EQ(largest_free_rectangle(left), 0);  // every free cell is in some face
  }
}

/// Every two-manifold corpus shape without deep semi-sharp creases: the packed set is the same
/// surface, its joins keep their claims, and it has fewer faces wherever regular regions exist.
class PackedCorpus : public ::testing::TestWithParam<std::string> {};

TEST_P(PackedCorpus, SameSurfaceAndJoins) {
  const LoadedCage cage = read_obj(std::string(SUBD2NURBS_CORPUS_DIR) + "/" + GetParam() + ".obj");
  const SubdivLevel base = SubdivLevel::from_input(cage.input);
  const PatchBuild b = build_patches(base, cage.input.positions);
  const PackedSet out = pack_patches(b);
  expect_consistent(b, out);
  const double size = b.set.model_size;
  EXPECT_LT(max_packed_difference(b, out), 1e-12 * size);
  const ContinuityReport r = measure_continuity(out.set);
  EXPECT_LT(r.max_gap, 1e-10 * size);
  EXPECT_LT(r.max_normal_angle_deg, 1e-6);  // over curves claimed G1 or smoother
  EXPECT_LT(r.max_coplanarity, 1e-8);
  RecordProperty("faces_per_quad", static_cast<int>(b.set.patches.size()));
  RecordProperty("faces_packed", static_cast<int>(out.set.patches.size()));
}

// The bar on real models: at least 3x fewer faces than one per quad (and fewer poles).
TEST(PackingSlow, AtLeastThreeTimesFewerFacesOnRealModels) {
  auto check = [](const std::string& name, const PatchBuild& b) {
    const PackedSet out = pack_patches(b);
    EXPECT_EQ(out.rejected_packs, 0) << name;
    EXPECT_LE(3 * out.set.patches.size(), b.set.patches.size()) << name << ": " << out.set.patches.size()
                                                                << " faces packed, " << b.set.patches.size() << " per quad";
    EXPECT_LE(out.total_poles, b.info.total_poles) << name;
    EXPECT_LT(max_packed_difference(b, out), 1e-12 * b.set.model_size) << name;
    std::printf("%s: %zu faces per quad, %zu packed; poles %lld -> %lld\n", name.c_str(), b.set.patches.size(),
                out.set.patches.size(), b.info.total_poles, out.total_poles);
  };
  check("10k torus with EVs", build_with(torus_with_rotated_edges()));
  for (const char* name : {"catmark_pawn", "catmark_bishop", "catmark_rook"}) {
    const LoadedCage cage = read_obj(std::string(SUBD2NURBS_CORPUS_DIR) + "/" + name + ".obj");
    check(name, build_patches(SubdivLevel::from_input(cage.input), cage.input.positions));
  }
}

// A real quad remesh whose packed faces have sides cut into pieces at whole quads that
// floating point does not hit exactly (23/42 x 42 = 22.999999999999996): every piece's curve
// must keep the side's own knots, whole quads apart, with no near-duplicate beside one (OCCT
// refuses knots closer than ~1e-15, and the conversion once failed there with exit 4).
TEST(Packing, SidePiecesKeepWholeQuadKnotsOnARealRemesh) {
  const LoadedCage cage = read_cage(std::string(SUBD2NURBS_TEST_DATA_DIR) + "/mesh/fandisk_quads.off");
  const PatchBuild b = build_patches(SubdivLevel::from_input(cage.input), cage.input.positions);
  const PackedSet out = pack_patches(b);
  expect_consistent(b, out);
  EXPECT_LT(max_packed_difference(b, out), 1e-12 * b.set.model_size);
  int pieces = 0;
  for (const NurbsPatch& p : out.set.patches)
    for (const auto& side : p.split_sides) pieces += static_cast<int>(side.size());
  EXPECT_GT(pieces, 0);  // the case this test is about is present
  for (size_t k = 0; k < out.set.curves.size(); ++k) {
    const auto& t = out.set.curves[k].knots.knots;
    for (size_t i = 1; i < t.size(); ++i) EXPECT_GT(t[i] - t[i - 1], 1e-6) << "curve " << k << " knot " << i;
  }
}

std::vector<std::string> corpus_without_deep_creases() {
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(SUBD2NURBS_CORPUS_DIR)) {
    if (e.path().extension() != ".obj") continue;
    const std::string name = e.path().stem().string();
    if (non_manifold_corpus_shapes().count(name)) continue;
    const LoadedCage cage = read_obj(e.path().string());
    double max_sharp = 0;
    for (const CreaseTag& c : cage.input.creases)
      if (c.sharpness < kInfiniteSharpness) max_sharp = std::max(max_sharp, c.sharpness);
    if (max_sharp <= 3.0) names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  return names;
}

INSTANTIATE_TEST_SUITE_P(Corpus, PackedCorpus, ::testing::ValuesIn(corpus_without_deep_creases()),
                         [](const ::testing::TestParamInfo<std::string>& i) { return i.param; });

}  // namespace
}  // namespace subd2nurbs::testing
