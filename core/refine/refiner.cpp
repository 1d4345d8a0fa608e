// Uniform Catmull-Clark refinement. The rules follow OpenSubdiv (our oracle) exactly:
// sdc/catmarkScheme.h (masks), sdc/scheme.h (rule transitions), sdc/crease.cpp (sharpness
// decay and fractional weights), vtr/refinement.cpp (which rule a child vertex gets) and
// far/topologyRefinerFactory.cpp (base-level boundary tagging). docs/math.md section 1.
#include "core/refine/refiner.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <thread>
#include <utility>

#include "core/mesh/validate.h"
#include "core/util/parallel.h"

namespace subd2nurbs {

namespace {

constexpr float kInf = static_cast<float>(kInfiniteSharpness);

/// Meshes with at least this many corners build child topology and stencils concurrently.
constexpr int kConcurrentCorners = 1 << 16;

/// Index of the child half of parent edge e that touches parent vertex v (see refiner.h).
int half_at(const PolyMesh& pm, int e, int v) { return 2 * e + (pm.edge_vertex(e, 0) == v ? 0 : 1); }

bool is_sharp(float s) { return s > 0.0f; }
bool is_infinite(float s) { return s >= kInf; }
bool is_semi_sharp(float s) { return s > 0.0f && s < kInf; }

/// Uniform decay s -> s - 1 (infinite stays infinite, <= 1 becomes smooth).
float decrement_sharpness(float s) {
  if (!is_sharp(s)) return 0.0f;
  if (is_infinite(s)) return kInf;
  if (s > 1.0f) return s - 1.0f;
  return 0.0f;
}

VertexRule rule_from(float vertex_sharpness, int sharp_edge_count) {
  if (is_sharp(vertex_sharpness) || sharp_edge_count > 2) return VertexRule::Corner;
  static constexpr VertexRule by_count[3] = {VertexRule::Smooth, VertexRule::Dart,
                                             VertexRule::Crease};
  return by_count[sharp_edge_count];
}

/// Sharpness of the child half of an edge that touches `end_vertex`. Uniform: s - 1.
/// Chaikin: (3/4 s + 1/4 mean of the other semi-sharp edges at that vertex) - 1, in float
/// and in the same order of operations as OpenSubdiv's Crease::SubdivideEdgeSharpnessAtVertex.
float child_edge_sharpness(const SubdivLevel& level, int edge, int end_vertex) {
  const float s = level.edge_sharpness[edge];
  if (level.options.crease_method == CreaseMethod::Uniform) return decrement_sharpness(s);
  const PolyMesh& m = level.mesh;
  if (m.valence(end_vertex) < 2) return decrement_sharpness(s);
  if (!is_sharp(s)) return 0.0f;
  if (is_infinite(s)) return kInf;
  float sum = 0.0f;
  int count = 0;
  for_each_vertex_edge(m, end_vertex, [&](int e, int) {
    const float se = level.edge_sharpness[e];
    if (is_semi_sharp(se)) {
      ++count;
      sum += se;
    }
  });
  float child = s;
  if (count > 1) {
    const float others = (sum - s) / static_cast<float>(count - 1);
    child = (0.75f * s) + (0.25f * others);
  }
  child -= 1.0f;
  return is_sharp(child) ? child : 0.0f;
}

/// Accumulates one stencil row, merging repeated sources in O(1) with a slot map.
class RowBuilder {
 public:
  explicit RowBuilder(int num_sources) : slot_(num_sources, -1) {}
  void add(int source, double weight) {
    int& s = slot_[source];
    if (s < 0) {
      s = static_cast<int>(idx_.size());
      idx_.push_back(source);
      w_.push_back(weight);
    } else {
      w_[s] += weight;
    }
  }
  /// Adds weight times the centroid of face f.
  void add_face_centre(const PolyMesh& m, int f, double weight) {
    const int n = m.face_size(f);
    const int* fv = m.face_vertices(f);
    const double w = weight / n;
    for (int i = 0; i < n; ++i) add(fv[i], w);
  }
  void emit(StencilTable& t) {
    for (size_t k = 0; k < idx_.size(); ++k) {
      t.indices.push_back(idx_[k]);
      t.weights.push_back(w_[k]);
      slot_[idx_[k]] = -1;
    }
    t.offsets.push_back(static_cast<int>(t.indices.size()));
    idx_.clear();
    w_.clear();
  }

