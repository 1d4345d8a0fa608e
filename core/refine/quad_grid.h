// The 4 x 4 B-spline control points around a quad of a subdivision level: the one gathering of
// a quad's regular neighbourhood, shared by the patch builder (core/patch/regular_net: Bezier
// nets of regular quads) and the exact limit evaluator (core/limit: regular, semi-sharp and
// Stam faces).
#pragma once

#include <vector>

#include "core/refine/refiner.h"
#include "core/util/point3.h"

namespace subd2nurbs {

/// Grid coordinates (i, j), each in -1..2, index (i + 1) * 4 + (j + 1): the face's corners are
/// (0,0), (1,0), (1,1), (0,1) in the order of its corners; i runs along its first edge.
struct QuadGrid {
  Point3 P[16];
  bool have[16] = {};
  int vertex[16] = {-1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1};  ///< -1: phantom
  Point3& at(int i, int j) { return P[(i + 1) * 4 + (j + 1)]; }
  const Point3& at(int i, int j) const { return P[(i + 1) * 4 + (j + 1)]; }
  bool& has(int i, int j) { return have[(i + 1) * 4 + (j + 1)]; }
  int& vertex_at(int i, int j) { return vertex[(i + 1) * 4 + (j + 1)]; }
  void set(int i, int j, const Point3& p) {
    at(i, j) = p;
    has(i, j) = true;
  }
};

/// Corner k's local coordinates (a, b) (a along the corner's outgoing edge, b along its
/// incoming one reversed) in the face's grid coordinates (i, j).
void corner_to_grid(int k, int a, int b, int& i, int& j);

/// Gathers quad f's grid: the face's corners; the rows across every side that is neither a
/// boundary nor infinitely sharp; the diagonal point at each corner k with diagonal[k] (a smooth
/// valence-4 corner: two faces on from the face); then phantom points (docs/math.md 6.2)
/// reflected across the infinitely sharp and boundary sides, first across the sides along j
/// (i = -1, i = 2), then across the sides along i for every i. Points left out stay !have.
void gather_quad_grid(const SubdivLevel& L, const std::vector<Point3>& P, int f, const bool diagonal[4], QuadGrid& g);

}  // namespace subd2nurbs
