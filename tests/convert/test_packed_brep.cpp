// Packed faces through OCCT, on shapes made for packing: creases across a grid, T-junctions on
// both sides of an edge, an open tube (a seam), a pack next to polar caps. Oracles: OCCT's
// checker and its own measures (free edges, solids, area and volume integrated to 1e-12), the
// per-quad B-rep of the same patches, and the crease lines packs must not cross.
#include <gtest/gtest.h>

#include <BRepBndLib.hxx>
#include <BRepClass_FaceClassifier.hxx>
#include <Bnd_Box.hxx>
#include <BRep_Tool.hxx>
#include <Geom_Plane.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "common/shapes.h"
#include "converter/occt/brep_builder.h"
#include "converter/occt/shape_check.h"
#include "core/patch/packing.h"
#include "core/patch/planar_faces.h"
#include "core/nurbs/nurbs_eval.h"
#include "core/util/tolerances.h"
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

// --- planar faces (BrepOptions::merge_planar, core/patch/planar_faces.h) ----------------------

/// The box [0, a] x [0, b] x [0, c] with n x n quads on each side, outward, its 12 edges
/// infinitely sharp and its 8 corners sharp: its limit surface is exactly the box.
MeshInput creased_box(int n, double a, double b, double c) {
  MeshInput m;
  std::map<std::array<int, 3>, int> id;
  auto vertex = [&](std::array<int, 3> g) {
    auto [it, added] = id.emplace(g, static_cast<int>(m.positions.size()));
    if (added) m.positions.push_back({a * g[0] / n, b * g[1] / n, c * g[2] / n});
    return it->second;
  };
  for (int d = 0; d < 3; ++d)
    for (int side : {0, n}) {
      const int u = (d + 1) % 3, w = (d + 2) % 3;  // e_u x e_w = e_d
      for (int p = 0; p < n; ++p)
        for (int q = 0; q < n; ++q) {
          std::array<int, 4> f;
          const int pu[4] = {p, p + 1, p + 1, p}, qw[4] = {q, q, q + 1, q + 1};
          for (int k = 0; k < 4; ++k) {
            std::array<int, 3> g{};
            g[d] = side;
            g[u] = pu[k];
            g[w] = qw[k];
            f[k] = vertex(g);
          }
          if (side == 0) add_face(m, {f[0], f[3], f[2], f[1]});
          else add_face(m, {f[0], f[1], f[2], f[3]});
        }
    }
  auto on_edge = [&](const std::array<int, 3>& g, int axis) {
    for (int e = 0; e < 3; ++e)
      if (e != axis && g[e] != 0 && g[e] != n) return false;
    return true;
  };
  for (const auto& [g, v] : id) {
    int ends = 0;
    for (int e = 0; e < 3; ++e) ends += g[e] == 0 || g[e] == n;
    if (ends == 3) m.corners.push_back({v, kInfiniteSharpness});
    for (int axis = 0; axis < 3; ++axis) {
      if (!on_edge(g, axis) || g[axis] == n) continue;
      std::array<int, 3> h = g;
      ++h[axis];
      m.creases.push_back({v, id.at(h), kInfiniteSharpness});
    }
  }
  return m;
}

int plane_faces(const TopoDS_Shape& shape) {
  int planes = 0;
  for (TopExp_Explorer x(shape, TopAbs_FACE); x.More(); x.Next())
    planes += !Handle(Geom_Plane)::DownCast(BRep_Tool::Surface(TopoDS::Face(x.Current()))).IsNull();
  return planes;
}

