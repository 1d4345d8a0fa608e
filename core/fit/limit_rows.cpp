#include "core/fit/limit_rows.h"

#include <Eigen/Dense>
#include <algorithm>
#include <map>
#include <stdexcept>
#include <unordered_map>

#include "core/mesh/errors.h"
#include "core/polar/polar_net.h"

namespace subd2nurbs {

namespace {

constexpr float kInf = static_cast<float>(kInfiniteSharpness);

bool semi(float s) { return s > 0.0f && s < kInf; }

/// The faces at vertex v of `level`, cut out as a level of their own: v is local vertex 0,
/// its edge neighbours are keyed by edge (so the fan is a clean disk or half-disk even where
/// a vertex appears twice around v), every other corner is a vertex of its own. Edges at v keep
/// their sharpness, the fan's outer edges are boundary (infinitely sharp); only v keeps its
/// vertex sharpness. Everything v's vertex-child and its limit depend on is kept exactly.
struct Fan {
  SubdivLevel level;
  std::vector<int> orig;  ///< local vertex -> vertex of the source level
};

Fan cut_fan(const SubdivLevel& L, int v) {
  const PolyMesh& m = L.mesh;
  Fan fan;
  fan.orig.push_back(v);
  std::unordered_map<int, int> by_edge;  // source edge at v -> local id of its other end
  std::unordered_map<int, int> local_edge_source;  // local id -> source edge (edge neighbours)
  auto neighbour = [&](int e, int w) {
    auto it = by_edge.find(e);
    if (it != by_edge.end()) return it->second;
    const int id = static_cast<int>(fan.orig.size());
    fan.orig.push_back(w);
    by_edge.emplace(e, id);
    local_edge_source.emplace(id, e);
    return id;
  };
  std::vector<int> sizes, idx, faces;
  const int* c = m.vertex_corners(v);
  for (int i = 0, nf = m.vertex_face_count(v); i < nf; ++i) {
    const int h = c[i];
    const int f = m.corner_face(h);
    faces.push_back(f);
    sizes.push_back(m.face_size(f));
    idx.push_back(0);
    idx.push_back(neighbour(m.corner_edge(h), m.to_vertex(h)));
    for (int k = m.next(m.next(h)); k != m.prev(h); k = m.next(k)) {
      idx.push_back(static_cast<int>(fan.orig.size()));
      fan.orig.push_back(m.corner_vertex(k));
    }
    const int p = m.prev(h);
    idx.push_back(neighbour(m.corner_edge(p), m.corner_vertex(p)));
  }
  const int nv = static_cast<int>(fan.orig.size());
  fan.level.mesh = PolyMesh::build(nv, sizes, idx);
  const PolyMesh& lm = fan.level.mesh;
  fan.level.options = L.options;
  fan.level.vertex_sharpness.assign(nv, 0.0f);
  fan.level.vertex_sharpness[0] = L.vertex_sharpness[v];
  fan.level.face_hole.resize(faces.size());
  for (size_t f = 0; f < faces.size(); ++f) fan.level.face_hole[f] = L.face_hole[faces[f]];
  fan.level.edge_sharpness.assign(lm.num_edges(), kInf);
  for (int e = 0; e < lm.num_edges(); ++e) {
    const int a = lm.edge_vertex(e, 0), b = lm.edge_vertex(e, 1);
    if (a != 0 && b != 0) continue;  // an outer edge: boundary of the fan
    const int other = a == 0 ? b : a;
    fan.level.edge_sharpness[e] = L.edge_sharpness[local_edge_source.at(other)];
  }
  if (lm.vertex_face_count(0) != m.vertex_face_count(v) ||
      lm.is_boundary_vertex(0) != m.is_boundary_vertex(v))
    throw std::logic_error("cut_fan: the fan of the vertex changed");
  return fan;
}

/// True when v's limit has a closed-form (or exact eigenvector) mask in `L`: its faces are
/// quads and no semi-sharp tag is at v or on its edges.
bool closed_form_at(const SubdivLevel& L, int v) {
  const PolyMesh& m = L.mesh;
  if (semi(L.vertex_sharpness[v])) return false;
  const int* c = m.vertex_corners(v);
  for (int i = 0, nf = m.vertex_face_count(v); i < nf; ++i)
    if (m.face_size(m.corner_face(c[i])) != 4) return false;
  bool ok = true;
  for_each_vertex_edge(m, v, [&](int e, int) {
    if (semi(L.edge_sharpness[e])) ok = false;
  });
  return ok;
}

bool has_surface(const SubdivLevel& L, int v) {
  const PolyMesh& m = L.mesh;
  const int* c = m.vertex_corners(v);
  for (int i = 0, nf = m.vertex_face_count(v); i < nf; ++i)
    if (!L.face_hole[m.corner_face(c[i])]) return true;
  return false;
}

}  // namespace

std::vector<std::pair<int, double>> local_limit_row(const SubdivLevel& level, int v) {
  Fan fan = cut_fan(level, v);
  const int n0 = static_cast<int>(fan.orig.size());
  // map: current local vertices x fan-0 vertices.
  Eigen::MatrixXd map = Eigen::MatrixXd::Identity(n0, n0);
  SubdivLevel cur = fan.level;
  // A semi-sharp tag decays by at least 1 per level, so this ends after ceil(s) + 1 levels.
  for (int guard = 0; !closed_form_at(cur, 0); ++guard) {
    if (guard > 12) throw std::logic_error("local_limit_row: sharpness did not decay");
    RefinementStep step = refine_once(cur);
    Fan next = cut_fan(step.child, 0);  // vertex-child of local 0 is child vertex 0
    const StencilTable& st = step.stencils;
    Eigen::MatrixXd m2 = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(next.orig.size()), n0);
    for (size_t i = 0; i < next.orig.size(); ++i) {
      const int r = next.orig[i];
      for (int k = st.offsets[r]; k < st.offsets[r + 1]; ++k)
        m2.row(static_cast<Eigen::Index>(i)) += st.weights[k] * map.row(st.indices[k]);
    }
    map = std::move(m2);
    cur = std::move(next.level);
  }
  const StencilTable lim = limit_stencils(cur);
  Eigen::RowVectorXd w = Eigen::RowVectorXd::Zero(n0);
  for (int k = lim.offsets[0]; k < lim.offsets[1]; ++k) w += lim.weights[k] * map.row(lim.indices[k]);
  std::map<int, double> merged;
  for (int i = 0; i < n0; ++i)
    if (w[i] != 0.0) merged[fan.orig[i]] += w[i];
  return {merged.begin(), merged.end()};
}

