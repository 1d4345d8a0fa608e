#include "core/patch/patch_builder.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Core>

#include "core/patch/fan_construction.h"
#include "core/patch/knot_assembly.h"
#include "core/patch/quad_frames.h"
#include "core/patch/regular_net.h"
#include "core/polar/polar_separation.h"
#include "core/util/eigen_point.h"
#include "core/util/parallel.h"
#include "core/util/tolerances.h"

namespace subd2nurbs {

const char* to_string(FanMode mode) {
  switch (mode) {
    case FanMode::Smooth: return "smooth";
    case FanMode::Dart: return "dart";
    case FanMode::Crease: return "crease";
    case FanMode::Corner: return "corner";
    case FanMode::Approximate: return "approximate";
  }
  return "?";
}


namespace {

using frames::face_net_index;
using frames::rotation_in_face;
using frames::step_x;
using frames::step_y;

/// Deepest level any local refinement may reach above the coarse level. Semi-sharp tags below
/// infinity (10) decay to 0 within 11 levels (Chaikin's averaging within a few more), and
/// extra levels for a tolerance are bounded by the caller; this only guards against a bug.
constexpr int kMaxDepth = 30;

constexpr int kFanRings = 5;     ///< faces kept around a fan's vertex at its level
constexpr int kRefineRings = 3;  ///< faces kept around it on the level refined into k_v
constexpr int kFanClear = 3;   ///< rings around it that must be free of semi-sharp tags

bool semi(float s) { return s > 0.0f && s < static_cast<float>(kInfiniteSharpness); }

/// A semi-sharp tag on a vertex, or on an edge of a face, within `rings` rings of v.
bool semi_sharp_near(const SubdivLevel& l, int v, int rings) {
  const PolyMesh& m = l.mesh;
  for (int f : face_rings(m, {v}, rings))
    for (int h = m.face_begin(f); h < m.face_end(f); ++h)
      if (semi(l.edge_sharpness[m.corner_edge(h)]) || semi(l.vertex_sharpness[m.corner_vertex(h)])) return true;
  return false;
}

/// Cuts the faces within `rings` rings of `seeds` out of `piece`; `follow` are corners of the
/// piece, returned as the same corners of the new piece.
LocalMesh recut(const LocalMesh& piece, const std::vector<int>& seeds, int rings, std::vector<int>& follow) {
  const PolyMesh& m = piece.level.mesh;
  const std::vector<int> faces = face_rings(m, seeds, rings);
  LocalMesh out = cut_out(piece, faces);
  for (int& c : follow) {
    const int f = m.corner_face(c);
    const auto it = std::lower_bound(faces.begin(), faces.end(), f);
    if (it == faces.end() || *it != f) throw std::logic_error("patch builder: a needed face fell out of its piece");
    c = out.level.mesh.face_begin(static_cast<int>(it - faces.begin())) + (c - m.face_begin(f));
  }
  return out;
}

/// The zone of one sector of a fan: the 7 x 7 Bezier points of its four level-k_v quads in
/// the sector's frame (x along the coarse face's edge leaving the vertex).
struct Zone {
  int level = 0;
  std::array<Point3, 49> net{};
};

/// Zone points (sector frame, x, y in 0..6) seen from corner i of the coarse face: patch
/// indices (I, J) with I along u.
std::pair<int, int> zone_to_patch(int i, int x, int y) {
  switch (i) {
    case 0: return {x, y};
    case 1: return {6 - y, x};
    case 2: return {6 - x, 6 - y};
    default: return {y, 6 - x};
  }
}

struct RayRecord {
  int fan = -1;
  Continuity continuity = Continuity::C2;
  double c = 0;
};

/// Everything the fans leave for the coarse quads.
struct FanResults {
  std::vector<std::array<int, 4>> zone_of_corner;  ///< per level-a face and corner: index into zones
  std::vector<Zone> zones;
  std::vector<RayRecord> rays;  ///< per level-a edge and end: 2 e + (edge_vertex(e, 0) == v ? 0 : 1)
};

/// The fans of one coarse vertex, before they are numbered among all fans.
struct VertexFans {
  std::vector<IrregularFan> fans;  ///< `piece` is 0: the vertex's own piece
  std::vector<FanPiece> pieces;    ///< none or one
  std::vector<std::pair<std::array<int, 2>, Zone>> zones;  ///< (coarse face, corner) -> zone
  std::vector<std::pair<int, RayRecord>> rays;              ///< FanResults::rays slot -> ray (local fan index)
  int level = 0;
};

/// Builds the fans of coarse vertex v (if it has any once its semi-sharp tags decay).
VertexFans build_fans_at(const SubdivLevel& la, const std::vector<Point3>& xa, int v, int min_level, int a,
                         int cage_vertices, const std::vector<char>& capped_a) {
  VertexFans out;
  const PolyMesh& ma = la.mesh;
  std::vector<int> follow;
  // The fan is built on the kFanRings rings around v at its level. A piece of r rings that is
  // refined gives children whose points within 2r - 1 rings of v are exact: such a child point
  // is the point of a face within r rings, of an edge with an end within r - 1 rings, or of a
  // vertex within r - 1 rings, and reads only faces within r (for Chaikin creases, the edges at
  // that end or vertex, inside the same faces). The points the cut gets wrong (its outer
  // vertices and the edges between them) are children 2r rings out, which no later step reads.
  // So the level before k_v keeps 3 rings (5 exact rings at k_v), the levels before it 2 (3
  // exact rings, all the next cut takes), and the last piece is cut to kFanRings.
  auto rings_at = [&](int l) { return l + 1 < min_level ? 2 : l < min_level ? kRefineRings : kFanRings; };
  LocalMesh piece = cut_out(la, xa, face_rings(ma, {v}, rings_at(a)));
  auto local_vertex = [&](const LocalMesh& p) {
    for (int u = 0; u < p.level.mesh.num_vertices(); ++u)
      if (p.origin_vertex[u] == v && p.level.mesh.vertex_face_count(u) == ma.vertex_face_count(v)) return u;
    throw std::logic_error("patch builder: fan vertex lost in its piece");
  };
  int lv = local_vertex(piece);
  int level = a;
  while (level < min_level || semi_sharp_near(piece.level, lv, kFanClear)) {
    if (level - a >= kMaxDepth) throw std::logic_error("patch builder: semi-sharp tags do not decay at vertex " + std::to_string(v));
    const LocalMesh refined = refine_piece(piece);
    piece = recut(refined, {lv}, rings_at(level + 1), follow);  // lv: vertex-child keeps its index
    lv = local_vertex(piece);
    ++level;
  }
  const LevelView L{piece.level, piece.level.mesh, piece.x};
  std::vector<Fan> fans = fans_at(L, lv);
  // Fans inside a polar cap (the pole itself) make no Catmull-Clark patch.
  fans.erase(std::remove_if(fans.begin(), fans.end(),
                            [&](const Fan& f) {
                              for (int c : f.sectors)
                                if (!capped_a[piece.origin_face[piece.level.mesh.corner_face(c)]]) return false;
                              return true;
                            }),
             fans.end());
  if (fans.empty()) return out;
  const PolyMesh& m = piece.level.mesh;
  FanPiece fp;
  fp.vertex = lv;
  fp.level = level;
  fp.nets.assign(static_cast<size_t>(m.num_faces()) * 16, Point3{});
  fp.has_net.assign(m.num_faces(), 0);
  for (int f : face_rings(m, {lv}, kFanClear))
    if (is_regular_leaf(L, f)) {
      regular_net(L, f, &fp.nets[static_cast<size_t>(f) * 16]);
      fp.has_net[f] = 1;
    }
  const Point3 limit = vertex_limit(piece.level, piece.x, lv);
  FanBuilder fb(L, limit, fp.nets);
  for (const Fan& fan : fans) {
    std::vector<RayKind> kinds;
    std::vector<int> ray_edges;
    IrregularFan rec;
    rec.vertex = v;
    rec.base_vertex = a == 0 || v < cage_vertices ? v : -1;
    rec.mode = fan.mode;
    rec.valence = m.valence(lv);
    rec.sectors = static_cast<int>(fan.sectors.size());
    rec.c = fb.build(fan, kinds, ray_edges);
    rec.level = level;
    rec.piece = 0;
    out.fans.push_back(rec);
    const int fan_index = static_cast<int>(out.fans.size()) - 1;
    const int ns = static_cast<int>(fan.sectors.size());
    // Zones, keyed by coarse face and corner.
    std::vector<std::pair<int, int>> face_corner(ns);
    for (int s = 0; s < ns; ++s) {
      const int c00 = fan.sectors[s];
      const int F = piece.origin_face[m.corner_face(c00)];
      int i = 0;
      while (i < 4 && ma.corner_vertex(ma.face_begin(F) + i) != v) ++i;
      if (i == 4) throw std::logic_error("patch builder: a fan sector outside its coarse face");
      face_corner[s] = {F, i};
      Zone z;
      z.level = level;
      const int q[4] = {c00, step_x(m, c00), step_y(m, c00), step_y(m, step_x(m, c00))};
      const int qa[4] = {0, 1, 0, 1}, qb[4] = {0, 0, 1, 1};
      for (int k = 0; k < 4; ++k) {
        const int f = m.corner_face(q[k]), r = rotation_in_face(m, q[k]);
        fp.has_net[f] = 1;
        for (int x = 0; x < 4; ++x)
          for (int y = 0; y < 4; ++y) z.net[(3 * qa[k] + x) * 7 + 3 * qb[k] + y] = fp.nets[static_cast<size_t>(f) * 16 + face_net_index(r, x, y)];
      }
      out.zones.push_back({{F, i}, z});
    }
    // Rays: ray r < ns is sector r's x axis (edge i of its coarse face), the end ray of an
    // open fan is the last sector's y axis (the edge before corner i).
    for (size_t r = 0; r < kinds.size(); ++r) {
      const bool end = static_cast<int>(r) == ns;
      const auto [F, i] = face_corner[end ? ns - 1 : r];
      const int corner = ma.face_begin(F) + i;
      const int e = ma.corner_edge(end ? ma.prev(corner) : corner);
      out.rays.push_back({2 * e + (ma.edge_vertex(e, 0) == v ? 0 : 1),
                          {fan_index, kinds[r] == RayKind::G1 ? Continuity::G1 : Continuity::C0, rec.c}});
    }
  }
  fp.mesh = std::move(piece);
  out.pieces.push_back(std::move(fp));
  out.level = level;
  return out;
}

/// An active sub-quad of a coarse face: its frame corner in the current piece (x along u), its
/// square in the patch domain, and which of the faces being built it belongs to.
struct SubQuad {
  int corner;
  double u0, v0, size;
  int owner;
};

/// The leaves of the coarse faces Fs (quads, none a regular leaf at level a), refining locally
/// where they are not yet one bicubic: leaves[k] and deepest[k] for Fs[k]. All of Fs share one
/// piece per level, the union of the 2-rings of what they still split; a point of a level that
/// lies inside the 2-ring margin of both a face's own piece and a shared one is the same number
/// (the pieces' faces, corners and fans keep the order of the whole level, so every stencil
/// sums in the same order), so the leaves do not depend on which faces are built together.
/// Several quads at a valence-n vertex built together cost O(n L) instead of O(n^2 L).
void leaves_of_faces(const SubdivLevel& la, const std::vector<Point3>& xa, const std::vector<int>& Fs, int a,
                     const FanResults& fans, std::vector<PatchLeaves*>& leaves, std::vector<int>& deepest) {
  const PolyMesh& ma = la.mesh;
  auto emit_regular = [&](const LevelView& L, int c, const SubQuad& q, int level) {
    const int f = L.m.corner_face(c), r = rotation_in_face(L.m, c);
    Point3 net[16];
    regular_net(L, f, net);
    PatchLeaf leaf;
    leaf.u0 = q.u0;
    leaf.v0 = q.v0;
    leaf.size = q.size;
    leaf.level = level;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) leaf.net[i * 4 + j] = net[face_net_index(r, i, j)];
    leaves[q.owner]->push_back(leaf);
  };
  // The corner of F a sub-quad touches (-1 if none); corner i sits at (cu, cv).
  auto touched_corner = [](const SubQuad& q) {
    const bool lo_u = q.u0 == 0, hi_u = q.u0 + q.size == 1, lo_v = q.v0 == 0, hi_v = q.v0 + q.size == 1;
    if (lo_u && lo_v) return 0;
    if (hi_u && lo_v) return 1;
    if (hi_u && hi_v) return 2;
    if (lo_u && hi_v) return 3;
    return -1;
  };
  std::vector<int> follow;
  const std::vector<int> first_faces = face_rings(ma, vertices_of(ma, Fs), 2);
  LocalMesh piece = cut_out(la, xa, first_faces);
  std::vector<SubQuad> active;
  for (size_t k = 0; k < Fs.size(); ++k) {
    const int F_in_piece = static_cast<int>(std::lower_bound(first_faces.begin(), first_faces.end(), Fs[k]) - first_faces.begin());
    active.push_back({piece.level.mesh.face_begin(F_in_piece), 0, 0, 1, static_cast<int>(k)});
  }
  for (int level = a;; ++level) {
    if (level - a > kMaxDepth) throw std::logic_error("patch builder: coarse face " + std::to_string(Fs.front()) + " does not resolve");
    const LevelView L{piece.level, piece.level.mesh, piece.x};
    std::vector<SubQuad> split;
    for (const SubQuad& q : active) {
      const int ci = touched_corner(q);
      const int zi = ci >= 0 ? fans.zone_of_corner[Fs[q.owner]][ci] : -1;
      if (zi >= 0) {
        const Zone& z = fans.zones[zi];
        if (level == z.level - 1) {
          const double h = q.size / 2;
          for (int qa = 0; qa < 2; ++qa)
            for (int qb = 0; qb < 2; ++qb) {
              PatchLeaf leaf;
              leaf.u0 = q.u0 + qa * h;
              leaf.v0 = q.v0 + qb * h;
              leaf.size = h;
              leaf.level = z.level;
              leaf.zone = true;
              for (int x = 0; x < 7; ++x)
                for (int y = 0; y < 7; ++y) {
                  const auto [I, J] = zone_to_patch(ci, x, y);
                  if (I >= 3 * qa && I <= 3 * qa + 3 && J >= 3 * qb && J <= 3 * qb + 3)
                    leaf.net[(I - 3 * qa) * 4 + (J - 3 * qb)] = z.net[x * 7 + y];
                }
              leaves[q.owner]->push_back(leaf);
            }
          deepest[q.owner] = std::max(deepest[q.owner], z.level);
          continue;
        }
        split.push_back(q);
        continue;
      }
      if (is_regular_leaf(L, L.m.corner_face(q.corner))) {
        emit_regular(L, q.corner, q, level);
        deepest[q.owner] = std::max(deepest[q.owner], level);
      } else {
        split.push_back(q);
      }
    }
    if (split.empty()) break;
    // Keep the 2-ring of the sub-quads to split (the first piece is that ring already), then
    // refine it: the children's 1-rings, all that their nets and tags read, are exact.
    if (level > a) {
      follow.clear();
      std::vector<int> split_faces;
      for (const SubQuad& q : split) {
        follow.push_back(q.corner);
        split_faces.push_back(piece.level.mesh.corner_face(q.corner));
      }
      piece = recut(piece, vertices_of(piece.level.mesh, split_faces), 2, follow);
      for (size_t i = 0; i < split.size(); ++i) split[i].corner = follow[i];
    }
    const PolyMesh& mp = piece.level.mesh;
    LocalMesh refined = refine_piece(piece);
    const PolyMesh& mc = refined.level.mesh;
    const int dx[4] = {0, 1, 1, 0}, dy[4] = {0, 0, 1, 1};
    std::vector<SubQuad> children;
    for (const SubQuad& q : split) {
      const int P = mp.corner_face(q.corner), r = rotation_in_face(mp, q.corner);
      const double h = q.size / 2;
      for (int j = 0; j < 4; ++j) {
        const int child_face = mp.face_begin(P) + (r + j) % mp.face_size(P);
        const int child_corner = mc.face_begin(child_face) + (4 - j) % 4;
        children.push_back({child_corner, q.u0 + dx[j] * h, q.v0 + dy[j] * h, h, q.owner});
      }
    }
    piece = std::move(refined);
    active.swap(children);
  }
}

/// The leaves of coarse face F alone; a regular leaf at level a is its own patch.
PatchLeaves leaves_of(const SubdivLevel& la, const std::vector<Point3>& xa, int F, int a, const FanResults& fans,
                      int& deepest) {
  const PolyMesh& ma = la.mesh;
  PatchLeaves leaves;
  const LevelView L{la, ma, xa};
  if (is_regular_leaf(L, F)) {  // most coarse quads are one bicubic already
    const int r = 0;
    Point3 net[16];
    regular_net(L, F, net);
    PatchLeaf leaf;
    leaf.level = a;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) leaf.net[i * 4 + j] = net[face_net_index(r, i, j)];
    leaves.push_back(leaf);
    return leaves;
  }
  std::vector<PatchLeaves*> out{&leaves};
  std::vector<int> d{deepest};
  leaves_of_faces(la, xa, {F}, a, fans, out, d);
  deepest = d[0];
  return leaves;
}