TEST(PlanarFaces, CreasedBoxIsSixPlanes) {
  const double a = 2, b = 3, c = 5;
  const PatchBuild build_ = build(creased_box(4, a, b, c));
  const PackedSet packed = pack_patches(build_);
  const PlanarFaces planar = find_planar_faces(packed.set, tolerances::kSameSurface);
  ASSERT_EQ(planar.faces.size(), 6u);
  EXPECT_EQ(planar.skipped, 0);
  for (const PlanarFace& f : planar.faces) {
    EXPECT_EQ(f.loops.size(), 1u);
    // Its normal is an axis, pointing out of the box, and its origin on that side.
    int axis = 0;
    for (int d = 1; d < 3; ++d)
      if (std::abs(f.normal[d]) > std::abs(f.normal[axis])) axis = d;
    EXPECT_NEAR(std::abs(f.normal[axis]), 1.0, 1e-14);
    const double side = f.normal[axis] > 0 ? std::array<double, 3>{a, b, c}[axis] : 0.0;
    EXPECT_NEAR(f.origin[axis], side, 1e-13);
  }
  occt::BrepOptions merge;
  merge.merge_planar = true;
  const occt::BrepResult r = occt::build_brep(packed.set, {}, merge);
  ASSERT_TRUE(r.valid) << r.check_message;
  EXPECT_TRUE(r.is_solid);
  EXPECT_EQ(r.num_faces, 6);
  EXPECT_EQ(r.planar_faces, 6);
  EXPECT_EQ(r.merged_patches, static_cast<int>(packed.set.patches.size()));
  EXPECT_EQ(plane_faces(r.shape), 6);
  const occt::ShapeSummary s = occt::summarize(r.shape, 8);
  EXPECT_EQ(s.free_edges, 0);
  EXPECT_NEAR(s.volume, a * b * c, 1e-12 * a * b * c);               // the box, exactly
  EXPECT_NEAR(s.area, 2 * (a * b + b * c + c * a), 1e-12 * a * b * c);
  EXPECT_NEAR(s.max_normal_angle_deg, 90.0, 1e-9);
}

TEST(PlanarFaces, FlatSheetWithAHoleIsOneFaceWithTwoWires) {
  // A flat 8 x 8 grid with its middle 2 x 2 quads removed: one planar face, outer loop and hole.
  MeshInput in = grid(8, 8);
  for (Point3& p : in.positions) p[2] = 0.25 * p[0] - 0.5 * p[1] + 1;  // a tilted plane
  for (int j = 3; j < 5; ++j)
    for (int i = 3; i < 5; ++i) in.holes.push_back(j * 8 + i);
  const PatchBuild b = build(in);
  const PackedSet packed = pack_patches(b);
  const PlanarFaces planar = find_planar_faces(packed.set, tolerances::kSameSurface);
  ASSERT_EQ(planar.faces.size(), 1u);
  EXPECT_EQ(planar.faces[0].loops.size(), 2u);
  const Point3 n = planar.faces[0].normal;  // (-0.25, 0.5, 1) normalized, the grid's side
  const double len = std::sqrt(0.25 * 0.25 + 0.5 * 0.5 + 1);
  EXPECT_NEAR(n[0], -0.25 / len, 1e-14);
  EXPECT_NEAR(n[1], 0.5 / len, 1e-14);
  EXPECT_NEAR(n[2], 1 / len, 1e-14);
  occt::BrepOptions merge;
  merge.merge_planar = true;
  const occt::BrepResult r = occt::build_brep(packed.set, {}, merge), q = occt::build_brep(packed.set);
  ASSERT_TRUE(r.valid) << r.check_message;
  EXPECT_EQ(r.num_faces, 1);
  EXPECT_EQ(plane_faces(r.shape), 1);
  int wires = 0;
  for (TopExp_Explorer x(r.shape, TopAbs_WIRE); x.More(); x.Next()) ++wires;
  EXPECT_EQ(wires, 2);
  // The same region of the plane as the B-spline faces it replaces.
  const occt::ShapeSummary s = occt::summarize(r.shape, 8), sq = occt::summarize(q.shape, 8);
  EXPECT_NEAR(s.area, sq.area, 1e-9 * sq.area);
  EXPECT_EQ(s.free_edges, sq.free_edges);
}

