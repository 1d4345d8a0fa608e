// The phases of the patch builder on their own:
// - local refinement (core/patch/local_mesh): a cut-out 2-ring refined alone gives exactly the
//   points the whole cage's uniform refinement gives, two levels down, with semi-sharp creases
//   of both decay rules (an edge point's rule reads the child sharpness of both halves, and
//   the Chaikin rule for the far half reads the edges at the far end: hence 2 rings, not 1);
// - knot assembly (core/patch/knot_assembly): pieces cut from one polynomial merge back into
//   16 poles; pieces of a B-spline with real knots keep exactly those knots; double knots stay.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "core/nurbs/nurbs_eval.h"
#include "core/patch/knot_assembly.h"
#include "core/patch/local_mesh.h"
#include "core/patch/patch_builder.h"
#include "io/obj_reader.h"
#include "patch/patch_test_util.h"

namespace subd2nurbs::testing {
namespace {

double dist(const Point3& a, const Point3& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

// Cuts the 2-ring of every face of the cage, refines it twice (cutting the 2-ring of the
// children in between) and compares the grandchildren's corners with the uniform refinement.
double worst_local_refinement_error(const std::string& name, int rings = 2) {
  const LoadedCage cage = read_obj(std::string(SUBD2NURBS_CORPUS_DIR) + "/" + name + ".obj");
  const SubdivLevel base = SubdivLevel::from_input(cage.input);
  const std::vector<Point3> x0(cage.input.positions.begin(), cage.input.positions.end());
  const Refinement r = refine_uniform(base, 2);
  const std::vector<std::vector<Point3>> X = r.positions(x0);
  const PolyMesh& m0 = base.mesh;
  const PolyMesh& m1 = r.levels[1].mesh;
  const PolyMesh& m2 = r.levels[2].mesh;
  double worst = 0;
  for (int F = 0; F < m0.num_faces(); ++F) {
    const std::vector<int> faces = face_rings(m0, vertices_of(m0, {F}), rings);
    const int local_F = static_cast<int>(std::lower_bound(faces.begin(), faces.end(), F) - faces.begin());
    const LocalMesh piece0 = cut_out(base, x0, faces);
    const LocalMesh piece1 = refine_piece(piece0);
    // Children of F: face index = corner index, in the whole level and in the piece.
    std::vector<int> children_local, children_global;
    for (int k = 0; k < m0.face_size(F); ++k) {
      children_local.push_back(piece0.level.mesh.face_begin(local_F) + k);
      children_global.push_back(m0.face_begin(F) + k);
    }
    const std::vector<int> faces1 = face_rings(piece1.level.mesh, vertices_of(piece1.level.mesh, children_local), rings);
    const LocalMesh cut1 = cut_out(piece1, faces1);
    const LocalMesh piece2 = refine_piece(cut1);
    for (size_t c = 0; c < children_local.size(); ++c) {
      const int local1 = static_cast<int>(std::lower_bound(faces1.begin(), faces1.end(), children_local[c]) - faces1.begin());
      for (int k = 0; k < 4; ++k) {
        const int g_face = m1.face_begin(children_global[c]) + k;  // grandchild, whole level 2
        const int l_face = cut1.level.mesh.face_begin(local1) + k;  // grandchild, in the piece
        for (int j = 0; j < 4; ++j) {
          const Point3& g = X[2][m2.corner_vertex(m2.face_begin(g_face) + j)];
          const Point3& l = piece2.x[piece2.level.mesh.corner_vertex(piece2.level.mesh.face_begin(l_face) + j)];
          worst = std::max(worst, dist(g, l));
        }
      }
    }
  }
  return worst;
}

TEST(LocalRefinement, CutOutTwoRingsRefineLikeTheWholeCage) {
  // Uniform and Chaikin semi-sharp creases, boundaries, n-gons, an extraordinary vertex.
  for (const char* name : {"catmark_chaikin1", "catmark_torus_creases1", "catmark_nonquads", "catmark_edgecorner",
                           "catmark_cube_creases1", "catmark_xord_interior", "catmark_chaikin2",
                           "catmark_helmet"}) {
    SCOPED_TRACE(name);
    EXPECT_LT(worst_local_refinement_error(name), 1e-14);
  }
}

// cut_out assembles the piece's connectivity from the source's (twins, fans) instead of
// searching for it. Oracle: PolyMesh::build of the piece's own face list, compared array by
// array, on rings around vertices and on scattered face sets (vertices split into several runs,
// n-gons, boundaries, and pieces of pieces).
TEST(CutOut, ConnectivityIsPolyMeshBuildOfItsFaces) {
  auto same = [](const PolyMesh& a, const PolyMesh& b) {
    if (a.num_vertices() != b.num_vertices() || a.num_faces() != b.num_faces() || a.num_edges() != b.num_edges() ||
        a.num_corners() != b.num_corners() || a.all_quads() != b.all_quads())
      return false;
    for (int h = 0; h < a.num_corners(); ++h)
      if (a.corner_vertex(h) != b.corner_vertex(h) || a.corner_face(h) != b.corner_face(h) ||
          a.corner_edge(h) != b.corner_edge(h) || a.twin(h) != b.twin(h))
        return false;
    for (int e = 0; e < a.num_edges(); ++e)
      if (a.edge_corner(e) != b.edge_corner(e)) return false;
    for (int v = 0; v < a.num_vertices(); ++v) {
      if (a.vertex_face_count(v) != b.vertex_face_count(v)) return false;
      for (int i = 0; i < a.vertex_face_count(v); ++i)
        if (a.vertex_corners(v)[i] != b.vertex_corners(v)[i]) return false;
    }
    return true;
  };
  auto rebuilt = [](const PolyMesh& p) {
    std::vector<int> sizes, indices;
    for (int f = 0; f < p.num_faces(); ++f) {
      sizes.push_back(p.face_size(f));
      for (int h = p.face_begin(f); h < p.face_end(f); ++h) indices.push_back(p.corner_vertex(h));
    }
    return PolyMesh::build(p.num_vertices(), sizes, indices);
  };
  int pieces = 0, split_vertices = 0;
  for (const char* name : {"catmark_nonquads", "catmark_edgecorner", "catmark_helmet", "catmark_bishop",
                           "catmark_xord_interior"}) {
    SCOPED_TRACE(name);
    const LoadedCage cage = read_obj(std::string(SUBD2NURBS_CORPUS_DIR) + "/" + name + ".obj");
    const SubdivLevel base = SubdivLevel::from_input(cage.input);
    const std::vector<Point3> x0(cage.input.positions.begin(), cage.input.positions.end());
    const PolyMesh& m = base.mesh;
    for (int v = 0; v < m.num_vertices(); v += 3) {
      if (m.is_unused_vertex(v)) continue;
      // Rings around v, and every other face of its 2-ring (scattered: vertices split).
      std::vector<int> scattered;
      const std::vector<int> ring2 = face_rings(m, {v}, 2);
      for (size_t i = 0; i < ring2.size(); i += 2) scattered.push_back(ring2[i]);
      for (const std::vector<int>& faces : {face_rings(m, {v}, 1), ring2, face_rings(m, {v}, 3), scattered}) {
        const LocalMesh piece = cut_out(base, x0, faces);
        ASSERT_TRUE(same(piece.level.mesh, rebuilt(piece.level.mesh))) << "vertex " << v;
        ++pieces;
        split_vertices += piece.level.mesh.num_vertices() - static_cast<int>(vertices_of(m, faces).size());
        // A piece of the piece, after a refinement.
        const LocalMesh refined = refine_piece(piece);
        const std::vector<int> inner = face_rings(refined.level.mesh, {0}, 2);
        const LocalMesh again = cut_out(refined, inner);
        ASSERT_TRUE(same(again.level.mesh, rebuilt(again.level.mesh))) << "vertex " << v << ", refined";
      }
    }
  }
  EXPECT_GT(pieces, 100);
  EXPECT_GT(split_vertices, 0);  // the scattered sets did split vertices into runs
}

// A bicubic polynomial (Bezier net on [0,1]^2) restricted to [u0, u0 + s] x [v0, v0 + s].
PatchLeaf sub_leaf(const std::array<Point3, 16>& net, double u0, double v0, double s) {
  PatchLeaf l;
  l.u0 = u0;
  l.v0 = v0;
  l.size = s;
  // The restriction's Bezier points: blossoms at (a, a, a), (a, a, b), (a, b, b), (b, b, b).
  auto blossom_1d = [](const double args[3], double w[4]) {
    w[0] = 1;
    w[1] = w[2] = w[3] = 0;
    for (int k = 0; k < 3; ++k) {
      const double t = args[k];
      for (int q = k + 1; q >= 0; --q) w[q] = (q <= k ? w[q] * (1 - t) : 0) + (q > 0 ? w[q - 1] * t : 0);
    }
  };
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      double au[3], av[3];
      for (int k = 0; k < 3; ++k) {
        au[k] = u0 + (k < 3 - i ? 0 : s);
        av[k] = v0 + (k < 3 - j ? 0 : s);
      }
      double wu[4], wv[4];
      blossom_1d(au, wu);
      blossom_1d(av, wv);
      Point3 p{0, 0, 0};
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b)
          for (int d = 0; d < 3; ++d) p[d] += wu[a] * wv[b] * net[a * 4 + b][d];
      l.net[i * 4 + j] = p;
    }
  return l;
}

std::array<Point3, 16> some_net() {
  std::array<Point3, 16> net;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      net[i * 4 + j] = {i + 0.1 * j * j, j - 0.2 * i * j, std::sin(1.0 + i) * std::cos(0.5 * j)};
  return net;
}

TEST(KnotAssembly, PiecesOfOnePolynomialMergeBackIntoSixteenPoles) {
  const std::array<Point3, 16> net = some_net();
  // A quadtree: a quarter split twice more towards the corner (0, 0).
  std::vector<PatchLeaf> leaves;
  for (const auto& q : std::vector<std::array<double, 3>>{{0.5, 0, 0.5}, {0, 0.5, 0.5}, {0.5, 0.5, 0.5},
                                                          {0.25, 0, 0.25}, {0, 0.25, 0.25}, {0.25, 0.25, 0.25},
                                                          {0, 0, 0.125}, {0.125, 0, 0.125}, {0, 0.125, 0.125},
                                                          {0.125, 0.125, 0.125}})
    leaves.push_back(sub_leaf(net, q[0], q[1], q[2]));
  NurbsPatch patch;
  const AssemblyStats st = assemble_patch(leaves, {}, {}, 1e-14, 1e-13, patch);
  EXPECT_EQ(patch.num_poles_u, 4);
  EXPECT_EQ(patch.num_poles_v, 4);
  EXPECT_EQ(st.removed_knots, 6);  // 1/8, 1/4, 1/2 in each direction
  for (int i = 0; i < 16; ++i) EXPECT_LT(dist(patch.poles[i], net[i]), 1e-14);
}

TEST(KnotAssembly, RealKnotsAndZoneKnotsStay) {
  // Two different polynomials left and right of u = 1/2 joined C2: a cubic B-spline with one
  // interior knot, cut into pieces. The knot at 1/2 stays, the piece boundaries at 1/4, 3/4
  // and v = 1/2 go; a double knot requested at v = 1/4 (a zone line) stays double.
  NurbsPatch spline;
  spline.knots_u = {{0, 0.5, 1}, {4, 1, 4}, false};
  spline.knots_v = {{0, 1}, {4, 4}, false};
  spline.num_poles_u = 5;
  spline.num_poles_v = 4;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 4; ++j) spline.poles.push_back({double(i), double(j), (i == 2 ? 1.0 : 0.0) + 0.1 * i * j});
  // Pieces: squares of 1/4, each the spline's polynomial there (interpolated at 4 x 4 points).
  std::vector<PatchLeaf> leaves;
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b) {
      PatchLeaf l;
      l.u0 = a * 0.25;
      l.v0 = b * 0.25;
      l.size = 0.25;
      // Interpolate the spline's polynomial on this square (it is one polynomial there).
      const double t[4] = {0.0, 1.0 / 3, 2.0 / 3, 1.0};
      Point3 s[4][4];
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) s[i][j] = evaluate(spline, l.u0 + t[i] * l.size, l.v0 + t[j] * l.size).p;
      // Inverse of the Bernstein matrix at 0, 1/3, 2/3, 1.
      const double Bi[4][4] = {{1, 0, 0, 0}, {-5.0 / 6, 3, -3.0 / 2, 1.0 / 3}, {1.0 / 3, -3.0 / 2, 3, -5.0 / 6}, {0, 0, 0, 1}};
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
          Point3 p{0, 0, 0};
          for (int x = 0; x < 4; ++x)
            for (int y = 0; y < 4; ++y)
              for (int d = 0; d < 3; ++d) p[d] += Bi[i][x] * Bi[j][y] * s[x][y][d];
          l.net[i * 4 + j] = p;
        }
      leaves.push_back(l);
    }
  NurbsPatch patch;
  assemble_patch(leaves, {}, {0.25}, 1e-13, 1e-12, patch);
  EXPECT_EQ(patch.knots_u.knots, (std::vector<double>{0, 0.5, 1}));
  EXPECT_EQ(patch.knots_u.mults, (std::vector<int>{4, 1, 4}));
  EXPECT_EQ(patch.knots_v.knots, (std::vector<double>{0, 0.25, 1}));
  EXPECT_EQ(patch.knots_v.mults, (std::vector<int>{4, 2, 4}));
  for (double u : {0.0, 0.1, 0.37, 0.5, 0.81, 1.0})
    for (double v : {0.0, 0.2, 0.6, 1.0}) EXPECT_LT(dist(evaluate(patch, u, v).p, evaluate(spline, u, v).p), 1e-13);
}

}  // namespace
}  // namespace subd2nurbs::testing

