#include "core/patch/regular_net.h"

namespace subd2nurbs {

namespace {

using V3 = Eigen::Vector3d;

const double kM[4][4] = {{1.0 / 6, 4.0 / 6, 1.0 / 6, 0},
                         {0, 4.0 / 6, 2.0 / 6, 0},
                         {0, 2.0 / 6, 4.0 / 6, 0},
                         {0, 1.0 / 6, 4.0 / 6, 1.0 / 6}};

}  // namespace

// Bezier net (face frame) of a quad whose four corners are regular for it.
void regular_net(const LevelView& L, int f, Point3* net) {
  const PolyMesh& m = L.m;
  const int h0 = m.face_begin(f);
  V3 G[4][4];      // G[x+1][y+1], x, y in -1..2
  bool have[4][4] = {};
  auto set = [&](int x, int y, int v) { G[x + 1][y + 1] = L.X(v); have[x + 1][y + 1] = true; };
  // Corners (0,0), (1,0), (1,1), (0,1).
  const int cx[4] = {0, 1, 1, 0}, cy[4] = {0, 0, 1, 1};
  for (int i = 0; i < 4; ++i) set(cx[i], cy[i], m.corner_vertex(h0 + i));
  // Outer rows across each open side i (edge of corner h_i, from corner i to corner i+1).
  // In the neighbour across the edge, next(next(t)) is next to corner i, prev(t) to corner i+1.
  // Outward step of side i: side 0 -> (0,-1), 1 -> (+1,0), 2 -> (0,+1), 3 -> (-1,0).
  const int ox[4] = {0, 1, 0, -1}, oy[4] = {-1, 0, 1, 0};
  bool open[4];
  for (int i = 0; i < 4; ++i) {
    const int h = h0 + i;
    open[i] = !L.sharp(m.corner_edge(h));
    if (!open[i]) continue;
    const int t = m.twin(h);
    const int a = i, b = (i + 1) % 4;
    set(cx[a] + ox[i], cy[a] + oy[i], m.corner_vertex(m.next(m.next(t))));
    set(cx[b] + ox[i], cy[b] + oy[i], m.corner_vertex(m.prev(t)));
  }
  // Diagonal points at smooth 4-valent corners: two faces around the corner.
  for (int i = 0; i < 4; ++i) {
    const int h = h0 + i;
    const int prev_side = (i + 3) % 4;
    if (!open[i] || !open[prev_side]) continue;
    const int opposite = m.twin(m.prev(m.twin(m.prev(h))));  // two faces counter-clockwise
    set(cx[i] + ox[i] + ox[prev_side], cy[i] + oy[i] + oy[prev_side],
        m.corner_vertex(m.next(m.next(opposite))));
  }
  // Phantom points: first the rows beside the four corners, then the diagonals. A missing
  // x = -1 or 2 point reflects in x; otherwise (missing y row) it reflects in y.
  auto phantom = [&](int x, int y) {
    if (have[x + 1][y + 1]) return;
    if (x == -1) G[0][y + 1] = 2 * G[1][y + 1] - G[2][y + 1];
    else if (x == 2) G[3][y + 1] = 2 * G[2][y + 1] - G[1][y + 1];
    else if (y == -1) G[x + 1][0] = 2 * G[x + 1][1] - G[x + 1][2];
    else G[x + 1][3] = 2 * G[x + 1][2] - G[x + 1][1];
    have[x + 1][y + 1] = true;
  };
  for (int t = 0; t <= 1; ++t) {
    phantom(-1, t); phantom(2, t); phantom(t, -1); phantom(t, 2);
  }
  for (int x : {-1, 2})
    for (int y : {-1, 2}) {
      const bool x_side_sharp = (x == -1) ? !open[3] : !open[1];
      if (x_side_sharp) {
        G[x + 1][y + 1] = (x == -1) ? 2 * G[1][y + 1] - G[2][y + 1] : 2 * G[2][y + 1] - G[1][y + 1];
        have[x + 1][y + 1] = true;
      } else if (!have[x + 1][y + 1]) {  // the x side is open: reflect across the y side
        G[x + 1][y + 1] = (y == -1) ? 2 * G[x + 1][1] - G[x + 1][2] : 2 * G[x + 1][2] - G[x + 1][1];
        have[x + 1][y + 1] = true;
      }
    }
  // B = M G M^T
  V3 T[4][4];
  for (int i = 0; i < 4; ++i)
    for (int b = 0; b < 4; ++b) {
      T[i][b] = V3::Zero();
      for (int a = 0; a < 4; ++a) T[i][b] += kM[i][a] * G[a][b];
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