TEST(PlanarFaces, CurvedSurfacesAreNotMerged) {
  // The grid's sin-bumps and a torus: no patch is planar, nothing changes.
  for (const MeshInput& in : {grid(6, 5), torus(12, 8)}) {
    const PatchBuild b = build(in);
    const PackedSet packed = pack_patches(b);
    const PlanarFaces planar = find_planar_faces(packed.set, tolerances::kSameSurface);
    EXPECT_EQ(planar.faces.size(), 0u);
    EXPECT_EQ(planar.planar_patches, 0);
  }
}

TEST(PlanarFaces, OverlapInThePlaneIsLeftOutNotTheWholeSet) {
  // A flat 10 x 10 sheet with one inner vertex pulled past its neighbours so far that patches
  // around it turn over whole (their normals point the other way): they are no part of the
  // sheet's coplanar set, which then has loops that cross round them. BRepCheck refuses such a
  // set's planar face (SelfIntersectingWire); all its patches used to be written one by one. Now
  // the patches along the crossings are left out and the rest is merged. Oracles: OCCT's
  // checker, and OCCT's face classifier: every point of every patch lies in a face of the result.
  for (const Point3 moved : {Point3{7.2, 5.5, 0}, Point3{4, -1.5, 0}}) {
    MeshInput in = grid(10, 10);
    for (Point3& p : in.positions) p[2] = 0;
    in.positions[4 * 11 + 4] = moved;  // vertex (4, 4)
    const PatchBuild b = build(in);    // one patch per quad (packed, the flat grid is one face)
    const PatchSet& set = b.set;
    // The sheet's set (its lowest patch's) has loops that cross; its parts leave the crossing curves out.
    const PlanarFaces planar = find_planar_faces(set, tolerances::kSameSurface);
    ASSERT_GE(planar.faces.size(), 1u);
    ASSERT_EQ(planar.faces[0].patches.front(), 0);
    const std::vector<int> crossing = crossing_curves(set, planar.faces[0]);
    EXPECT_FALSE(crossing.empty());
    const std::vector<PlanarFace> parts = split_planar_face(set, planar.faces[0]);
    ASSERT_GE(parts.size(), 1u);
    for (const PlanarFace& part : parts)
      for (int p : part.patches)
        for (int side = 0; side < 4; ++side)
          EXPECT_EQ(std::count(crossing.begin(), crossing.end(), set.patches[p].curves[side]), 0);
    occt::BrepOptions merge;
    merge.merge_planar = true;
    const occt::BrepResult r = occt::build_brep(set, {}, merge);
    ASSERT_TRUE(r.valid) << r.check_message;
    // The turned-over patches are a set of their own facing the other way, which OCCT may refuse
    // (then written patch by patch); the sheet's set is split, not refused.
    EXPECT_LE(r.rejected_planar_faces, static_cast<int>(planar.faces.size()) - 1);
    EXPECT_GE(r.split_planar_sets, 1);
    EXPECT_GE(r.planar_faces, 1);
    EXPECT_LT(r.num_faces, 20) << "of " << set.patches.size() << " patches";  // most of the sheet is one plane
    std::vector<TopoDS_Face> result_faces;
    std::vector<Bnd_Box> boxes;
    for (TopExp_Explorer x(r.shape, TopAbs_FACE); x.More(); x.Next()) {
      result_faces.push_back(TopoDS::Face(x.Current()));
      boxes.emplace_back();
      BRepBndLib::Add(result_faces.back(), boxes.back());
      boxes.back().Enlarge(1e-6);
    }
    int outside = 0;
    for (const NurbsPatch& patch : set.patches)
      for (double u : {0.25, 0.5, 0.75})
        for (double v : {0.25, 0.5, 0.75}) {
          const Point3 x = evaluate(patch, u, v).p;
          bool in_a_face = false;
          for (size_t k = 0; k < result_faces.size() && !in_a_face; ++k) {
            if (boxes[k].IsOut(gp_Pnt(x[0], x[1], x[2]))) continue;
            BRepClass_FaceClassifier c(result_faces[k], gp_Pnt(x[0], x[1], x[2]), 1e-7);
            in_a_face = in_a_face || c.State() == TopAbs_IN || c.State() == TopAbs_ON;
          }
          outside += !in_a_face;
        }
    EXPECT_EQ(outside, 0);
  }
}