KnotVector reversed(const KnotVector& kv) {
  KnotVector r;
  for (size_t i = kv.knots.size(); i-- > 0;) {
    r.knots.push_back(1.0 - kv.knots[i]);
    r.mults.push_back(kv.mults[i]);
  }
  r.knots.front() = 0.0;
  r.knots.back() = 1.0;
  return r;
}

/// PatchOptions::separate_poles: the separating first step at the poles that need it, then
/// the ordinary build of that level-1 cage. False (and `out` untouched) if no pole needs it.
bool build_with_separated_poles(const SubdivLevel& base, const std::vector<Point3>& positions,
                                const PatchOptions& options, PatchBuild& out) {
  const PolyMesh& m = base.mesh;
  const PolarDetection polar = detect_polar_structures(base);
  std::vector<int> chosen;
  std::vector<RejectedPole> left;
  std::vector<char> taken(m.num_vertices(), 0);
  for (const RejectedPole& r : polar.rejected) {
    bool ok = (r.kind == RejectedPole::Kind::LowValence || r.kind == RejectedPole::Kind::TooClose) &&
              separation_obstacle(base, r.vertex).empty();
    for (int i = 0; ok && i < m.vertex_face_count(r.vertex); ++i) ok = !taken[m.to_vertex(m.vertex_corners(r.vertex)[i])];
    if (ok) {
      chosen.push_back(r.vertex);
      taken[r.vertex] = 1;
    } else {
      left.push_back(r);
    }
  }
  if (chosen.empty()) return false;
  const SeparatedLevel sl = separate_poles(base, positions, chosen);
  PatchOptions once = options;
  once.separate_poles = false;
  out = build_patches(sl.level, sl.positions, once);
  for (NurbsPatch& p : out.set.patches) {
    for (int& f : p.base_faces) f = sl.cage_face[f];
    std::sort(p.base_faces.begin(), p.base_faces.end());
    p.base_faces.erase(std::unique(p.base_faces.begin(), p.base_faces.end()), p.base_faces.end());
  }
  out.info.separated_poles = chosen;
  out.info.rejected_poles = left;  // the level-1 cage has no other all-triangle vertices
  out.set.model_size = bounding_diagonal(base.mesh, positions);  // of the cage, not of its level 1
  return true;
}

