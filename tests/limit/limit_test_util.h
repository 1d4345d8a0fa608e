// Shared helpers of the limit tests.
#pragma once

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "core/limit/limit_evaluator.h"
#include "io/obj_reader.h"

namespace subd2nurbs::testing {

inline std::string limit_corpus_path(const std::string& name) {
  return std::string(SUBD2NURBS_CORPUS_DIR) + "/" + name + ".obj";
}

inline double diagonal(const std::vector<Point3>& p) {
  Point3 lo = p[0], hi = p[0];
  for (const Point3& q : p)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], q[k]);
      hi[k] = std::max(hi[k], q[k]);
    }
  return std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                   (hi[2] - lo[2]) * (hi[2] - lo[2]));
}

inline double dist(const Point3& a, const Point3& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                   (a[2] - b[2]) * (a[2] - b[2]));
}

inline std::vector<Point3> positions_of(const MeshInput& in) {
  return std::vector<Point3>(in.positions.begin(), in.positions.end());
}

/// A corpus shape's exact limit, with the cage's positions and bounding-box diagonal.
struct ShapeLimit {
  std::vector<Point3> pos;
  LimitEvaluator limit;
  double diag;
};

inline ShapeLimit shape_limit(const std::string& name) {
  const LoadedCage cage = read_obj(limit_corpus_path(name));
  std::vector<Point3> pos = positions_of(cage.input);
  const double diag = diagonal(pos);
  LimitEvaluator limit(SubdivLevel::from_input(cage.input), pos);
  return {std::move(pos), std::move(limit), diag};
}

constexpr int kRings = 3;  // quads per sector side

/// A wavy disc: an interior vertex of valence n, each sector a kRings x kRings grid of quads.
/// Face (s, a, b) has index (s * kRings + a) * kRings + b; its first vertex is G_s[a][b] and
/// its first edge runs along ray s, so face (s, 0, 0) has the EV at ptex (0, 0).
inline MeshInput ev_disc(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.08, 0.08);
  MeshInput m;
  auto id = [&](int s, int i, int j) {
    s %= n;
    if (i == 0 && j == 0) return 0;
    if (j == 0) return 1 + s * kRings + (i - 1);
    if (i == 0) return 1 + ((s + 1) % n) * kRings + (j - 1);
    return 1 + n * kRings + (s * kRings + (i - 1)) * kRings + (j - 1);
  };
  const double pi = std::acos(-1.0);
  m.positions.assign(1 + n * kRings + n * kRings * kRings, {0, 0, 0});
  for (int s = 0; s < n; ++s)
    for (int i = 0; i <= kRings; ++i)
      for (int j = 0; j <= kRings; ++j) {
        // Sector s spans the angle between rays s and s+1.
        const double a0 = 2 * pi * s / n, a1 = 2 * pi * (s + 1) / n;
        const double x = i * std::cos(a0) + j * std::cos(a1);
        const double y = i * std::sin(a0) + j * std::sin(a1);
        Point3 p = {x, y, 0.15 * std::sin(x) * std::cos(0.7 * y) + 0.05 * (x * x - y * y) / 4};
        if (i + j > 0)
          for (double& c : p) c += jitter(rng);
        m.positions[id(s, i, j)] = p;
      }
  for (int s = 0; s < n; ++s)
    for (int a = 0; a < kRings; ++a)
      for (int b = 0; b < kRings; ++b) {
        m.face_sizes.push_back(4);
        for (int q : {id(s, a, b), id(s, a + 1, b), id(s, a + 1, b + 1), id(s, a, b + 1)})
          m.face_indices.push_back(q);
      }
  return m;
}

}  // namespace subd2nurbs::testing
