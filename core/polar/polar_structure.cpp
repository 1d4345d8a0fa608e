#include "core/polar/polar_structure.h"

#include <algorithm>
#include <string>

namespace subd2nurbs {
namespace {

std::string vtx(int v) { return "vertex " + std::to_string(v); }

/// Tries to read the polar structure around pole p; returns an empty reason on success.
std::string read_structure(const SubdivLevel& level, int p, PolarStructure& s) {
  const PolyMesh& m = level.mesh;
  const int n = m.vertex_face_count(p);
  const int* c = m.vertex_corners(p);
  s.pole = p;
  s.valence = n;
  for (auto& ring : s.rings) ring.assign(n, -1);
  std::vector<int> triangles(n), layer_quads[2];
  std::vector<int> inner(n);  // per spoke j: the halfedge ring_L[j] -> ring_L[j+1] inside ring L
  for (int j = 0; j < n; ++j) {
    s.rings[0][j] = m.to_vertex(c[j]);
    triangles[j] = m.corner_face(c[j]);
    inner[j] = m.next(c[j]);
  }
  // Layer L = 1, 2: the quads across the edges of ring L (ring L - 1 in s.rings), which give
  // ring L + 1; their outer edges are the next layer's inner ones.
  for (int L = 1; L <= 2; ++L) {
    const std::vector<int>& ring = s.rings[L - 1];
    std::vector<int>& outer = s.rings[L];
    std::vector<int>& quads = layer_quads[L - 1];
    quads.assign(n, -1);
    const std::string layer = std::to_string(L) + "-layer";
    for (int j = 0; j < n; ++j) {
      const int t = m.twin(inner[j]);  // ring[j+1] -> ring[j] in the layer's quad
      if (t < 0) {
        const std::string edge = vtx(ring[j]) + " - " + vtx(ring[(j + 1) % n]) + " is on the boundary";
        return L == 1 ? "its 1-link edge " + edge
                      : "it has no 2-layer (only one quad ring): the 1-layer's outer edge " + edge;
      }
      const int f = m.corner_face(t);
      if (m.face_size(f) != 4)
        return "face " + std::to_string(f) + " of its " + layer + " has " + std::to_string(m.face_size(f)) +
               " sides, polar structures need quads there";
      quads[j] = f;
      inner[j] = m.next(m.next(t));  // outer[j] -> outer[j+1]
      for (const auto& [slot, value] : {std::pair<int, int>{j, m.corner_vertex(inner[j])},
                                        std::pair<int, int>{(j + 1) % n, m.corner_vertex(m.prev(t))}}) {
        int& cur = outer[slot];
        if (cur >= 0 && cur != value)
          return "its " + layer + " quads do not form a ring (ring-" + std::to_string(L) + " " + vtx(ring[slot]) +
                 " has more than one ring-" + std::to_string(L + 1) + " neighbour)";
        cur = value;
      }
    }
  }
  // 1-link and 2-link vertices are interior and 4-valent.
  for (int r = 0; r < 2; ++r)
    for (int v : s.rings[r]) {
      if (m.is_boundary_vertex(v)) return "ring-" + std::to_string(r + 1) + " " + vtx(v) + " is on the boundary";
      if (m.valence(v) != 4)
        return "ring-" + std::to_string(r + 1) + " " + vtx(v) + " has valence " + std::to_string(m.valence(v)) +
               ", polar structures need 4";
    }
  // Rings 0..3 are 1 + 3n distinct vertices.
  std::vector<int> all{p};
  for (const auto& ring : s.rings) all.insert(all.end(), ring.begin(), ring.end());
  std::sort(all.begin(), all.end());
  if (std::adjacent_find(all.begin(), all.end()) != all.end())
    return "its rings 0..3 are not 1 + 3n distinct vertices (the structure wraps onto itself)";
  // No tags inside: BP has no crease rules. Sharp edges at rings 0..2 and sharp vertices there
  // would change the rules the cap reproduces; holes would leave the cap without neighbours.
  for (int r = -1; r < 2; ++r) {
    const std::vector<int> one{p};
    for (int v : r < 0 ? one : s.rings[r]) {
      if (level.vertex_sharpness[v] > 0) return vtx(v) + " of the structure has a corner tag";
      bool sharp = false;
      for_each_vertex_edge(m, v, [&](int e, int) { sharp = sharp || level.edge_sharpness[e] > 0; });
      if (sharp) return "an edge at " + vtx(v) + " of the structure is creased";
    }
  }
  s.cap_faces = triangles;
  s.cap_faces.insert(s.cap_faces.end(), layer_quads[0].begin(), layer_quads[0].end());
  s.layer2_faces = layer_quads[1];
  for (const auto& list : {s.cap_faces, s.layer2_faces})
    for (int f : list)
      if (level.face_hole[f]) return "face " + std::to_string(f) + " of the structure is a hole";
  return {};
}

}  // namespace

PolarDetection detect_polar_structures(const SubdivLevel& level, int min_valence) {
  const PolyMesh& m = level.mesh;
  PolarDetection out;
  std::vector<PolarStructure> found;
  std::vector<RejectedPole> rejected;
  for (int v = 0; v < m.num_vertices(); ++v) {
    const int n = m.vertex_face_count(v);
    if (n < 3 || m.is_boundary_vertex(v)) continue;
    bool triangles = true;
    for (int i = 0; i < n && triangles; ++i) triangles = m.face_size(m.corner_face(m.vertex_corners(v)[i])) == 3;
    if (!triangles) continue;
    if (n < min_valence) {
      rejected.push_back({v, n,
                          "valence " + std::to_string(n) + " is below " + std::to_string(min_valence) +
                              " (BP subdivision needs n >= 6, docs/math.md 3.4)",
                          RejectedPole::Kind::LowValence});
      continue;
    }
    PolarStructure s;
    const std::string why = read_structure(level, v, s);
    if (why.empty()) found.push_back(std::move(s));
    else rejected.push_back({v, n, why});
  }
  // Structures sharing a vertex of rings 0..3 are too close: both are rejected.
  std::vector<int> owner(m.num_vertices(), -1);
  std::vector<int> clash(found.size(), -1);
  for (int i = 0; i < static_cast<int>(found.size()); ++i) {
    std::vector<int> all{found[i].pole};
    for (const auto& ring : found[i].rings) all.insert(all.end(), ring.begin(), ring.end());
    for (int v : all) {
      if (owner[v] >= 0 && owner[v] != i) {
        clash[i] = found[owner[v]].pole;
        if (clash[owner[v]] < 0) clash[owner[v]] = found[i].pole;
      } else {
        owner[v] = i;
      }
    }
  }
  for (int i = 0; i < static_cast<int>(found.size()); ++i) {
    if (clash[i] < 0) out.structures.push_back(std::move(found[i]));
    else
      rejected.push_back({found[i].pole, found[i].valence,
                          "its rings 0..3 overlap those of the polar structure at " + vtx(clash[i]) +
                              " (too close)",
                          RejectedPole::Kind::TooClose});
  }
  std::sort(rejected.begin(), rejected.end(), [](const RejectedPole& a, const RejectedPole& b) { return a.vertex < b.vertex; });
  out.rejected = std::move(rejected);
  return out;
}

}  // namespace subd2nurbs