/// The fans of every coarse vertex that stays irregular for some quad once its semi-sharp tags
/// have decayed (those tags count as smooth in this view; infinitely sharp ones stay), built in
/// parallel and numbered in vertex order into out.info.fans and out.fan_pieces.
FanResults build_all_fans(const SubdivLevel& la, const std::vector<Point3>& xa, int a, int cage_vertices,
                          const std::vector<char>& capped_a, PatchBuild& out) {
  FanResults fans;
  PatchBuildInfo& info = out.info;
  const PolyMesh& ma = la.mesh;
  fans.zone_of_corner.assign(ma.num_faces(), {-1, -1, -1, -1});
  fans.rays.assign(static_cast<size_t>(2) * ma.num_edges(), RayRecord{});
  {
    // The level with its semi-sharp tags decayed (a copy only when it has any).
    const bool any_semi = std::any_of(la.edge_sharpness.begin(), la.edge_sharpness.end(), semi) ||
                          std::any_of(la.vertex_sharpness.begin(), la.vertex_sharpness.end(), semi);
    SubdivLevel decayed;
    if (any_semi) {
      decayed = la;
      for (float& s : decayed.edge_sharpness) if (semi(s)) s = 0.0f;
      for (float& s : decayed.vertex_sharpness) if (semi(s)) s = 0.0f;
    }
    const SubdivLevel& dl = any_semi ? decayed : la;
    const LevelView D{dl, dl.mesh, xa};
    std::vector<int> candidates;
    for (int v = 0; v < ma.num_vertices(); ++v)
      if (ma.vertex_face_count(v) > 0 && !fans_at(D, v).empty()) candidates.push_back(v);
    std::vector<VertexFans> built(candidates.size());
    parallel_for(static_cast<int>(candidates.size()), [&](int i) {
      const int v = candidates[i];
      built[i] = build_fans_at(la, xa, v, a + 2 + out.vertex_extra[v], a, cage_vertices, capped_a);
    });
    // Number them in vertex order (the same whatever the threads did).
    for (VertexFans& vf : built) {
      if (vf.fans.empty()) continue;
      const int first_fan = static_cast<int>(info.fans.size());
      for (IrregularFan& f : vf.fans) {
        f.piece = static_cast<int>(out.fan_pieces.size());
        info.fans.push_back(f);
      }
      out.fan_pieces.push_back(std::move(vf.pieces.front()));
      for (auto& [key, z] : vf.zones) {
        fans.zone_of_corner[key[0]][key[1]] = static_cast<int>(fans.zones.size());
        fans.zones.push_back(z);
      }
      for (auto& [slot, rr] : vf.rays) {
        rr.fan += first_fan;
        fans.rays[slot] = rr;
      }
      info.level = std::max(info.level, vf.level);
    }
  }
  return fans;
}

