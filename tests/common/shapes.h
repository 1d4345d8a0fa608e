// Small generated cages for tests and benchmarks (header-only).
#pragma once

#include <array>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "core/mesh/mesh_input.h"

namespace subd2nurbs::testing {

inline void add_face(MeshInput& m, std::initializer_list<int> vs) {
  m.face_sizes.push_back(static_cast<int>(vs.size()));
  m.face_indices.insert(m.face_indices.end(), vs);
}

/// Unit cube [0,1]^3, six outward quads.
inline MeshInput cube() {
  MeshInput m;
  for (int i = 0; i < 8; ++i) m.positions.push_back({double(i & 1), double((i >> 1) & 1), double(i >> 2)});
  add_face(m, {0, 2, 3, 1});
  add_face(m, {4, 5, 7, 6});
  add_face(m, {0, 1, 5, 4});
  add_face(m, {2, 6, 7, 3});
  add_face(m, {0, 4, 6, 2});
  add_face(m, {1, 3, 7, 5});
  return m;
}

/// The unit cube with its top face split into two quads by a raised vertex (index 8) joined
/// to two opposite corners only: vertex 8 is interior with valence 2.
inline MeshInput cube_with_valence_two_vertex() {
  MeshInput m = cube();
  m.positions.push_back({0.5, 0.5, 1.2});
  m.face_sizes.erase(m.face_sizes.begin() + 1);
  m.face_indices.erase(m.face_indices.begin() + 4, m.face_indices.begin() + 8);  // {4,5,7,6}
  add_face(m, {4, 5, 7, 8});
  add_face(m, {7, 6, 4, 8});
  return m;
}

/// Open nx-by-ny grid of quads in the plane z = 0 (a bit of z noise keeps it non-planar).
inline MeshInput grid(int nx, int ny) {
  MeshInput m;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i)
      m.positions.push_back({double(i), double(j), 0.1 * std::sin(1.3 * i + 0.7 * j)});
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      int a = j * (nx + 1) + i;
      add_face(m, {a, a + 1, a + nx + 2, a + nx + 1});
    }
  return m;
}

/// Closed torus of nu x nv quads (major radius R, minor r).
inline MeshInput torus(int nu, int nv, double R = 3.0, double r = 1.0) {
  MeshInput m;
  m.positions.reserve(static_cast<size_t>(nu) * nv);
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      double u = 2 * M_PI * i / nu, v = 2 * M_PI * j / nv;
      m.positions.push_back({(R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u),
                             r * std::sin(v)});
    }
  m.face_sizes.assign(static_cast<size_t>(nu) * nv, 4);
  m.face_indices.reserve(static_cast<size_t>(4) * nu * nv);
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      int i1 = (i + 1) % nu, j1 = (j + 1) % nv;
      for (int v : {i * nv + j, i1 * nv + j, i1 * nv + j1, i * nv + j1}) m.face_indices.push_back(v);
    }
  return m;
}

/// Rotates the edge shared by faces (i, j) and (i + 1, j) of torus(nu, nv): the quads
/// (a b c d), (b e f c) become (d a b e), (e f c d), so b and c drop to valence 3 and d and e
/// rise to valence 5. \throw std::logic_error if those faces are not the torus's own.
inline void rotate_torus_edge(MeshInput& m, int nu, int nv, int i, int j) {
  auto vtx = [&](int a, int b) { return ((a + nu) % nu) * nv + (b + nv) % nv; };
  const int a = vtx(i, j), b = vtx(i + 1, j), c = vtx(i + 1, j + 1), d = vtx(i, j + 1);
  const int e = vtx(i + 2, j), f = vtx(i + 2, j + 1);
  int* f1 = &m.face_indices[4 * static_cast<size_t>(vtx(i, j))];
  int* f2 = &m.face_indices[4 * static_cast<size_t>(vtx(i + 1, j))];
  if (f1[0] != a || f1[1] != b || f1[2] != c || f1[3] != d || f2[0] != b || f2[1] != e ||
      f2[2] != f || f2[3] != c)
    throw std::logic_error("rotate_torus_edge: faces are not the expected torus faces");
  const int q1[4] = {d, a, b, e}, q2[4] = {e, f, c, d};
  for (int k = 0; k < 4; ++k) f1[k] = q1[k], f2[k] = q2[k];
}

