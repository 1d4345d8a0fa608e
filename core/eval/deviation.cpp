#include "core/eval/deviation.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include <Eigen/Core>
#include <Eigen/Dense>

#include "core/patch/quad_frames.h"
#include "core/util/bicubic.h"
#include "core/util/constants.h"
#include "core/util/eigen_point.h"
#include "core/util/parallel.h"

namespace subd2nurbs {
namespace {

using V3 = Eigen::Vector3d;

// Cubic Bernstein values and first derivatives.
void bernstein(double t, double b[4], double db[4]) {
  const double s = 1 - t;
  b[0] = s * s * s; b[1] = 3 * t * s * s; b[2] = 3 * t * t * s; b[3] = t * t * t;
  db[0] = -3 * s * s; db[1] = 3 * s * s - 6 * t * s; db[2] = 6 * t * s - 3 * t * t; db[3] = 3 * t * t;
}

struct NetPoint { V3 p, du, dv; };
NetPoint eval_net(const Point3* net, double u, double v) {
  double bu[4], dbu[4], bv[4], dbv[4];
  bernstein(u, bu, dbu);
  bernstein(v, bv, dbv);
  Point3 p, du, dv;
  bicubic_first(net, bu, dbu, bv, dbv, p, du, dv);
  return {to_eigen(p), to_eigen(du), to_eigen(dv)};
}

// Squared distance from q to the bounding box of a net: a lower bound of its squared distance
// to the patch (a Bezier patch lies in the convex hull of its net).
double squared_distance_to_box(const Point3* net, const V3& q) {
  double d2 = 0;
  for (int c = 0; c < 3; ++c) {
    double lo = net[0][c], hi = net[0][c];
    for (int k = 1; k < 16; ++k) {
      lo = std::min(lo, net[k][c]);
      hi = std::max(hi, net[k][c]);
    }
    const double out = q[c] < lo ? lo - q[c] : (q[c] > hi ? q[c] - hi : 0.0);
    d2 += out * out;
  }
  return d2;
}

// Distance from q to a Bezier patch: best of a 3x3 seed grid, then clamped Gauss-Newton.
double distance_to_net(const Point3* net, const V3& q) {
  double best = 1e300, bu = 0.5, bv = 0.5;
  for (int a = 0; a <= 2; ++a)
    for (int b = 0; b <= 2; ++b) {
      const double d = (eval_net(net, a / 2.0, b / 2.0).p - q).squaredNorm();
      if (d < best) { best = d; bu = a / 2.0; bv = b / 2.0; }
    }
  double u = bu, v = bv;
  for (int it = 0; it < 20; ++it) {
    const NetPoint e = eval_net(net, u, v);
    const V3 r = e.p - q;
    Eigen::Matrix2d J;
    J << e.du.dot(e.du), e.du.dot(e.dv), e.du.dot(e.dv), e.dv.dot(e.dv);
    const Eigen::Vector2d g(e.du.dot(r), e.dv.dot(r));
    if (std::abs(J.determinant()) < 1e-300) break;
    const Eigen::Vector2d step = J.ldlt().solve(g);
    const double nu = std::clamp(u - step.x(), 0.0, 1.0), nv = std::clamp(v - step.y(), 0.0, 1.0);
    const bool small = std::abs(nu - u) + std::abs(nv - v) < 1e-15;
    u = nu;
    v = nv;
    if (small) break;
  }
  return std::min(std::sqrt(best), (eval_net(net, u, v).p - q).norm());
}

// Level-k faces within `rings` face rings of vertex v, in breadth-first order, with the ring
// each lies in (0 = faces touching v).
std::vector<std::pair<int, int>> face_rings(const PolyMesh& m, int v, int rings) {
  std::vector<std::pair<int, int>> faces;
  std::unordered_set<int> seen_face, seen_vertex{v};
  std::vector<int> frontier{v};
  for (int r = 0; r < rings; ++r) {
    std::vector<int> next;
    for (int x : frontier) {
      const int* cs = m.vertex_corners(x);
      for (int i = 0; i < m.vertex_face_count(x); ++i) {
        const int f = m.corner_face(cs[i]);
        if (!seen_face.insert(f).second) continue;
        faces.emplace_back(f, r);
        for (int h = m.face_begin(f); h < m.face_end(f); ++h)
          if (seen_vertex.insert(m.corner_vertex(h)).second) next.push_back(m.corner_vertex(h));
      }
    }
    frontier.swap(next);
  }
  return faces;
}

}  // namespace

double deviation_rate(int n) {
  if (n < 3) return 1.0;
  const double c1 = std::cos(2 * kPi / n), h1 = std::cos(kPi / n);
  const double lambda = (5 + c1 + h1 * std::sqrt(2 * (9 + c1))) / 16;
  const double c2 = std::cos(4 * kPi / n), h2 = std::cos(2 * kPi / n);
  const double mu = (5 + c2 + h2 * std::sqrt(2 * (9 + c2))) / 16;
  return 1.0 / std::max(lambda * lambda, mu);
}

DeviationReport measure_deviation(const PatchBuild& build, int sample_levels, const DeviationReport* previous,
                                  const std::vector<char>* remeasure) {
  DeviationReport out;
  out.sample_levels = sample_levels;
  // Fans are measured in parallel, then summarised in fan order (the result does not depend on
  // the threads).
  std::vector<FanDeviation> per_fan(build.info.fans.size());
  const bool incremental = previous && remeasure && previous->fans.size() == per_fan.size() &&
                           remeasure->size() == per_fan.size() && previous->sample_levels == sample_levels;
  parallel_for(static_cast<int>(build.info.fans.size()), [&](int fi) {
    FanDeviation& fd = per_fan[fi];
    if (incremental && !(*remeasure)[fi]) {
      fd = previous->fans[fi];
      return;
    }
    const IrregularFan& fan = build.info.fans[fi];
    double& sum = fd.sum;
    const FanPiece& piece = build.fan_pieces.at(static_cast<size_t>(fan.piece));
    const SubdivLevel& lk = piece.mesh.level;
    const PolyMesh& mk = lk.mesh;
    // The zone (2 face rings) and a margin of 3 more rings (the fan's piece of level k_v), as
    // a stand-alone cage.
    const std::vector<std::pair<int, int>> local = face_rings(mk, piece.vertex, 5);  // zone: rings 0, 1
    std::unordered_map<int, int> local_vertex;
    MeshInput sub;
    sub.options = lk.options;
    auto local_index = [&](int v) {
      auto [it, inserted] = local_vertex.emplace(v, static_cast<int>(sub.positions.size()));
      if (inserted) {
        sub.positions.push_back(piece.mesh.x[v]);
        // Semi-sharp tags are at least 3 rings from the vertex at its fan's level (its zone and
        // the samples' neighbourhoods are clear of them): dropping them changes no sample.
        if (lk.vertex_sharpness[v] >= kInfiniteSharpness) sub.corners.push_back({it->second, lk.vertex_sharpness[v]});
      }
      return it->second;
    };
    std::unordered_map<int, int> local_face;
    for (const auto& [f, ring] : local) {
      if (lk.face_hole[f]) sub.holes.push_back(static_cast<int>(sub.face_sizes.size()));
      local_face[f] = static_cast<int>(sub.face_sizes.size());
      sub.face_sizes.push_back(mk.face_size(f));
      for (int h = mk.face_begin(f); h < mk.face_end(f); ++h) sub.face_indices.push_back(local_index(mk.corner_vertex(h)));
    }
    // Interior sharp edges keep their sharpness (boundary edges of the real mesh stay boundary).
    for (const auto& [f, ring] : local)
      for (int h = mk.face_begin(f); h < mk.face_end(f); ++h) {
        const int e = mk.corner_edge(h);
        if (lk.edge_sharpness[e] >= kInfiniteSharpness && !mk.is_boundary_edge(e) && mk.edge_corner(e) == h)
          sub.creases.push_back({local_vertex[mk.edge_vertex(e, 0)], local_vertex[mk.edge_vertex(e, 1)], lk.edge_sharpness[e]});
      }
    // Refine the local cage, following the zone faces' descendants.
    SubdivLevel level = SubdivLevel::from_input(sub);
    std::vector<Point3> x = sub.positions;
    std::vector<int> faces;  // descendants, with their root level-k face
    std::vector<int> roots;
    for (const auto& [f, ring] : local)
      if (ring < 2 && !lk.face_hole[f]) { faces.push_back(local_face[f]); roots.push_back(f); }
    for (int s = 0; s < sample_levels; ++s) {
      RefinementStep step = refine_once(level);
      std::vector<Point3> y;
      step.stencils.apply(x, y);
      std::vector<int> child_faces, child_roots;
      for (size_t i = 0; i < faces.size(); ++i)
        for (int h = level.mesh.face_begin(faces[i]); h < level.mesh.face_end(faces[i]); ++h) {
          child_faces.push_back(h);  // child face index = parent corner
          child_roots.push_back(roots[i]);
        }
      level = std::move(step.child);
      x.swap(y);
      faces.swap(child_faces);
      roots.swap(child_roots);
    }
    std::vector<Point3> limit;
    limit_stencils(level).apply(x, limit);
    // Samples: the vertices of the descendant faces, each measured against its root face's
    // net and the nets of the faces sharing an edge with it.
    fd.fan = fi;
    std::vector<char> done(level.mesh.num_vertices(), 0);
    for (size_t i = 0; i < faces.size(); ++i) {
      const int root = roots[i];
      std::vector<int> candidates{root};
      for (int h = mk.face_begin(root); h < mk.face_end(root); ++h)
        if (const int t = mk.twin(h); t >= 0) candidates.push_back(mk.corner_face(t));
      for (int h = level.mesh.face_begin(faces[i]); h < level.mesh.face_end(faces[i]); ++h) {
        const int v = level.mesh.corner_vertex(h);
        if (done[v]) continue;
        done[v] = 1;
        const V3 q = to_eigen(limit[v]);
        double d = 1e300;
        for (int c : candidates) {  // the root face first: it usually holds the nearest point
          if (!piece.has_net[c]) continue;
          const Point3* net = &piece.nets[static_cast<size_t>(c) * 16];
          // A net whose box is no nearer than the best distance so far cannot lower it.
          if (d < 1e300 && squared_distance_to_box(net, q) >= d * d) continue;
          d = std::min(d, distance_to_net(net, q));
        }
        if (d > fd.max) fd.where = limit[v];
        fd.max = std::max(fd.max, d);
        ++fd.samples;
        sum += d;
      }
    }
  });
  double sum = 0;
  for (size_t fi = 0; fi < per_fan.size(); ++fi) {
    const FanDeviation& fd = per_fan[fi];
    sum += fd.sum;
    if (fd.max > out.max) {
      out.max = fd.max;
      out.where = fd.where;
      out.worst_fan = static_cast<int>(fi);
    }
    out.samples += fd.samples;
    out.fans.push_back(fd);
  }
  out.mean = out.samples ? sum / out.samples : 0;
  return out;
}

int fan_extra_levels_for_tolerance(const IrregularFan& fan, double max, double tolerance) {
  if (max <= tolerance) return 0;
  double rate = 2.0;
  switch (fan.mode) {
    case FanMode::Smooth:
    case FanMode::Dart: rate = deviation_rate(fan.valence); break;
    case FanMode::Crease: rate = deviation_rate(2 * fan.sectors); break;
    case FanMode::Corner: rate = deviation_rate(4 * fan.sectors); break;
    case FanMode::Approximate: rate = 2.0; break;
  }
  rate = std::max(rate, 1.2);
  return static_cast<int>(std::ceil(std::log(max / tolerance) / std::log(rate) - 1e-9));
}

}  // namespace subd2nurbs
