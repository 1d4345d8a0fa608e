#include "core/polar/polar_refine.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/polar/polar_cap.h"
#include "core/polar/polar_net.h"

namespace subd2nurbs {
namespace {

/// (ring, spoke) label of a vertex inside one structure's rings; ring -1 = unlabelled.
struct Label {
  int ring = -1, spoke = 0;
};

/// Labels of the level-k vertices on rings 2^k .. 3 2^k of structure s (spokes n 2^k),
/// propagated level by level: a vertex child doubles its parent's label, an edge child is
/// the sum of its two grid-neighbour ends, a face child half the sum of a unit grid square.
std::vector<Label> ring_labels(const Refinement& ref, const PolarStructure& s, int k) {
  const PolyMesh& m0 = ref.levels[0].mesh;
  std::vector<Label> lab(m0.num_vertices());
  for (int r = 0; r < 3; ++r)
    for (int j = 0; j < s.valence; ++j) lab[s.rings[r][j]] = {r + 1, j};
  for (int t = 0; t < k; ++t) {
    const PolyMesh& m = ref.levels[t].mesh;
    const int N = s.valence << t;  // spokes at level t
    // Unwraps spoke b next to spoke a (|difference| <= N / 2).
    auto near = [N](int a, int b) { return b - a > N / 2 ? b - N : a - b > N / 2 ? b + N : b; };
    std::vector<Label> next(ref.levels[t + 1].mesh.num_vertices());
    for (int v = 0; v < m.num_vertices(); ++v)
      if (lab[v].ring >= 0) next[child_of_vertex(m, v)] = {2 * lab[v].ring, 2 * lab[v].spoke};
    for (int e = 0; e < m.num_edges(); ++e) {
      const Label a = lab[m.edge_vertex(e, 0)], b = lab[m.edge_vertex(e, 1)];
      if (a.ring < 0 || b.ring < 0) continue;
      const int bj = near(a.spoke, b.spoke);
      if (std::abs(a.ring - b.ring) + std::abs(a.spoke - bj) != 1) continue;
      next[child_of_edge(m, e)] = {a.ring + b.ring, ((a.spoke + bj) % (2 * N) + 2 * N) % (2 * N)};
    }
    for (int f = 0; f < m.num_faces(); ++f) {
      if (m.face_size(f) != 4) continue;
      const int* fv = m.face_vertices(f);
      const Label a = lab[fv[0]];
      if (a.ring < 0) continue;
      int rs = 0, js = 0, rmin = a.ring, rmax = a.ring, jmin = a.spoke, jmax = a.spoke;
      bool ok = true;
      for (int i = 0; i < 4 && ok; ++i) {
        const Label b = lab[fv[i]];
        ok = b.ring >= 0;
        const int bj = near(a.spoke, b.spoke);
        rs += b.ring;
        js += bj;
        rmin = std::min(rmin, b.ring);
        rmax = std::max(rmax, b.ring);
        jmin = std::min(jmin, bj);
        jmax = std::max(jmax, bj);
      }
      if (!ok || rmax - rmin != 1 || jmax - jmin != 1) continue;
      next[child_of_face(m, f)] = {rs / 2, ((js / 2) % (2 * N) + 2 * N) % (2 * N)};
    }
    lab.swap(next);
  }
  return lab;
}

}  // namespace

SubdivLevel rebuild_level(const SubdivLevel& source, const std::vector<int>& index, int num_vertices,
                          const std::vector<int>& sizes, const std::vector<int>& faces,
                          const std::vector<int>& face_source) {
  const PolyMesh& ms = source.mesh;
  SubdivLevel level;
  level.mesh = PolyMesh::build(num_vertices, sizes, faces);
  level.options = source.options;
  level.edge_sharpness.assign(level.mesh.num_edges(), 0.0f);
  level.vertex_sharpness.assign(num_vertices, 0.0f);
  level.face_hole.assign(level.mesh.num_faces(), 0);
  for (int e = 0; e < ms.num_edges(); ++e) {
    if (source.edge_sharpness[e] <= 0) continue;
    const int a = index[ms.edge_vertex(e, 0)], b = index[ms.edge_vertex(e, 1)];
    const int ne = a >= 0 && b >= 0 ? level.mesh.find_edge(a, b) : -1;
    if (ne >= 0) level.edge_sharpness[ne] = source.edge_sharpness[e];
  }
  for (int v = 0; v < ms.num_vertices(); ++v)
    if (index[v] >= 0) level.vertex_sharpness[index[v]] = source.vertex_sharpness[v];
  for (int f = 0; f < level.mesh.num_faces(); ++f)
    if (face_source[f] >= 0) level.face_hole[f] = source.face_hole[face_source[f]];
  return level;
}

PolarRefinement refine_with_polar(const SubdivLevel& base, const std::vector<Point3>& positions, int levels,
                                  const std::vector<PolarStructure>& structures) {
  if (levels < 0) throw std::invalid_argument("refine_with_polar: levels must be >= 0");
  PolarRefinement out;
  const Refinement ref = refine_uniform(base, levels);
  std::vector<Point3> x = ref.positions(positions).back();
  const SubdivLevel& lk = ref.levels.back();
  const PolyMesh& mk = lk.mesh;
  const int k = levels;
  if (k == 0 || structures.empty()) {
    out.level = lk;
    out.positions = x;
    return out;
  }
  // Level-k faces descended from the structures' triangles: replaced by BP's pole region.
  std::vector<char> removed(base.mesh.num_faces(), 0);
  for (const PolarStructure& s : structures)
    for (int j = 0; j < s.valence; ++j) removed[s.cap_faces[j]] = 1;
  for (int t = 0; t < k; ++t) {
    const PolyMesh& mt = ref.levels[t].mesh;
    std::vector<char> next(mt.num_corners());
    for (int h = 0; h < mt.num_corners(); ++h) next[h] = removed[mt.corner_face(h)];
    removed.swap(next);
  }
  // New vertex numbering: kept level-k vertices (those on a kept face), then per structure the
  // BP pole and rings 1 .. 2^k - 1.
  std::vector<int> index(mk.num_vertices(), -1);
  std::vector<int> sizes, faces;
  int count = 0;
  for (int f = 0; f < mk.num_faces(); ++f) {
    if (removed[f]) continue;
    sizes.push_back(mk.face_size(f));
    for (int i = 0; i < mk.face_size(f); ++i) {
      int& id = index[mk.face_vertices(f)[i]];
      if (id < 0) id = count++;
      faces.push_back(id);
    }
  }
  std::vector<Point3> merged(count);
  for (int v = 0; v < mk.num_vertices(); ++v)
    if (index[v] >= 0) merged[index[v]] = x[v];
  const int inner = 1 << k, overlap = 2 << k;  // ring 2^k is shared; BP is valid to 2^(k+1)+1
  for (const PolarStructure& s : structures) {
    // BP: k radial steps, then k circular ones.
    PolarNet net = polar_net_of(s, positions);
    for (int t = 0; t < k; ++t) net = radial_step(net);
    for (int t = 0; t < k; ++t) net = circular_step(net);
    const int N = net.n;
    // Catmull-Clark's vertices of rings 2^k .. 2^(k+1) + 1 by (ring, spoke).
    const std::vector<Label> lab = ring_labels(ref, s, k);
    std::vector<int> cc(static_cast<size_t>(overlap + 2) * N, -1);
    for (int v = 0; v < mk.num_vertices(); ++v)
      if (lab[v].ring >= inner && lab[v].ring <= overlap + 1) cc[static_cast<size_t>(lab[v].ring) * N + lab[v].spoke] = v;
    for (int r = inner; r <= overlap + 1; ++r)
      for (int j = 0; j < N; ++j) {
        const int v = cc[static_cast<size_t>(r) * N + j];
        if (v < 0 || index[v] < 0) throw std::logic_error("refine_with_polar: ring vertex not found");
        if (r <= overlap - 2) {
          merged[index[v]] = net.at(r, j);  // BP's own rings
        } else {
          const Point3& a = net.at(r, j);
          const double d = std::sqrt((a[0] - x[v][0]) * (a[0] - x[v][0]) + (a[1] - x[v][1]) * (a[1] - x[v][1]) +
                                     (a[2] - x[v][2]) * (a[2] - x[v][2]));
          out.max_overlap_difference = std::max(out.max_overlap_difference, d);
        }
      }
    // The pole region: pole, rings 1 .. 2^k - 1, ring 2^k from Catmull-Clark.
    const int pole = count++;
    merged.push_back(net.pole);
    std::vector<int> ring_id(static_cast<size_t>(inner + 1) * N);
    for (int r = 1; r < inner; ++r)
      for (int j = 0; j < N; ++j) {
        ring_id[static_cast<size_t>(r) * N + j] = count++;
        merged.push_back(net.at(r, j));
      }
    for (int j = 0; j < N; ++j) ring_id[static_cast<size_t>(inner) * N + j] = index[cc[static_cast<size_t>(inner) * N + j]];
    auto id = [&](int r, int j) { return ring_id[static_cast<size_t>(r) * N + (j + N) % N]; };
    for (int j = 0; j < N; ++j) {
      sizes.push_back(3);
      faces.insert(faces.end(), {pole, id(1, j), id(1, j + 1)});
    }
    for (int r = 1; r < inner; ++r)
      for (int j = 0; j < N; ++j) {
        sizes.push_back(4);
        faces.insert(faces.end(), {id(r, j + 1), id(r, j), id(r + 1, j), id(r + 1, j + 1)});
      }
    ++out.structures;
  }
  // The merged level with Catmull-Clark's tags on the kept elements.
  std::vector<int> face_source;
  for (int f = 0; f < mk.num_faces(); ++f)
    if (!removed[f]) face_source.push_back(f);
  face_source.resize(sizes.size(), -1);
  out.level = rebuild_level(lk, index, count, sizes, faces, face_source);
  out.positions = std::move(merged);
  return out;
}

}  // namespace subd2nurbs