namespace subd2nurbs::testing {
namespace {

TEST(PatchReuse, RebuildingOnlyTheDeepenedCornersGivesTheSamePatches) {
  // A tolerance rebuilds with more levels at some vertices, reusing the other quads: the result
  // must equal a build from scratch with the same levels, pole for pole.
  const LoadedCage cage = read_obj(std::string(SUBD2NURBS_CORPUS_DIR) + "/catmark_xord_interior.obj");
  const SubdivLevel base = SubdivLevel::from_input(cage.input);
  const std::vector<Point3> x(cage.input.positions.begin(), cage.input.positions.end());
  const PatchBuild first = build_patches(base, x);
  ASSERT_FALSE(first.info.fans.empty());
  PatchOptions deeper;
  deeper.vertex_extra_levels.assign(base.mesh.num_vertices(), 0);
  deeper.vertex_extra_levels[first.info.fans[0].vertex] = 2;
  const PatchBuild scratch = build_patches(base, x, deeper);
  deeper.reuse = &first;
  const PatchBuild reused = build_patches(base, x, deeper);
  ASSERT_EQ(scratch.set.patches.size(), reused.set.patches.size());
  int changed = 0;
  for (size_t i = 0; i < scratch.set.patches.size(); ++i) {
    EXPECT_EQ(scratch.set.patches[i].poles, reused.set.patches[i].poles) << "patch " << i;
    EXPECT_EQ(scratch.set.patches[i].base_faces, reused.set.patches[i].base_faces) << "patch " << i;
    changed += scratch.set.patches[i].poles != first.set.patches[i].poles;
  }
  EXPECT_GT(changed, 0);  // the deepened vertex's quads did change
  EXPECT_EQ(scratch.info.total_poles, reused.info.total_poles);
  EXPECT_EQ(scratch.info.removed_knots, reused.info.removed_knots);
}

}  // namespace
}  // namespace subd2nurbs::testing

