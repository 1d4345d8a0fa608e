// Shared helpers of the shape fit's tests (core, CLI): a torus cage, a cage's exact limit
// sampled as a triangle mesh target, a perturbed cage.
#pragma once

#include <array>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "core/limit/limit_evaluator.h"
#include "core/mesh/mesh_input.h"
#include "limit/limit_test_util.h"  // diagonal

namespace subd2nurbs::testing {

/// A regular torus cage: m x n quads, radii R and r, every vertex of valence 4; stretched along x
/// and bent along z so that no rotation about its axis nearly maps its limit onto itself (a
/// surface of revolution leaves a fit free to slide round).
inline MeshInput torus_cage(int m, int n, double R, double r) {
  MeshInput in;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < n; ++j) {
      const double a = 2 * M_PI * i / m, b = 2 * M_PI * j / n;
      in.positions.push_back({1.4 * (R + r * std::cos(b)) * std::cos(a), (R + r * std::cos(b)) * std::sin(a),
                              r * std::sin(b) + 0.5 * std::cos(a) * std::cos(a)});
    }
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < n; ++j) {
      in.face_sizes.push_back(4);
      const int i1 = (i + 1) % m, j1 = (j + 1) % n;
      for (int v : {i * n + j, i1 * n + j, i1 * n + j1, i * n + j1}) in.face_indices.push_back(v);
    }
  return in;
}

/// The exact limit of `limit` on a (g + 1) x (g + 1) grid per ptex face (u, v = i / g; g / 2 on
/// the ptex faces of n-gons, which are level-1 quads: so g = 2^k gives the level-k vertices),
/// triangulated per face (points on shared edges repeated), and their ptex parameters.
struct LimitTarget {
  std::vector<Point3> points;  ///< welded: a point on a ptex seam is stored once
  std::vector<std::array<int, 3>> triangles;
  std::vector<std::array<double, 3>> where;  ///< ptex, u, v
};

inline LimitTarget limit_target(const LimitEvaluator& limit, int g) {
  LimitTarget t;
  const int full = g;
  std::map<std::tuple<long long, long long, long long>, int> weld;
  for (int p = 0; p < limit.num_ptex_faces(); ++p) {
    const int f = limit.ptex_to_face(p);
    if (limit.base().face_hole[f]) continue;
    g = limit.base().mesh.face_size(f) == 4 || full == 1 ? full : full / 2;
    std::vector<double> us(g + 1);
    for (int i = 0; i <= g; ++i) us[i] = static_cast<double>(i) / g;
    std::vector<LimitSample> s((g + 1) * (g + 1));
    limit.evaluate_grid(f, p - limit.first_ptex(f), us.data(), g + 1, us.data(), g + 1, s.data());
    std::vector<int> id((g + 1) * (g + 1));
    for (int a = 0; a <= g; ++a)
      for (int b = 0; b <= g; ++b) {
        const Point3& q = s[a * (g + 1) + b].p;
        // Seam points evaluated from two faces agree to rounding: welded on a 1e-9 lattice.
        const auto key = std::make_tuple(std::llround(q[0] * 1e9), std::llround(q[1] * 1e9), std::llround(q[2] * 1e9));
        const auto it = weld.find(key);
        if (it != weld.end()) {
          id[a * (g + 1) + b] = it->second;
          continue;
        }
        id[a * (g + 1) + b] = weld[key] = static_cast<int>(t.points.size());
        t.points.push_back(q);
        t.where.push_back({static_cast<double>(p), us[a], us[b]});
      }
    for (int a = 0; a < g; ++a)
      for (int b = 0; b < g; ++b) {
        const int q00 = id[a * (g + 1) + b], q10 = id[(a + 1) * (g + 1) + b], q11 = id[(a + 1) * (g + 1) + b + 1],
                  q01 = id[a * (g + 1) + b + 1];
        t.triangles.push_back({q00, q10, q11});
        t.triangles.push_back({q00, q11, q01});
      }
  }
  return t;
}

inline std::vector<Point3> perturbed(const std::vector<Point3>& p, double amount, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  const double d = diagonal(p) * amount;
  std::vector<Point3> out = p;
  for (Point3& q : out)
    for (double& c : q) c += d * u(rng);
  return out;
}

/// A box cage: n x n quads per side of [-1, 1]^3 scaled by `size`, its 12 edges tagged
/// infinitely sharp (creases = true): its limit is the box itself (flat sides, straight sharp
/// edges, corners at the box's corners).
inline MeshInput box_cage(int n, const Point3& size, bool creases) {
  MeshInput in;
  std::map<std::tuple<int, int, int>, int> id;
  auto vertex = [&](int x, int y, int z) {  // lattice coordinates 0..n
    const auto key = std::make_tuple(x, y, z);
    const auto it = id.find(key);
    if (it != id.end()) return it->second;
    in.positions.push_back({size[0] * (-1 + 2.0 * x / n), size[1] * (-1 + 2.0 * y / n), size[2] * (-1 + 2.0 * z / n)});
    return id[key] = static_cast<int>(in.positions.size()) - 1;
  };
  for (int a = 0; a < 3; ++a)
    for (int side : {0, n}) {
      const int b = (a + 1) % 3, c = (a + 2) % 3;
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          int q[4];
          const int ij[4][2] = {{i, j}, {i + 1, j}, {i + 1, j + 1}, {i, j + 1}};
          for (int k = 0; k < 4; ++k) {
            int l[3];
            l[a] = side;
            l[b] = ij[k][0];
            l[c] = ij[k][1];
            q[k] = vertex(l[0], l[1], l[2]);
          }
          in.face_sizes.push_back(4);
          if (side == n)
            for (int k = 0; k < 4; ++k) in.face_indices.push_back(q[k]);
          else
            for (int k = 3; k >= 0; --k) in.face_indices.push_back(q[k]);
        }
    }
  if (creases) {
    std::set<std::pair<int, int>> seen;
    for (size_t f = 0; f < in.face_sizes.size(); ++f)
      for (int k = 0; k < 4; ++k) {
        const int v0 = in.face_indices[4 * f + k], v1 = in.face_indices[4 * f + (k + 1) % 4];
        int shared = 0;
        for (int d = 0; d < 3; ++d)
          shared += std::abs(std::abs(in.positions[v0][d]) - size[d]) < 1e-12 && in.positions[v0][d] == in.positions[v1][d];
        if (shared >= 2 && seen.insert({std::min(v0, v1), std::max(v0, v1)}).second) in.creases.push_back({v0, v1, 10.0});
      }
  }
  return in;
}

}  // namespace subd2nurbs::testing