/// The coarse quads' corners and boundary curves, each made once in face order and shared
/// (corner_of_vertex, curve_of_edge: the index made for each level-a vertex and edge), with the
/// counts of out.info.
void share_corners_and_curves(const SubdivLevel& base, const PolyMesh& ma, int a, const std::vector<int>& patch_of_face,
                              PatchBuild& out, std::vector<int>& corner_of_vertex, std::vector<int>& curve_of_edge) {
  PatchSet& ps = out.set;
  PatchBuildInfo& info = out.info;
  for (int F = 0; F < ma.num_faces(); ++F) {
    const int pi = patch_of_face[F];
    if (pi < 0) continue;
    NurbsPatch& patch = ps.patches[pi];
    info.level = std::max(info.level, out.patch_deepest[pi]);
    info.removed_knots += out.patch_removed_knots[pi];
    info.leaves += static_cast<long long>(out.leaves[pi].size());
    (patch.kind == PatchKind::Pccm ? info.pccm_patches : info.regular_patches)++;
    // Corners and boundary curves.
    for (int i = 0; i < 4; ++i) {
      const int va_i = ma.corner_vertex(ma.face_begin(F) + i);
      if (corner_of_vertex[va_i] < 0) {
        corner_of_vertex[va_i] = static_cast<int>(ps.corners.size());
        PatchCorner pc;
        pc.base_vertex = a == 0 || va_i < base.mesh.num_vertices() ? va_i : -1;
        const int ui = (i == 1 || i == 2) ? patch.num_poles_u - 1 : 0;  // corner i of the domain
        const int vi = (i == 2 || i == 3) ? patch.num_poles_v - 1 : 0;
        pc.position = patch.pole(ui, vi);
        ps.corners.push_back(pc);
      }
      patch.corners[i] = corner_of_vertex[va_i];
    }
    for (int side = 0; side < 4; ++side) {
      const int e = ma.corner_edge(ma.face_begin(F) + side);
      if (curve_of_edge[e] < 0) {
        curve_of_edge[e] = static_cast<int>(ps.curves.size());
        BoundaryCurve bc;
        bc.corner0 = patch.corners[side];
        bc.corner1 = patch.corners[(side + 1) % 4];
        const int nu = patch.num_poles_u, nv = patch.num_poles_v;
        bc.poles.reserve(side % 2 == 0 ? nu : nv);
        switch (side) {
          case 0: bc.knots = patch.knots_u; for (int i = 0; i < nu; ++i) bc.poles.push_back(patch.pole(i, 0)); break;
          case 1: bc.knots = patch.knots_v; for (int j = 0; j < nv; ++j) bc.poles.push_back(patch.pole(nu - 1, j)); break;
          case 2: bc.knots = reversed(patch.knots_u); for (int i = nu; i-- > 0;) bc.poles.push_back(patch.pole(i, nv - 1)); break;
          default: bc.knots = reversed(patch.knots_v); for (int j = nv; j-- > 0;) bc.poles.push_back(patch.pole(0, j)); break;
        }
        ps.curves.push_back(std::move(bc));
        ps.curves.back().uses.push_back({pi, side, false});
      } else {
        BoundaryCurve& bc = ps.curves[curve_of_edge[e]];
        bc.uses.push_back({pi, side, bc.corner0 != patch.corners[side]});
      }
      patch.curves[side] = curve_of_edge[e];
      patch.curve_reversed[side] = ps.curves[curve_of_edge[e]].uses.back().reversed;
    }
  }
}