namespace subd2nurbs::testing {
namespace {

// A wavy n-gon (an open disc whose rim goes up and down), a prism with wavy n-gon caps (closed;
// rim vertices of valence 3 next to the caps' centres) and a bipyramid (two triangle fans: the
// poles of valence n at level 1), with a semi-sharp crease on one spoke of the prism's cap.
MeshInput wavy_ngon(int n) {
  MeshInput in;
  for (int k = 0; k < n; ++k) {
    const double t = 2 * M_PI * k / n;
    in.positions.push_back({std::cos(t), std::sin(t), 0.2 * std::sin(3 * t)});
  }
  in.face_sizes = {n};
  for (int k = 0; k < n; ++k) in.face_indices.push_back(k);
  return in;
}

MeshInput wavy_prism(int n) {
  MeshInput in;
  for (int z = 0; z < 2; ++z)
    for (int k = 0; k < n; ++k) {
      const double t = 2 * M_PI * k / n;
      in.positions.push_back({std::cos(t), std::sin(t), z + 0.15 * std::sin(5 * t)});
    }
  in.face_sizes = {n, n};
  for (int k = n; k-- > 0;) in.face_indices.push_back(k);
  for (int k = 0; k < n; ++k) in.face_indices.push_back(n + k);
  for (int k = 0; k < n; ++k) {
    const int a = k, b = (k + 1) % n;
    in.face_sizes.push_back(4);
    for (int v : {a, b, b + n, a + n}) in.face_indices.push_back(v);
  }
  in.creases.push_back({0, 1, 1.5});  // a semi-sharp rim edge: deeper pieces at one sector
  return in;
}

MeshInput bipyramid(int n) {
  MeshInput in;
  in.positions = {{0, 0, 1}, {0, 0, -1}};
  for (int k = 0; k < n; ++k) {
    const double t = 2 * M_PI * k / n;
    in.positions.push_back({std::cos(t), std::sin(t), 0.1 * std::cos(4 * t)});
  }
  for (int k = 0; k < n; ++k) {
    const int a = 2 + k, b = 2 + (k + 1) % n;
    in.face_sizes.push_back(3);
    for (int v : {0, a, b}) in.face_indices.push_back(v);
    in.face_sizes.push_back(3);
    for (int v : {1, b, a}) in.face_indices.push_back(v);
  }
  return in;
}

// The quads at a vertex of high valence are refined in one shared piece per vertex
// (PatchOptions::shared_piece_valence, O(n L)); the reference is the per-quad definition (each
// quad's own piece, O(n^2 L)): every leaf and every pole must be the same number. Fans deepened
// by 3 extra levels, so that the shared piece is refined several levels down.
TEST(SharedPieces, HighValenceQuadsBuiltTogetherGiveThePiecesOfTheirOwnPieces) {
  for (const auto& [name, in] : {std::pair<std::string, MeshInput>{"wavy 40-gon", wavy_ngon(40)},
                                 {"prism with wavy 40-gon caps", wavy_prism(40)},
                                 {"bipyramid of valence 24", bipyramid(24)}}) {
    SCOPED_TRACE(name);
    const SubdivLevel base = SubdivLevel::from_input(in);
    PatchOptions shared, own;
    shared.extra_levels = own.extra_levels = 3;
    own.shared_piece_valence = 1 << 30;
    ASSERT_LT(shared.shared_piece_valence, 24);
    const PatchBuild a = build_patches(base, in.positions, shared);
    const PatchBuild b = build_patches(base, in.positions, own);
    ASSERT_EQ(a.leaves.size(), b.leaves.size());
    long long zone_leaves = 0, deep_leaves = 0;
    for (size_t pi = 0; pi < a.leaves.size(); ++pi) {
      ASSERT_EQ(a.leaves[pi].size(), b.leaves[pi].size()) << "patch " << pi;
      EXPECT_EQ(a.patch_deepest[pi], b.patch_deepest[pi]) << "patch " << pi;
      for (size_t k = 0; k < a.leaves[pi].size(); ++k) {
        const PatchLeaf &x = a.leaves[pi][k], &y = b.leaves[pi][k];
        EXPECT_EQ(x.u0, y.u0);
        EXPECT_EQ(x.v0, y.v0);
        EXPECT_EQ(x.size, y.size);
        EXPECT_EQ(x.level, y.level);
        EXPECT_EQ(x.zone, y.zone);
        EXPECT_EQ(x.net, y.net) << "patch " << pi << " leaf " << k;
        zone_leaves += x.zone;
        deep_leaves += x.level >= b.info.coarse_level + 4;
      }
    }
    EXPECT_GT(zone_leaves, 0);
    EXPECT_GT(deep_leaves, 0);
    ASSERT_EQ(a.set.patches.size(), b.set.patches.size());
    for (size_t pi = 0; pi < a.set.patches.size(); ++pi) {
      EXPECT_EQ(a.set.patches[pi].poles, b.set.patches[pi].poles) << "patch " << pi;
      EXPECT_EQ(a.set.patches[pi].knots_u.knots, b.set.patches[pi].knots_u.knots) << "patch " << pi;
      EXPECT_EQ(a.set.patches[pi].knots_v.knots, b.set.patches[pi].knots_v.knots) << "patch " << pi;
    }
    // And against the exact limit (core/limit, Stam's eigenbases): the regular pieces are it.
    EXPECT_LT(max_corner_limit_error(a), 1e-11 * a.set.model_size);
    EXPECT_LT(max_piece_error(a), 1e-11 * a.set.model_size);
  }
}

}  // namespace
}  // namespace subd2nurbs::testing
