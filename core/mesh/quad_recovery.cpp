#include "core/mesh/quad_recovery.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

#include "core/util/constants.h"

namespace subd2nurbs {

namespace {

using P = std::array<double, 3>;

P sub(const P& a, const P& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
P cross(const P& a, const P& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const P& a, const P& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(const P& a) { return std::sqrt(dot(a, a)); }

/// Angle between two vectors in degrees; -1 if either is zero.
double angle_deg(const P& a, const P& b) {
  const double na = norm(a), nb = norm(b);
  if (!(na > 0) || !(nb > 0)) return -1;
  const double c = std::clamp(dot(a, b) / (na * nb), -1.0, 1.0);
  return std::acos(c) * 180.0 / kPi;
}

constexpr double kRightAngle = 90.0;

/// One way to pair two triangles: the edge (a, b) between them is removed.
struct Candidate {
  double quality = 0;
  int t1 = -1, t2 = -1;          ///< input faces: t1 has a -> b, t2 has b -> a
  std::array<int, 4> quad{};     ///< (a, d, b, c)
  int a = -1, b = -1;            ///< the removed diagonal
};

}  // namespace

double quad_quality(const P& p0, const P& p1, const P& p2, const P& p3, const QuadRecoveryOptions& options) {
  const P q[4] = {p0, p1, p2, p3};
  // Quad normal from its diagonals (exact for planar quads, a fair average otherwise).
  const P n = cross(sub(p2, p0), sub(p3, p1));
  if (!(norm(n) > 0)) return -1;
  double deviation = 0;
  for (int i = 0; i < 4; ++i) {
    const P& prev = q[(i + 3) % 4];
    const P& next = q[(i + 1) % 4];
    const P e1 = sub(next, q[i]), e2 = sub(prev, q[i]);
    const double angle = angle_deg(e1, e2);
    if (angle < 0) return -1;
    // Convex: every corner turns the same way as the quad.
    if (!(dot(cross(e1, e2), n) > 0)) return -1;
    deviation = std::max(deviation, std::abs(angle - kRightAngle));
  }
  const double fold = angle_deg(cross(sub(p1, p0), sub(p2, p0)), cross(sub(p2, p0), sub(p3, p0)));
  if (fold < 0) return -1;
  if (deviation > options.max_corner_deviation_deg || fold > options.max_fold_deg) return -1;
  return (1 - deviation / options.max_corner_deviation_deg) * (1 - 0.5 * fold / options.max_fold_deg);
}

QuadRecoveryResult recover_quads(const MeshInput& input, const QuadRecoveryOptions& options) {
  QuadRecoveryResult r;
  const int nf = input.num_faces();
  const int nv = input.num_vertices();
  std::vector<int> offset(static_cast<size_t>(nf) + 1, 0);
  for (int f = 0; f < nf; ++f) offset[f + 1] = offset[f] + input.face_sizes[f];
  auto vertex = [&](int f, int i) { return input.face_indices[offset[f] + i]; };
  auto is_triangle = [&](int f) { return input.face_sizes[f] == 3; };
  auto in_range = [&](int f) {
    for (int i = 0; i < input.face_sizes[f]; ++i)
      if (vertex(f, i) < 0 || vertex(f, i) >= nv) return false;
    return true;
  };

  // Directed edges of every face, grouped by undirected edge.
  struct HalfEdge {
    std::uint64_t key;
    int face, local;  ///< the edge runs from vertex(face, local) to the next one
  };
  std::vector<HalfEdge> halves;
  halves.reserve(input.face_indices.size());
  for (int f = 0; f < nf; ++f) {
    if (!in_range(f)) continue;  // left for validation to report
    const int n = input.face_sizes[f];
    for (int i = 0; i < n; ++i) {
      const auto a = static_cast<std::uint32_t>(vertex(f, i)), b = static_cast<std::uint32_t>(vertex(f, (i + 1) % n));
      halves.push_back({(std::uint64_t{std::min(a, b)} << 32) | std::max(a, b), f, i});
    }
  }
  std::sort(halves.begin(), halves.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return x.key != y.key ? x.key < y.key : x.face < y.face;
  });

  // Vertex data for fans: triangles around it, and whether it is interior and triangles-only.
  std::vector<int> triangles_at(static_cast<size_t>(nv), 0);
  std::vector<char> fan_candidate(static_cast<size_t>(nv), 1);
  for (int f = 0; f < nf; ++f) {
    if (!in_range(f)) continue;
    for (int i = 0; i < input.face_sizes[f]; ++i) {
      if (is_triangle(f)) ++triangles_at[vertex(f, i)];
      else fan_candidate[vertex(f, i)] = 0;
    }
  }

  std::vector<Candidate> candidates;
  for (size_t i = 0; i < halves.size();) {
    size_t j = i;
    while (j < halves.size() && halves[j].key == halves[i].key) ++j;
    if (j - i == 1) {  // boundary edge: its vertices are not interior
      const int f = halves[i].face, l = halves[i].local;
      fan_candidate[vertex(f, l)] = 0;
      fan_candidate[vertex(f, (l + 1) % input.face_sizes[f])] = 0;
    } else if (j - i == 2) {
      const HalfEdge& h1 = halves[i];
      const HalfEdge& h2 = halves[i + 1];
      if (is_triangle(h1.face) && is_triangle(h2.face) && h1.face != h2.face) {
        const int a = vertex(h1.face, h1.local), b = vertex(h1.face, (h1.local + 1) % 3);
        const int a2 = vertex(h2.face, h2.local), b2 = vertex(h2.face, (h2.local + 1) % 3);
        if (a2 == b && b2 == a) {  // opposite directions: consistently oriented
          const int c = vertex(h1.face, (h1.local + 2) % 3), d = vertex(h2.face, (h2.local + 2) % 3);
          if (c != d) {
            Candidate cand;
            cand.t1 = h1.face;
            cand.t2 = h2.face;
            cand.a = a;
            cand.b = b;
            cand.quad = {a, d, b, c};
            cand.quality = quad_quality(input.positions[a], input.positions[d], input.positions[b],
                                        input.positions[c], options);
            candidates.push_back(cand);
          }
        }
      }
    } else {  // non-manifold edge: never removed, and its vertices are not fans
      for (size_t k = i; k < j; ++k) {
        const int f = halves[k].face, l = halves[k].local;
        fan_candidate[vertex(f, l)] = 0;
        fan_candidate[vertex(f, (l + 1) % input.face_sizes[f])] = 0;
      }
    }
    i = j;
  }

  // Fans: candidates whose spokes pair into no good quad and are all about as long (a pole
  // is rotationally symmetric; a grid vertex that all four quad diagonals pass through is
  // not: its spokes alternate between edges and longer diagonals).
  std::vector<double> best_spoke(static_cast<size_t>(nv), -1);
  for (const Candidate& c : candidates) {
    best_spoke[c.a] = std::max(best_spoke[c.a], c.quality);
    best_spoke[c.b] = std::max(best_spoke[c.b], c.quality);
  }
  std::vector<double> shortest(static_cast<size_t>(nv), 1e300), longest(static_cast<size_t>(nv), 0);
  for (const HalfEdge& h : halves) {
    const int a = static_cast<int>(h.key >> 32), b = static_cast<int>(h.key & 0xffffffffu);
    const double len = norm(sub(input.positions[a], input.positions[b]));
    for (int v : {a, b}) {
      shortest[v] = std::min(shortest[v], len);
      longest[v] = std::max(longest[v], len);
    }
  }
  for (int v = 0; v < nv; ++v)
    if (fan_candidate[v] && !(longest[v] <= options.fan_max_spoke_ratio * shortest[v])) fan_candidate[v] = 0;
  std::vector<char> in_fan(static_cast<size_t>(nf), 0);
  for (int v = 0; v < nv; ++v) {
    if (!fan_candidate[v] || triangles_at[v] < options.fan_min_triangles) continue;
    if (best_spoke[v] >= options.fan_max_spoke_quality) continue;
    ++r.fan_vertices;
  }
  if (r.fan_vertices > 0) {
    for (int f = 0; f < nf; ++f) {
      if (!is_triangle(f) || !in_range(f)) continue;
      for (int i = 0; i < 3; ++i) {
        const int v = vertex(f, i);
        if (fan_candidate[v] && triangles_at[v] >= options.fan_min_triangles &&
            best_spoke[v] < options.fan_max_spoke_quality)
          in_fan[f] = 1;
      }
    }
  }

  // Greedy matching, best quad first (ties: input order, for determinism).
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& x, const Candidate& y) { return x.quality > y.quality; });
  std::vector<int> partner(static_cast<size_t>(nf), -1);
  std::vector<int> chosen(static_cast<size_t>(nf), -1);  // candidate index, at both triangles
  for (size_t k = 0; k < candidates.size(); ++k) {
    const Candidate& c = candidates[k];
    if (!(c.quality > 0)) break;
    if (partner[c.t1] >= 0 || partner[c.t2] >= 0 || in_fan[c.t1] || in_fan[c.t2]) continue;
    partner[c.t1] = c.t2;
    partner[c.t2] = c.t1;
    chosen[c.t1] = chosen[c.t2] = static_cast<int>(k);
  }

