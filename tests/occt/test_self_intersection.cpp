// find_self_intersections (core/eval/self_intersection.h) against OCCT's own checker,
// BOPAlgo_ArgumentAnalyzer in its self-interference mode (what FreeCAD's Shape.check(True)
// runs), on the B-rep of the same PatchSet: two interpenetrating cube cages and a torus cage
// whose tube is pushed through the opposite side of the ring (its limit surface passes through
// itself) are
// flagged by both, the same cubes apart and corpus shapes OCCT finds clean are flagged by
// neither. The faces we name must be among the faces OCCT names.
#include <gtest/gtest.h>

#include <BOPAlgo_ArgumentAnalyzer.hxx>
#include <BOPAlgo_CheckResult.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <string>

#include "converter/occt/brep_builder.h"
#include "core/eval/self_intersection.h"
#include "core/nurbs/nurbs_eval.h"
#include "core/patch/packing.h"
#include "core/patch/patch_builder.h"
#include "io/obj_reader.h"

namespace subd2nurbs {
namespace {

constexpr double kPi = 3.14159265358979323846;

PatchSet packed_set(const MeshInput& input) {
  return pack_patches(build_patches(SubdivLevel::from_input(input), input.positions)).set;
}

void add_cube(MeshInput& m, double dx, double dy, double dz) {
  const int base = m.num_vertices();
  for (int k = 0; k < 8; ++k)
    m.positions.push_back({(k & 1 ? 0.5 : -0.5) + dx, (k & 2 ? 0.5 : -0.5) + dy, (k & 4 ? 0.5 : -0.5) + dz});
  // Outward faces of the cube with vertex k = x + 2y + 4z.
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) {
    m.face_sizes.push_back(4);
    for (int v : f) m.face_indices.push_back(base + v);
  }
}

MeshInput two_cubes(double dx) {
  MeshInput m;
  add_cube(m, 0, 0, 0);
  add_cube(m, dx, 0.1 * dx, 0.2 * dx);
  return m;
}

/// A torus cage: `ring` quads around the axis, `tube` around the tube, radii R (axis to the
/// tube's centre) and r (tube); the rings of the cage at angles 0 and +-1 step around the axis
/// are moved by `push` along x (and a little in z, against symmetric contacts): pushed far
/// enough, that part of the tube passes through the opposite side of the torus.
MeshInput torus_cage(int ring, int tube, double R, double r, double push = 0) {
  MeshInput m;
  for (int i = 0; i < ring; ++i)
    for (int j = 0; j < tube; ++j) {
      const double t = 2 * kPi * i / ring, p = 2 * kPi * j / tube;
      const bool pushed = i == 0 || i == 1 || i == ring - 1;
      m.positions.push_back({(R + r * std::cos(p)) * std::cos(t) + (pushed ? push : 0),
                             (R + r * std::cos(p)) * std::sin(t), r * std::sin(p) + (pushed ? 0.05 * std::fabs(push) : 0)});
    }
  for (int i = 0; i < ring; ++i)
    for (int j = 0; j < tube; ++j) {
      const int i1 = (i + 1) % ring, j1 = (j + 1) % tube;
      m.face_sizes.push_back(4);
      for (int v : {i * tube + j, i * tube + j1, i1 * tube + j1, i1 * tube + j}) m.face_indices.push_back(v);
    }
  return m;
}

/// OCCT's verdict: the faces (indices in TopExp::MapShapes order, which is the patch order for
/// a connected PatchSet) that BOPAlgo_ArgumentAnalyzer's self-interference test names, and
/// whether it found anything at all.
struct OcctVerdict {
  bool faulty = false;
  std::set<int> faces;
};

OcctVerdict occt_self_interference(const PatchSet& ps) {
  const occt::BrepResult b = occt::build_brep(ps);
  EXPECT_TRUE(b.valid) << b.check_message;
  TopTools_IndexedMapOfShape faces;
  TopExp::MapShapes(b.shape, TopAbs_FACE, faces);
  BOPAlgo_ArgumentAnalyzer a;
  a.SetShape1(b.shape);
  a.ArgumentTypeMode() = false;
  a.SelfInterMode() = true;
  a.Perform();
  OcctVerdict v;
  v.faulty = a.HasFaulty();
  for (const BOPAlgo_CheckResult& r : a.GetCheckResult())
    for (const TopoDS_Shape& s : r.GetFaultyShapes1())
      if (s.ShapeType() == TopAbs_FACE) v.faces.insert(faces.FindIndex(s) - 1);
  return v;
}

double distance(const Point3& a, const Point3& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

/// The witness lies on both faces at the parameters given.
void expect_witness_on_faces(const PatchSet& ps, const FaceCrossing& w) {
  const Point3 a = evaluate(ps.patches[w.face_a], w.ua, w.va).p, b = evaluate(ps.patches[w.face_b], w.ub, w.vb).p;
  EXPECT_LT(distance(a, w.point), 1e-9 * ps.model_size);
  EXPECT_LT(distance(b, w.point), 1e-9 * ps.model_size);
  EXPECT_GT(w.angle_deg, 0.05);
}

TEST(SelfIntersection, InterpenetratingCubesAreFlaggedLikeOcct) {
  const PatchSet ps = packed_set(two_cubes(0.4));
  const SelfIntersectionReport r = find_self_intersections(ps);
  EXPECT_EQ(r.components, 2);
  EXPECT_TRUE(r.self.empty());
  ASSERT_FALSE(r.overlaps.empty());
  ASSERT_EQ(r.overlapping_components.size(), 1u);
  EXPECT_EQ(r.overlapping_components[0], std::make_pair(0, 1));
  for (const FaceCrossing& w : r.overlaps) {
    EXPECT_FALSE(w.inside);
    EXPECT_NE(w.component_a, w.component_b);
    expect_witness_on_faces(ps, w);
  }
  EXPECT_TRUE(occt_self_interference(ps).faulty);
}

TEST(SelfIntersection, CubesApartAreCleanLikeOcct) {
  // 1.2 apart along x: the cages' convex hulls (which hold their limit surfaces) are disjoint.
  const PatchSet ps = packed_set(two_cubes(1.2));
  const SelfIntersectionReport r = find_self_intersections(ps);
  EXPECT_EQ(r.components, 2);
  EXPECT_TRUE(r.empty());
  EXPECT_FALSE(occt_self_interference(ps).faulty);
}

TEST(SelfIntersection, CubeInsideCubeIsAnOverlap) {
  // A small cube cage wholly inside a big one: no crossing, but the solids overlap. OCCT's
  // self-interference test says so too (solid / solid).
  MeshInput m;
  add_cube(m, 0, 0, 0);
  for (auto& p : m.positions)
    for (double& x : p) x *= 4;
  add_cube(m, 0.1, 0.05, 0);
  const PatchSet ps = packed_set(m);
  const SelfIntersectionReport r = find_self_intersections(ps);
  ASSERT_EQ(r.overlaps.size(), 1u);
  EXPECT_TRUE(r.overlaps[0].inside);
  EXPECT_EQ(r.overlaps[0].component_a, 1);
  EXPECT_EQ(r.overlaps[0].component_b, 0);
  EXPECT_TRUE(r.self.empty());
  EXPECT_TRUE(occt_self_interference(ps).faulty);
}

TEST(SelfIntersection, DentedTorusIsFlaggedOnFacesOcctNames) {
  for (const bool packed : {true, false}) {
    SCOPED_TRACE(packed ? "packed" : "per quad");
    const MeshInput cage = torus_cage(8, 6, 2.0, 0.7, -3.3);
    const PatchBuild b = build_patches(SubdivLevel::from_input(cage), cage.positions);
    const PatchSet ps = packed ? pack_patches(b).set : b.set;
    const SelfIntersectionReport r = find_self_intersections(ps);
    EXPECT_EQ(r.components, 1);
    EXPECT_TRUE(r.overlaps.empty());
    ASSERT_FALSE(r.self.empty());
    const OcctVerdict occt = occt_self_interference(ps);
    EXPECT_TRUE(occt.faulty);
    for (const FaceCrossing& w : r.self) {
      expect_witness_on_faces(ps, w);
      EXPECT_TRUE(occt.faces.count(w.face_a)) << w.face_a;
      EXPECT_TRUE(occt.faces.count(w.face_b)) << w.face_b;
    }
  }
}

TEST(SelfIntersection, OrdinaryTorusIsClean) {
  const PatchSet ps = packed_set(torus_cage(8, 6, 2.0, 0.8));
  EXPECT_TRUE(find_self_intersections(ps).empty());
  EXPECT_FALSE(occt_self_interference(ps).faulty);
}

/// Every edge of the cube cages in `m` infinitely sharp and every vertex a corner: the limit
/// surface is the cube itself (flat faces).
void sharpen_all(MeshInput& m) {
  for (size_t f = 0, at = 0; f < m.face_sizes.size(); at += m.face_sizes[f], ++f)
    for (int i = 0; i < m.face_sizes[f]; ++i) {
      const int a = m.face_indices[at + i], b = m.face_indices[at + (i + 1) % m.face_sizes[f]];
      if (a < b) m.creases.push_back({a, b, kInfiniteSharpness});
    }
  for (int v = 0; v < m.num_vertices(); ++v) m.corners.push_back({v, kInfiniteSharpness});
}

/// Each touching witness lies on both faces; the number of them where the surfaces are
/// parallel (the others must be on the edge of a face).
int expect_touching_witnesses(const PatchSet& ps, const std::vector<FaceCrossing>& list) {
  int parallel = 0;
  for (const FaceCrossing& w : list) {
    EXPECT_TRUE(w.touching);
    const NurbsPatch &pa = ps.patches[w.face_a], &pb = ps.patches[w.face_b];
    EXPECT_LT(distance(evaluate(pa, w.ua, w.va).p, w.point), 1e-9 * ps.model_size);
    EXPECT_LT(distance(evaluate(pb, w.ub, w.vb).p, w.point), 1e-9 * ps.model_size);
    if (std::min(w.angle_deg, 180 - w.angle_deg) < 0.06) {
      ++parallel;
      continue;
    }
    const auto on_edge = [](const NurbsPatch& p, double u, double v) {
      const double u0 = p.knots_u.knots.front(), u1 = p.knots_u.knots.back();
      const double v0 = p.knots_v.knots.front(), v1 = p.knots_v.knots.back();
      return std::min({u - u0, u1 - u, v - v0, v1 - v}) <= 1e-6 * std::max(u1 - u0, v1 - v0);
    };
    EXPECT_TRUE(on_edge(pa, w.ua, w.va) || on_edge(pb, w.ub, w.vb)) << w.face_a << " " << w.face_b;
  }
  return parallel;
}

// Sheets lying on each other without crossing: the flat valence-2 cages folded over onto
// themselves (OpenSubdiv's catmark_val2_foldover and catmark_val2_back2back), which OCCT's checker
// flags (asked here on back2back only: it takes 20 s on foldover's 110 faces), are flagged by
// ours as touching, not as crossing.
TEST(SelfIntersection, FoldedFlatSheetsTouchLikeOcct) {
  for (const char* name : {"catmark_val2_foldover", "catmark_val2_back2back"}) {
    SCOPED_TRACE(name);
    const LoadedCage cage = read_obj(std::string(SUBD2NURBS_CORPUS_DIR) + "/" + name + ".obj");
    const PatchSet ps = packed_set(cage.input);
    const SelfIntersectionReport r = find_self_intersections(ps);
    ASSERT_FALSE(r.self.empty());
    EXPECT_EQ(SelfIntersectionReport::touching_count(r.self), static_cast<long long>(r.self.size()));
    EXPECT_EQ(expect_touching_witnesses(ps, r.self), static_cast<int>(r.self.size()));  // all parallel
    EXPECT_TRUE(r.overlaps.empty());
    if (std::string(name) == "catmark_val2_back2back") EXPECT_TRUE(occt_self_interference(ps).faulty);
  }
}

// Two sharp-edged cubes side by side, one face of each on the other (shifted, so the squares
// overlap in part): touching parts, for OCCT and for us; moved 1e-3 apart, clean for both.
TEST(SelfIntersection, CubesFaceToFaceTouchLikeOcct) {
  for (const double gap : {0.0, 1e-3}) {
    SCOPED_TRACE(gap);
    MeshInput m;
    add_cube(m, 0, 0, 0);
    add_cube(m, 1 + gap, 0.3, 0.2);
    sharpen_all(m);
    const PatchSet ps = packed_set(m);
    const SelfIntersectionReport r = find_self_intersections(ps);
    EXPECT_EQ(r.components, 2);
    EXPECT_TRUE(r.self.empty());
    if (gap == 0) {
      ASSERT_FALSE(r.overlaps.empty());
      EXPECT_EQ(SelfIntersectionReport::touching_count(r.overlaps), static_cast<long long>(r.overlaps.size()));
      // The two squares on each other, and the side faces standing on the other cube's face.
      EXPECT_GE(expect_touching_witnesses(ps, r.overlaps), 1);
      for (const FaceCrossing& w : r.overlaps) EXPECT_NEAR(w.point[0], 0.5, 1e-9);
      ASSERT_EQ(r.overlapping_components.size(), 1u);
    } else {
      EXPECT_TRUE(r.empty());
    }
    EXPECT_EQ(occt_self_interference(ps).faulty, gap == 0);
  }
}

/// A double cone: two fans of n triangles around the poles (0, 0, +-1), both of valence n, round
/// the unit circle; the first `folded` vertices of the circle are moved across the axis (to -0.7
/// times their place, at height 0.3), so that the faces at the top pole there fold over the
/// faces on the other side of it and cross them.
MeshInput double_cone(int n, int folded) {
  MeshInput m;
  m.positions = {{0, 0, 1}, {0, 0, -1}};
  for (int k = 0; k < n; ++k) {
    const double a = 2 * kPi * k / n;
    m.positions.push_back(k < folded ? Point3{-0.7 * std::cos(a), -0.7 * std::sin(a), 0.3}
                                     : Point3{std::cos(a), std::sin(a), 0.0});
  }
  for (int k = 0; k < n; ++k) {
    const int a = 2 + k, b = 2 + (k + 1) % n;
    for (const std::array<int, 3> f : {std::array<int, 3>{0, a, b}, std::array<int, 3>{1, b, a}}) {
      m.face_sizes.push_back(3);
      m.face_indices.insert(m.face_indices.end(), f.begin(), f.end());
    }
  }
  return m;
}

std::set<std::pair<std::array<int, 2>, bool>> face_pairs(const std::vector<FaceCrossing>& list) {
  std::set<std::pair<std::array<int, 2>, bool>> out;
  for (const FaceCrossing& w : list) out.insert({{w.face_a, w.face_b}, w.touching});
  return out;
}

// The thin faces round a vertex of high valence are ordered by their angle around it
// (SelfIntersectionOptions::hub_valence), and groups apart in angle are not compared. The oracle
// is the check without that order: the same crossing triangle pairs and, all of them tried on
// the exact surfaces, the same pairs of faces, crossing or touching, on a double cone of valence
// 40 folded at its top pole (faces at that pole cross faces at it half a turn away) and on a
// plain one of valence 128; and far fewer triangle pairs tested.
TEST(SelfIntersection, FacesOrderedRoundAHubGiveTheSamePairs) {
  for (const bool folded : {true, false}) {
    SCOPED_TRACE(folded);
    const int n = folded ? 40 : 128;
    const PatchSet ps = packed_set(double_cone(n, folded ? 6 : 0));
    // Every candidate tried on the exact surfaces: which ones come first depends on the tree.
    SelfIntersectionOptions ordered;
    ordered.candidates_per_pair = 1 << 20;
    SelfIntersectionOptions plain = ordered;
    plain.hub_valence = 0;
    const SelfIntersectionReport a = find_self_intersections(ps, plain);
    const SelfIntersectionReport b = find_self_intersections(ps, ordered);
    EXPECT_EQ(a.hubs, 0);
    EXPECT_EQ(b.hubs, 2);
    EXPECT_EQ(face_pairs(a.self), face_pairs(b.self));
    EXPECT_EQ(face_pairs(a.overlaps), face_pairs(b.overlaps));
    EXPECT_EQ(a.candidate_pairs, b.candidate_pairs);  // every crossing triangle pair is still tested
    if (folded) {
      // Crossings between two faces at the same pole: the pairs the order could have dropped.
      int at_one_pole = 0;
      for (const FaceCrossing& w : b.self) {
        if (w.touching) continue;
        for (const int c : ps.patches[w.face_a].corners) {
          auto at = [&](const NurbsPatch& p) { return std::count(p.corners.begin(), p.corners.end(), c) > 0; };
          if (c >= 0 && at(ps.patches[w.face_b]) && std::count_if(ps.patches.begin(), ps.patches.end(), at) == n)
            ++at_one_pole;
        }
      }
      EXPECT_GE(at_one_pole, 10);
      EXPECT_LT(b.tested_pairs, 0.8 * a.tested_pairs) << a.tested_pairs << " " << b.tested_pairs;
    } else {
      EXPECT_TRUE(b.empty());
      EXPECT_LT(b.tested_pairs, 0.4 * a.tested_pairs) << a.tested_pairs << " " << b.tested_pairs;
    }
  }
}

TEST(SelfIntersection, CorpusShapesOcctFindsCleanAreClean) {
  for (const char* name : {"catmark_cube", "catmark_torus", "catmark_pyramid_creases1", "catmark_cube_creases2",
                           "catmark_helmet", "catmark_tent_creases1", "catmark_cubes_infsharp"}) {
    SCOPED_TRACE(name);
    const LoadedCage cage = read_obj(std::string(SUBD2NURBS_CORPUS_DIR) + "/" + name + ".obj");
    for (const bool packed : {true, false}) {
      const PatchBuild b = build_patches(SubdivLevel::from_input(cage.input), cage.input.positions);
      const PatchSet ps = packed ? pack_patches(b).set : b.set;
      EXPECT_FALSE(occt_self_interference(ps).faulty);
      const SelfIntersectionReport r = find_self_intersections(ps);
      EXPECT_TRUE(r.empty()) << (r.self.empty() ? r.overlaps.front().face_a : r.self.front().face_a);
    }
  }
}

}  // namespace
}  // namespace subd2nurbs