 private:
  std::vector<int> slot_;
  std::vector<int> idx_;
  std::vector<double> w_;
};

/// A vertex-vertex mask in OpenSubdiv's form: weight on the vertex, per incident edge (on the
/// edge's other vertex, in for_each_vertex_edge order) and per incident face (on its centre,
/// in fan order).
struct VertexMask {
  double vertex = 0;
  std::vector<double> edge;
  std::vector<double> face;

  void assign(VertexRule rule, int num_edges, int num_faces, const std::vector<float>& sharp) {
    edge.assign(num_edges, 0.0);
    face.assign(num_faces, 0.0);
    switch (rule) {
      case VertexRule::Smooth:
      case VertexRule::Dart: {  // interior: num_faces == num_edges == n
        const double n = num_faces;
        vertex = (n - 2.0) / n;
        const double w = 1.0 / (n * n);
        std::fill(edge.begin(), edge.end(), w);
        std::fill(face.begin(), face.end(), w);
        break;
      }
      case VertexRule::Crease: {  // the two sharp edges: first and last sharp in edge order
        vertex = 0.75;
        int first = 0, last = num_edges - 1;
        while (!is_sharp(sharp[first])) ++first;
        while (!is_sharp(sharp[last])) --last;
        edge[first] = 0.125;
        edge[last] = 0.125;
        break;
      }
      case VertexRule::Corner:
        vertex = 1.0;
        break;
    }
  }
};

/// OpenSubdiv's Crease::ComputeFractionalWeightAtVertex (float arithmetic, same order).
float fractional_weight(const SubdivLevel& level, float parent_vs, float child_vs,
                        const std::vector<float>& parent_es, const std::vector<float>& child_es) {
  int count = 0;
  float sum = 0.0f;
  if (is_sharp(parent_vs) && !is_sharp(child_vs)) {
    count = 1;
    sum = parent_vs;
  }
  const bool uniform = level.options.crease_method == CreaseMethod::Uniform;
  for (size_t i = 0; i < parent_es.size(); ++i) {
    const float p = parent_es[i];
    const bool transition = uniform ? (is_sharp(p) && p <= 1.0f) : (is_sharp(p) && !is_sharp(child_es[i]));
    if (transition) {
      sum += p;
      ++count;
    }
  }
  if (count == 0) return 0.0f;
  const float w = sum / static_cast<float>(count);
  return w > 1.0f ? 1.0f : w;
}

}  // namespace

VertexRule vertex_rule(const SubdivLevel& level, int v) {
  int sharp = 0;
  for_each_vertex_edge(level.mesh, v, [&](int e, int) { sharp += is_sharp(level.edge_sharpness[e]); });
  return rule_from(level.vertex_sharpness[v], sharp);
}

bool is_sharpened_by_tagging(const PolyMesh& mesh, BoundaryRule rule, int v) {
  return mesh.is_unused_vertex(v) ||
         (rule == BoundaryRule::EdgeAndCorner && mesh.is_topological_corner(v));
}

SubdivLevel SubdivLevel::from_input(const MeshInput& input, Diagnostics* diagnostics) {
  return from_validated(validate_and_build(input, diagnostics), input);
}

SubdivLevel SubdivLevel::from_validated(PolyMesh mesh, const MeshInput& input) {
  SubdivLevel level;
  level.mesh = std::move(mesh);
  level.options = input.options;
  const PolyMesh& m = level.mesh;
  level.edge_sharpness.assign(m.num_edges(), 0.0f);
  level.vertex_sharpness.assign(m.num_vertices(), 0.0f);
  level.face_hole.assign(m.num_faces(), 0);
  for (const CreaseTag& c : input.creases)
    level.edge_sharpness[m.find_edge(c.v0, c.v1)] = static_cast<float>(c.sharpness);
  for (const CornerTag& c : input.corners)
    level.vertex_sharpness[c.vertex] = static_cast<float>(c.sharpness);
  for (int f : input.holes) level.face_hole[f] = 1;

  // BoundaryRule::None: faces around a boundary vertex produce no surface, unless every
  // boundary edge at that vertex was already tagged infinitely sharp (OpenSubdiv's factory
  // decides this before it sharpens the boundary).
  if (input.options.boundary == BoundaryRule::None) {
    for (int v = 0; v < m.num_vertices(); ++v) {
      if (!m.is_boundary_vertex(v)) continue;
      bool soft_boundary = false;
      for_each_vertex_edge(m, v, [&](int e, int) {
        soft_boundary |= m.is_boundary_edge(e) && !is_infinite(level.edge_sharpness[e]);
      });
      if (!soft_boundary) continue;
      const int* c = m.vertex_corners(v);
      for (int i = 0; i < m.vertex_face_count(v); ++i) level.face_hole[m.corner_face(c[i])] = 1;
    }
  }
  // Boundary edges are infinitely sharp under every boundary rule; so are unused vertices.
  for (int e = 0; e < m.num_edges(); ++e)
    if (m.is_boundary_edge(e)) level.edge_sharpness[e] = kInf;
  for (int v = 0; v < m.num_vertices(); ++v) {
    if (is_sharpened_by_tagging(m, input.options.boundary, v)) level.vertex_sharpness[v] = kInf;
  }
  return level;
}

double SubdivLevel::max_semi_sharpness() const {
  double s = 0;
  for (float x : edge_sharpness)
    if (is_semi_sharp(x)) s = std::max(s, static_cast<double>(x));
  for (float x : vertex_sharpness)
    if (is_semi_sharp(x)) s = std::max(s, static_cast<double>(x));
  return s;
}

namespace {

/// Builds the child connectivity of one Catmull-Clark step directly from the parent's
/// (layout in refiner.h): no searching for twins, every array filled in one pass.
void build_child_topology(const PolyMesh& pm, PolyMesh& cm) {
  const int V = pm.num_vertices(), F = pm.num_faces(), E = pm.num_edges(), H = pm.num_corners();
  PolyMeshAssembler::num_vertices(cm) = V + F + E;
  auto& offsets = PolyMeshAssembler::face_offsets(cm);
  auto& cv = PolyMeshAssembler::corner_vertex(cm);
  auto& cf = PolyMeshAssembler::corner_face(cm);
  auto& ce = PolyMeshAssembler::corner_edge(cm);
  auto& tw = PolyMeshAssembler::twin(cm);
  auto& edge_corner = PolyMeshAssembler::edge_corner(cm);
  auto& voff = PolyMeshAssembler::vertex_offsets(cm);
  auto& vcor = PolyMeshAssembler::vertex_corners(cm);
  PolyMeshAssembler::all_quads(cm) = true;
  cf.clear();
  offsets.resize(H + 1);
  cv.resize(4 * H);
  ce.resize(4 * H);
  tw.resize(4 * H);
  for (int h = 0; h < H; ++h) {
    const int p = pm.prev(h), n = pm.next(h), f = pm.corner_face(h), v = pm.corner_vertex(h);
    const int eh = pm.corner_edge(h), ep = pm.corner_edge(p);
    offsets[h] = 4 * h;
    const int c = 4 * h;
    cv[c + 0] = v;
    cv[c + 1] = V + F + eh;
    cv[c + 2] = V + f;
    cv[c + 3] = V + F + ep;
    ce[c + 0] = 2 * eh + (pm.edge_corner(eh) == h ? 0 : 1);  // the half of eh at v
    ce[c + 1] = 2 * E + h;
    ce[c + 2] = 2 * E + p;
    ce[c + 3] = 2 * ep + (pm.edge_corner(ep) == p ? 1 : 0);  // the half of ep at v
    const int t = pm.twin(h), tp = pm.twin(p);
    tw[c + 0] = t < 0 ? -1 : 4 * pm.next(t) + 3;
    tw[c + 1] = 4 * n + 2;
    tw[c + 2] = 4 * p + 1;
    tw[c + 3] = tp < 0 ? -1 : 4 * tp;
  }
  offsets[H] = 4 * H;
  edge_corner.resize(2 * E + H);
  for (int e = 0; e < E; ++e) {
    const int h0 = pm.edge_corner(e);
    edge_corner[2 * e] = 4 * h0;
    edge_corner[2 * e + 1] = 4 * pm.next(h0) + 3;
  }
  for (int h = 0; h < H; ++h) edge_corner[2 * E + h] = 4 * h + 1;
  voff.resize(V + F + E + 1);
  vcor.resize(4 * H);
  voff[0] = 0;
  int k = 0;
  for (int v = 0; v < V; ++v) {
    const int* c = pm.vertex_corners(v);
    for (int i = 0; i < pm.vertex_face_count(v); ++i) vcor[k++] = 4 * c[i];
    voff[v + 1] = k;
  }
  for (int f = 0; f < F; ++f) {
    for (int h = pm.face_begin(f); h < pm.face_end(f); ++h) vcor[k++] = 4 * h + 2;
    voff[V + f + 1] = k;
  }
  for (int e = 0; e < E; ++e) {
    const int h0 = pm.edge_corner(e), t = pm.twin(h0);
    vcor[k++] = 4 * pm.next(h0) + 3;
    vcor[k++] = 4 * h0 + 1;
    if (t >= 0) {
      vcor[k++] = 4 * pm.next(t) + 3;
      vcor[k++] = 4 * t + 1;
    }
    voff[V + F + e + 1] = k;
  }

}

}  // namespace

RefinementStep refine_once(const SubdivLevel& parent) {
  const PolyMesh& pm = parent.mesh;
  const int V = pm.num_vertices(), F = pm.num_faces(), E = pm.num_edges(), H = pm.num_corners();
  RefinementStep step;
  SubdivLevel& child = step.child;
  child.options = parent.options;

  // ---- child sharpness ------------------------------------------------------------------
  // Child edges: 2e + k is the half of parent edge e at its end vertex k; 2E + h is the
  // interior edge from the centre of corner_face(h) to the midpoint of corner_edge(h).
  child.edge_sharpness.assign(2 * E + H, 0.0f);
  for (int e = 0; e < E; ++e) {
    const float s = parent.edge_sharpness[e];
    if (!is_sharp(s)) continue;
    child.edge_sharpness[2 * e] = child_edge_sharpness(parent, e, pm.edge_vertex(e, 0));
    child.edge_sharpness[2 * e + 1] = child_edge_sharpness(parent, e, pm.edge_vertex(e, 1));
  }
  child.vertex_sharpness.assign(V + F + E, 0.0f);
  for (int v = 0; v < V; ++v) {
    child.vertex_sharpness[v] = decrement_sharpness(parent.vertex_sharpness[v]);
  }
  child.face_hole.resize(H);
  for (int h = 0; h < H; ++h) child.face_hole[h] = parent.face_hole[pm.corner_face(h)];

  // ---- child topology and stencils --------------------------------------------------
  // The two are independent given the child sharpness; on big meshes the topology is built
  // on a second thread while this one writes the stencils.
  // (Not under a ThreadLimit of 1: then this thread does both.)
  const bool concurrent = H >= kConcurrentCorners && loop_threads() > 1;
  std::thread topology;
  std::exception_ptr topology_error;
  struct JoinOnExit {  // never leave the thread running if the stencils throw
    std::thread& t;
    ~JoinOnExit() {
      if (t.joinable()) t.join();
    }
  } join_on_exit{topology};
  if (concurrent) {
    topology = std::thread([&pm, &child, &topology_error] {
      try {
        build_child_topology(pm, child.mesh);
      } catch (...) {
        topology_error = std::current_exception();
      }
    });
  } else {
    build_child_topology(pm, child.mesh);
  }

  // ---- stencils: vertex points, face points, edge points --------------------------------
  StencilTable& st = step.stencils;
  st.num_sources = V;
  st.offsets.reserve(V + F + E + 1);
  st.indices.reserve(static_cast<size_t>(9) * V + 4 * static_cast<size_t>(F) + 6 * static_cast<size_t>(E));
  st.weights.reserve(st.indices.capacity());
  RowBuilder row(V);

  // Vertices touching a sharp edge need the general (rule-based) mask; the rest are smooth.
  std::vector<char> near_sharp(V, 0);
  for (int e = 0; e < E; ++e)
    if (is_sharp(parent.edge_sharpness[e])) near_sharp[pm.edge_vertex(e, 0)] = near_sharp[pm.edge_vertex(e, 1)] = 1;
  // Appends a row of n entries and returns where to write its sources and weights.
  auto append_row = [&st](int n) {
    const size_t k = st.indices.size();
    st.indices.resize(k + n);
    st.weights.resize(k + n);
    return std::make_pair(st.indices.data() + k, st.weights.data() + k);
  };
  auto end_row = [&st] { st.offsets.push_back(static_cast<int>(st.indices.size())); };

  std::vector<float> pes, ces;  // parent / child sharpness of the edges at a vertex
  std::vector<int> nbr;         // other vertex of each incident edge
  VertexMask pmask, cmask;
  for (int v = 0; v < V; ++v) {
    const int nf = pm.vertex_face_count(v);
    if (nf == 0) {  // unused vertex: carried along unchanged
      row.add(v, 1.0);
      row.emit(st);
      continue;
    }
    const int* vc = pm.vertex_corners(v);
    if (!near_sharp[v] && !is_sharp(parent.vertex_sharpness[v])) {
      bool quads = true;
      for (int i = 0; i < nf; ++i) quads &= pm.face_size(pm.corner_face(vc[i])) == 4;
      if (quads) {
        // Smooth rule with the face centres expanded: each quad (v, e_r, d_r, e_r+1) adds
        // 1/(4n^2) to its four corners (docs/math.md 1.1).
        const double n = nf, fw = 0.25 / (n * n), ew = 1.0 / (n * n) + 2.0 * fw;
        auto [idx, w] = append_row(1 + 2 * nf);
        idx[0] = v;
        w[0] = (n - 2.0) / n + n * fw;
        for (int i = 0; i < nf; ++i) {
          idx[1 + 2 * i] = pm.to_vertex(vc[i]);
          w[1 + 2 * i] = ew;
          idx[2 + 2 * i] = pm.corner_vertex(pm.next(pm.next(vc[i])));
          w[2 + 2 * i] = fw;
        }
        end_row();
        continue;
      }
    }
    pes.clear();
    ces.clear();
    nbr.clear();
    int psharp = 0, csharp = 0;
    for_each_vertex_edge(pm, v, [&](int e, int other) {
      const float ps = parent.edge_sharpness[e];
      const float cs = child.edge_sharpness[half_at(pm, e, v)];
      pes.push_back(ps);
      ces.push_back(cs);
      nbr.push_back(other);
      psharp += is_sharp(ps);
      csharp += is_sharp(cs);
    });
    const int ne = static_cast<int>(nbr.size());
    const VertexRule prule = rule_from(parent.vertex_sharpness[v], psharp);
    const VertexRule crule = rule_from(child.vertex_sharpness[v], csharp);
    pmask.assign(prule, ne, nf, pes);
    const bool parent_smooth = prule == VertexRule::Smooth || prule == VertexRule::Dart;
    if (!parent_smooth && crule != prule) {
      cmask.assign(crule, ne, nf, ces);
      const double pw = fractional_weight(parent, parent.vertex_sharpness[v],
                                          child.vertex_sharpness[v], pes, ces);
      const double cw = 1.0 - pw;
      pmask.vertex = pw * pmask.vertex + cw * cmask.vertex;
      for (int i = 0; i < ne; ++i) pmask.edge[i] = pw * pmask.edge[i] + cw * cmask.edge[i];
      for (int i = 0; i < nf; ++i) pmask.face[i] = pw * pmask.face[i] + cw * cmask.face[i];
    }
    row.add(v, pmask.vertex);
    for (int i = 0; i < ne; ++i)
      if (pmask.edge[i] != 0.0) row.add(nbr[i], pmask.edge[i]);
    const int* c = pm.vertex_corners(v);
    for (int i = 0; i < nf; ++i)
      if (pmask.face[i] != 0.0) row.add_face_centre(pm, pm.corner_face(c[i]), pmask.face[i]);
    row.emit(st);
  }
  for (int f = 0; f < F; ++f) {
    const int m = pm.face_size(f);
    auto [idx, w] = append_row(m);
    for (int i = 0; i < m; ++i) {
      idx[i] = pm.face_vertices(f)[i];
      w[i] = 1.0 / m;
    }
    end_row();
  }
  const bool smooth_triangles = parent.options.triangles == TriangleRule::Smooth;
  for (int e = 0; e < E; ++e) {
    const int h0 = pm.edge_corner(e), t = pm.twin(h0);
    const int a = pm.corner_vertex(h0), b = pm.to_vertex(h0);
    const float s = parent.edge_sharpness[e];
    // Rule of the child vertex on this edge: from how many of the two halves stay sharp.
    bool child_crease = false;
    if (is_infinite(s)) {
      child_crease = true;
    } else if (is_sharp(s)) {
      child_crease = is_sharp(child.edge_sharpness[2 * e]) && is_sharp(child.edge_sharpness[2 * e + 1]);
    }
    if (is_sharp(s) && child_crease) {
      row.add(a, 0.5);
      row.add(b, 0.5);
      row.emit(st);
      continue;
    }
    // Smooth mask (boundary edges are always sharp, so there are two faces here).
    const int f0 = pm.corner_face(h0), f1 = pm.corner_face(t);
    if (!is_sharp(s) && pm.face_size(f0) == 4 && pm.face_size(f1) == 4) {
      // (a + b)/4 + (centre f0 + centre f1)/4 with the centres expanded.
      auto [idx, w] = append_row(6);
      idx[0] = a;
      idx[1] = b;
      idx[2] = pm.corner_vertex(pm.next(pm.next(h0)));
      idx[3] = pm.corner_vertex(pm.prev(h0));
      idx[4] = pm.corner_vertex(pm.next(pm.next(t)));
      idx[5] = pm.corner_vertex(pm.prev(t));
      w[0] = w[1] = 0.375;
      w[2] = w[3] = w[4] = w[5] = 0.0625;
      end_row();
      continue;
    }
    double wv = 0.25, wf = 0.25;
    if (smooth_triangles && (pm.face_size(f0) == 3 || pm.face_size(f1) == 3)) {
      const double tri = 0.470;  // OpenSubdiv's CATMARK_SMOOTH_TRI_EDGE_WEIGHT
      const double w0 = pm.face_size(f0) == 3 ? tri : 0.25;
      const double w1 = pm.face_size(f1) == 3 ? tri : 0.25;
      wf = 0.5 * (w0 + w1);
      wv = 0.5 * (1.0 - 2.0 * wf);
    }
    if (is_sharp(s)) {  // semi-sharp parent, smooth child: blend by the parent sharpness
      const double pw = s, cw = 1.0 - pw;
      wv = pw * 0.5 + cw * wv;
      wf *= cw;
    }
    row.add(a, wv);
    row.add(b, wv);
    row.add_face_centre(pm, f0, wf);
    row.add_face_centre(pm, f1, wf);
    row.emit(st);
  }
  if (concurrent) topology.join();
  if (topology_error) std::rethrow_exception(topology_error);
  return step;
}

Refinement refine_uniform(const SubdivLevel& base, int levels) {
  Refinement r;
  r.levels.reserve(levels + 1);
  r.levels.push_back(base);
  for (int l = 0; l < levels; ++l) {
    RefinementStep s = refine_once(r.levels.back());
    r.levels.push_back(std::move(s.child));
    r.steps.push_back(std::move(s.stencils));
  }
  return r;
}

StencilTable Refinement::stencils_from_base(int k) const {
  StencilTable t;
  const int n = levels.at(0).mesh.num_vertices();
  t.num_sources = n;
  for (int i = 0; i < n; ++i) {
    t.indices.push_back(i);
    t.weights.push_back(1.0);
    t.offsets.push_back(i + 1);
  }
  for (int l = 0; l < k; ++l) t = steps.at(l).compose(t);
  return t;
}

std::vector<std::vector<Point3>> Refinement::positions(const std::vector<Point3>& base) const {
  std::vector<std::vector<Point3>> out(levels.size());
  out[0] = base;
  for (size_t l = 0; l < steps.size(); ++l) steps[l].apply(out[l], out[l + 1]);
  return out;
}

}  // namespace subd2nurbs