/// One patch per polar cap, after its neighbours (their boundary curves exist by now): the seam
/// at spoke 0, the pole a corner of its own, the side along ring 2 split into the neighbours'
/// curves. Marks those level-a edges in cap_boundary_edge.
void add_cap_patches(const SubdivLevel& base, const std::vector<Point3>& positions, const PatchOptions& options, int a,
                     const std::vector<int>& corner_of_vertex, const std::vector<int>& curve_of_edge, PatchBuild& out,
                     std::vector<char>& cap_boundary_edge) {
  PatchSet& ps = out.set;
  PatchBuildInfo& info = out.info;
  for (CapInfo& ci : info.caps) {
    const PolarStructure& st = ci.structure;
    ci.input = polar_net_of(st, positions);
    ci.cap = build_polar_cap(ci.input, options.cap);
    NurbsPatch patch = polar_cap_patch(ci.cap, a);
    patch.base_faces = st.cap_faces;
    const int pi = static_cast<int>(ps.patches.size());
    // Corners: the pole at (0,0) and (0,1); ring 2's spoke 0 at (1,0) and (1,1).
    const int pole_corner = static_cast<int>(ps.corners.size());
    ps.corners.push_back({ci.cap.centre, st.pole});
    const int rim_corner = corner_of_vertex[st.rings[1][0]];  // level-a index = cage index
    if (rim_corner < 0) throw std::logic_error("patch builder: polar cap without neighbour patches");
    patch.corners = {pole_corner, rim_corner, rim_corner, pole_corner};
    // The seam at spoke 0, used by sides 0 and 2.
    BoundaryCurve seam;
    seam.corner0 = pole_corner;
    seam.corner1 = rim_corner;
    seam.knots = patch.knots_u;
    for (int i = 0; i < patch.num_poles_u; ++i) seam.poles.push_back(patch.pole(i, 0));
    seam.uses = {{pi, 0, false}, {pi, 2, true}};
    seam.continuity = Continuity::C2;
    const int seam_curve = static_cast<int>(ps.curves.size());
    ps.curves.push_back(std::move(seam));
    patch.curves = {seam_curve, -1, seam_curve, -1};
    patch.curve_reversed = {false, false, true, false};
    // Side 1 (u = 1, v from 0 to 1): the level-a edges along ring 2, spoke 0 onwards.
    const int n = st.valence, pieces = n << a;
    int q = 0;
    for (int j = 0; j < n; ++j) {
      const int v0 = st.rings[1][j], v1 = st.rings[1][(j + 1) % n];
      const int e0 = base.mesh.find_edge(v0, v1);
      std::vector<int> level_edges{e0};
      if (a == 1) {  // the two halves: child edge 2e is the half at edge_vertex(e, 0)
        const bool v0_first = base.mesh.edge_vertex(e0, 0) == v0;
        level_edges = {2 * e0 + (v0_first ? 0 : 1), 2 * e0 + (v0_first ? 1 : 0)};
      }
      int at = corner_of_vertex[v0];
      for (int e : level_edges) {
        const int k_curve = curve_of_edge[e];
        if (k_curve < 0) throw std::logic_error("patch builder: polar cap boundary edge without a curve");
        BoundaryCurve& bc = ps.curves[k_curve];
        SidePiece piece;
        piece.curve = k_curve;
        piece.reversed = bc.corner0 != at;
        piece.t0 = static_cast<double>(q) / pieces;
        piece.t1 = static_cast<double>(q + 1) / pieces;
        at = piece.reversed ? bc.corner0 : bc.corner1;
        bc.uses.push_back({pi, 1, piece.reversed, piece.t0, piece.t1});
        patch.split_sides[1].push_back(piece);
        cap_boundary_edge[e] = 1;
        ++q;
      }
    }
    ci.patch = pi;
    out.coarse_face.push_back(-1);
    out.leaves.emplace_back();
    out.patch_deepest.push_back(a);
    out.patch_removed_knots.push_back(0);
    ps.patches.push_back(std::move(patch));
  }
}

