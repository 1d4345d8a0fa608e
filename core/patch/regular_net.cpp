#include "core/patch/regular_net.h"

#include "core/refine/quad_grid.h"

namespace subd2nurbs {

namespace {

using V3 = Eigen::Vector3d;

const double kM[4][4] = {{1.0 / 6, 4.0 / 6, 1.0 / 6, 0},
                         {0, 4.0 / 6, 2.0 / 6, 0},
                         {0, 2.0 / 6, 4.0 / 6, 0},
                         {0, 1.0 / 6, 4.0 / 6, 1.0 / 6}};

}  // namespace

// Bezier net (face frame) of a quad whose four corners are regular for it: its B-spline grid
// (gather_quad_grid; the diagonal point at each corner whose two sides are open, which for a
// regular corner is a smooth valence-4 one), then B = M G M^T.
void regular_net(const LevelView& L, int f, Point3* net) {
  const PolyMesh& m = L.m;
  const int h0 = m.face_begin(f);
  bool open[4];
  for (int i = 0; i < 4; ++i) open[i] = !L.sharp(m.corner_edge(h0 + i));
  const bool diagonal[4] = {open[0] && open[3], open[1] && open[0], open[2] && open[1], open[3] && open[2]};
  QuadGrid g;
  gather_quad_grid(L.level, L.x, f, diagonal, g);
  V3 T[4][4];
  for (int i = 0; i < 4; ++i)
    for (int b = 0; b < 4; ++b) {
      T[i][b] = V3::Zero();
      for (int a = 0; a < 4; ++a) T[i][b] += kM[i][a] * to_eigen(g.at(a - 1, b - 1));
    }
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      V3 s = V3::Zero();
      for (int b = 0; b < 4; ++b) s += kM[j][b] * T[i][b];
      net[i * 4 + j] = to_point(s);
    }
}

bool is_regular_leaf(const LevelView& L, int f) {
  const PolyMesh& m = L.m;
  if (m.face_size(f) != 4) return false;
  auto semi = [](float s) { return s > 0.0f && s < static_cast<float>(kInfiniteSharpness); };
  for (int h = m.face_begin(f); h < m.face_end(f); ++h) {
    const int v = m.corner_vertex(h);
    if (semi(L.level.vertex_sharpness[v])) return false;
    bool semi_edge = false;
    for_each_vertex_edge(m, v, [&](int e, int) { semi_edge = semi_edge || semi(L.level.edge_sharpness[e]); });
    if (semi_edge || !L.regular_corner(h)) return false;
  }
  return true;
}

}  // namespace subd2nurbs
