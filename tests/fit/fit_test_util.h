// Shared helpers of the fitting tests (interpolation, fairing).
#pragma once

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <random>
#include <tuple>
#include <string>
#include <vector>

#include "common/corpus.h"
#include "core/limit/limit_evaluator.h"
#include "io/obj_reader.h"
#include "limit/limit_test_util.h"  // limit_corpus_path, diagonal, dist, positions_of

namespace subd2nurbs::testing {

inline std::vector<std::string> manifold_corpus_shapes() {
  std::vector<std::string> out;
  for (const auto& e : std::filesystem::directory_iterator(SUBD2NURBS_CORPUS_DIR))
    if (e.path().extension() == ".obj" && !non_manifold_corpus_shapes().count(e.path().stem().string()))
      out.push_back(e.path().stem().string());
  std::sort(out.begin(), out.end());
  return out;
}

/// Where the limit surface of a face has a vertex: ptex sub-face and (u, v) at that corner.
struct CornerPtex {
  int face = -1, sub = 0;
  double u = 0, v = 0;
};

/// A face at v that is not a hole, and v's corner in its ptex parametrisation; face -1 if none.
inline CornerPtex corner_ptex(const SubdivLevel& level, int v) {
  const PolyMesh& m = level.mesh;
  const int* c = m.vertex_corners(v);
  for (int i = 0, nf = m.vertex_face_count(v); i < nf; ++i) {
    const int f = m.corner_face(c[i]);
    if (level.face_hole[f]) continue;
    const int k = c[i] - m.face_begin(f);
    CornerPtex out;
    out.face = f;
    if (m.face_size(f) == 4) {
      const double uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      out.u = uv[k][0];
      out.v = uv[k][1];
    } else {
      out.sub = k;
    }
    return out;
  }
  return {};
}


/// A quad-mesh sphere: each face of the cube [-1,1]^3 as an n x n grid, projected onto the
/// sphere of radius `radius`, vertices moved radially by uniform noise in [-noise, noise]
/// times the radius (seeded). Eight valence-3 vertices, the rest regular.
inline MeshInput cube_sphere(int n, double radius, double noise, unsigned seed) {
  MeshInput m;
  std::map<std::tuple<long, long, long>, int> ids;
  auto vertex = [&](double x, double y, double z) {
    const auto key = std::make_tuple(std::lround(x * 1e6), std::lround(y * 1e6), std::lround(z * 1e6));
    auto it = ids.find(key);
    if (it != ids.end()) return it->second;
    const double r = std::sqrt(x * x + y * y + z * z);
    m.positions.push_back({radius * x / r, radius * y / r, radius * z / r});
    return ids[key] = static_cast<int>(m.positions.size()) - 1;
  };
  // For each cube face: the normal axis, its sign, and two in-face axes with a x b = normal.
  for (int axis = 0; axis < 3; ++axis)
    for (int sign : {1, -1}) {
      const int a = (axis + 1) % 3, b = (axis + 2) % 3;
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          int q[4];
          const int di[4] = {0, 1, 1, 0}, dj[4] = {0, 0, 1, 1};
          for (int k = 0; k < 4; ++k) {
            double p[3];
            p[axis] = sign;
            p[a] = -1 + 2.0 * (i + di[k]) / n;
            p[b] = (-1 + 2.0 * (j + dj[k]) / n) * sign;
            q[k] = vertex(p[0], p[1], p[2]);
          }
          m.face_sizes.push_back(4);
          for (int k = 0; k < 4; ++k) m.face_indices.push_back(q[k]);
        }
    }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-noise, noise);
  for (auto& p : m.positions) {
    const double f = 1 + u(rng);
    for (double& c : p) c *= f;
  }
  return m;
}

}  // namespace subd2nurbs::testing