std::vector<std::vector<std::pair<int, double>>> bp_limit_rows(const PolarStructure& s) {
  const int n = s.valence;
  const int nsrc = 1 + 3 * n;
  auto src_vertex = [&](int q) { return q == 0 ? s.pole : s.rings[(q - 1) / n][(q - 1) % n]; };
  // out[row][q]: weight of source q in row (pole, ring 1, ring 2).
  std::vector<std::vector<double>> w(1 + 2 * n, std::vector<double>(nsrc, 0.0));
  // The rows are linear in the net: evaluate them on unit nets, three sources at a time
  // (one per coordinate).
  for (int q0 = 0; q0 < nsrc; q0 += 3) {
    PolarNet net;
    net.n = n;
    net.rings.assign(3 * n, Point3{0, 0, 0});
    for (int c = 0; c < 3 && q0 + c < nsrc; ++c) {
      const int q = q0 + c;
      if (q == 0)
        net.pole[c] = 1;
      else
        net.rings[q - 1][c] = 1;
    }
    const Point3 pole = bp_limit_point(net);
    // Two radial steps: ring 1 -> ring 4, ring 2 -> ring 8 (vertex-children), both on the
    // tensor bicubic part of the radial-only net (rings >= 3), which has rings 0..9.
    const PolarNet r2 = radial_step(radial_step(net));
    for (int c = 0; c < 3 && q0 + c < nsrc; ++c) {
      const int q = q0 + c;
      w[0][q] = pole[c];
      for (int j = 0; j < n; ++j) {
        w[1 + j][q] = bp_grid_limit(r2, 4, j)[c];
        w[1 + n + j][q] = bp_grid_limit(r2, 8, j)[c];
      }
    }
  }
  std::vector<std::vector<std::pair<int, double>>> out(w.size());
  for (size_t r = 0; r < w.size(); ++r)
    for (int q = 0; q < nsrc; ++q)
      if (std::abs(w[r][q]) > 1e-300) out[r].push_back({src_vertex(q), w[r][q]});
  return out;
}

LimitRows limit_rows(const SubdivLevel& level, const std::vector<PolarStructure>* polar) {
  const PolyMesh& m = level.mesh;
  const int nv = m.num_vertices();
  LimitRows out;
  std::vector<std::vector<std::pair<int, double>>> rows(nv);
  if (level.max_semi_sharpness() == 0.0) {
    // Closed forms everywhere (n-gons: one global step, as cheap as it gets).
    const StencilTable t = limit_stencils(level);
    for (int v = 0; v < nv; ++v)
      for (int k = t.offsets[v]; k < t.offsets[v + 1]; ++k) rows[v].push_back({t.indices[k], t.weights[k]});
  } else {
    for (int v = 0; v < nv; ++v) {
      if (m.is_unused_vertex(v)) continue;
      rows[v] = local_limit_row(level, v);
      ++out.local_rows;
    }
  }
  if (polar)
    for (const PolarStructure& s : *polar) {
      auto bp = bp_limit_rows(s);
      rows[s.pole] = std::move(bp[0]);
      out.polar_rows.push_back(s.pole);
      for (int j = 0; j < s.valence; ++j) {
        rows[s.rings[0][j]] = std::move(bp[1 + j]);
        rows[s.rings[1][j]] = std::move(bp[1 + s.valence + j]);
        out.polar_rows.push_back(s.rings[0][j]);
        out.polar_rows.push_back(s.rings[1][j]);
      }
    }
  out.rows.num_sources = nv;
  for (int v = 0; v < nv; ++v) {
    if (m.is_unused_vertex(v) || !has_surface(level, v)) {
      out.no_surface.push_back(v);
      rows[v] = {{v, 1.0}};
    }
    for (const auto& [s, w] : rows[v]) {
      out.rows.indices.push_back(s);
      out.rows.weights.push_back(w);
    }
    out.rows.offsets.push_back(static_cast<int>(out.rows.indices.size()));
  }
  return out;
}

}  // namespace subd2nurbs