/// Continuity claims per coarse edge (boundary, C0 at infinitely sharp edges, G1 at a polar
/// cap's rim, else C2 lowered by the rays of irregular vertices) and the rays themselves; whether
/// the set is closed.
void claim_continuity(const SubdivLevel& la, const FanResults& fans, const std::vector<int>& curve_of_edge,
                      const std::vector<int>& corner_of_vertex, const std::vector<char>& cap_boundary_edge,
                      PatchBuild& out) {
  PatchSet& ps = out.set;
  PatchBuildInfo& info = out.info;
  const PolyMesh& ma = la.mesh;
  ps.closed = true;
  for (int e = 0; e < ma.num_edges(); ++e) {
    const int ci = curve_of_edge[e];
    if (ci < 0) continue;
    BoundaryCurve& bc = ps.curves[ci];
    if (bc.uses.size() < 2) {
      bc.continuity = Continuity::Boundary;
      ps.closed = false;
      continue;
    }
    // Semi-sharp creases are refined exactly: the limit is C2 across them.
    if (la.edge_sharpness[e] >= static_cast<float>(kInfiniteSharpness)) {
      bc.continuity = Continuity::C0;
      continue;
    }
    if (cap_boundary_edge[e]) {
      // C2 in geometry, but the cap's parameter is an affine image of the neighbours'
      // (docs/polar.md: x_u = 2^-s x_U), so derivatives are not equal: claimed G1.
      bc.continuity = Continuity::G1;
      continue;
    }
    bc.continuity = Continuity::C2;
    for (int end = 0; end < 2; ++end) {
      const RayRecord& rr = fans.rays[2 * e + end];
      if (rr.fan < 0) continue;
      const int v = ma.edge_vertex(e, end);
      if (static_cast<int>(rr.continuity) < static_cast<int>(bc.continuity)) bc.continuity = rr.continuity;
      RayCurve ray;
      ray.curve = ci;
      ray.vertex_at_start = corner_of_vertex[v] == bc.corner0;
      ray.fan = rr.fan;
      ray.continuity = rr.continuity;
      ray.c = rr.c;
      info.rays.push_back(ray);
    }
  }
}

}  // namespace

