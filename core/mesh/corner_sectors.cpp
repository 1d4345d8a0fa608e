#include "core/mesh/corner_sectors.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <set>
#include <utility>

#include "core/util/constants.h"

namespace subd2nurbs {
namespace {

using V3 = Eigen::Vector3d;

std::pair<int, int> edge_of(int a, int b) { return {std::min(a, b), std::max(a, b)}; }

// A sector's faces' normals within this of their mean: flat.
constexpr double kFlatDegrees = 5;

}  // namespace

std::vector<CornerSector> wide_corner_sectors(const MeshInput& cage, double min_degrees) {
  const int nv = cage.num_vertices();
  auto at = [&](int v) { return V3(cage.positions[v][0], cage.positions[v][1], cage.positions[v][2]); };
  // Corners need an infinitely sharp crease or a corner tag (boundary edges alone give a vertex of
  // a manifold cage two sharp edges at most), so only those vertices and their neighbours are
  // looked at: a cage without such tags costs one pass over its tags.
  std::set<std::pair<int, int>> sharp;  // infinitely sharp creases, then the boundary edges near corners
  for (const CreaseTag& c : cage.creases)
    if (c.sharpness >= kInfiniteSharpness) sharp.insert(edge_of(c.v0, c.v1));
  std::vector<char> corner(static_cast<std::size_t>(nv), 0), candidate(static_cast<std::size_t>(nv), 0);
  for (const CornerTag& c : cage.corners)
    if (c.sharpness >= kInfiniteSharpness && c.vertex >= 0 && c.vertex < nv)
      corner[static_cast<std::size_t>(c.vertex)] = candidate[static_cast<std::size_t>(c.vertex)] = 1;
  for (const auto& [a, b] : sharp) candidate[static_cast<std::size_t>(a)] = candidate[static_cast<std::size_t>(b)] = 1;
  if (std::find(candidate.begin(), candidate.end(), 1) == candidate.end()) return {};
  std::vector<char> hole(cage.face_sizes.size(), 0);
  for (const int h : cage.holes)
    if (h >= 0 && h < static_cast<int>(hole.size())) hole[static_cast<std::size_t>(h)] = 1;
  // The faces around candidates: their vertices are near (a sector's inside edges end there).
  std::vector<char> near(static_cast<std::size_t>(nv), 0);
  auto faces = [&](auto&& visit) {  // visit(offset, size) for each face with surface (no hole)
    std::size_t off = 0;
    for (std::size_t f = 0; f < cage.face_sizes.size(); ++f) {
      const int n = cage.face_sizes[f];
      if (!hole[f]) visit(off, n);
      off += static_cast<std::size_t>(n);
    }
  };
  auto touches = [&](std::size_t off, int n, const std::vector<char>& mark) {
    for (int k = 0; k < n; ++k)
      if (mark[static_cast<std::size_t>(cage.face_indices[off + k])]) return true;
    return false;
  };
  faces([&](std::size_t off, int n) {
    if (touches(off, n, candidate))
      for (int k = 0; k < n; ++k) near[static_cast<std::size_t>(cage.face_indices[off + k])] = 1;
  });
  // Around each candidate v, per face: the edge v -> a it leaves by, the edge v -> b it comes back
  // by (a face ... b v a ...; the next face around v leaves by v -> b) and its normal; the faces
  // of each edge at a near vertex (one: a boundary edge).
  struct FanFace {
    int a, b;
    V3 normal;
  };
  std::vector<std::vector<FanFace>> fans(static_cast<std::size_t>(nv));
  std::map<std::pair<int, int>, int> edge_faces;
  faces([&](std::size_t off, int n) {
    if (!touches(off, n, near)) return;
    const bool fan = touches(off, n, candidate);
    V3 normal = V3::Zero();
    if (fan) {
      for (int k = 0; k < n; ++k)
        normal += at(cage.face_indices[off + k]).cross(at(cage.face_indices[off + (k + 1) % n]));
      if (normal.norm() > 0) normal.normalize();
    }
    for (int k = 0; k < n; ++k) {
      const int v = cage.face_indices[off + k], a = cage.face_indices[off + (k + 1) % n];
      if (fan && candidate[static_cast<std::size_t>(v)])
        fans[static_cast<std::size_t>(v)].push_back({a, cage.face_indices[off + (k + n - 1) % n], normal});
      if (near[static_cast<std::size_t>(v)] || near[static_cast<std::size_t>(a)]) ++edge_faces[edge_of(v, a)];
    }
  });
  for (const auto& [e, count] : edge_faces)
    if (count == 1) sharp.insert(e);
  std::vector<int> sharp_count(static_cast<std::size_t>(nv), 0);
  for (const auto& [a, b] : sharp) ++sharp_count[static_cast<std::size_t>(a)], ++sharp_count[static_cast<std::size_t>(b)];

  const double flat = std::cos(kFlatDegrees * kPi / 180);
  std::vector<CornerSector> out;
  for (int v = 0; v < nv; ++v) {
    const std::vector<FanFace>& fan = fans[static_cast<std::size_t>(v)];
    if (fan.empty() || !(corner[static_cast<std::size_t>(v)] || sharp_count[static_cast<std::size_t>(v)] >= 3)) continue;
    std::map<int, int> leaving;  // a -> the face (index in fan) leaving by v -> a
    for (std::size_t i = 0; i < fan.size(); ++i) leaving[fan[i].a] = static_cast<int>(i);
    std::vector<int> starts;  // sectors start at a sharp or boundary edge
    for (const auto& [a, i] : leaving)
      if (sharp.count(edge_of(v, a))) starts.push_back(a);
    if (starts.size() < 2) continue;  // a dart, or a tagged vertex inside a smooth fan
    for (const int start : starts) {
      CornerSector s;
      s.corner = v;
      double angle = 0;
      std::vector<std::pair<int, double>> inside;  // edges v -> b inside the sector, the angle up to each
      std::vector<V3> normals;
      for (int a = start;;) {
        const FanFace& f = fan[static_cast<std::size_t>(leaving.at(a))];
        const V3 ea = at(a) - at(v), eb = at(f.b) - at(v);
        angle += std::atan2(ea.cross(eb).norm(), ea.dot(eb));
        normals.push_back(f.normal);
        if (sharp.count(edge_of(v, f.b)) || !leaving.count(f.b) || f.b == start) break;
        inside.emplace_back(f.b, angle);
        a = f.b;
      }
      s.degrees = angle * 180 / kPi;
      if (!(s.degrees > min_degrees)) continue;
      s.faces = static_cast<int>(normals.size());
      V3 mean = V3::Zero();
      for (const V3& n : normals) mean += n;
      s.flat = mean.norm() > 0 && std::all_of(normals.begin(), normals.end(), [&, unit = mean.normalized()](const V3& n) {
                 return n.dot(unit) >= flat;
               });
      // The middle edge: its far vertex on no sharp edge and no corner (a crease tagged there
      // would make a corner of it: a kink in a curve, or curves joined).
      double best = INFINITY;
      for (const auto& [b, up_to] : inside)
        if (sharp_count[static_cast<std::size_t>(b)] == 0 && !corner[static_cast<std::size_t>(b)] &&
            std::abs(up_to - angle / 2) < best)
          best = std::abs(up_to - angle / 2), s.middle = b;
      out.push_back(s);
    }
  }
  return out;
}

}  // namespace subd2nurbs