  // Output in input order; a quad takes the place of its first triangle.
  MeshInput& out = r.mesh;
  out.positions = input.positions;
  out.options = input.options;
  out.corners = input.corners;
  std::vector<int> output_face(static_cast<size_t>(nf), -1);
  for (int f = 0; f < nf; ++f) {
    if (is_triangle(f)) ++r.input_triangles;
    if (partner[f] >= 0) {
      if (partner[f] < f) {
        output_face[f] = output_face[partner[f]];
        continue;
      }
      const Candidate& c = candidates[chosen[f]];
      output_face[f] = out.num_faces();
      out.face_sizes.push_back(4);
      out.face_indices.insert(out.face_indices.end(), c.quad.begin(), c.quad.end());
      r.sources.push_back({f, partner[f]});
      ++r.quads;
      continue;
    }
    output_face[f] = out.num_faces();
    out.face_sizes.push_back(input.face_sizes[f]);
    out.face_indices.insert(out.face_indices.end(), input.face_indices.begin() + offset[f],
                            input.face_indices.begin() + offset[f + 1]);
    r.sources.push_back({f});
    if (is_triangle(f)) {
      ++r.triangles_kept;
      if (in_fan[f]) ++r.fan_triangles;
    } else {
      ++r.other_faces;
    }
  }

  // Tags: creases on removed diagonals go, holes follow their faces.
  std::vector<std::uint64_t> removed;
  for (int f = 0; f < nf; ++f) {
    if (partner[f] > f) {
      const Candidate& c = candidates[chosen[f]];
      const auto a = static_cast<std::uint32_t>(c.a), b = static_cast<std::uint32_t>(c.b);
      removed.push_back((std::uint64_t{std::min(a, b)} << 32) | std::max(a, b));
    }
  }
  std::sort(removed.begin(), removed.end());
  for (const CreaseTag& t : input.creases) {
    if (t.v0 >= 0 && t.v1 >= 0) {
      const auto a = static_cast<std::uint32_t>(t.v0), b = static_cast<std::uint32_t>(t.v1);
      if (std::binary_search(removed.begin(), removed.end(), (std::uint64_t{std::min(a, b)} << 32) | std::max(a, b)))
        continue;
    }
    out.creases.push_back(t);
  }
  for (int h : input.holes) {
    const int o = h >= 0 && h < nf ? output_face[h] : h;
    if (std::find(out.holes.begin(), out.holes.end(), o) == out.holes.end()) out.holes.push_back(o);
  }
  return r;
}

}  // namespace subd2nurbs