// A fold inside a coplanar set (core/patch/planar_faces.h): a flat 10 x 10 sheet with one inner
// vertex pulled past its neighbours, not so far that a patch turns over whole. The patches round
// it fold over one another in the plane, the sheet's loops (made of its boundary vertices alone)
// stay as they were, and every point they enclose is covered (its winding number is 1), so the
// planar face is that region, covered once, and the whole sheet is one face. Oracles: the flat
// sheet (the vertex not moved) has the same loops, so the folded sheet's planar face has its area
// and classifies every point as it does (OCCT's face classifier on both); the points of a flap
// pulled out past the boundary ((1, 5) moved to x = -1.5) are outside both.
TEST(PlanarFaces, FoldInsideTheSetIsOneFaceOfItsRegion) {
  MeshInput flat = grid(10, 10);
  for (Point3& p : flat.positions) p[2] = 0;
  occt::BrepOptions merge;
  merge.merge_planar = true;
  const PatchBuild flat_build = build(flat);
  const occt::BrepResult plain = occt::build_brep(flat_build.set, {}, merge);
  ASSERT_TRUE(plain.valid) << plain.check_message;
  ASSERT_EQ(plain.num_faces, 1);
  EXPECT_EQ(plain.folded_planar_patches, 0);
  TopExp_Explorer plain_face(plain.shape, TopAbs_FACE);
  const double plain_area = occt::summarize(plain.shape, 8).area;
  struct Move {
    int vertex;
    Point3 to;
    bool flap;  // some of the surface lies out past the boundary
  };
  for (const Move m : {Move{4 * 11 + 4, {7.2, 4.8, 0}, false}, Move{5 * 11 + 1, {-1.5, 5, 0}, true}}) {
    MeshInput in = flat;
    in.positions[m.vertex] = m.to;
    const PatchBuild b = build(in);
    const PlanarFaces planar = find_planar_faces(b.set, tolerances::kSameSurface);
    ASSERT_EQ(planar.faces.size(), 1u);
    EXPECT_EQ(planar.faces[0].patches.size(), b.set.patches.size());
    EXPECT_TRUE(crossing_curves(b.set, planar.faces[0]).empty());
    const occt::BrepResult r = occt::build_brep(b.set, {}, merge);
    ASSERT_TRUE(r.valid) << r.check_message;
    EXPECT_EQ(r.num_faces, 1);
    EXPECT_EQ(r.planar_faces, 1);
    EXPECT_EQ(r.split_planar_sets, 0);
    EXPECT_GE(r.folded_planar_patches, 1);
    EXPECT_NEAR(occt::summarize(r.shape, 8).area, plain_area, 1e-9 * plain_area);
    TopExp_Explorer face(r.shape, TopAbs_FACE);
    int differ = 0, outside = 0, samples = 0;
    for (const NurbsPatch& patch : b.set.patches)
      for (double u : {0.1, 0.3, 0.5, 0.7, 0.9})
        for (double v : {0.1, 0.3, 0.5, 0.7, 0.9}) {
          const Point3 x = evaluate(patch, u, v).p;
          const gp_Pnt q(x[0], x[1], x[2]);
          const bool in_face = BRepClass_FaceClassifier(TopoDS::Face(face.Current()), q, 1e-7).State() != TopAbs_OUT;
          const bool in_plain = BRepClass_FaceClassifier(TopoDS::Face(plain_face.Current()), q, 1e-7).State() != TopAbs_OUT;
          differ += in_face != in_plain;
          outside += !in_face;
          ++samples;
        }
    std::printf("  vertex %d moved: %d folded patches, %d of %d samples out past the boundary\n", m.vertex,
                r.folded_planar_patches, outside, samples);
    EXPECT_EQ(differ, 0);
    if (m.flap) EXPECT_GT(outside, 0);
    else EXPECT_EQ(outside, 0);
  }
}

}  // namespace