/// The benchmarks' torus with extraordinary vertices: torus(100, 100) with 36 edge rotations
/// on a 6 x 6 grid of sites, 16 faces apart: 72 valence-3 and 72 valence-5 vertices.
inline MeshInput torus_with_rotated_edges() {
  constexpr int n = 100;
  MeshInput m = torus(n, n);
  for (int si = 0; si < 6; ++si)
    for (int sj = 0; sj < 6; ++sj) rotate_torus_edge(m, n, n, 8 + 16 * si, 8 + 16 * sj);
  return m;
}

/// A closed "star" around an extraordinary vertex of valence n: a pyramid-like fan of n quads
/// on top, closed by one n-gon at the bottom. Exercises n-gons and high valence.
inline MeshInput star(int n) {
  MeshInput m;
  m.positions.push_back({0, 0, 1});
  for (int r = 0; r < n; ++r) {
    double a = 2 * M_PI * r / n, b = 2 * M_PI * (r + 0.5) / n;
    m.positions.push_back({std::cos(a), std::sin(a), 0.6});
    m.positions.push_back({1.3 * std::cos(b), 1.3 * std::sin(b), 0.0});
  }
  for (int r = 0; r < n; ++r) {
    int e0 = 1 + 2 * r, d = 2 + 2 * r, e1 = 1 + 2 * ((r + 1) % n);
    add_face(m, {0, e0, d, e1});
  }
  // Bottom: the ring of e and d vertices, reversed so it faces down.
  m.face_sizes.push_back(2 * n);
  for (int k = 2 * n; k >= 1; --k) m.face_indices.push_back(k);
  return m;
}


/// A closed surface of revolution with a polar structure at each end: profile[0] and
/// profile.back() are the poles (radius ignored), every other entry a ring of n vertices
/// (radius, z), top to bottom. Ring i is turned by twist * i radians; `noise` moves every
/// vertex by a deterministic pseudo-random offset of at most that size. Vertex 0 is the top
/// pole, ring i (1-based) spoke j is 1 + (i - 1) * n + j, the bottom pole is last.
inline MeshInput revolved(int n, const std::vector<std::array<double, 2>>& profile, double twist = 0,
                          double noise = 0) {
  MeshInput m;
  const int rings = static_cast<int>(profile.size()) - 2;
  auto jitter = [&](int k, int axis) {
    return noise * std::sin(12.9898 * k + 78.233 * axis + 0.5 * k * axis);
  };
  auto push = [&](double x, double y, double z) {
    const int k = static_cast<int>(m.positions.size());
    m.positions.push_back({x + jitter(k, 0), y + jitter(k, 1), z + jitter(k, 2)});
  };
  push(0, 0, profile.front()[1]);
  for (int i = 1; i <= rings; ++i)
    for (int j = 0; j < n; ++j) {
      const double a = 2 * M_PI * j / n + twist * i;
      push(profile[i][0] * std::cos(a), profile[i][0] * std::sin(a), profile[i][1]);
    }
  push(0, 0, profile.back()[1]);
  auto ring = [&](int i, int j) { return 1 + (i - 1) * n + ((j % n) + n) % n; };
  const int bottom = 1 + rings * n;
  for (int j = 0; j < n; ++j) add_face(m, {0, ring(1, j), ring(1, j + 1)});
  for (int i = 1; i < rings; ++i)
    for (int j = 0; j < n; ++j) add_face(m, {ring(i, j + 1), ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
  for (int j = 0; j < n; ++j) add_face(m, {bottom, ring(rings, j + 1), ring(rings, j)});
  return m;
}

/// A cylinder of radius 1 and height 2 with flat polar caps: rings at radius 1/3 and 2/3 on
/// each end face, then the rim and three rings down the side.
inline MeshInput capped_cylinder(int n, double twist = 0, double noise = 0) {
  return revolved(n, {{0, 1}, {1.0 / 3, 1}, {2.0 / 3, 1}, {1, 1}, {1, 1.0 / 3}, {1, -1.0 / 3}, {1, -1},
                      {2.0 / 3, -1}, {1.0 / 3, -1}, {0, -1}},
                  twist, noise);
}

/// A mushroom: a wide domed head on a narrow stem, poles at the top of the head and the
/// bottom of the stem.
inline MeshInput mushroom(int n, double twist = 0, double noise = 0) {
  return revolved(n, {{0, 2.0}, {0.5, 1.97}, {1.0, 1.85}, {1.45, 1.6}, {1.6, 1.3}, {1.2, 1.1},
                      {0.5, 1.0}, {0.4, 0.6}, {0.45, 0.2}, {0.55, 0.05}, {0.3, 0.0}, {0.15, 0.0},
                      {0, 0.0}},
                  twist, noise);
}

}  // namespace subd2nurbs::testing