// The model size: the bounding-box diagonal of the cage's points that at least one face uses
// (an unused vertex far away must not set the tolerances, #32 item 2); 1 for a cage without
// faces.
double bounding_diagonal(const PolyMesh& m, const std::vector<Point3>& positions) {
  if (m.num_corners() == 0) return 1.0;
  Eigen::Vector3d lo = to_eigen(positions[m.corner_vertex(0)]), hi = lo;
  for (int h = 0; h < m.num_corners(); ++h) {
    const Eigen::Vector3d q = to_eigen(positions[m.corner_vertex(h)]);
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  return (hi - lo).norm();
}

PatchBuild build_patches(const SubdivLevel& base, const std::vector<Point3>& positions,
                         const PatchOptions& options) {
  if (static_cast<int>(positions.size()) != base.mesh.num_vertices())
    throw std::invalid_argument("build_patches: one position per cage vertex expected");
  if (options.polar && options.separate_poles) {
    PatchBuild separated;
    if (build_with_separated_poles(base, positions, options, separated)) return separated;
  }
  PatchBuild out;
  PatchBuildInfo& info = out.info;
  // Polar structures: their cap faces make no Catmull-Clark patch.
  std::vector<char> cap_face(base.mesh.num_faces(), 0);
  if (options.polar) {
    PolarDetection polar = detect_polar_structures(base);
    info.rejected_poles = std::move(polar.rejected);
    for (PolarStructure& s : polar.structures) {
      for (int f : s.cap_faces) cap_face[f] = 1;
      CapInfo ci;
      ci.structure = std::move(s);
      info.caps.push_back(std::move(ci));
    }
  }
  bool quads = true;
  for (int f = 0; f < base.mesh.num_faces(); ++f)
    quads = quads && (cap_face[f] || base.mesh.face_size(f) == 4);  // holes too: as before
  const int a = quads ? 0 : 1;
  info.coarse_level = a;
  info.level = a;
  info.min_fan_level = a + 2 + std::max(0, options.extra_levels);

  // The coarse level: the cage, or its first Catmull-Clark step.
  out.refinement.levels.push_back(base);
  out.cage_positions = positions;
  out.coarse_positions = positions;
  std::vector<char> capped_a = cap_face;
  if (a == 1) {
    RefinementStep step = refine_once(base);
    std::vector<Point3> y;
    step.stencils.apply(positions, y);
    out.coarse_positions.swap(y);
    const PolyMesh& m0 = base.mesh;
    capped_a.assign(m0.num_corners(), 0);
    for (int h = 0; h < m0.num_corners(); ++h) capped_a[h] = cap_face[m0.corner_face(h)];  // child face h of corner h
    out.refinement.levels.push_back(std::move(step.child));
    out.refinement.steps.push_back(std::move(step.stencils));
  }
  const SubdivLevel& la = out.refinement.levels[a];
  const PolyMesh& ma = la.mesh;
  const std::vector<Point3>& xa = out.coarse_positions;
  const double model_size = bounding_diagonal(base.mesh, positions);

  out.vertex_extra.assign(ma.num_vertices(), std::max(0, options.extra_levels));
  for (int v = 0; v < ma.num_vertices() && v < static_cast<int>(options.vertex_extra_levels.size()); ++v)
    out.vertex_extra[v] += std::max(0, options.vertex_extra_levels[v]);

  // Fans: every coarse vertex that stays irregular for some quad once its semi-sharp tags have
  // decayed (those tags count as smooth in this view; infinitely sharp ones stay).
  const FanResults fans = build_all_fans(la, xa, a, base.mesh.num_vertices(), capped_a, out);

  // Coarse quads: leaves, then knots. Each is built straight into its patch slot; holes and
  // polar cap faces make no patch.
  PatchSet& ps = out.set;
  std::vector<int> corner_of_vertex(ma.num_vertices(), -1);
  std::vector<int> curve_of_edge(ma.num_edges(), -1);
  const double knot_tolerance = tolerances::kKnotRemoval * model_size;
  const double same_surface = tolerances::kSameSurface * model_size;
  std::vector<int> patch_of_face(ma.num_faces(), -1);
  size_t num_quads = 0;
  for (int F = 0; F < ma.num_faces(); ++F)
    if (!la.face_hole[F] && !capped_a[F]) patch_of_face[F] = static_cast<int>(num_quads++);
  ps.patches.reserve(num_quads + info.caps.size());
  ps.patches.resize(num_quads);
  out.leaves.resize(num_quads);
  out.patch_deepest.assign(num_quads, a);
  out.patch_removed_knots.assign(num_quads, 0);
  out.coarse_face.resize(num_quads);
  // A previous build of the same cage: its patch per coarse quad, where the quad's corners kept
  // their extra levels.
  const PatchBuild* reuse = options.reuse;
  std::vector<int> reuse_patch;
  if (reuse && reuse->vertex_extra.size() == out.vertex_extra.size()) {
    reuse_patch.assign(ma.num_faces(), -1);
    for (size_t pi = 0; pi < reuse->coarse_face.size(); ++pi)
      if (reuse->coarse_face[pi] >= 0) reuse_patch[reuse->coarse_face[pi]] = static_cast<int>(pi);
  }
  // Which quads to build (not copied from `reuse`), and in which piece: the quads at a vertex
  // of more than shared_piece_valence faces share one piece per vertex, the others have their own.
  std::vector<char> copied(ma.num_faces(), 0);
  if (!reuse_patch.empty())
    for (int F = 0; F < ma.num_faces(); ++F) {
      if (patch_of_face[F] < 0 || reuse_patch[F] < 0) continue;
      bool same = true;
      for (int h = ma.face_begin(F); h < ma.face_end(F); ++h)
        same = same && reuse->vertex_extra[ma.corner_vertex(h)] == out.vertex_extra[ma.corner_vertex(h)];
      copied[F] = same;
    }
  std::vector<std::vector<int>> tasks;  // coarse faces built together
  {
    std::vector<int> task_of_vertex(ma.num_vertices(), -1);
    const LevelView La{la, ma, xa};
    for (int F = 0; F < ma.num_faces(); ++F) {
      if (patch_of_face[F] < 0 || copied[F]) continue;
      int hub = -1;
      for (int h = ma.face_begin(F); h < ma.face_end(F); ++h) {
        const int v = ma.corner_vertex(h);
        if (ma.vertex_face_count(v) > options.shared_piece_valence &&
            (hub < 0 || ma.vertex_face_count(v) > ma.vertex_face_count(hub)))
          hub = v;
      }
      if (hub < 0 || is_regular_leaf(La, F)) {
        tasks.push_back({F});
        continue;
      }
      if (task_of_vertex[hub] < 0) {
        task_of_vertex[hub] = static_cast<int>(tasks.size());
        tasks.emplace_back();
      }
      tasks[task_of_vertex[hub]].push_back(F);
    }
  }
  parallel_for(static_cast<int>(tasks.size()), [&](int t) {
    const std::vector<int>& Fs = tasks[t];
    if (Fs.size() == 1) {
      const int F = Fs[0], pi = patch_of_face[F];
      int deepest = a;
      out.leaves[pi] = leaves_of(la, xa, F, a, fans, deepest);
      out.patch_deepest[pi] = deepest;
      return;
    }
    std::vector<PatchLeaves*> leaves;
    std::vector<int> deepest(Fs.size(), a);
    for (int F : Fs) leaves.push_back(&out.leaves[patch_of_face[F]]);
    leaves_of_faces(la, xa, Fs, a, fans, leaves, deepest);
    for (size_t k = 0; k < Fs.size(); ++k) out.patch_deepest[patch_of_face[Fs[k]]] = deepest[k];
  });
  parallel_for(ma.num_faces(), [&](int F) {
    const int pi = patch_of_face[F];
    if (pi < 0) return;
    NurbsPatch& patch = ps.patches[pi];
    PatchLeaves& leaves = out.leaves[pi];
    out.coarse_face[pi] = F;
    const int base_face = a == 0 ? F : base.mesh.corner_face(F);  // level-1 face F = child of corner F
    if (copied[F]) {
      const int ri = reuse_patch[F];
      leaves = reuse->leaves[ri];
      patch = reuse->set.patches[ri];
      patch.base_faces = {base_face};
      out.patch_deepest[pi] = reuse->patch_deepest[ri];
      out.patch_removed_knots[pi] = reuse->patch_removed_knots[ri];
      return;
    }
    patch.base_faces = {base_face};
    // Zone lines: h and 2h from every corner with a zone.
    std::vector<double> du, dv;
    bool pccm = false;
    for (int i = 0; i < 4; ++i) {
      const int zi = fans.zone_of_corner[F][i];
      if (zi < 0) continue;
      pccm = true;
      const double h = std::ldexp(1.0, -(fans.zones[zi].level - a));
      const bool hi_u = i == 1 || i == 2, hi_v = i == 2 || i == 3;
      for (double t : {h, 2 * h}) {
        du.push_back(hi_u ? 1 - t : t);
        dv.push_back(hi_v ? 1 - t : t);
      }
    }
    patch.kind = pccm ? PatchKind::Pccm : PatchKind::RegularBSpline;
    out.patch_removed_knots[pi] = assemble_patch(leaves, du, dv, knot_tolerance, same_surface, patch).removed_knots;
  });
  ps.curves.reserve(ma.num_edges() + info.caps.size());
  ps.corners.reserve(ma.num_vertices() + info.caps.size());
  for (auto* v : {&out.coarse_face, &out.patch_deepest, &out.patch_removed_knots}) v->reserve(num_quads + info.caps.size());
  out.leaves.reserve(num_quads + info.caps.size());
  share_corners_and_curves(base, ma, a, patch_of_face, out, corner_of_vertex, curve_of_edge);

  // Polar caps, after their neighbours: the boundary curves exist by now.
  std::vector<char> cap_boundary_edge(ma.num_edges(), 0);
  add_cap_patches(base, positions, options, a, corner_of_vertex, curve_of_edge, out, cap_boundary_edge);

  // Continuity claims per coarse edge, and the rays of irregular vertices.
  claim_continuity(la, fans, curve_of_edge, corner_of_vertex, cap_boundary_edge, out);
  for (const NurbsPatch& p : ps.patches) info.total_poles += static_cast<long long>(p.poles.size());
  ps.model_size = model_size;
  return out;
}

}  // namespace subd2nurbs
