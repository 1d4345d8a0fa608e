// Regular pieces: where the Catmull-Clark limit over a quad is one bicubic.
//
// A quad whose four corners are regular *for it* (smooth and 4-valent; a crease vertex with 2
// faces on the quad's side; a corner vertex with 1 face) is exactly the bicubic B-spline of
// its 4x4 neighbourhood, with phantom points 2 P0 - P1 across sharp sides (docs/patches.md,
// "Regular pieces"). LevelView answers the topological questions on one level (the whole
// coarse level or a local piece of a deeper one).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "core/refine/refiner.h"
#include "core/util/eigen_point.h"

namespace subd2nurbs {

struct LevelView {
  const SubdivLevel& level;
  const PolyMesh& m;
  const std::vector<Point3>& x;

  bool sharp(int e) const { return level.infinitely_sharp(e); }
  // The ray along corner c's edge, leaving corner_vertex(c).
  bool sharp_ray_out(int c) const { return sharp(m.corner_edge(c)); }
  // The ray along prev(c)'s edge, i.e. the other edge of c's face at corner_vertex(c).
  bool sharp_ray_in(int c) const { return sharp(m.corner_edge(m.prev(c))); }
  // Counter-clockwise neighbour face's corner at the same vertex (across the "in" ray).
  int ccw(int c) const { return sharp_ray_in(c) ? -1 : m.twin(m.prev(c)); }
  int cw(int c) const { return sharp_ray_out(c) ? -1 : m.next(m.twin(c)); }

  // Faces in the fan (between sharp edges) that contains corner c; -1 if cyclic.
  int fan_size(int c) const {
    int n = 1;
    for (int d = ccw(c); d != -1; d = ccw(d)) {
      if (d == c) return -1;
      ++n;
    }
    for (int d = cw(c); d != -1; d = cw(d)) ++n;
    return n;
  }

  bool regular_corner(int c) const {
    const int v = m.corner_vertex(c);
    switch (vertex_rule(level, v)) {
      case VertexRule::Smooth: return !m.is_boundary_vertex(v) && m.valence(v) == 4;
      case VertexRule::Crease: return fan_size(c) == 2;
      case VertexRule::Corner: return fan_size(c) == 1;
      case VertexRule::Dart: return false;
    }
    return false;
  }
  Eigen::Vector3d X(int v) const { return to_eigen(x[v]); }
};

/// Bezier net (16 points, index i * 4 + j, i along the face's first edge) of quad f, whose four
/// corners must be regular for it.
void regular_net(const LevelView& L, int f, Point3* net);

/// True if the limit over quad f is the bicubic of regular_net: every corner is regular for f,
/// and no corner or edge at a corner carries a semi-sharp sharpness (0 < s < infinity). The
/// refinement of the 16 points uses only the rules of the four corners and of the edges at
/// them, so sharpness elsewhere in the neighbourhood does not matter.
bool is_regular_leaf(const LevelView& L, int f);

}  // namespace subd2nurbs
