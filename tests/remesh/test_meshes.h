// Analytic triangle meshes for the feature and remesh tests: welded, consistently oriented
// outwards, built from parametric patches.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <vector>

#include "core/mesh/mesh_input.h"

namespace subd2nurbs::test {

constexpr double kTestPi = 3.14159265358979323846;
using P3 = std::array<double, 3>;

/// Collects triangles by position; equal positions (to 1e-9) are one vertex.
class MeshBuilder {
 public:
  int vertex(const P3& p) {
    std::array<long long, 3> key;
    for (int k = 0; k < 3; ++k) key[k] = std::llround(p[k] * 1e9);
    auto it = ids_.find(key);
    if (it != ids_.end()) return it->second;
    int id = static_cast<int>(mesh_.positions.size());
    mesh_.positions.push_back(p);
    ids_[key] = id;
    return id;
  }
  void triangle(const P3& a, const P3& b, const P3& c) {
    int ia = vertex(a), ib = vertex(b), ic = vertex(c);
    if (ia == ib || ib == ic || ia == ic) return;
    mesh_.face_sizes.push_back(3);
    mesh_.face_indices.insert(mesh_.face_indices.end(), {ia, ib, ic});
  }
  /// A parametric patch f(u, v), u, v in [0, 1], as nu x nv quads split into triangles.
  void patch(const std::function<P3(double, double)>& f, int nu, int nv) {
    for (int i = 0; i < nu; ++i)
      for (int j = 0; j < nv; ++j) {
        P3 a = f(double(i) / nu, double(j) / nv), b = f(double(i + 1) / nu, double(j) / nv);
        P3 c = f(double(i + 1) / nu, double(j + 1) / nv), d = f(double(i) / nu, double(j + 1) / nv);
        if ((i + j) % 2 == 0) {
          triangle(a, b, c);
          triangle(a, c, d);
        } else {
          triangle(a, b, d);
          triangle(b, c, d);
        }
      }
  }
  /// The mesh with its triangles oriented consistently (breadth first over shared edges), each
  /// component outwards (positive signed volume) when closed.
  MeshInput mesh() const {
    MeshInput m = mesh_;
    int nf = m.num_faces();
    std::map<std::pair<int, int>, std::vector<int>> edge_faces;
    auto tri = [&](int f) { return &m.face_indices[3 * f]; };
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) {
        int a = tri(f)[k], c = tri(f)[(k + 1) % 3];
        edge_faces[{std::min(a, c), std::max(a, c)}].push_back(f);
      }
    std::vector<int> done(nf, 0);
    for (int seed = 0; seed < nf; ++seed) {
      if (done[seed]) continue;
      std::vector<int> component{seed}, queue{seed};
      done[seed] = 1;
      while (!queue.empty()) {
        int f = queue.back();
        queue.pop_back();
        for (int k = 0; k < 3; ++k) {
          int a = tri(f)[k], c = tri(f)[(k + 1) % 3];
          for (int g : edge_faces[{std::min(a, c), std::max(a, c)}]) {
            if (done[g]) continue;
            bool same = false;  // g runs a -> c too: flip it
            for (int j = 0; j < 3; ++j) same |= tri(g)[j] == a && tri(g)[(j + 1) % 3] == c;
            if (same) std::swap(tri(g)[1], tri(g)[2]);
            done[g] = 1;
            component.push_back(g);
            queue.push_back(g);
          }
        }
      }
      double volume = 0;
      for (int f : component) {
        const P3 &a = m.positions[tri(f)[0]], &b = m.positions[tri(f)[1]], &c = m.positions[tri(f)[2]];
        volume += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
      }
      if (volume < 0)
        for (int f : component) std::swap(tri(f)[1], tri(f)[2]);
    }
    return m;
  }

 private:
  MeshInput mesh_;
  std::map<std::array<long long, 3>, int> ids_;
};

