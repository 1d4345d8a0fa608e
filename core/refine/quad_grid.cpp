#include "core/refine/quad_grid.h"

namespace subd2nurbs {

void corner_to_grid(int k, int a, int b, int& i, int& j) {
  switch (k & 3) {
    case 0: i = a; j = b; return;
    case 1: i = 1 - b; j = a; return;
    case 2: i = 1 - a; j = 1 - b; return;
    default: i = b; j = 1 - a; return;
  }
}

void gather_quad_grid(const SubdivLevel& L, const std::vector<Point3>& P, int f, const bool diagonal[4], QuadGrid& g) {
  const PolyMesh& m = L.mesh;
  const int h0 = m.face_begin(f);
  auto put = [&](int k, int a, int b, int vertex) {
    int i, j;
    corner_to_grid(k, a, b, i, j);
    g.set(i, j, P[vertex]);
    g.vertex_at(i, j) = vertex;
  };
  bool sharp_side[4];
  for (int k = 0; k < 4; ++k) {
    const int h = h0 + k;
    put(k, 0, 0, m.corner_vertex(h));
    sharp_side[k] = L.infinitely_sharp(m.corner_edge(h));
    if (sharp_side[k]) continue;
    const int t = m.twin(h);  // across side k: quad (to, from, x, y)
    put(k, 0, -1, m.to_vertex(m.next(t)));
    put(k, 1, -1, m.corner_vertex(m.prev(t)));
    if (diagonal[k]) {
      const int q = m.twin(m.next(t));
      put(k, -1, -1, m.corner_vertex(m.prev(q)));
    }
  }
  // Side k of the face in grid terms: 0 is j = -1 (v = 0), 1 is i = 2, 2 is j = 2, 3 is i = -1.
  auto reflect = [](const Point3& inner, const Point3& next) {
    return Point3{2 * inner[0] - next[0], 2 * inner[1] - next[1], 2 * inner[2] - next[2]};
  };
  if (sharp_side[3] || sharp_side[1])
    for (int j = -1; j <= 2; ++j) {
      if (!g.has(0, j) || !g.has(1, j)) continue;
      if (sharp_side[3]) g.set(-1, j, reflect(g.at(0, j), g.at(1, j)));
      if (sharp_side[1]) g.set(2, j, reflect(g.at(1, j), g.at(0, j)));
    }
  for (int i = -1; i <= 2; ++i) {
    if (!g.has(i, 0) || !g.has(i, 1)) continue;
    if (sharp_side[0]) g.set(i, -1, reflect(g.at(i, 0), g.at(i, 1)));
    if (sharp_side[2]) g.set(i, 2, reflect(g.at(i, 1), g.at(i, 0)));
  }
}

}  // namespace subd2nurbs