inline MeshInput icosphere(int levels, double radius = 1.0, P3 centre = {0, 0, 0}) {
  double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<P3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                       {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8}, {3, 8, 9},
                                       {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  auto unit = [](P3 p) {
    double l = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    return P3{p[0] / l, p[1] / l, p[2] / l};
  };
  for (auto& p : v) p = unit(p);
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<int, int>, int> mids;
    auto mid = [&](int a, int b) {
      auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mids.find(key);
      if (it != mids.end()) return it->second;
      v.push_back(unit({v[a][0] + v[b][0], v[a][1] + v[b][1], v[a][2] + v[b][2]}));
      return mids[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> g;
    for (auto& tri : f) {
      int ab = mid(tri[0], tri[1]), bc = mid(tri[1], tri[2]), ca = mid(tri[2], tri[0]);
      g.push_back({tri[0], ab, ca});
      g.push_back({tri[1], bc, ab});
      g.push_back({tri[2], ca, bc});
      g.push_back({ab, bc, ca});
    }
    f = g;
  }
  MeshInput m;
  for (auto& p : v) m.positions.push_back({centre[0] + radius * p[0], centre[1] + radius * p[1], centre[2] + radius * p[2]});
  for (auto& tri : f) {
    m.face_sizes.push_back(3);
    m.face_indices.insert(m.face_indices.end(), tri.begin(), tri.end());
  }
  return m;
}

inline MeshInput torus(double major, double minor, int nu, int nv) {
  MeshBuilder b;
  b.patch([&](double u, double v) {
    double a = 2 * kTestPi * u, c = 2 * kTestPi * v;
    double r = major + minor * std::cos(c);
    return P3{r * std::cos(a), r * std::sin(a), minor * std::sin(c)};
  }, nu, nv);
  return b.mesh();
}

/// The box [-1, 1]^3, each face an n x n grid, outward.
inline MeshInput box(int n) {
  MeshBuilder b;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = -1; side <= 1; side += 2)
      b.patch([&](double u, double v) {
        P3 p;
        int i = (axis + 1) % 3, j = (axis + 2) % 3;
        p[axis] = side;
        // (i, j, axis) is right-handed: swap u, v on the negative side to face outwards
        double s = side > 0 ? u : v, t = side > 0 ? v : u;
        p[i] = 2 * s - 1;
        p[j] = 2 * t - 1;
        return p;
      }, n, n);
  return b.mesh();
}

/// The point of the square [-1, 1]^2's boundary in direction a.
inline std::array<double, 2> square_point(double a) {
  double c = std::cos(a), s = std::sin(a);
  double l = 1 / std::max(std::abs(c), std::abs(s));
  return {l * c, l * s};
}

/// The point a fraction v of the way from the circle of radius r out to the square's boundary
/// (square_point), in direction a: an annulus between a hole's rim and the box's outline.
inline std::array<double, 2> circle_to_square(double r, double a, double v) {
  const auto q = square_point(a);
  return {r * std::cos(a) + v * (q[0] - r * std::cos(a)), r * std::sin(a) + v * (q[1] - r * std::sin(a))};
}

/// The box [-1, 1]^3 with a hole of radius r drilled along z: genus 1, sharp circular edges.
/// m angular samples (a multiple of 8, so the square's corners are samples), k radial rings,
/// nz layers along z.
inline MeshInput drilled_box(double r, int m, int k, int nz) {
  MeshBuilder b;
  auto angle = [&](double u) { return 2 * kTestPi * u; };
  for (int side = -1; side <= 1; side += 2)
    b.patch([&](double u, double v) {
      const auto p = circle_to_square(r, angle(side > 0 ? u : 1 - u), v);
      return P3{p[0], p[1], double(side)};
    }, m, k);
  // outer walls: the square's boundary samples times z
  b.patch([&](double u, double v) {
    auto q = square_point(angle(u));
    return P3{q[0], q[1], 2 * v - 1};
  }, m, nz);
  // the hole's wall, facing the axis
  b.patch([&](double u, double v) {
    double a = angle(1 - u);
    return P3{r * std::cos(a), r * std::sin(a), 2 * v - 1};
  }, m, nz);
  return b.mesh();
}

/// The point at fraction u (by length, counter-clockwise from (1, -(1 - rho))) of the outline of
/// the square [-1, 1]^2 with its corners rounded by radius rho.
inline std::array<double, 2> rounded_square(double rho, double u) {
  const double straight = 2 * (1 - rho), arc = kTestPi * rho / 2, side = straight + arc;
  double t = (u - std::floor(u)) * 4 * side;
  const int i = std::min(3, static_cast<int>(t / side));
  t -= i * side;
  double x, y;  // on the side x = 1, then its arc, in the frame of side 0
  if (t <= straight) {
    x = 1, y = -(1 - rho) + t;
  } else {
    const double a = (t - straight) / rho;
    x = (1 - rho) + rho * std::cos(a), y = (1 - rho) + rho * std::sin(a);
  }
  const double c = std::cos(i * kTestPi / 2), s = std::sin(i * kTestPi / 2);
  return {c * x - s * y, s * x + c * y};
}

/// A slab: the rounded square (rounded_square) times z in [-h, h]. Its rims (top and bottom
/// outlines) are sharp 90-degree edges with tight arcs (radius rho) at the corners; its wall is
/// smooth (planes tangent to quarter cylinders). m samples around the outline, k rings on the
/// caps, nz layers on the wall.
inline MeshInput rounded_slab(double rho, double h, int m, int k, int nz) {
  MeshBuilder b;
  for (int side = -1; side <= 1; side += 2)
    b.patch([&](double u, double v) {
      const auto q = rounded_square(rho, u);
      return P3{v * q[0], v * q[1], side * h};
    }, m, k);
  b.patch([&](double u, double v) {
    const auto q = rounded_square(rho, u);
    return P3{q[0], q[1], h * (2 * v - 1)};
  }, m, nz);
  return b.mesh();
}

/// A counterbored box: the cube [-1, 1]^3 with a through hole of radius r1 along z and, from the
/// top, a counterbore of radius r2 > r1 down to z = c: four circular rims (r1 at z = -1 and c, r2
/// at z = c and 1) joined by two cylinder walls and the counterbore's flat annulus. m samples
/// round every circle (the same angles), k rings on the top and bottom, nz layers on the walls.
inline MeshInput counterbored_box(double r1, double r2, double c, int m, int k, int nz) {
  MeshBuilder b;
  auto angle = [&](double u) { return 2 * kTestPi * u; };
  auto annulus = [&](double r, double z) {  // from the circle of radius r out to the square
    b.patch([&, r, z](double u, double v) {
      const auto p = circle_to_square(r, angle(u), v);
      return P3{p[0], p[1], z};
    }, m, k);
  };
  annulus(r2, 1);
  annulus(r1, -1);
  b.patch([&](double u, double v) {  // outer walls
    auto q = square_point(angle(u));
    return P3{q[0], q[1], 2 * v - 1};
  }, m, nz);
  b.patch([&](double u, double v) {  // the counterbore's floor
    double a = angle(u), r = r1 + v * (r2 - r1);
    return P3{r * std::cos(a), r * std::sin(a), c};
  }, m, 2);
  b.patch([&](double u, double v) {  // the counterbore's wall
    double a = angle(u);
    return P3{r2 * std::cos(a), r2 * std::sin(a), c + v * (1 - c)};
  }, m, nz);
  b.patch([&](double u, double v) {  // the through hole's wall
    double a = angle(u);
    return P3{r1 * std::cos(a), r1 * std::sin(a), -1 + v * (c + 1)};
  }, m, nz);
  return b.mesh();
}

inline MeshInput open_cylinder(double radius, double height, int nu, int nv) {
  MeshBuilder b;
  b.patch([&](double u, double v) {
    double a = 2 * kTestPi * u;
    return P3{radius * std::cos(a), radius * std::sin(a), height * v};
  }, nu, nv);
  return b.mesh();
}

inline MeshInput concat(const MeshInput& a, const MeshInput& b) {
  MeshInput m = a;
  int offset = a.num_vertices();
  m.positions.insert(m.positions.end(), b.positions.begin(), b.positions.end());
  m.face_sizes.insert(m.face_sizes.end(), b.face_sizes.begin(), b.face_sizes.end());
  for (int i : b.face_indices) m.face_indices.push_back(i + offset);
  return m;
}

}  // namespace subd2nurbs::test
