#include "core/remesh/quad_remesh.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <deque>
#include <numeric>
#include <optional>
#include <queue>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "core/fit/planar_regions.h"
#include "core/mesh/corner_sectors.h"
#include "core/mesh/poly_mesh.h"
#include "core/remesh/quad_cleanup.h"
#include "core/util/constants.h"
#include "core/util/error.h"
#include "core/util/parallel.h"
#include "core/util/wave_sweeps.h"

namespace subd2nurbs {
namespace {

using V3 = Eigen::Vector3d;
using Clock = std::chrono::steady_clock;
using Tri = std::array<int, 3>;

struct CancelSignal {};

// How far a feature chain may stray from the coarse edge standing for it, relative to the
// edge's length (Collapser::chord_follows_chain): 0.15 lets an arc turn by up to ~67 degrees per
// coarse edge (~33 per cage edge). (0.1 crowded the drilled box's rims with chain vertices and
// folded a quad; 0.2 and 0.25 folded a quad at the stepped block's hole, radius 4 against a
// spacing of ~5 (feature angle 89.5 and 6.1 degrees off); 0.3 rounds the drilled box's rims.
// At 0.15 both test parts keep every feature within 3 degrees; the CAD STLs get ~10 % more
// faces than at 0.2.)
constexpr double kChainSag = 0.15;

std::uint64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}
std::uint64_t half_key(int a, int b) { return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b); }

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// --- topology of a polygon mesh: per component (Euler characteristic, boundary loops) ---------
struct Topology {
  int euler = 0, boundaries = 0, components = 0;
  std::vector<std::pair<int, int>> per_component;  // sorted
};

int find_root(std::vector<int>& parent, int x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}

Topology topology(int num_vertices, const std::vector<int>& sizes, const std::vector<int>& indices) {
  std::vector<int> parent(num_vertices);
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<char> used(num_vertices, 0);
  std::vector<std::uint64_t> edges;
  std::vector<int> face_first;
  int begin = 0;
  for (int size : sizes) {
    face_first.push_back(indices[begin]);
    for (int k = 0; k < size; ++k) {
      int a = indices[begin + k], b = indices[begin + (k + 1) % size];
      used[a] = 1;
      edges.push_back(edge_key(a, b));
      parent[find_root(parent, a)] = find_root(parent, b);
    }
    begin += size;
  }
  std::sort(edges.begin(), edges.end());
  std::vector<int> boundary_parent(num_vertices);
  std::iota(boundary_parent.begin(), boundary_parent.end(), 0);
  std::vector<char> on_boundary(num_vertices, 0);
  std::unordered_map<int, std::array<int, 3>> comp;  // root -> V - E + F, boundary loops
  std::vector<int> roots;
  for (int v = 0; v < num_vertices; ++v)
    if (used[v]) comp[find_root(parent, v)][0] += 1;
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    int a = int(edges[i] >> 32), b = int(edges[i] & 0xffffffffu);
    comp[find_root(parent, a)][0] -= 1;
    if (j - i == 1) {
      on_boundary[a] = on_boundary[b] = 1;
      boundary_parent[find_root(boundary_parent, a)] = find_root(boundary_parent, b);
    }
    i = j;
  }
  for (int f : face_first) comp[find_root(parent, f)][0] += 1;
  for (int v = 0; v < num_vertices; ++v)
    if (on_boundary[v] && find_root(boundary_parent, v) == v) comp[find_root(parent, v)][1] += 1;
  Topology t;
  for (const auto& [root, c] : comp) {
    t.per_component.push_back({c[0], c[1]});
    t.euler += c[0];
    t.boundaries += c[1];
  }
  t.components = static_cast<int>(comp.size());
  std::sort(t.per_component.begin(), t.per_component.end());
  return t;
}

// --- dense mesh: the input's triangles with long edges split --------------------------------
struct Dense {
  std::vector<V3> p;
  std::vector<Tri> t;
  std::unordered_set<std::uint64_t> feature;  // feature edge keys
  std::vector<char> corner;
  std::vector<char> dart;  // corners that end a fading crease (FeatureSet::darts): held like corners, not tagged in the cage
};

// Directed edge (half_key(a, b)) -> the triangle that has it.
std::unordered_map<std::uint64_t, int> half_edges(const std::vector<Tri>& tris) {
  std::unordered_map<std::uint64_t, int> half;
  half.reserve(tris.size() * 3);
  for (size_t f = 0; f < tris.size(); ++f)
    for (int k = 0; k < 3; ++k) half[half_key(tris[f][k], tris[f][(k + 1) % 3])] = int(f);
  return half;
}

// Per triangle, the triangle across each of its edges t[k] -> t[k + 1] (-1: none).
std::vector<std::array<int, 3>> triangles_across(const std::vector<Tri>& tris) {
  const std::unordered_map<std::uint64_t, int> half = half_edges(tris);
  std::vector<std::array<int, 3>> across(tris.size(), {-1, -1, -1});
  for (size_t f = 0; f < tris.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      auto it = half.find(half_key(tris[f][(k + 1) % 3], tris[f][k]));
      if (it != half.end()) across[f][k] = it->second;
    }
  return across;
}

void split_long_edges(Dense& d, double lmax) {
  // The half-edge map is kept up to date by the splits (built once, not once per pass): a pass
  // looks up only triangles it has not split yet, whose entries no split of the pass changes.
  std::unordered_map<std::uint64_t, int> half = half_edges(d.t);
  auto set_half = [&](int f) {
    for (int k = 0; k < 3; ++k) half[half_key(d.t[f][k], d.t[f][(k + 1) % 3])] = f;
  };
  for (int pass = 0; pass < 400; ++pass) {
    struct Cand {
      double length;
      std::uint64_t key;
      int face, k;
    };
    std::vector<Cand> cands;
    for (size_t f = 0; f < d.t.size(); ++f) {
      int best = -1;
      double bl = lmax;
      for (int k = 0; k < 3; ++k) {
        double l = (d.p[d.t[f][k]] - d.p[d.t[f][(k + 1) % 3]]).norm();
        if (l > bl) bl = l, best = k;
      }
      if (best >= 0) cands.push_back({bl, edge_key(d.t[f][best], d.t[f][(best + 1) % 3]), int(f), best});
    }
    if (cands.empty()) return;
    std::sort(cands.begin(), cands.end(), [](const Cand& a, const Cand& b) {
      return a.length != b.length ? a.length > b.length : a.key != b.key ? a.key < b.key : a.face < b.face;
    });
    std::vector<char> touched(d.t.size(), 0);
    for (const Cand& c : cands) {
      int f = c.face;
      if (touched[f]) continue;
      int a = d.t[f][c.k], b = d.t[f][(c.k + 1) % 3], cc = d.t[f][(c.k + 2) % 3];
      auto it = half.find(half_key(b, a));
      int g = it == half.end() ? -1 : it->second;
      if (g >= 0 && touched[g]) continue;
      int m = static_cast<int>(d.p.size());
      d.p.push_back(0.5 * (d.p[a] + d.p[b]));
      d.corner.push_back(0);
      half.erase(half_key(a, b));
      d.t[f] = {a, m, cc};
      d.t.push_back({m, b, cc});
      set_half(f);
      set_half(static_cast<int>(d.t.size()) - 1);
      touched[f] = 1;
      touched.push_back(1);
      if (g >= 0) {
        int j = 0;
        while (!(d.t[g][j] == b && d.t[g][(j + 1) % 3] == a)) ++j;
        int w = d.t[g][(j + 2) % 3];
        half.erase(half_key(b, a));
        d.t[g] = {b, m, w};
        d.t.push_back({m, a, w});
        set_half(g);
        set_half(static_cast<int>(d.t.size()) - 1);
        touched[g] = 1;
        touched.push_back(1);
      }
      if (d.feature.erase(edge_key(a, b))) {
        d.feature.insert(edge_key(a, m));
        d.feature.insert(edge_key(m, b));
      }
    }
  }
}

// --- fields ---------------------------------------------------------------------------------
V3 any_perpendicular(const V3& n) {
  V3 a = std::abs(n.x()) < 0.6 ? V3(1, 0, 0) : V3(0, 1, 0);
  return (a - n * n.dot(a)).normalized();
}

// Which members of the crosses {a0, a1} and {±b0, ±b1} agree best (4-fold symmetry): a[i] and
// sign x b[j] (the first best in the order i, j).
struct CrossMatch {
  int i = 0, j = 0;
  double sign = 1;
};
[[gnu::always_inline]] inline CrossMatch best_cross_match(const V3& a0, const V3& a1, const V3& b0, const V3& b1) {
  const V3* a[2] = {&a0, &a1};
  const V3* b[2] = {&b0, &b1};
  double best = -1;
  CrossMatch m;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) {
      double s = std::abs(a[i]->dot(*b[j]));
      if (s > best) best = s, m.i = i, m.j = j;
    }
  m.sign = a[m.i]->dot(*b[m.j]) < 0 ? -1.0 : 1.0;
  return m;
}

// The members of {q0, n0 x q0} and {±q1, ±n1 x q1} that agree best (4-fold symmetry).
std::pair<V3, V3> match_cross(const V3& q0, const V3& n0, const V3& q1, const V3& n1) {
  const V3 a[2] = {q0, n0.cross(q0)};
  const V3 b[2] = {q1, n1.cross(q1)};
  const CrossMatch m = best_cross_match(a[0], a[1], b[0], b[1]);
  return {a[m.i], m.sign * b[m.j]};
}

// The point nearest the midpoint of p0, p1 on both tangent planes.
V3 middle_point(const V3& p0, const V3& n0, const V3& p1, const V3& n1) {
  V3 c = 0.5 * (p0 + p1);
  double r0 = n0.dot(p0 - c), r1 = n1.dot(p1 - c), k = n0.dot(n1);
  double det = 1 - k * k + 1e-4;
  return c + ((r0 - k * r1) / det) * n0 + ((r1 - k * r0) / det) * n1;
}

using remesh_detail::round_half_away;

// Inlined into the sweeps (the same arithmetic; a call made them pass the vectors through memory).
[[gnu::always_inline]] inline V3 round_lattice(const V3& x, const V3& origin, const V3& q, const V3& t, double s) {
  V3 d = x - origin;
  return origin + q * (s * round_half_away(d.dot(q) / s)) + t * (s * round_half_away(d.dot(t) / s));
}

struct Fields {
  int n = 0;
  std::vector<int> offsets, adj;  // CSR neighbours (sorted)
  std::vector<V3> normal, q, o;
  std::vector<V3> p;              // positions
  std::vector<V3> anchor;         // corners: where o stays; feature vertices: a point of o's line
  std::vector<double> weight;     // dense vertices represented (coarse levels)
  std::vector<int> kind;          // 0 free, 1 on a feature chain, 2 corner
  std::vector<V3> tangent;        // feature tangent (kind 1), zero if none
  std::vector<V3> principal;      // principal curvature direction
  std::vector<double> principal_weight;
  std::vector<std::array<int, 2>> chain;  // dense level: a chain vertex's feature neighbours (-1: none)
  bool pin_arcs = false;                  // dense level: pin_tight_arcs (QuadRemeshOptions)
  int arc_pins = 0;                       // dense level: vertices pinned by the last position solve
  std::vector<char> pinned;               // position field: o stays at pin (ends of tight arcs, step 3)
  std::vector<V3> pin;
  double s = 1;
};

// Quarter turns k with (x, y) in v's lattice frame = rotate_turns((x, y), k) in u's frame.
int frame_turns(const Fields& fl, const std::vector<V3>& nq, int u, int v) {
  const CrossMatch m = best_cross_match(fl.q[u], nq[u], fl.q[v], nq[v]);
  if (m.i == m.j) return m.sign > 0 ? 0 : 2;
  if (m.i == 0) return m.sign > 0 ? 3 : 1;  // u's first axis along v's second
  return m.sign > 0 ? 1 : 3;                // u's second axis along v's first
}

// The cross field's index around each dense triangle (as Instant Meshes counts it): per edge
// i -> j the quarter turns between the members of the two crosses that agree best (j's frame
// against i's: -frame_turns(i, j)), summed around the triangle, mod 4: 1 a singularity of index
// +1/4 (a valence-3 vertex), 3 one of -1/4 (valence 5), 2 (half a turn) counted as +2.
void count_singularities(const Dense& d, const Fields& fl, QuadRemeshStats& st) {
  std::vector<V3> nq(fl.n);
  for (int v = 0; v < fl.n; ++v) nq[v] = fl.normal[v].cross(fl.q[v]);
  auto turns = [&](int i, int j) { return -frame_turns(fl, nq, i, j); };
  st.field_singularities = st.field_index_sum = 0;
  for (const Tri& t : d.t) {
    const int k = (((turns(t[0], t[1]) + turns(t[1], t[2]) + turns(t[2], t[0])) % 4) + 4) % 4;
    if (k == 0) continue;
    ++st.field_singularities;
    st.field_index_sum += k == 3 ? -1 : k;
  }
}

void build_adjacency(const Dense& d, Fields& fl) {
  int n = static_cast<int>(d.p.size());
  fl.n = n;
  fl.p = d.p;
  fl.anchor = d.p;
  fl.weight.assign(n, 1.0);
  std::vector<std::uint64_t> pairs;
  pairs.reserve(d.t.size() * 6);
  fl.normal.assign(n, V3::Zero());
  for (const Tri& t : d.t) {
    V3 fn = (d.p[t[1]] - d.p[t[0]]).cross(d.p[t[2]] - d.p[t[0]]);
    for (int k = 0; k < 3; ++k) {
      fl.normal[t[k]] += fn;
      pairs.push_back(half_key(t[k], t[(k + 1) % 3]));
      pairs.push_back(half_key(t[(k + 1) % 3], t[k]));
    }
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  fl.offsets.assign(n + 1, 0);
  for (auto k : pairs) fl.offsets[(k >> 32) + 1]++;
  for (int v = 0; v < n; ++v) fl.offsets[v + 1] += fl.offsets[v];
  fl.adj.resize(pairs.size());
  for (size_t i = 0; i < pairs.size(); ++i) fl.adj[i] = int(pairs[i] & 0xffffffffu);
  for (auto& nv : fl.normal) {
    double l = nv.norm();
    nv = l > 0 ? V3(nv / l) : V3(0, 0, 1);
  }
}

void classify(const Dense& d, Fields& fl) {
  fl.kind.assign(fl.n, 0);
  fl.tangent.assign(fl.n, V3::Zero());
  fl.chain.assign(fl.n, {-1, -1});
  for (int v = 0; v < fl.n; ++v) {
    std::vector<int> fn;
    for (int i = fl.offsets[v]; i < fl.offsets[v + 1]; ++i)
      if (d.feature.count(edge_key(v, fl.adj[i]))) fn.push_back(fl.adj[i]);
    if (d.corner[v]) {
      fl.kind[v] = 2;
    } else if (!fn.empty()) {
      fl.kind[v] = 1;
      if (fn.size() <= 2) fl.chain[v] = {fn[0], fn.size() == 2 ? fn[1] : -1};
      V3 t = fn.size() == 2 ? V3(d.p[fn[1]] - d.p[fn[0]]) : V3(d.p[v] - d.p[fn[0]]);
      t -= fl.normal[v] * fl.normal[v].dot(t);
      if (fn.size() <= 2 && t.norm() > 0) fl.tangent[v] = t.normalized();
      if (fn.size() > 2) fl.kind[v] = 2;  // a junction the feature set missed: keep it in place
    }
  }
}

// Principal curvature directions from a least-squares shape operator (normal differences along
// the edges), weighted by anisotropy and by how much the curvature matters at the lattice scale.
void curvature(const Dense& d, Fields& fl, double alignment) {
  fl.principal.assign(fl.n, V3::Zero());
  fl.principal_weight.assign(fl.n, 0.0);
  if (alignment <= 0) return;
  for (int v = 0; v < fl.n; ++v) {
    if (fl.kind[v] != 0) continue;
    bool near_feature = false;
    for (int i = fl.offsets[v]; i < fl.offsets[v + 1]; ++i) near_feature |= fl.kind[fl.adj[i]] != 0;
    if (near_feature || fl.offsets[v + 1] - fl.offsets[v] < 3) continue;
    const V3& n = fl.normal[v];
    V3 e1 = any_perpendicular(n), e2 = n.cross(e1);
    Eigen::Matrix2d a = Eigen::Matrix2d::Zero(), b = Eigen::Matrix2d::Zero();
    for (int i = fl.offsets[v]; i < fl.offsets[v + 1]; ++i) {
      int w = fl.adj[i];
      V3 e = d.p[w] - d.p[v], dn = fl.normal[w] - n;
      Eigen::Vector2d e2d(e.dot(e1), e.dot(e2)), dn2d(dn.dot(e1), dn.dot(e2));
      a += e2d * e2d.transpose();
      b += dn2d * e2d.transpose();
    }
    if (std::abs(a.determinant()) < 1e-12 * a.squaredNorm()) continue;
    Eigen::Matrix2d shape = b * a.inverse();
    shape = 0.5 * (shape + shape.transpose()).eval();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(shape);
    double k1 = es.eigenvalues()(0), k2 = es.eigenvalues()(1);
    double spread = std::abs(k1 - k2), total = std::abs(k1) + std::abs(k2);
    if (total <= 0) continue;
    Eigen::Vector2d dir = es.eigenvectors().col(std::abs(k1) > std::abs(k2) ? 0 : 1);
    fl.principal[v] = (e1 * dir(0) + e2 * dir(1)).normalized();
    fl.principal_weight[v] = alignment * (spread / total) * std::min(1.0, spread * fl.s);
  }
}

// Breadth-first propagation over the vertex graph, shared by both fields' initialisation: from the
// vertices `seeded` (set[v] = 1), each unset neighbour w of a reached vertex v is set by
// spread(v, w); when the queue runs dry (a component without seeds), the next unset vertex with
// neighbours is seeded by seed(v) and the walk goes on.
template <class Spread, class Seed, class Check>
void propagate(const Fields& fl, std::vector<char>& set, std::deque<int>& queue, Spread&& spread, Seed&& seed_vertex,
               Check&& check) {
  for (int seed = 0;; ++seed) {
    while (!queue.empty()) {
      int v = queue.front();
      queue.pop_front();
      for (int i = fl.offsets[v]; i < fl.offsets[v + 1]; ++i) {
        int w = fl.adj[i];
        if (set[w]) continue;
        spread(v, w);
        set[w] = 1;
        queue.push_back(w);
      }
    }
    while (seed < fl.n && (set[seed] || fl.offsets[seed] == fl.offsets[seed + 1])) ++seed;
    if (seed >= fl.n) break;
    seed_vertex(seed);
    set[seed] = 1;
    queue.push_back(seed);
    check();
  }
}

template <class Check>
void init_cross_field(Fields& fl, Check&& check) {
  fl.q.assign(fl.n, V3::Zero());
  std::vector<char> set(fl.n, 0);
  std::deque<int> queue;
  for (int v = 0; v < fl.n; ++v) {
    if (fl.kind[v] == 1 && fl.tangent[v].norm() > 0) {
      fl.q[v] = fl.tangent[v];
    } else if (fl.principal_weight[v] > 0.5) {
      fl.q[v] = fl.principal[v];
    } else {
      continue;
    }
    set[v] = 1;
    queue.push_back(v);
  }
  propagate(
      fl, set, queue,
      [&](int v, int w) {
        V3 t = fl.q[v] - fl.normal[w] * fl.normal[w].dot(fl.q[v]);
        fl.q[w] = t.norm() > 1e-9 ? V3(t.normalized()) : any_perpendicular(fl.normal[w]);
      },
      [&](int v) { fl.q[v] = any_perpendicular(fl.normal[v]); }, check);
  for (int v = 0; v < fl.n; ++v)
    if (!set[v]) fl.q[v] = any_perpendicular(fl.normal[v]);
}

// match_cross with n1 x q1 given (`nq1`).
std::pair<V3, V3> match_cross_given(const V3& q0, const V3& n0, const V3& q1, const V3& nq1) {
  const V3 a[2] = {q0, n0.cross(q0)};
  const CrossMatch m = best_cross_match(a[0], a[1], q1, nq1);
  return {a[m.i], m.sign * (m.j == 0 ? q1 : nq1)};
}

// One vertex's cross field step; `nq` holds normal x q of every vertex, kept up to date.
void smooth_cross_vertex(Fields& fl, std::vector<V3>& nq, int v) {
  if (fl.kind[v] == 1 && fl.tangent[v].norm() > 0) return;  // constrained to the feature
  const V3& n = fl.normal[v];
  V3 sum = fl.q[v];
  double weight = 0;
  for (int i = fl.offsets[v]; i < fl.offsets[v + 1]; ++i) {
    int w = fl.adj[i];
    auto [a, b] = match_cross_given(sum, n, fl.q[w], nq[w]);
    sum = a * weight + b;
    sum -= n * n.dot(sum);
    weight += 1;
    double l = sum.norm();
    if (l > 0) sum /= l;
  }
  if (fl.principal_weight[v] > 0) {
    auto [a, b] = match_cross(sum, n, fl.principal[v], n);
    sum = a + b * fl.principal_weight[v];
    sum -= n * n.dot(sum);
  }
  double l = sum.norm();
  if (l > 1e-12) {
    fl.q[v] = sum / l;
    nq[v] = n.cross(fl.q[v]);
  }
}

// A feature vertex's lattice point kept on the line through it along its chain (q there is the
// chain's tangent): o projected onto that line; any other vertex's o as it is.
V3 on_chain_line(const Fields& fl, int v, const V3& o) {
  if (fl.kind[v] != 1 || !(fl.tangent[v].norm() > 0)) return o;
  return fl.anchor[v] + fl.q[v] * fl.q[v].dot(o - fl.anchor[v]);
}

void constrain_position(Fields& fl, int v) {
  if (fl.kind[v] == 2) {
    fl.o[v] = fl.anchor[v];
  } else if (fl.pinned[v]) {
    fl.o[v] = fl.pin[v];
  } else {
    fl.o[v] = on_chain_line(fl, v, fl.o[v]);
  }
  V3 t = fl.normal[v].cross(fl.q[v]);
  fl.o[v] = round_lattice(fl.p[v], fl.o[v], fl.q[v], t, fl.s);
}

template <class Check>
void init_position_field(Fields& fl, Check&& check) {
  fl.o.assign(fl.n, V3::Zero());
  std::vector<char> set(fl.n, 0);
  std::deque<int> queue;
  for (int v = 0; v < fl.n; ++v)
    if (fl.kind[v] == 2 || fl.pinned[v]) {
      fl.o[v] = fl.kind[v] == 2 ? fl.anchor[v] : fl.pin[v];
      constrain_position(fl, v);
      set[v] = 1;
      queue.push_back(v);
    }
  propagate(
      fl, set, queue,
      [&](int v, int w) {
        const V3& n = fl.normal[w];
        fl.o[w] = fl.o[v] - n * n.dot(fl.o[v] - fl.p[w]);
        constrain_position(fl, w);
      },
      [&](int v) { fl.o[v] = fl.p[v]; }, check);
}

// What a position sweep reads of a neighbour, side by side (one or two cache lines instead of
// three arrays' worth: the sweeps visit neighbours all over the dense mesh).
struct PositionNode {
  V3 o, q, t;  // the lattice point, the lattice directions q and t = n x q
};

// What the position field's sweeps on one level read: per vertex its node (q and t never change
// then: the cross field is fixed; o follows the sweeps), and for each neighbour entry of the
// adjacency the middle point of the two vertices' tangent planes (the positions are fixed too).
struct PositionFrame {
  std::vector<PositionNode> node;  // per vertex; node[v].o follows fl.o[v] through the sweeps
  std::vector<V3> mid;             // per adjacency entry i of v (neighbour adj[i]): middle_point(v, adj[i])
};

PositionFrame position_frame(const Fields& fl) {
  PositionFrame f;
  f.node.resize(fl.n);
  f.mid.resize(fl.adj.size());
  for (int v = 0; v < fl.n; ++v) {
    f.node[v] = {fl.o[v], fl.q[v], fl.normal[v].cross(fl.q[v])};
    for (int i = fl.offsets[v]; i < fl.offsets[v + 1]; ++i) {
      const int w = fl.adj[i];
      f.mid[i] = middle_point(fl.p[v], fl.normal[v], fl.p[w], fl.normal[w]);
    }
  }
  return f;
}

void smooth_position_vertex(Fields& fl, PositionFrame& frame, int v) {
  if (fl.kind[v] == 2 || fl.pinned[v]) return;
  const V3& n = fl.normal[v];
  const V3& p = fl.p[v];
  PositionNode& me = frame.node[v];
  V3 sum = me.o;
  double weight = 0;
  for (int i = fl.offsets[v]; i < fl.offsets[v + 1]; ++i) {
    const PositionNode& other = frame.node[fl.adj[i]];
    V3 a = round_lattice(frame.mid[i], sum, me.q, me.t, fl.s);
    V3 b = round_lattice(a, other.o, other.q, other.t, fl.s);  // the same lattice point
    sum = (a * weight + b) / (weight + 1);
    sum -= n * n.dot(sum - p);
    weight += 1;
  }
  fl.o[v] = sum;
  constrain_position(fl, v);
  me.o = fl.o[v];
}

// --- multiresolution (as Instant Meshes): vertices paired along edges level by level --------
// One coarser level: edges sorted by how well their normals agree, greedily matched; a pair
// becomes one vertex (weighted mean position, summed normal, the stronger constraint).
Fields coarsen(const Fields& f, std::vector<int>& parent) {
  struct Candidate {
    double score;
    int u, v;
  };
  std::vector<Candidate> edges;
  for (int u = 0; u < f.n; ++u)
    for (int i = f.offsets[u]; i < f.offsets[u + 1]; ++i) {
      int v = f.adj[i];
      if (v > u && !(f.kind[u] == 2 && f.kind[v] == 2)) edges.push_back({f.normal[u].dot(f.normal[v]), u, v});
    }
  std::sort(edges.begin(), edges.end(), [](const Candidate& a, const Candidate& b) {
    return a.score != b.score ? a.score > b.score : a.u != b.u ? a.u < b.u : a.v < b.v;
  });
  parent.assign(f.n, -1);
  int n = 0;
  for (const Candidate& e : edges)
    if (parent[e.u] < 0 && parent[e.v] < 0) parent[e.u] = parent[e.v] = n++;
  for (int u = 0; u < f.n; ++u)
    if (parent[u] < 0) parent[u] = n++;
  Fields c;
  c.n = n;
  c.s = f.s;
  c.p.assign(n, V3::Zero());
  c.normal.assign(n, V3::Zero());
  c.weight.assign(n, 0.0);
  c.kind.assign(n, -1);
  c.anchor.assign(n, V3::Zero());
  c.tangent.assign(n, V3::Zero());
  c.principal.assign(n, V3::Zero());
  c.principal_weight.assign(n, 0.0);
  for (int u = 0; u < f.n; ++u) {
    int a = parent[u];
    c.p[a] += f.weight[u] * f.p[u];
    c.normal[a] += f.weight[u] * f.normal[u];
    c.weight[a] += f.weight[u];
    if (f.kind[u] > c.kind[a]) {
      c.kind[a] = f.kind[u];
      c.anchor[a] = f.anchor[u];
      c.tangent[a] = f.tangent[u];
    }
    if (f.principal_weight[u] > c.principal_weight[a]) {
      c.principal_weight[a] = f.principal_weight[u];
      c.principal[a] = f.principal[u];
    }
  }
  for (int a = 0; a < n; ++a) {
    c.p[a] /= c.weight[a];
    double l = c.normal[a].norm();
    c.normal[a] = l > 0 ? V3(c.normal[a] / l) : V3(0, 0, 1);
    for (V3* t : {&c.tangent[a], &c.principal[a]}) {
      *t -= c.normal[a] * c.normal[a].dot(*t);
      double lt = t->norm();
      *t = lt > 1e-9 ? V3(*t / lt) : V3::Zero();
    }
    if (c.kind[a] == 1 && c.tangent[a].norm() == 0) c.kind[a] = 0;
    if (c.principal[a].norm() == 0) c.principal_weight[a] = 0;
  }
  std::vector<std::uint64_t> pairs;
  for (int u = 0; u < f.n; ++u)
    for (int i = f.offsets[u]; i < f.offsets[u + 1]; ++i) {
      int a = parent[u], b = parent[f.adj[i]];
      if (a != b) pairs.push_back(half_key(a, b));
    }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  c.offsets.assign(n + 1, 0);
  for (auto k : pairs) c.offsets[(k >> 32) + 1]++;
  for (int a = 0; a < n; ++a) c.offsets[a + 1] += c.offsets[a];
  c.adj.resize(pairs.size());
  for (size_t i = 0; i < pairs.size(); ++i) c.adj[i] = int(pairs[i] & 0xffffffffu);
  return c;
}

struct Hierarchy {
  std::vector<Fields> levels;             // levels[0] is the dense mesh's
  std::vector<std::vector<int>> parents;  // parents[l][v]: v's vertex on level l + 1
};

void build_hierarchy(Hierarchy& h) {
  while (h.levels.size() < 40 && h.levels.back().n > 64) {
    std::vector<int> parent;
    Fields c = coarsen(h.levels.back(), parent);
    if (c.n > 0.9 * h.levels.back().n) break;
    h.parents.push_back(std::move(parent));
    h.levels.push_back(std::move(c));
  }
}

// Gauss-Seidel sweeps, forwards and backwards in turn: sweep(fields, vertex). While a vertex is
// smoothed, fetch(w) is called for each neighbour w of the vertex two ahead, to bring what the
// sweep will read of w into the cache (neighbours lie all over the dense mesh: ~15 % less time,
// the same arithmetic). On the threads the conversion may use, in waves of vertices that are no
// neighbours of each other, with the sequential sweeps' result bit for bit (core/util/wave_sweeps.h).
// Returns the threads used.
template <class Sweep, class Fetch, class Check>
int sweeps(Fields& fl, int iterations, Sweep&& sweep, Fetch&& fetch, Check&& check) {
  const int threads = std::min(loop_threads(), available_threads());
  return gauss_seidel_sweeps(
      fl.offsets, fl.adj, iterations, threads, [&](int v) { sweep(fl, v); }, fetch, check);
}

// Lattice columns at feature arcs tighter than the lattice (docs/remesh.md step 3). Where a chain
// turns by much within one lattice spacing s (a rim rounding a corner of the part in plan), the
// extraction keeps chain vertices of the arc's own (step 4's chain rule) wherever the lattice
// points fall, and a kept rim vertex with no lattice column under it leaves the side's vertices
// beside it stuck (step 6c). A chain vertex is tight when its radius of curvature (its turn over
// the mean of its two chain edges) is below kArcRadius x s; an arc is a run of tight vertices
// along a chain, joined across gaps up to s / 2 (a faceted arc's split edges). An arc that turns
// by kArcTurn or more, with a mean radius below kArcRadius x s, is pinned: the position field
// keeps the lattice point of its middle vertex (an arc shorter than s / 2) or of its two end
// vertices at the vertex itself, as at a corner, so that a lattice column runs down the side
// from there. Left alone: closed tight loops (a small hole's rim), arcs within s / 2 of a corner,
// and pins with no room for a row under them (below). Pins hold on the dense level only: carried
// to the coarser levels they shifted fandisk's lattice elsewhere (docs/remesh.md step 3).
constexpr double kArcRadius = 0.75;
constexpr double kArcRoom = 0.75;  // another feature this near (x s): no row under the arc
constexpr double kArcTurn = 1.17;  // radians (67 deg: a coarse chain edge turning more keeps a vertex, step 4)

// The chain neighbour of w other than prev (-1: the chain ends at w).
int chain_next(const Fields& fl, int prev, int w) {
  const auto& c = fl.chain[w];
  return c[0] == prev ? c[1] : c[0];
}

void pin_tight_arcs(Hierarchy& h) {
  Fields& fl = h.levels[0];
  const double s = fl.s;
  for (Fields& level : h.levels) {
    level.pinned.assign(level.n, 0);
    level.pin = level.anchor;
  }
  fl.arc_pins = 0;
  if (!fl.pin_arcs || fl.chain.size() != size_t(fl.n)) return;
  std::vector<double> turn(fl.n, 0.0);
  for (int v = 0; v < fl.n; ++v) {
    const auto& c = fl.chain[v];
    if (fl.kind[v] != 1 || c[0] < 0 || c[1] < 0) continue;
    V3 a = fl.p[v] - fl.p[c[0]], b = fl.p[c[1]] - fl.p[v];
    if (a.norm() > 0 && b.norm() > 0) turn[v] = std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0));
  }
  // Tight vertices: the chain's radius of curvature there (turn over the mean of the two chain
  // edges) below kArcRadius x s.
  std::vector<char> tight(fl.n, 0);
  for (int v = 0; v < fl.n; ++v) {
    const auto& c = fl.chain[v];
    if (turn[v] <= 0) continue;
    const double dual = 0.5 * ((fl.p[v] - fl.p[c[0]]).norm() + (fl.p[c[1]] - fl.p[v]).norm());
    tight[v] = turn[v] * kArcRadius * s > dual;
  }
  // Arcs: runs of tight vertices along a chain, joined across gaps up to s / 2 (a faceted arc
  // whose long edges were split has straight vertices between its facets' corners).
  std::vector<char> seen(fl.n, 0);
  std::vector<int> pins;
  for (int v = 0; v < fl.n; ++v) {
    if (!tight[v] || seen[v]) continue;
    seen[v] = 1;
    std::vector<int> ends(2, v);
    std::vector<double> reach(2, 0.0);
    std::vector<int> side[2];  // the chain vertices walked from v, each way, up to the arc's end
    double total = turn[v];
    bool closed = false, near_corner = false;
    for (int k = 0; k < 2 && !closed; ++k) {
      int prev = v, w = fl.chain[v][k];
      double len = 0, gap = 0;
      while (w >= 0) {
        const double e = (fl.p[w] - fl.p[prev]).norm();
        len += e;
        gap += e;
        if (w == v) {
          closed = true;
          break;
        }
        if (fl.kind[w] != 1) {
          if (gap <= 0.5 * s) near_corner = true;
          break;
        }
        if (tight[w]) {
          if (seen[w]) {  // met the run from the other side: a closed loop
            closed = true;
            break;
          }
          seen[w] = 1;
          total += turn[w];
          side[k].push_back(w);
          ends[k] = w;
          reach[k] = len;
          gap = 0;
        } else if (gap > 0.5 * s) {
          break;
        } else {
          side[k].push_back(w);
        }
        const int next = chain_next(fl, prev, w);
        prev = w;
        w = next;
      }
    }
    const double length = reach[0] + reach[1];
    if (closed || near_corner || total < kArcTurn || length > kArcRadius * s * total) continue;
    if (length < 0.5 * s) {  // a short arc: one column at its middle
      std::vector<int> run(side[0].rbegin(), side[0].rend());
      run.push_back(v);
      run.insert(run.end(), side[1].begin(), side[1].end());
      const int first = int(std::find(run.begin(), run.end(), ends[0]) - run.begin());
      const int last = int(std::find(run.begin(), run.end(), ends[1]) - run.begin());
      double at = 0, best_d = INFINITY;
      int best = v;
      for (int i = first; i <= last; ++i) {
        if (i > first) at += (fl.p[run[i]] - fl.p[run[i - 1]]).norm();
        if (std::abs(at - 0.5 * length) < best_d) best_d = std::abs(at - 0.5 * length), best = run[i];
      }
      pins.push_back(best);
    } else {
      pins.push_back(ends[0]);
      pins.push_back(ends[1]);
    }
  }
  // A pin with another feature curve within kArcRoom x s (a wall less than a row high under the
  // rim, the other rim of a thin plate), or a surface facing away from it there (the far side of
  // a thin part whose other outline is no feature): no row fits under it, so no column is made.
  std::vector<int> kept;
  for (int v : pins) {
    std::vector<int> own{v};  // the chain within 2 s of v, both ways
    for (int k = 0; k < 2; ++k) {
      int prev = v, w = fl.chain[v][k];
      double len = 0;
      while (w >= 0 && w != v && len < 2 * s) {
        len += (fl.p[w] - fl.p[prev]).norm();
        own.push_back(w);
        if (fl.kind[w] != 1) break;
        const int next = chain_next(fl, prev, w);
        prev = w;
        w = next;
      }
    }
    std::sort(own.begin(), own.end());
    bool room = true;
    for (int w = 0; w < fl.n && room; ++w) {
      if ((fl.p[w] - fl.p[v]).norm() >= kArcRoom * s) continue;
      if (fl.kind[w] != 0 && !std::binary_search(own.begin(), own.end(), w)) room = false;
      if (fl.normal[w].dot(fl.normal[v]) < -0.5) room = false;  // the far side of a thin part
    }
    if (room) kept.push_back(v);
  }
  pins = kept;
  fl.arc_pins = static_cast<int>(pins.size());
  for (int v : pins) {
    fl.pinned[v] = 1;
    fl.pin[v] = fl.p[v];
  }
}

// Both fields solved coarse to fine: initialised on the coarsest level, smoothed there, carried
// to each finer level (projected onto its tangent planes, constraints applied) and smoothed again.
// Returns the threads the finest (dense) level's sweeps used.
template <class Check>
int solve_fields(Hierarchy& h, int iterations, bool cross, Check&& check) {
  int threads = 1;
  int top = static_cast<int>(h.levels.size()) - 1;
  if (!cross) pin_tight_arcs(h);
  if (cross)
    init_cross_field(h.levels[top], check);
  else
    init_position_field(h.levels[top], check);
  for (int l = top; l >= 0; --l) {
    Fields& fl = h.levels[l];
    if (l < top) {
      const Fields& up = h.levels[l + 1];
      const std::vector<int>& parent = h.parents[l];
      if (cross) {
        fl.q.resize(fl.n);
        for (int v = 0; v < fl.n; ++v) {
          if (fl.kind[v] == 1 && fl.tangent[v].norm() > 0) {
            fl.q[v] = fl.tangent[v];
            continue;
          }
          V3 q = up.q[parent[v]] - fl.normal[v] * fl.normal[v].dot(up.q[parent[v]]);
          fl.q[v] = q.norm() > 1e-9 ? V3(q.normalized()) : any_perpendicular(fl.normal[v]);
        }
      } else {
        fl.o.resize(fl.n);
        for (int v = 0; v < fl.n; ++v) {
          const V3& o = up.o[parent[v]];
          fl.o[v] = o - fl.normal[v] * fl.normal[v].dot(o - fl.p[v]);
          constrain_position(fl, v);
        }
      }
    }
    if (cross) {
      std::vector<V3> nq(fl.n);
      for (int v = 0; v < fl.n; ++v) nq[v] = fl.normal[v].cross(fl.q[v]);
      threads = sweeps(
          fl, iterations, [&](Fields& f, int v) { smooth_cross_vertex(f, nq, v); },
          [&](int w) {
            __builtin_prefetch(&fl.q[w]);
            __builtin_prefetch(&nq[w]);
          },
          check);
    } else {
      PositionFrame frame = position_frame(fl);
      threads = sweeps(
          fl, iterations, [&](Fields& f, int v) { smooth_position_vertex(f, frame, v); },
          [&](int w) { __builtin_prefetch(&frame.node[w]); }, check);
    }
  }
  return threads;
}

V3 closest_on_segment(const V3& x, const V3& a, const V3& b) {
  V3 ab = b - a;
  double l = ab.squaredNorm();
  double t = l > 0 ? std::clamp((x - a).dot(ab) / l, 0.0, 1.0) : 0.0;
  return a + ab * t;
}

// Per dense vertex: its neighbours along the input's feature edges (`feature`: their edge_keys).
std::vector<std::vector<int>> chain_neighbours(const Fields& fl, const std::unordered_set<std::uint64_t>& feature) {
  const int n = static_cast<int>(fl.offsets.size()) - 1;
  std::vector<std::vector<int>> chain(n);
  for (int v = 0; v < n; ++v)
    for (int i = fl.offsets[v]; i < fl.offsets[v + 1]; ++i)
      if (feature.count(edge_key(v, fl.adj[i]))) chain[v].push_back(fl.adj[i]);
  return chain;
}

// The dense feature chain from `start` through its neighbour `first`, followed through vertices
// of exactly two chain neighbours until `stop(v)` holds for the last one (or the chain forks,
// ends, or has gone round as many steps as there are vertices): the vertices passed, in order.
template <class Stop>
std::vector<int> follow_chain(const std::vector<std::vector<int>>& chain, int start, int first, Stop&& stop) {
  std::vector<int> path{start, first};
  while (!stop(path.back()) && path.size() < chain.size()) {
    const int x = path.back();
    if (chain[x].size() != 2) break;
    path.push_back(chain[x][0] == path[path.size() - 2] ? chain[x][1] : chain[x][0]);
  }
  return path;
}

// --- cancelling the position field's dislocations (docs/remesh.md step 3b) ------------------
// Per dense edge u -> v the position field gives the lattice translation from u's lattice
// point to v's, in u's lattice frame (q_u, n_u x q_u) and units of s: x = (o_v - o_u) . (q_u,
// n_u x q_u) / s, rounded t = round(x), the residual r = x - t. Around a dense triangle whose
// cross field does not turn, the translations carried into one frame sum to zero unless the
// lattice has a dislocation there: a lattice row that ends (a stretched lattice: a torus's
// parallels are shorter inside than outside, a scan's bulges). The extraction turns each
// dislocation into a pair of extraordinary vertices, or, where the rounding is ambiguous, a
// knot of coarse vertices closer than the spacing that the fit folds. As QuadriFlow does with
// its flow, dislocations are cancelled in pairs: a unit of the sum is carried from its
// triangle across edges to the nearest triangle with the opposite sum, each edge crossed
// changing its translation by the unit (the dual path of least added |r|^2, found breadth first
// by cost), so that every triangle passed still sums to zero and the two ends do too. Then the
// lattice points near the changed edges are re-solved with the translations held (the
// lattice stretches to take up the row it lost or gained) and each vertex takes the point of
// that lattice nearest itself. Triangles within kDislocationFeatureReach x s of a feature take no
// part: near feature curves the chain rules of step 4 fix the lattice, and moving it there cost
// feature angles (fandisk's default cage: 4.5 -> 11 degrees at 0.5 s).
constexpr int kDislocationVisits = 4000;         // triangles a carry may search
constexpr double kDislocationFeatureReach = 1.5;  // x s
constexpr int kRestretchRings = 8;               // around the changed edges' vertices
constexpr int kRestretchIterations = 30;

using I2 = std::array<int, 2>;
// (x, y) turned by k quarter turns counter-clockwise: 1 gives (-y, x).
I2 rotate_turns(const I2& x, int k) {
  switch (((k % 4) + 4) % 4) {
    case 1: return {-x[1], x[0]};
    case 2: return {-x[0], -x[1]};
    case 3: return {x[1], -x[0]};
    default: return x;
  }
}

struct Translations {
  std::vector<I2> t;         // per adjacency entry i of v (neighbour adj[i]), in v's frame
  std::vector<int> changed;  // vertices of the edges whose translation was changed
  int before = 0, left = 0;  // dislocated triangles before and after the cancelling
};

class DislocationCanceller {
 public:
  DislocationCanceller(const Dense& d, const Fields& fl) : d_(d), fl_(fl) {
    nq_.resize(fl.n);
    for (int v = 0; v < fl.n; ++v) nq_[v] = fl.normal[v].cross(fl.q[v]);
    tr_.t.resize(fl.adj.size());
    x_.resize(fl.adj.size());
    for (int u = 0; u < fl.n; ++u)
      for (int i = fl.offsets[u]; i < fl.offsets[u + 1]; ++i) {
        const int v = fl.adj[i];
        const V3 dv = (fl.o[v] - fl.o[u]) / fl.s;
        x_[i] = {dv.dot(fl.q[u]), dv.dot(nq_[u])};
      }
    for (int u = 0; u < fl.n; ++u)  // rounded on u < v; v's entry the same translation seen from v
      for (int i = fl.offsets[u]; i < fl.offsets[u + 1]; ++i)
        if (u < fl.adj[i]) set(u, i, {int(round_half_away(x_[i][0])), int(round_half_away(x_[i][1]))});
    across_ = triangles_across(d.t);
  }

  Translations cancel() {
    const int nf = static_cast<int>(d_.t.size());
    curls_.assign(nf, I2{0, 0});
    closed_.assign(nf, 1);
    std::vector<int> charged;
    for (int f = 0; f < nf; ++f) {
      closed_[f] = curl(f, curls_[f]);
      if (closed_[f] && curls_[f] != I2{0, 0}) charged.push_back(f);
    }
    tr_.before = static_cast<int>(charged.size());
    blocked_ = near_features();
    for (int f = 0; f < nf; ++f) blocked_[f] = blocked_[f] || !closed_[f];
    for (int f : charged)
      for (int axis = 0; axis < 2 && !blocked_[f]; ++axis)
        while (curls_[f][axis] != 0) {
          I2 unit{0, 0};
          unit[axis] = curls_[f][axis] > 0 ? 1 : -1;
          if (!carry(f, unit)) break;
        }
    for (int f = 0; f < nf; ++f) tr_.left += closed_[f] && curls_[f] != I2{0, 0};
    return std::move(tr_);
  }

 private:
  int entry(int u, int v) const {
    auto b = fl_.adj.begin() + fl_.offsets[u], e = fl_.adj.begin() + fl_.offsets[u + 1];
    return static_cast<int>(std::lower_bound(b, e, v) - fl_.adj.begin());
  }
  // Entry i of u (to v) becomes t, and v's entry to u the same translation seen from v.
  void set(int u, int i, const I2& t) {
    const int v = fl_.adj[i];
    tr_.t[i] = t;
    const I2 back = rotate_turns(t, frame_turns(fl_, nq_, v, u));
    tr_.t[entry(v, u)] = {-back[0], -back[1]};
  }

  // The sum of the translations around triangle f in its first vertex's frame; false where the
  // cross field turns around it (a field singularity: the sum does not close).
  bool curl(int f, I2& c) const {
    const Tri& t = d_.t[f];
    const int k01 = frame_turns(fl_, nq_, t[0], t[1]), k02 = frame_turns(fl_, nq_, t[0], t[2]);
    const int k12 = frame_turns(fl_, nq_, t[1], t[2]);
    if (((k01 + k12 - k02) % 4 + 4) % 4 != 0) return false;
    const I2& a = tr_.t[entry(t[0], t[1])];
    const I2 b = rotate_turns(tr_.t[entry(t[1], t[2])], k01);
    const I2 e = rotate_turns(tr_.t[entry(t[2], t[0])], k02);
    c = {a[0] + b[0] + e[0], a[1] + b[1] + e[1]};
    return true;
  }

  // Triangles with a vertex within kDislocationFeatureReach x s of a feature vertex (along edges).
  std::vector<char> near_features() const {
    const double reach = kDislocationFeatureReach * fl_.s;
    std::vector<double> dist(fl_.n, INFINITY);
    using Item = std::pair<double, int>;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
    for (int v = 0; v < fl_.n; ++v)
      if (fl_.kind[v] != 0) dist[v] = 0, queue.push({0.0, v});
    while (!queue.empty()) {
      const auto [dv, v] = queue.top();
      queue.pop();
      if (dv > dist[v] || dv > reach) continue;
      for (int i = fl_.offsets[v]; i < fl_.offsets[v + 1]; ++i) {
        const int w = fl_.adj[i];
        const double nd = dv + (fl_.p[w] - fl_.p[v]).norm();
        if (nd < dist[w]) dist[w] = nd, queue.push({nd, w});
      }
    }
    std::vector<char> near(d_.t.size(), 0);
    for (size_t f = 0; f < d_.t.size(); ++f)
      for (int k = 0; k < 3; ++k) near[f] = near[f] || dist[d_.t[f][k]] < reach;
    return near;
  }

  // Carries the unit sum c (in f0's first vertex's frame) from f0 to the nearest triangle whose
  // sum has the opposite component, by the dual path of least cost; true if both shrank.
  bool carry(int f0, const I2& c) {
    struct Step {
      double cost;
      int f;
    };
    auto later = [](const Step& a, const Step& b) { return a.cost > b.cost || (a.cost == b.cost && a.f > b.f); };
    std::vector<Step> heap{{0.0, f0}};
    std::unordered_map<int, double> best{{f0, 0.0}};
    std::unordered_map<int, std::pair<int, int>> from;  // triangle -> (previous triangle, its edge crossed)
    std::unordered_map<int, I2> carried{{f0, c}};        // the unit in each reached triangle's frame
    int visits = 0, found = -1;
    while (!heap.empty() && visits < kDislocationVisits) {
      std::pop_heap(heap.begin(), heap.end(), later);
      const Step s = heap.back();
      heap.pop_back();
      if (s.cost > best[s.f]) continue;
      ++visits;
      const I2 cf = carried[s.f];
      if (s.f != f0 && curls_[s.f][0] * cf[0] + curls_[s.f][1] * cf[1] < 0) {
        found = s.f;
        break;
      }
      const Tri& t = d_.t[s.f];
      for (int k = 0; k < 3; ++k) {
        const int u = t[k], v = t[(k + 1) % 3];
        const int g = across_[s.f][k];
        if (g < 0 || d_.feature.count(edge_key(u, v)) || blocked_[g]) continue;
        // t(u -> v) - delta (u's frame) changes f's sum by -rotate(delta, k_au) = -cf and g's
        // (which runs v -> u) by +rotate(delta, k_bu): the unit moves on into g.
        const I2 delta = rotate_turns(cf, 4 - frame_turns(fl_, nq_, t[0], u));
        const int i = entry(u, v);
        const double r0 = x_[i][0] - tr_.t[i][0], r1 = x_[i][1] - tr_.t[i][1];
        const double added = 2 * (r0 * delta[0] + r1 * delta[1]) + delta[0] * delta[0] + delta[1] * delta[1];
        const double cost = s.cost + std::max(0.0, added) + 0.05;
        auto it = best.find(g);
        if (it != best.end() && it->second <= cost) continue;
        best[g] = cost;
        from[g] = {s.f, k};
        carried[g] = rotate_turns(delta, frame_turns(fl_, nq_, d_.t[g][0], u));
        heap.push_back({cost, g});
        std::push_heap(heap.begin(), heap.end(), later);
      }
    }
    if (found < 0) return false;
    std::vector<int> path{found};
    while (path.back() != f0) path.push_back(from[path.back()].first);
    std::vector<std::pair<int, I2>> undo;  // (entry, old translation) of both directions
    for (size_t i = 0; i + 1 < path.size(); ++i) {
      const int g = path[i], f = path[i + 1];
      const Tri& t = d_.t[f];
      const int k = from[g].second;
      const int u = t[k], v = t[(k + 1) % 3];
      const I2 delta = rotate_turns(carried[f], 4 - frame_turns(fl_, nq_, t[0], u));
      const int iu = entry(u, v), iv = entry(v, u);
      undo.push_back({iu, tr_.t[iu]});
      undo.push_back({iv, tr_.t[iv]});
      set(u, iu, {tr_.t[iu][0] - delta[0], tr_.t[iu][1] - delta[1]});
    }
    // Every triangle passed keeps its sum, the two ends' shrink (else undone: the frames
    // disagreed along the path).
    bool ok = true;
    std::vector<I2> now(path.size());
    for (size_t i = 0; i < path.size() && ok; ++i)
      ok = curl(path[i], now[i]) && (path[i] == f0 || path[i] == found || now[i] == curls_[path[i]]);
    auto size = [](const I2& a) { return std::abs(a[0]) + std::abs(a[1]); };
    if (ok && size(now.back()) + size(now.front()) >= size(curls_[f0]) + size(curls_[found])) ok = false;
    if (!ok) {
      for (auto it = undo.rbegin(); it != undo.rend(); ++it) tr_.t[it->first] = it->second;
      return false;
    }
    curls_[f0] = now.back();
    curls_[found] = now.front();
    for (size_t i = 0; i + 1 < path.size(); ++i) {
      const Tri& t = d_.t[path[i + 1]];
      const int k = from[path[i]].second;
      tr_.changed.push_back(t[k]);
      tr_.changed.push_back(t[(k + 1) % 3]);
    }
    return true;
  }

  const Dense& d_;
  const Fields& fl_;
  std::vector<V3> nq_;
  std::vector<std::array<double, 2>> x_;  // the unrounded translation per adjacency entry
  Translations tr_;
  std::vector<I2> curls_;
  std::vector<char> closed_, blocked_;
  std::vector<std::array<int, 3>> across_;  // per triangle: the triangle across its edge k (-1: none)
};

// The position field re-solved near the changed edges (kRestretchRings around their vertices)
// with the translations held: each vertex's lattice point the mean of where its neighbours'
// lattice points and the edges' translations put it, on its tangent plane (feature vertices on
// their chain's line; corners and pins held), Gauss-Seidel sweeps both ways; then each vertex
// there takes the point of the stretched lattice nearest itself.
void restretch_positions(Fields& fl, const Translations& tr) {
  std::vector<char> active(fl.n, 0);
  std::vector<int> region, front;
  for (int v : tr.changed)
    if (!active[v]) active[v] = 1, front.push_back(v);
  region = front;
  for (int r = 0; r < kRestretchRings; ++r) {
    std::vector<int> next;
    for (int v : front)
      for (int i = fl.offsets[v]; i < fl.offsets[v + 1]; ++i)
        if (!active[fl.adj[i]]) active[fl.adj[i]] = 1, next.push_back(fl.adj[i]);
    region.insert(region.end(), next.begin(), next.end());
    front.swap(next);
  }
  std::sort(region.begin(), region.end());
  for (int it = 0; it < kRestretchIterations; ++it)
    for (int pass = 0; pass < 2; ++pass)
      for (size_t k = 0; k < region.size(); ++k) {
        const int v = pass == 0 ? region[k] : region[region.size() - 1 - k];
        if (fl.kind[v] == 2 || fl.pinned[v] || fl.offsets[v + 1] == fl.offsets[v]) continue;
        const V3 t = fl.normal[v].cross(fl.q[v]);
        V3 sum = V3::Zero();
        for (int i = fl.offsets[v]; i < fl.offsets[v + 1]; ++i)
          sum += fl.o[fl.adj[i]] - fl.s * (tr.t[i][0] * fl.q[v] + tr.t[i][1] * t);
        V3 o = sum / double(fl.offsets[v + 1] - fl.offsets[v]);
        o -= fl.normal[v] * fl.normal[v].dot(o - fl.p[v]);
        fl.o[v] = on_chain_line(fl, v, o);
      }
  for (int v : region) constrain_position(fl, v);
}

// --- extraction by edge collapses -------------------------------------------------------------
constexpr double kTurnedOver = -0.3;  // cos 107 deg: a face turned over (Collapser::turned_over, docs/remesh.md step 4)

struct Collapser {
  const std::vector<V3>& p;
  const Fields& fl;
  std::vector<Tri> f;
  std::vector<char> face_alive, alive;
  std::vector<std::vector<int>> vf;
  std::unordered_set<std::uint64_t> feature;
  std::vector<double> dist;
  std::vector<int> scratch_u, scratch_v, scratch_common, scratch_opposite;
  std::vector<std::vector<int>> chain;  // per dense vertex: its neighbours along the input's feature edges
  double chain_sag = 0;                 // see chord_follows_chain
  // Change stamps: `epoch` counts the collapses made; touched[w] is the epoch of the last collapse
  // x -> y that changed anything can_collapse reads around w (w = x or a neighbour of x: their
  // faces, their lists of faces, their feature edges). can_collapse(u, v) reads only the faces of
  // u and v, their vertices and the feature edges of u; for a vertex on no feature (no chain walk)
  // its answer cannot change while neither u nor v is touched (collapse_to_lattice skips it).
  long epoch = 0;
  std::vector<long> touched;
  // Tight closed loops (anchor_tight_loops): their chosen vertices never collapse; the loops'
  // other vertices collapse along the loop into them at the end (collapse_to_lattice's stage 4).
  std::vector<char> anchor;
  std::vector<std::vector<int>> loops;

  Collapser(const Dense& d, const Fields& fields, double max_chain_sag)
      : p(d.p), fl(fields), f(d.t), feature(d.feature), chain_sag(max_chain_sag) {
    int n = static_cast<int>(p.size());
    face_alive.assign(f.size(), 1);
    alive.assign(n, 1);
    touched.assign(n, 0);
    vf.assign(n, {});
    for (size_t i = 0; i < f.size(); ++i)
      for (int v : f[i]) vf[v].push_back(int(i));
    dist.resize(n);
    for (int v = 0; v < n; ++v) dist[v] = (p[v] - fl.o[v]).norm();
    chain = chain_neighbours(fl, feature);
  }

  // Whether feature vertex u may collapse into its chain neighbour v without the coarse edge
  // that results, v - w (w: u's other coarse chain neighbour), cutting across a curved feature:
  // every dense chain vertex between v and w must lie within chain_sag x |vw| of the chord vw.
  // A feature arc tighter than the lattice spacing (a hole's rim, a rounded corner of a rim)
  // keeps chain vertices on it, so that the cage's crease curve can follow it.
  bool chord_follows_chain(int u, int v) const {
    if (chain_sag <= 0) return true;
    int w = -1;
    for (int g : vf[u])
      for (int x : f[g])
        if (x != u && x != v && feature.count(edge_key(u, x))) w = x;
    if (w < 0) return true;
    for (int first : chain[v]) {
      const std::vector<int> path = follow_chain(chain, v, first, [&](int x) { return alive[x] && x != u; });
      if (path.back() != w || std::find(path.begin(), path.end(), u) == path.end()) continue;
      const V3 a = p[v], b = p[w];
      const double limit = chain_sag * (b - a).norm();
      for (int x : path)
        if ((closest_on_segment(p[x], a, b) - p[x]).norm() > limit) return false;
      return true;
    }
    return true;
  }

  bool anchored(int v) const { return !anchor.empty() && anchor[v]; }
  bool higher(int a, int b) const {  // priority of a above b
    if (fl.kind[a] != fl.kind[b]) return fl.kind[a] > fl.kind[b];
    if (dist[a] != dist[b]) return dist[a] < dist[b];
    return a < b;
  }
  void neighbours(int u, std::vector<int>& out) const {
    out.clear();
    for (int fi : vf[u])
      for (int w : f[fi])
        if (w != u) out.push_back(w);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }
  static bool contains(const Tri& t, int v) { return t[0] == v || t[1] == v || t[2] == v; }
  int faces_with(int a, int b, int* out) const {
    int count = 0;
    for (int fi : vf[a])
      if (contains(f[fi], b)) {
        if (count < 2) out[count] = fi;
        ++count;
      }
    return count;
  }
  bool is_feature(int a, int b) const { return feature.count(edge_key(a, b)) != 0; }
  // Whether a face has the vertices a and b (searched in the shorter of their face lists).
  bool share_face(int a, int b) const {
    if (vf[b].size() < vf[a].size()) std::swap(a, b);
    for (int fi : vf[a])
      if (contains(f[fi], b)) return true;
    return false;
  }
  // Whether a face has the vertices a, b and c (the same: the shortest list).
  bool face_of(int a, int b, int c) const {
    if (vf[b].size() < vf[a].size()) std::swap(a, b);
    if (vf[c].size() < vf[a].size()) std::swap(a, c);
    for (int fi : vf[a])
      if (contains(f[fi], b) && contains(f[fi], c)) return true;
    return false;
  }
  bool boundary_vertex(int u, const std::vector<int>& nu) const {
    int tmp[2];
    for (int w : nu)
      if (faces_with(u, w, tmp) == 1) return true;
    return false;
  }
  // Whether a face of (unnormalized) normal n and vertices a, b, c, none on a feature, faces
  // away from the surface: more than ~107 deg from the sum of its vertices' normals. The turn
  // test of can_collapse bounds each collapse's turn of a face, not a run of them: on bob's limit
  // scan (668 quads) two coarse triangles had turned over (-0.72, -0.84), a knot of folded cage
  // faces whose limit surface crossed itself. A face with a vertex on a feature is left to the
  // turn test: its vertices' normals mix the sides of a sharp edge.
  bool turned_over(const V3& n, int a, int b, int c) const {
    if (fl.kind[a] != 0 || fl.kind[b] != 0 || fl.kind[c] != 0) return false;
    const V3 surface = fl.normal[a] + fl.normal[b] + fl.normal[c];
    return n.dot(surface) < kTurnedOver * n.norm() * surface.norm();
  }

  V3 face_normal(const Tri& t, int from, int to) const {
    auto at = [&](int k) -> const V3& { return p[t[k] == from ? to : t[k]]; };
    return (at(1) - at(0)).cross(at(2) - at(0));
  }

  // `chain_refused`: set when only the chain walk (chord_follows_chain, the one test that reads
  // beyond u, v and their faces) refused: the tests are independent, so their order is free,
  // and the walk comes last.
  bool can_collapse(int u, int v, bool* chain_refused = nullptr) {
    if (chain_refused) *chain_refused = false;
    if (fl.kind[u] == 2 || anchored(u)) return false;
    if (fl.kind[u] == 1 && !is_feature(u, v)) return false;
    int shared[2];
    int count = faces_with(u, v, shared);
    if (count == 0 || count > 2) return false;
    std::vector<int>& nu = scratch_u;
    std::vector<int>& nv = scratch_v;
    neighbours(u, nu);
    if (fl.kind[u] == 1)
      for (int w : nu)
        if (w != v && is_feature(u, w) && is_feature(v, w)) return false;
    // the common neighbours of u and v (u's neighbours, sorted, that share a face with v; a
    // cluster's centre has many faces: its own list is neither built nor sorted here)
    std::vector<int>& common = scratch_common;
    std::vector<int>& opposite = scratch_opposite;
    common.clear();
    opposite.clear();
    for (int w : nu)
      if (w != v && share_face(w, v)) common.push_back(w);
    for (int k = 0; k < count; ++k)
      for (int w : f[shared[k]])
        if (w != u && w != v) opposite.push_back(w);
    std::sort(opposite.begin(), opposite.end());
    if (common != opposite) return false;
    if (count == 2 && boundary_vertex(u, nu) && (neighbours(v, nv), boundary_vertex(v, nv))) return false;
    for (int fi : vf[u]) {
      if (fi == shared[0] || (count == 2 && fi == shared[1])) continue;
      V3 before = face_normal(f[fi], -1, -1), after = face_normal(f[fi], u, v);
      double lb = before.norm(), la = after.norm();
      if (la <= 1e-12 * lb || before.dot(after) <= 0.2 * la * lb) return false;
      int a = -1, b = -1;
      for (int w : f[fi])
        if (w != u) (a < 0 ? a : b) = w;
      if (turned_over(after, v, a, b)) return false;
      if (face_of(v, a, b)) return false;
    }
    if (fl.kind[u] == 1 && !chord_follows_chain(u, v)) {
      if (chain_refused) *chain_refused = true;
      return false;
    }
    return true;
  }

  void collapse(int u, int v) {
    std::vector<int> nu;
    neighbours(u, nu);
    ++epoch;
    touched[u] = epoch;
    for (int w : nu) touched[w] = epoch;  // v among them
    std::vector<int> faces = vf[u];
    for (int fi : faces) {
      if (contains(f[fi], v)) {
        face_alive[fi] = 0;
        for (int w : f[fi])
          if (w != u) vf[w].erase(std::find(vf[w].begin(), vf[w].end(), fi));
      } else {
        for (int& w : f[fi])
          if (w == u) w = v;
        vf[v].push_back(fi);
      }
    }
    vf[u].clear();
    for (int w : nu)
      if (feature.erase(edge_key(u, w)) && w != v) feature.insert(edge_key(v, w));
    alive[u] = 0;
  }
};

double quad_quality(const V3 c[4]) {
  V3 normal = (c[2] - c[0]).cross(c[3] - c[1]);
  if (normal.norm() <= 0) return -1;
  normal.normalize();
  double worst = 1;
  for (int k = 0; k < 4; ++k) {
    V3 a = c[(k + 1) % 4] - c[k], b = c[(k + 3) % 4] - c[k];
    double la = a.norm(), lb = b.norm();
    if (la <= 0 || lb <= 0) return -1;
    worst = std::min(worst, a.cross(b).dot(normal) / (la * lb));
  }
  return worst;
}

// Closest point on triangle abc to x.
V3 closest_on_triangle(const V3& x, const V3& a, const V3& b, const V3& c) {
  V3 ab = b - a, ac = c - a, ax = x - a;
  double d1 = ab.dot(ax), d2 = ac.dot(ax);
  if (d1 <= 0 && d2 <= 0) return a;
  V3 bx = x - b;
  double d3 = ab.dot(bx), d4 = ac.dot(bx);
  if (d3 >= 0 && d4 <= d3) return b;
  double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  V3 cx = x - c;
  double d5 = ab.dot(cx), d6 = ac.dot(cx);
  if (d6 >= 0 && d5 <= d6) return c;
  double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  double denom = 1 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

// Points of the split (edge midpoints, polygon centres) placed on the dense mesh.
struct Projector {
  const Dense& d;
  const Fields& fl;
  std::vector<int> vf_offsets, vf;
  std::vector<std::vector<int>> chain;  // per dense vertex: its neighbours along feature edges
  std::vector<V3> face_normal;          // unit normals of the dense triangles
  double longest_edge = 0;
  std::vector<std::array<int, 3>> across;  // per triangle: the triangle across its edge k (-1: none)
  mutable std::vector<int> mark;        // search stamps (per triangle)
  mutable int stamp = 0;

  Projector(const Dense& dense, const Fields& fields) : d(dense), fl(fields) {
    int n = static_cast<int>(d.p.size());
    vf_offsets.assign(n + 1, 0);
    for (const Tri& t : d.t)
      for (int v : t) vf_offsets[v + 1]++;
    for (int v = 0; v < n; ++v) vf_offsets[v + 1] += vf_offsets[v];
    vf.resize(vf_offsets[n]);
    std::vector<int> fill(vf_offsets.begin(), vf_offsets.end() - 1);
    for (size_t i = 0; i < d.t.size(); ++i)
      for (int v : d.t[i]) vf[fill[v]++] = int(i);
    chain = chain_neighbours(fl, d.feature);
    for (int v = 0; v < n; ++v)
      for (int i = fl.offsets[v]; i < fl.offsets[v + 1]; ++i)
        longest_edge = std::max(longest_edge, (d.p[v] - d.p[fl.adj[i]]).norm());
    for (const Tri& t : d.t) {
      V3 fn = (d.p[t[1]] - d.p[t[0]]).cross(d.p[t[2]] - d.p[t[0]]);
      double l = fn.norm();
      face_normal.push_back(l > 0 ? V3(fn / l) : V3::Zero());
    }
    mark.assign(d.t.size(), -1);
    across = triangles_across(d.t);
  }

  // The closest point to x on the part of the dense mesh that a coarse polygon (or edge) with
  // the dense vertices `corners` covers: the triangles reached from the triangles around its
  // corners that are on no feature (or, when all are, from the triangle around them that faces
  // most like `normal`) across edges that are no feature edges, within the distance of its
  // farthest corner from x (plus the longest edge); among them those facing within 90 degrees
  // of `normal` first. Coarse polygons never cross a feature chain (their edges follow the
  // chains), so the point stays on the polygon's own face of the part: a greedy walk towards x,
  // or the closest point anywhere, can land across a sharp edge (a wall quad's centre on the
  // bottom beside it when a coarse feature edge cuts across a tight arc of the rim).
  V3 project(const V3& x, const std::vector<int>& corners, const V3& normal) const {
    double reach = 0;
    for (int c : corners) reach = std::max(reach, (d.p[c] - x).norm());
    reach += longest_edge;
    ++stamp;
    std::vector<int> queue;
    for (int c : corners)
      if (fl.kind[c] == 0)
        for (int i = vf_offsets[c]; i < vf_offsets[c + 1]; ++i)
          if (mark[vf[i]] != stamp) mark[vf[i]] = stamp, queue.push_back(vf[i]);
    if (queue.empty()) {
      int best = -1;
      double bd = -INFINITY;
      for (int c : corners)
        for (int i = vf_offsets[c]; i < vf_offsets[c + 1]; ++i)
          if (face_normal[vf[i]].dot(normal) > bd) bd = face_normal[vf[i]].dot(normal), best = vf[i];
      if (best < 0) return d.p[corners[0]];
      mark[best] = stamp;
      queue.push_back(best);
    }
    V3 best[2] = {d.p[corners[0]], d.p[corners[0]]};  // facing `normal`, any
    double bd[2] = {INFINITY, INFINITY};
    for (size_t head = 0; head < queue.size(); ++head) {
      const int f = queue[head];
      const Tri& t = d.t[f];
      const V3 c = closest_on_triangle(x, d.p[t[0]], d.p[t[1]], d.p[t[2]]);
      const double dc = (c - x).squaredNorm();
      for (int k = 0; k < 2; ++k)
        if ((k == 1 || face_normal[f].dot(normal) > 0) && dc < bd[k]) bd[k] = dc, best[k] = c;
      for (int k = 0; k < 3; ++k) {
        const int g = across[f][k];
        if (g < 0 || mark[g] == stamp || d.feature.count(edge_key(t[k], t[(k + 1) % 3]))) continue;
        const int w = d.t[g][0] + d.t[g][1] + d.t[g][2] - t[k] - t[(k + 1) % 3];
        if ((d.p[w] - x).norm() > reach && (d.p[t[k]] - x).norm() > reach && (d.p[t[(k + 1) % 3]] - x).norm() > reach)
          continue;
        mark[g] = stamp;
        queue.push_back(g);
      }
    }
    return bd[0] < INFINITY ? best[0] : best[1];
  }

  // The point halfway (by length) along the feature chain of the dense mesh from dense vertex a
  // to dense vertex b, where `is_end(v)` marks the chain's vertices kept by the extraction (the
  // chain from a towards b meets none before b); a's own position if no such chain is found.
  template <class IsEnd>
  bool chain_middle(int a, int b, IsEnd&& is_end, V3& out) const {
    for (int first : chain[a]) {
      const std::vector<int> path = follow_chain(chain, a, first, is_end);
      if (path.back() != b || !is_end(b)) continue;
      double total = 0;
      for (size_t i = 1; i < path.size(); ++i) total += (d.p[path[i]] - d.p[path[i - 1]]).norm();
      double run = 0;
      for (size_t i = 1; i < path.size(); ++i) {
        const double l = (d.p[path[i]] - d.p[path[i - 1]]).norm();
        if (run + l >= 0.5 * total && l > 0) {
          out = d.p[path[i - 1]] + (d.p[path[i]] - d.p[path[i - 1]]) * ((0.5 * total - run) / l);
          return true;
        }
        run += l;
      }
    }
    return false;
  }

  // The old projection onto feature edges (a greedy walk along them, then the closest point on
  // the feature edges around the vertex reached): the fallback of chain_middle.
  V3 project_on_feature(const V3& x, int start) const {
    int v = start;
    for (int step = 0; step < 100000; ++step) {
      int best = v;
      double bd = (d.p[v] - x).squaredNorm();
      for (int w : chain[v]) {
        double dw = (d.p[w] - x).squaredNorm();
        if (dw < bd) bd = dw, best = w;
      }
      if (best == v) break;
      v = best;
    }
    V3 result = d.p[v];
    double bd = (result - x).squaredNorm();
    for (int w : chain[v]) {
      V3 c = closest_on_segment(x, d.p[v], d.p[w]);
      if ((c - x).squaredNorm() < bd) bd = (c - x).squaredNorm(), result = c;
    }
    return result;
  }
};


// The mesh's polygons as fans of triangles from their first corners (`polygon_of`, if given: each
// triangle's polygon).
std::vector<Tri> fan_triangles(const MeshInput& mesh, std::vector<int>* polygon_of = nullptr) {
  std::vector<Tri> t;
  int begin = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const int size = mesh.face_sizes[f];
    for (int k = 1; k + 1 < size; ++k) {
      t.push_back({mesh.face_indices[begin], mesh.face_indices[begin + k], mesh.face_indices[begin + k + 1]});
      if (polygon_of) polygon_of->push_back(f);
    }
    begin += size;
  }
  return t;
}

// The input's polygons fan-triangulated, with its features; `area` its area.
Dense make_dense(const MeshInput& mesh, const FeatureSet& features, double& area) {
  Dense d;
  for (const auto& x : mesh.positions) d.p.push_back(V3(x[0], x[1], x[2]));
  d.corner.assign(mesh.num_vertices(), 0);
  for (int c : features.corners) d.corner[c] = 1;
  d.dart.assign(mesh.num_vertices(), 0);
  for (int c : features.darts) d.dart[c] = 1;
  for (const auto& e : features.edges) d.feature.insert(edge_key(e[0], e[1]));
  d.t = fan_triangles(mesh);
  area = 0;
  for (const Tri& t : d.t) area += 0.5 * (d.p[t[1]] - d.p[t[0]]).cross(d.p[t[2]] - d.p[t[0]]).norm();
  return d;
}

// Tight closed loops (docs/remesh.md step 4, "Tight loops"). A closed feature loop without
// corners whose mean radius is below kArcRadius x s (a small hole's rim, the rims of its
// counterbore) lies within one or two lattice cells: the lattice cannot say which of its chain
// vertices to keep, the collapses keep whichever the chain rule lets stay, and the rims of one
// hole come out with different counts (featuretype.STL: 14, 16 and 18 on the three rims of one
// counterbored hole), so the strips between them cannot pair into quads.
struct TightLoop {
  std::vector<int> v;  // its dense chain vertices, in order
  V3 centroid, normal;
  double radius = 0;  // mean: length / 2 pi
  int group = -1;     // concentric loops share a group (-1: none)
};

std::vector<TightLoop> find_tight_loops(const Fields& fl, double s) {
  std::vector<TightLoop> loops;
  if (fl.chain.size() != size_t(fl.n)) return loops;
  std::vector<char> seen(fl.n, 0);
  for (int v = 0; v < fl.n; ++v) {
    if (seen[v] || fl.kind[v] != 1 || fl.chain[v][0] < 0 || fl.chain[v][1] < 0) continue;
    TightLoop loop;
    loop.v.push_back(v);
    seen[v] = 1;
    int prev = v, w = fl.chain[v][1];
    while (w >= 0 && w != v && fl.kind[w] == 1 && !seen[w]) {
      seen[w] = 1;
      loop.v.push_back(w);
      const int next = chain_next(fl, prev, w);
      prev = w;
      w = next;
    }
    const int m = static_cast<int>(loop.v.size());
    if (w != v || m < 3) continue;  // open, or through a corner
    double length = 0;
    V3 area = V3::Zero(), centroid = V3::Zero();
    for (int i = 0; i < m; ++i) {
      const V3 &a = fl.p[loop.v[i]], &b = fl.p[loop.v[(i + 1) % m]];
      const double e = (b - a).norm();
      length += e;
      centroid += 0.5 * e * (a + b);
      area += a.cross(b);
    }
    if (!(length > 0) || length >= 2 * kPi * kArcRadius * s || !(area.norm() > 0)) continue;
    loop.centroid = centroid / length;
    loop.normal = area.normalized();  // (its sign is never read: groups compare |n . n'|)
    loop.radius = length / (2 * kPi);
    loops.push_back(std::move(loop));
  }
  // Concentric loops with no room for a lattice row between them (the strip a wall or an annulus
  // narrower than kArcRoom x s): parallel planes (within 10 degrees), centroids on one axis
  // (within a quarter of the smaller radius), the circles of their mean radii closer than
  // kArcRoom x s. Across a wider strip the lattice keeps rows of its own, which anchors would fight.
  std::vector<int> parent(loops.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (size_t a = 0; a < loops.size(); ++a)
    for (size_t b = a + 1; b < loops.size(); ++b) {
      const TightLoop &la = loops[a], &lb = loops[b];
      const V3 d = lb.centroid - la.centroid;
      const double along = la.normal.dot(d);
      if (std::abs(la.normal.dot(lb.normal)) < std::cos(10 * kPi / 180) ||
          std::hypot(along, la.radius - lb.radius) > kArcRoom * s ||
          (d - along * la.normal).norm() > 0.25 * std::min(la.radius, lb.radius))
        continue;
      parent[find_root(parent, int(a))] = find_root(parent, int(b));
    }
  std::vector<int> size(loops.size(), 0);
  for (size_t a = 0; a < loops.size(); ++a) ++size[find_root(parent, int(a))];
  for (size_t a = 0; a < loops.size(); ++a) {
    const int r = find_root(parent, int(a));
    if (size[r] > 1) loops[a].group = r;
  }
  return loops;
}

// Anchors for each group of concentric tight loops: the loop on which a first extraction
// (`kept`: alive after it) kept the fewest vertices is the group's reference; its kept vertices
// are its anchors, and every other loop of the group gets as anchors its chain vertices nearest
// the reference's angles (round each loop's own centroid, in a frame fixed by the reference's
// plane): one vertex above the other on every rim. Anchors never collapse; the loops' other
// vertices collapse along them into anchors after the lattice's stages (collapse_to_lattice's
// stage 4). A loop alone is left to the lattice. Returns the loops anchored.
int anchor_tight_loops(const Fields& fl, const std::vector<TightLoop>& loops, const std::vector<char>& kept,
                       Collapser& col) {
  col.anchor.assign(fl.n, 0);
  col.loops.clear();
  std::vector<int> reference(loops.size(), -1), kept_count(loops.size(), 0);
  for (size_t a = 0; a < loops.size(); ++a) {
    for (int v : loops[a].v) kept_count[a] += kept[v] != 0;
    const int g = loops[a].group;
    if (g < 0) continue;
    int& r = reference[g];
    if (r < 0 || kept_count[a] < kept_count[r] ||
        (kept_count[a] == kept_count[r] && loops[a].radius > loops[r].radius))
      r = static_cast<int>(a);
  }
  for (size_t a = 0; a < loops.size(); ++a) {
    const int g = loops[a].group;
    if (g < 0 || reference[g] < 0 || kept_count[reference[g]] < 3) continue;
    const TightLoop& ref = loops[reference[g]];
    const V3 e1 = any_perpendicular(ref.normal), e2 = ref.normal.cross(e1);  // one frame for the group
    auto angle = [&](const TightLoop& l, int v) {
      const V3 d = fl.p[v] - l.centroid;
      return std::atan2(d.dot(e2), d.dot(e1));
    };
    if (int(a) == reference[g]) {
      for (int v : ref.v)
        if (kept[v]) col.anchor[v] = 1;
    } else {
      for (int r : ref.v) {
        if (!kept[r]) continue;
        const double target = angle(ref, r);
        int best = -1;
        double best_d = INFINITY;
        for (int v : loops[a].v) {
          const double dd = std::abs(std::remainder(angle(loops[a], v) - target, 2 * kPi));
          if (dd < best_d) best_d = dd, best = v;
        }
        col.anchor[best] = 1;
      }
    }
    col.loops.push_back(loops[a].v);
  }
  return static_cast<int>(col.loops.size());
}

// Collapses every edge whose ends share a lattice point (link condition, features kept).
// Clusters: vertices joined by edges whose ends share a lattice point (feature vertices only
// along their chains); each grows from its centre, the vertex of highest priority, by collapsing
// its neighbours into it ring by ring; then any vertex into a same-point neighbour of higher priority.
template <class Check>
void collapse_to_lattice(const Dense& d, const Fields& fl, double s, bool merge_knots, Collapser& col, Check&& check) {
  auto same_point = [&](int u, int v) { return (fl.o[u] - fl.o[v]).norm() < 0.5 * s; };
  std::vector<int> cluster(fl.n);
  std::iota(cluster.begin(), cluster.end(), 0);
  for (int u = 0; u < fl.n; ++u)
    for (int i = fl.offsets[u]; i < fl.offsets[u + 1]; ++i) {
      int v = fl.adj[i];
      if (v < u || !same_point(u, v)) continue;
      bool fu = fl.kind[u] != 0, fv = fl.kind[v] != 0;
      if (fu && fv && !d.feature.count(edge_key(u, v))) continue;
      cluster[find_root(cluster, u)] = find_root(cluster, v);
    }
  std::vector<int> centre_of(fl.n, -1);
  for (int u = 0; u < fl.n; ++u) {
    int r = find_root(cluster, u);
    if (centre_of[r] < 0 || col.higher(u, centre_of[r])) centre_of[r] = u;
  }
  // The vertices that are not their cluster's centre, in index order (the passes' order): a
  // centre never moves in these passes and a collapsed vertex never comes back, so the others
  // are never visited. A vertex whose last visit made no collapse (refused by a test other than
  // the chain walk), and around which (it or its centre) nothing has been touched since, would
  // answer the same: skipped
  // (the same collapses in the same order as visiting every vertex every pass).
  std::vector<int> centre(fl.n), pending;
  for (int u = 0; u < fl.n; ++u) {
    centre[u] = centre_of[find_root(cluster, u)];
    if (centre[u] != u) pending.push_back(u);
  }
  std::vector<long> visited(fl.n, -1);  // epoch of the last visit that made no collapse
  auto unchanged = [&](int u, int c) {
    return visited[u] >= 0 && col.touched[u] <= visited[u] && col.touched[c] <= visited[u];
  };
  for (int pass = 0; pass < 200; ++pass) {
    int changed = 0;
    size_t kept = 0;
    for (size_t i = 0; i < pending.size(); ++i) {
      const int u = pending[i];
      if (!col.alive[u]) continue;
      pending[kept++] = u;
      const int c = centre[u];
      if (unchanged(u, c)) continue;
      int tmp[2];
      bool chain_refused = false;
      if (!col.vf[u].empty() && col.faces_with(u, c, tmp) != 0 && col.can_collapse(u, c, &chain_refused)) {
        col.collapse(u, c);
        ++changed;
      } else {
        visited[u] = chain_refused ? -1 : col.epoch;  // the chain walk reads farther: asked again
      }
    }
    pending.resize(kept);
    check(0.7 + 0.1 * std::min(1.0, pass / 10.0));
    if (changed == 0) break;
  }
  // The same skip in the second stage: a vertex none of whose faces' vertices has been touched
  // since its last visit without a collapse (its neighbours, their faces and its candidates are
  // as they were), unless the chain walk refused one of its candidates.
  std::fill(visited.begin(), visited.end(), -1);
  auto quiet = [&](int u) {
    if (visited[u] < 0 || col.touched[u] > visited[u]) return false;
    for (int fi : col.vf[u])
      for (int w : col.f[fi])
        if (col.touched[w] > visited[u]) return false;
    return true;
  };
  std::vector<int> nu, cands;
  for (int pass = 0; pass < 200; ++pass) {
    int changed = 0;
    for (int u = 0; u < fl.n; ++u) {
      if (!col.alive[u] || fl.kind[u] == 2 || col.vf[u].empty()) continue;
      if (quiet(u)) continue;
      visited[u] = col.epoch;  // (a collapse below removes u: never visited again)
      col.neighbours(u, nu);
      cands.clear();
      for (int v : nu)
        if (col.higher(v, u) && (fl.o[u] - fl.o[v]).norm() < 0.5 * s) cands.push_back(v);
      std::sort(cands.begin(), cands.end(), [&](int a, int b) { return col.higher(a, b); });
      for (int v : cands) {
        bool chain_refused = false;
        if (col.can_collapse(u, v, &chain_refused)) {
          col.collapse(u, v);
          ++changed;
          break;
        }
        if (chain_refused) visited[u] = -1;
      }
    }
    check(0.7 + 0.2 * std::min(1.0, pass / 10.0));
    if (changed == 0) break;
  }
  // Stage 3 (merge_knots, with cancel_dislocations): a free vertex, away from features, still
  // beside a same-point neighbour (a knot: neither could collapse into its centre or a
  // neighbour of higher priority) takes that neighbour in, the neighbour of lowest priority
  // first, whatever their priorities (bob's limit scan: of the 38 same-point pairs left, 13
  // refused by the link condition and 11 by a face turning over one way round, 14 collapsible
  // the other way).
  for (int pass = 0; merge_knots && pass < 20; ++pass) {
    int changed = 0;
    for (int u = 0; u < fl.n; ++u) {
      if (!col.alive[u] || col.vf[u].empty() || fl.kind[u] != 0) continue;
      col.neighbours(u, nu);
      cands.clear();
      bool by_feature = false;
      for (int v : nu) by_feature = by_feature || fl.kind[v] != 0;
      if (by_feature) continue;
      for (int v : nu)
        if (same_point(u, v)) cands.push_back(v);
      std::sort(cands.begin(), cands.end(), [&](int a, int b) { return col.higher(b, a); });
      for (int v : cands)
        if (col.can_collapse(v, u)) {
          col.collapse(v, u);
          ++changed;
          break;
        }
    }
    check(0.9);
    if (changed == 0) break;
  }
  // Stage 4 (anchor_tight_loops): a tight loop's vertices that are no anchors collapse along
  // the loop into a neighbour on it, the nearer first, until only the anchors are left (or the
  // usual tests refuse: a strip narrower than the spacing can make a collapse turn a face over).
  for (int pass = 0; !col.loops.empty() && pass < 200; ++pass) {
    int changed = 0;
    for (const std::vector<int>& loop : col.loops)
      for (int u : loop) {
        if (!col.alive[u] || col.anchored(u) || col.vf[u].empty()) continue;
        col.neighbours(u, nu);
        cands.clear();
        for (int v : nu)
          if (col.is_feature(u, v)) cands.push_back(v);
        std::sort(cands.begin(), cands.end(), [&](int a, int b) {
          const double da = (d.p[a] - d.p[u]).norm(), db = (d.p[b] - d.p[u]).norm();
          return da != db ? da < db : a < b;
        });
        for (int v : cands)
          if (col.can_collapse(u, v)) {
            col.collapse(u, v);
            ++changed;
            break;
          }
      }
    check(0.9);
    if (changed == 0) break;
  }
}

// The coarse triangles left by the collapses (vertices renumbered; dense_of: coarse -> dense vertex).
std::vector<Tri> coarse_triangles(const Collapser& col, int n, std::vector<int>& dense_of) {
  std::vector<int> coarse_of(n, -1);
  dense_of.clear();
  for (int v = 0; v < n; ++v)
    if (col.alive[v] && !col.vf[v].empty()) {
      coarse_of[v] = static_cast<int>(dense_of.size());
      dense_of.push_back(v);
    }
  std::vector<Tri> tris;
  for (size_t i = 0; i < col.f.size(); ++i)
    if (col.face_alive[i]) tris.push_back({coarse_of[col.f[i][0]], coarse_of[col.f[i][1]], coarse_of[col.f[i][2]]});
  return tris;
}

// Augmenting paths (alternating between unused and used pairs, breadth first, bounded) from each
// unmatched triangle to another; cand[t][k]: t's pairable neighbour across its edge k, or -1.
void augment_matching(const std::vector<std::array<int, 3>>& cand, std::vector<int>& mate) {
  const int nt = static_cast<int>(mate.size());
  std::vector<int> from(nt, -1), seen(nt, -1);
  for (int t = 0; t < nt; ++t) {
    if (mate[t] >= 0) continue;
    std::vector<int> queue{t};
    seen[t] = t;
    int end_a = -1, end_b = -1;
    for (size_t head = 0; head < queue.size() && head < 400 && end_b < 0; ++head) {
      int a = queue[head];
      for (int k = 0; k < 3 && end_b < 0; ++k) {
        int b = cand[a][k];
        if (b < 0 || b == mate[a] || seen[b] == t) continue;
        if (mate[b] < 0) {
          end_a = a;
          end_b = b;
        } else if (seen[mate[b]] != t) {
          seen[b] = t;
          seen[mate[b]] = t;
          from[mate[b]] = a;
          queue.push_back(mate[b]);
        }
      }
    }
    if (end_b < 0) continue;
    // flip the path: end_b - end_a, then each a's old mate pairs with a's predecessor
    int a = end_a, b = end_b;
    while (true) {
      int old = mate[a];
      mate[a] = b;
      mate[b] = a;
      if (a == t) break;
      b = old;
      a = from[a];
    }
  }
}

// The vertex of triangle t that is neither a nor b (-1 if none).
int third_vertex(const Tri& t, int a, int b) {
  int v = -1;
  for (int m = 0; m < 3; ++m)
    if (t[m] != a && t[m] != b) v = t[m];
  return v;
}

// Flips the edge a - b shared by triangles i = (a, b, c) and j = (b, a, dd):
// -> (a, dd, c), (dd, b, c), with the directed-edge map `half` (edge -> triangle) kept up to date.
void flip_pair(std::vector<Tri>& tris, std::unordered_map<std::uint64_t, int>& half, int i, int j, int a, int b,
               int c, int dd) {
  for (int t : {i, j})
    for (int m = 0; m < 3; ++m) half.erase(half_key(tris[t][m], tris[t][(m + 1) % 3]));
  tris[i] = {a, dd, c};
  tris[j] = {dd, b, c};
  for (int t : {i, j})
    for (int m = 0; m < 3; ++m) half[half_key(tris[t][m], tris[t][(m + 1) % 3])] = t;
}

// The two new triangles of a flip (their normals n1, n2) face within 60 degrees of `ref`.
bool both_face(const V3& n1, const V3& n2, const V3& ref) {
  const double l = ref.norm();
  return l > 0 && n1.dot(ref) > 0.5 * n1.norm() * l && n2.dot(ref) > 0.5 * n2.norm() * l;
}

// The angle between u and v (radians).
double angle_between(const V3& u, const V3& v) { return std::atan2(u.cross(v).norm(), u.dot(v)); }

// The smallest angle of the triangle (x, y, z).
double min_angle(const V3& x, const V3& y, const V3& z) {
  return std::min({angle_between(y - x, z - x), angle_between(z - y, x - y), angle_between(x - z, y - z)});
}

// For a flip of edge p -> q of a triangle (p, q, r): the triangle j across it and its third
// vertex dd; false when there is none or r - dd is an edge already.
bool flip_partner(const std::vector<Tri>& tris, const std::unordered_map<std::uint64_t, int>& half, int p, int q,
                  int r, int& j, int& dd) {
  auto it = half.find(half_key(q, p));
  if (it == half.end()) return false;
  j = it->second;
  dd = third_vertex(tris[j], p, q);
  return dd >= 0 && dd != r && !half.count(half_key(r, dd)) && !half.count(half_key(dd, r));
}

// Passes over the coarse triangles (at most 10, until one makes no flip): for each triangle i
// and each of its corners k in turn, try(i, k, p, q, r, j, dd) says whether to flip its edge
// p -> q (r its third vertex) with triangle j (third vertex dd); a flip ends the triangle's turn.
// Returns the flips.
template <class Try>
int flip_passes(std::vector<Tri>& tris, std::unordered_map<std::uint64_t, int>& half, Try&& try_flip) {
  int flips = 0;
  for (int pass = 0; pass < 10; ++pass) {
    int changed = 0;
    for (size_t i = 0; i < tris.size(); ++i)
      for (int k = 0; k < 3; ++k) {
        int p, q, r, j, dd;
        if (!try_flip(int(i), k, p, q, r, j, dd)) continue;
        flip_pair(tris, half, int(i), j, p, q, r, dd);
        ++changed;
        break;
      }
    flips += changed;
    if (changed == 0) break;
  }
  return flips;
}

// Edge flips on the coarse triangles towards regular valences (6 inside, 4 on the boundary;
// corners free) and lattice edges: an interior edge that is no feature edge is flipped when the
// new edge is a lattice edge (displacement (±1, 0), (0, ±1) or (±1, ±1)) where the old one was
// not, without raising the summed valence excess of the four vertices, or when the excess drops
// and the new edge is no worse on the lattice; the new edge must not be an edge yet and both new
// triangles must face the way the old ones did (within 60 degrees) and their smallest angle must
// not be smaller than the old pair's. Flips keep the topology (same vertices,
// edges, faces) and every feature edge; fewer irregular coarse vertices mean fewer extraordinary
// vertices in the cage. Returns the number of flips.
template <class IsFeature>
int flip_to_regular_valence(const Dense& d, const Fields& fl, std::vector<Tri>& tris, const std::vector<int>& dense_of,
                            IsFeature&& coarse_feature) {
  const int nc = static_cast<int>(dense_of.size());
  std::unordered_map<std::uint64_t, int> half = half_edges(tris);
  std::unordered_map<std::uint64_t, int> count;  // undirected edge -> faces
  for (size_t i = 0; i < tris.size(); ++i)
    for (int k = 0; k < 3; ++k) count[edge_key(tris[i][k], tris[i][(k + 1) % 3])] += 1;
  std::vector<int> valence(nc, 0);
  std::vector<char> boundary(nc, 0);
  for (const auto& [key, n] : count) {
    int a = int(key >> 32), b = int(key & 0xffffffffu);
    valence[a] += 1;
    valence[b] += 1;
    if (n == 1) boundary[a] = boundary[b] = 1;
  }
  auto excess = [&](int v, int change) {
    if (fl.kind[dense_of[v]] == 2) return 0;
    return std::abs(valence[v] + change - (boundary[v] ? 4 : 6));
  };
  auto pos = [&](int v) -> const V3& { return d.p[dense_of[v]]; };
  auto normal = [&](int a, int b, int c) { return V3((pos(b) - pos(a)).cross(pos(c) - pos(a))); };
  // 1 when the edge is not a lattice edge (displacement other than (±1, 0), (0, ±1), (±1, ±1))
  auto off_lattice = [&](int a, int b) {
    const int da = dense_of[a], db = dense_of[b];
    const V3 disp = fl.o[db] - fl.o[da];
    const V3 t = fl.normal[da].cross(fl.q[da]);
    const double x = std::abs(std::round(disp.dot(fl.q[da]) / fl.s)), y = std::abs(std::round(disp.dot(t) / fl.s));
    return x <= 1 && y <= 1 && x + y > 0 ? 0 : 1;
  };
  auto smallest = [&](int a, int b, int c) { return min_angle(pos(a), pos(b), pos(c)); };
  int flips = 0;
  for (int pass = 0; pass < 10; ++pass) {
    int changed = 0;
    for (size_t i = 0; i < tris.size(); ++i)
      for (int k = 0; k < 3; ++k) {
        const int a = tris[i][k], b = tris[i][(k + 1) % 3], c = tris[i][(k + 2) % 3];
        if (a > b) continue;  // each interior edge once (from its triangle with a < b)
        auto it = half.find(half_key(b, a));
        if (it == half.end() || coarse_feature(a, b)) continue;
        const int j = it->second;
        const int dd = third_vertex(tris[j], a, b);
        if (dd < 0 || dd == c || count.count(edge_key(c, dd))) continue;
        const int before = excess(a, 0) + excess(b, 0) + excess(c, 0) + excess(dd, 0);
        const int after = excess(a, -1) + excess(b, -1) + excess(c, 1) + excess(dd, 1);
        const int lattice_old = off_lattice(a, b), lattice_new = off_lattice(c, dd);
        const bool better = (lattice_new < lattice_old && after <= before) || (lattice_new <= lattice_old && after < before);
        if (!better) continue;
        const V3 old_n = normal(a, b, c).normalized() + normal(b, a, dd).normalized();
        if (!both_face(normal(a, dd, c), normal(dd, b, c), old_n)) continue;
        if (std::min(smallest(a, dd, c), smallest(dd, b, c)) < std::min(smallest(a, b, c), smallest(b, a, dd)))
          continue;  // the pair's smallest angle must not shrink (the cage's quads stay even)
        flip_pair(tris, half, int(i), j, a, b, c, dd);  // (a, b, c), (b, a, dd) -> (a, dd, c), (dd, b, c)
        count.erase(edge_key(a, b));
        count[edge_key(c, dd)] = 2;
        valence[a] -= 1;
        valence[b] -= 1;
        valence[c] += 1;
        valence[dd] += 1;
        ++changed;
        break;  // triangle i changed: its other edges next pass
      }
    flips += changed;
    if (changed == 0) break;
  }
  return flips;
}

// Ears: a coarse triangle whose two edges are consecutive edges of one feature chain (a, c, b:
// c a chain vertex that is no corner) and whose third edge a - b is no feature edge lies along
// the chain, its third edge a chord of it. Where the chain bends (a rim rounding a corner of the
// part) the chord leaves the triangle's side of the part: on the wall side of a rounded rim the
// ear's plane is the top's, facing away from the wall, and the split's three quads lie along the
// sharp edge, folded over onto the top (fandisk's bottom rim at --target-faces 300: 180 degrees
// between the fitted normals across a 90 degree edge). Where the chain bends over three coarse
// edges the region between it and the chord is a fan of an ear and a chord triangle (one edge on
// the chain, a and b both on features: featuretype's rounded step corners, fandisk at 500 quads),
// which folds the same way and is flipped by the same rule. An ear that faces more than 60
// degrees away from the triangle across its chord (which lies on the side) has the chord flipped,
// (a, b, c), (b, a, dd) -> (a, dd, c), (dd, b, c), joining the chain vertex c to the side's
// vertex dd, when dd is on no feature or, across a wall one quad high, on another feature curve
// (no corner, no feature edge to a, b or c: the new edge crosses the wall from rim to rim;
// featuretype.STL has 10 such ears, and 7 pairs of crossing faces without their flips), the new
// edge is new and both new triangles face within 60 degrees of the triangle across. An ear
// lying on its side (on the top, inside the arc) is left as it is. Returns the flips made.
template <class IsFeature>
int flip_ears(const Dense& d, const Fields& fl, std::vector<Tri>& tris, const std::vector<int>& dense_of,
              IsFeature&& coarse_feature) {
  std::unordered_map<std::uint64_t, int> half = half_edges(tris);
  auto pos = [&](int v) -> const V3& { return d.p[dense_of[v]]; };
  auto normal = [&](int a, int b, int c) { return V3((pos(b) - pos(a)).cross(pos(c) - pos(a))); };
  return flip_passes(tris, half, [&](int i, int k, int& a, int& b, int& c, int& j, int& dd) {
    a = tris[i][k], b = tris[i][(k + 1) % 3], c = tris[i][(k + 2) % 3];
    // c on the chain by one edge (a chord triangle) or both (an ear; a feature edge's ends are on
    // features, so a and b are then too), a and b on features.
    if (fl.kind[dense_of[c]] != 1 || coarse_feature(a, b) || !(coarse_feature(b, c) || coarse_feature(c, a)) ||
        fl.kind[dense_of[a]] == 0 || fl.kind[dense_of[b]] == 0)
      return false;
    if (!flip_partner(tris, half, a, b, c, j, dd)) return false;
    // The side's vertex: on no feature, or (a wall one quad high) on another feature curve than
    // the ear's, which the new edge c - dd then crosses the wall to.
    const int side_kind = fl.kind[dense_of[dd]];
    if (side_kind == 2 || (side_kind == 1 && (coarse_feature(dd, a) || coarse_feature(dd, b) || coarse_feature(dd, c))))
      return false;
    const V3 side = normal(b, a, dd), ear = normal(a, b, c);
    if (!both_face(normal(a, dd, c), normal(dd, b, c), side)) return false;
    return !(ear.dot(side) > 0.5 * ear.norm() * side.norm());  // an ear lying on the side is left as it is
  });
}

// The largest angle of the triangle (x, y, z).
double max_angle(const V3& x, const V3& y, const V3& z) {
  return std::max({angle_between(y - x, z - x), angle_between(z - y, x - y), angle_between(x - z, y - z)});
}

// The conditions of the sliver and cap flips (docs/remesh.md step 5) for the edge p -> q of a
// triangle whose third vertex is r: a triangle j across it whose far vertex dd makes a new edge,
// both new triangles facing within 60 degrees of the old pair, and a larger smallest angle (or,
// with `or_largest_falls`, a smaller largest angle).
bool flip_improves(const Dense& d, const std::vector<Tri>& tris, const std::unordered_map<std::uint64_t, int>& half,
                   const std::vector<int>& dense_of, int p, int q, int r, int& j, int& dd, bool or_largest_falls = false) {
  auto pos = [&](int v) -> const V3& { return d.p[dense_of[v]]; };
  auto normal = [&](int a, int b, int c) { return V3((pos(b) - pos(a)).cross(pos(c) - pos(a))); };
  auto smallest = [&](int a, int b, int c) { return min_angle(pos(a), pos(b), pos(c)); };
  auto largest = [&](int a, int b, int c) { return max_angle(pos(a), pos(b), pos(c)); };
  if (!flip_partner(tris, half, p, q, r, j, dd)) return false;
  if (!both_face(normal(p, dd, r), normal(dd, q, r), normal(q, p, dd) + normal(p, q, r))) return false;
  if (std::min(smallest(p, dd, r), smallest(dd, q, r)) > std::min(smallest(p, q, r), smallest(q, p, dd))) return true;
  return or_largest_falls &&
         std::max(largest(p, dd, r), largest(dd, q, r)) < std::max(largest(p, q, r), largest(q, p, dd));
}

// Slivers along a chain (docs/remesh.md step 5, "Slivers"): a coarse triangle whose angle at a
// feature vertex is below max_degrees between a coarse feature edge and an edge that is none lies
// along the chain. Where the chain bends away from its chord, the feature edge's split point (the
// chain's middle) lands beside the other edge's, and the split quad between them turns over
// (fandisk at 1050 quads: the crease folded, 140 degrees off the mesh's dihedral). The other edge
// is flipped with the triangle across it when the new edge is new, both new triangles face
// within 60 degrees of the old pair and their smallest angle is larger than the old pair's.
// Returns the flips.
template <class IsFeature>
int flip_chain_slivers(const Dense& d, const Fields& fl, std::vector<Tri>& tris, const std::vector<int>& dense_of,
                       IsFeature&& coarse_feature, double max_degrees) {
  std::unordered_map<std::uint64_t, int> half = half_edges(tris);
  auto pos = [&](int v) -> const V3& { return d.p[dense_of[v]]; };
  const double sliver = max_degrees * kPi / 180;
  return flip_passes(tris, half, [&](int i, int k, int& p, int& q, int& r, int& j, int& dd) {
    const int a = tris[i][k], b = tris[i][(k + 1) % 3], c = tris[i][(k + 2) % 3];
    if (fl.kind[dense_of[a]] == 0 || angle_between(pos(b) - pos(a), pos(c) - pos(a)) >= sliver) return false;
    const bool fb = coarse_feature(a, b), fc = coarse_feature(c, a);
    if (fb == fc) return false;
    // The edge to flip, p -> q in the triangle's order, and the third vertex r (the chain's).
    p = fb ? c : a, q = fb ? a : b, r = fb ? b : c;
    return flip_improves(d, tris, half, dense_of, p, q, r, j, dd);
  });
}

constexpr double kChainSliver = 15;  // degrees (at 15 featuretype.STL: 16 -> 7 crossing face pairs, docs/remesh.md)

// Caps (docs/remesh.md step 5, "Caps"): a coarse triangle with an angle above max_degrees at a
// vertex r has r almost on its opposite edge p - q. Paired or not it makes a degenerate corner
// (a quad with a ~180 degree angle, or an unpaired triangle's split quad), an extraordinary
// vertex at best, and the fit can slide r across p - q and turn the triangle over (plate_holes'
// top plane: 27 pairs of faces touching). The edge p - q (no feature edge) is flipped with the
// triangle across it when the new edge is new, both new triangles face within 60 degrees of the
// old pair and their smallest angle is larger than the old pair's, or their largest angle smaller
// (the cap's: plate_holes' countersunk hole has a 170 degree cap whose partner reaches a vertex
// 65 mm off across the top, so every triangle there is a sliver and the smallest angle cannot
// grow; left, the cage folded there, 84 degrees off the mesh's dihedral). Returns the flips.
template <class IsFeature>
int flip_caps(const Dense& d, std::vector<Tri>& tris, const std::vector<int>& dense_of, IsFeature&& coarse_feature,
              double max_degrees) {
  std::unordered_map<std::uint64_t, int> half = half_edges(tris);
  auto pos = [&](int v) -> const V3& { return d.p[dense_of[v]]; };
  const double cap = max_degrees * kPi / 180;
  return flip_passes(tris, half, [&](int i, int k, int& p, int& q, int& r, int& j, int& dd) {
    p = tris[i][k], q = tris[i][(k + 1) % 3], r = tris[i][(k + 2) % 3];
    if (coarse_feature(p, q) || angle_between(pos(p) - pos(r), pos(q) - pos(r)) <= cap) return false;
    return flip_improves(d, tris, half, dense_of, p, q, r, j, dd, true);
  });
}

constexpr double kCapAngle = 160;  // degrees (lower angles measured: docs/remesh.md step 5, "Caps")

// Pairs the coarse triangles into quads (diagonal edges first, never across a feature edge);
// returns the quads, then the unpaired triangles; `quads` their count.
template <class IsFeature>
std::vector<std::vector<int>> pair_triangles(const Dense& d, const Fields& fl, double s, const std::vector<Tri>& tris,
                                             const std::vector<int>& dense_of, IsFeature&& coarse_feature, int& quads) {
  // Candidates: across "diagonal" edges (lattice displacement (±1, ±1)).
  std::unordered_map<std::uint64_t, int> half;
  for (size_t i = 0; i < tris.size(); ++i)
    for (int k = 0; k < 3; ++k) half[half_key(tris[i][k], tris[i][(k + 1) % 3])] = int(i);
  struct Pair {
    double score;
    int f, g, k;
  };
  std::vector<Pair> pairs;
  auto quad_of = [&](int fi, int k, int g, std::array<int, 4>& quad) {
    int x = tris[fi][k], y = tris[fi][(k + 1) % 3], z = tris[fi][(k + 2) % 3];
    int w = -1;
    for (int j = 0; j < 3; ++j)
      if (tris[g][j] != x && tris[g][j] != y) w = tris[g][j];
    quad = {x, w, y, z};
  };
  for (size_t i = 0; i < tris.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      int x = tris[i][k], y = tris[i][(k + 1) % 3];
      auto it = half.find(half_key(y, x));
      if (it == half.end() || it->second < int(i) || coarse_feature(x, y)) continue;
      std::array<int, 4> quad;
      quad_of(int(i), k, it->second, quad);
      if (quad[1] == quad[3]) continue;  // two triangles sharing two edges
      V3 c[4];
      for (int j = 0; j < 4; ++j) c[j] = d.p[dense_of[quad[j]]];
      double quality = quad_quality(c);
      if (quality < 0.2) continue;
      int dx = dense_of[x], dy = dense_of[y];
      V3 disp = fl.o[dy] - fl.o[dx];
      V3 tx = fl.normal[dx].cross(fl.q[dx]);
      double a = std::abs(std::round(disp.dot(fl.q[dx]) / s)), b = std::abs(std::round(disp.dot(tx) / s));
      bool diagonal = a == 1 && b == 1;
      pairs.push_back({(diagonal ? 1.0 : 0.0) + quality, int(i), it->second, k});
    }
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) {
    return a.score != b.score ? a.score > b.score : a.f != b.f ? a.f < b.f : a.k < b.k;
  });
  // Greedy matching, best pairs first; then augmenting paths (alternating between unused and
  // used pairs, breadth first, bounded) from each unpaired triangle to another.
  int nt = static_cast<int>(tris.size());
  std::vector<int> mate(nt, -1);
  std::vector<std::array<int, 3>> cand(nt, {-1, -1, -1});  // neighbour across edge k if pairable
  for (const Pair& pr : pairs) {
    cand[pr.f][pr.k] = pr.g;
    for (int j = 0; j < 3; ++j)
      if (tris[pr.g][j] == tris[pr.f][(pr.k + 1) % 3]) cand[pr.g][j] = pr.f;
  }
  for (const Pair& pr : pairs) {
    if (mate[pr.f] >= 0 || mate[pr.g] >= 0) continue;
    mate[pr.f] = pr.g;
    mate[pr.g] = pr.f;
  }
  augment_matching(cand, mate);
  std::vector<std::vector<int>> polygons;
  for (int f = 0; f < nt; ++f) {
    int g = mate[f];
    if (g < f) continue;
    int k = 0;
    while (cand[f][k] != g) ++k;
    std::array<int, 4> quad;
    quad_of(f, k, g, quad);
    polygons.push_back({quad[0], quad[1], quad[2], quad[3]});
  }
  quads = static_cast<int>(polygons.size());
  for (int f = 0; f < nt; ++f)
    if (mate[f] < 0) polygons.push_back({tris[f][0], tris[f][1], tris[f][2]});
  return polygons;
}

// Stuck vertices (docs/remesh.md step 6c): a coarse vertex on no feature whose lattice point is
// that of a feature vertex beside it should have collapsed into that feature vertex, and could
// not. Where a feature arc is tighter than the lattice spacing, the chain rule
// (Collapser::chord_follows_chain) keeps extra chain vertices, and a side's vertex between two of
// them stays just beside the curve (fandisk's bottom rim: a wall vertex 0.037 above a 0.105 chord,
// 0.2 of the spacing): its polygons are slivers along the crease, and the split's quads there, a
// quarter as high as long, leave the limit normal across the crease ill-conditioned. Each such
// vertex whose polygons touch one feature curve only (not a wall one polygon high between two
// rims) moves to the dense vertex, on no feature and reached from it without crossing one, at
// least 0.1 x the spacing farther from its feature neighbours, that makes the worst of what the
// move changes best: the corner measure 2 (e x f) . n / (|e|^2 + |f|^2) (1 at a square's corners,
// small at a sliver's) at the vertex and at the corners beside it in its polygons, and its
// distance from each feature edge of its polygons over the edge's length. The move must gain 0.05 (0.01
// in the later passes, where two stuck vertices side by side make room for each other), and every
// polygon must face within 60 degrees of its old normal and of the surface's normal there. Only
// the vertex's place changes (a coarse vertex is a dense vertex): no count, edge or feature, so
// the topology is kept. Returns the vertices moved.
template <class IsFeature>
int relocate_stuck_vertices(const Dense& d, const Fields& fl, double s, const std::vector<std::vector<int>>& polygons,
                            std::vector<int>& dense_of, IsFeature&& coarse_feature) {
  const int nc = static_cast<int>(dense_of.size());
  std::vector<std::vector<int>> around(nc);  // polygons per coarse vertex
  for (size_t i = 0; i < polygons.size(); ++i)
    for (int v : polygons[i]) around[v].push_back(static_cast<int>(i));
  std::vector<char> taken(d.p.size(), 0);  // dense vertices that are coarse vertices
  for (int v : dense_of) taken[v] = 1;
  auto corner = [&](int w, int v, int at) -> const V3& { return d.p[w == v ? at : dense_of[w]]; };
  auto newell = [&](const auto& poly, int v, int at) {
    V3 n = V3::Zero();
    const int m = static_cast<int>(poly.size());
    for (int k = 0; k < m; ++k) n += corner(poly[k], v, at).cross(corner(poly[(k + 1) % m], v, at));
    return n;
  };
  // The distance of v (at dense vertex `at`) from each feature edge of polygon `poly`, relative
  // to the edge's length (1 if the polygon has no feature edge without v).
  auto off_feature_edge = [&](const auto& poly, int v, int at) {
    const int m = static_cast<int>(poly.size());
    double result = 1;
    for (int k = 0; k < m; ++k) {
      const int a = poly[k], b = poly[(k + 1) % m];
      if (a == v || b == v || !coarse_feature(a, b)) continue;
      const V3 &pa = d.p[dense_of[a]], &pb = d.p[dense_of[b]];
      const double l = (pb - pa).norm();
      for (int w : poly)
        if (w == v) {
          const V3& x = corner(w, v, at);
          result = std::min(result, (x - closest_on_segment(x, pa, pb)).norm() / l);
        }
    }
    return result;
  };
  // The worst corner of v's polygons with v at dense vertex `at`: 2 (e x f) . n / (|e|^2 + |f|^2)
  // for the corner's two edges e, f and the polygon's unit normal n (1 at a square's corners,
  // 0.87 at an equilateral triangle's; small for a sliver or a thin quad); -1 when a polygon
  // turns by 60 degrees or more from its old normal or from the surface's normal at `at`.
  auto worst = [&](int v, int at, const std::vector<V3>& old_normal) {
    double result = 1;
    for (size_t j = 0; j < around[v].size(); ++j) {
      double pq = 1;
      const auto& poly = polygons[around[v][j]];
      const int m = static_cast<int>(poly.size());
      V3 n = newell(poly, v, at);
      const double ln = n.norm();
      if (!(ln > 0) || n.dot(old_normal[j]) <= 0.5 * ln || n.dot(fl.normal[at]) <= 0.5 * ln) return -1.0;
      n /= ln;
      for (int k = 0; k < m; ++k) {
        if (poly[k] != v && poly[(k + 1) % m] != v && poly[(k + m - 1) % m] != v) continue;  // unchanged by v
        const V3& x = corner(poly[k], v, at);
        const V3 e = corner(poly[(k + 1) % m], v, at) - x, f = corner(poly[(k + m - 1) % m], v, at) - x;
        const double l = e.squaredNorm() + f.squaredNorm();
        if (!(l > 0)) return -1.0;
        pq = std::min(pq, 2 * e.cross(f).dot(n) / l);
      }
      if (pq <= 0) return -1.0;
      pq = std::min(pq, off_feature_edge(poly, v, at));
      result = std::min(result, pq);
    }
    return result;
  };
  // The distance from dense vertex `at` to the nearest feature vertex among v's neighbours.
  auto off_curve = [&](int v, int at) {
    double nearest = INFINITY;
    for (int pi : around[v])
      for (int w : polygons[pi])
        if (w != v && fl.kind[dense_of[w]] != 0) nearest = std::min(nearest, (d.p[dense_of[w]] - d.p[at]).norm());
    return nearest;
  };
  std::vector<int> stuck;  // the coarse vertices to move, found before any moves
  for (int v = 0; v < nc; ++v) {
    const int dv = dense_of[v];
    if (fl.kind[dv] != 0) continue;
    bool is_stuck = false;
    for (int pi : around[v]) {
      const auto& poly = polygons[pi];
      const int m = static_cast<int>(poly.size());
      for (int k = 0; k < m; ++k)
        if (poly[k] == v)
          for (int w : {poly[(k + 1) % m], poly[(k + m - 1) % m]})
            if (fl.kind[dense_of[w]] != 0 && (fl.o[dense_of[w]] - fl.o[dv]).norm() < 0.5 * s) is_stuck = true;
    }
    // and the feature vertices of its polygons are one path of feature edges (one curve: not a
    // wall one quad high between two rims, where the vertex has no room to move away)
    std::vector<int> on_curve;
    for (int pi : around[v])
      for (int w : polygons[pi])
        if (fl.kind[dense_of[w]] != 0) on_curve.push_back(w);
    std::sort(on_curve.begin(), on_curve.end());
    on_curve.erase(std::unique(on_curve.begin(), on_curve.end()), on_curve.end());
    std::vector<int> part(on_curve.size());
    std::iota(part.begin(), part.end(), 0);
    for (size_t i = 0; i < on_curve.size(); ++i)
      for (size_t j = 0; j < i; ++j)
        if (coarse_feature(on_curve[i], on_curve[j])) part[find_root(part, int(i))] = find_root(part, int(j));
    for (size_t i = 0; i < on_curve.size(); ++i)
      if (find_root(part, int(i)) != find_root(part, 0)) is_stuck = false;
    if (is_stuck) stuck.push_back(v);
  }
  // Moved one at a time, a few passes (two stuck vertices side by side make room for each other).
  std::vector<char> was_moved(nc, 0);
  std::vector<int> queue, seen(d.p.size(), -1);
  int stamp = 0;
  for (int pass = 0; pass < 4; ++pass) {
    int changed = 0;
    for (int v : stuck) {
      const int dv = dense_of[v];
      double reach = 0;  // candidates: no farther than its farthest polygon corner
      for (int pi : around[v])
        for (int w : polygons[pi]) reach = std::max(reach, (d.p[dense_of[w]] - d.p[dv]).norm());
      std::vector<V3> old_normal;
      for (int pi : around[v]) {
        const V3 n = newell(polygons[pi], v, dv);
        old_normal.push_back(n.norm() > 0 ? V3(n.normalized()) : V3::Zero());
      }
      const double now = worst(v, dv, old_normal);
      double best = now + (pass == 0 ? 0.05 : 0.01);
      int best_at = -1;
      queue.assign(1, dv);
      seen[dv] = ++stamp;
      for (size_t head = 0; head < queue.size(); ++head) {
        const int x = queue[head];
        if (!taken[x] && off_curve(v, x) >= off_curve(v, dv) + 0.1 * s) {
          const double q = worst(v, x, old_normal);
          if (q > best) best = q, best_at = x;
        }
        for (int i = fl.offsets[x]; i < fl.offsets[x + 1]; ++i) {
          const int y = fl.adj[i];
          if (seen[y] == stamp || fl.kind[y] != 0 || (d.p[y] - d.p[dv]).norm() > reach) continue;
          seen[y] = stamp;
          queue.push_back(y);
        }
      }
      if (best_at < 0) continue;
      taken[dv] = 0;
      taken[best_at] = 1;
      dense_of[v] = best_at;
      was_moved[v] = 1;
      ++changed;
    }
    if (changed == 0) break;
  }
  return static_cast<int>(std::count(was_moved.begin(), was_moved.end(), 1));
}

// One split: every polygon into quads (corner, edge midpoints, centre) on the input surface;
// feature edges into two feature edges, feature corners tagged.
template <class IsFeature>
MeshInput split_into_quads(const MeshInput& mesh, const Dense& d, const Fields& fl, const Projector& proj,
                           const std::vector<std::vector<int>>& polygons, const std::vector<int>& dense_of,
                           IsFeature&& coarse_feature) {
  const int nc = static_cast<int>(dense_of.size());
  MeshInput cage;
  cage.options = mesh.options;
  for (int v = 0; v < nc; ++v) {
    const V3& x = d.p[dense_of[v]];
    cage.positions.push_back({x.x(), x.y(), x.z()});
  }
  // Each polygon's normal (Newell's, of its corners) and, per edge, the sum of its polygons':
  // the side of the surface a point of the split belongs to.
  std::vector<V3> poly_normal;
  std::unordered_map<std::uint64_t, V3> edge_normal;
  for (const auto& poly : polygons) {
    V3 n = V3::Zero();
    const int m = static_cast<int>(poly.size());
    for (int k = 0; k < m; ++k) n += d.p[dense_of[poly[k]]].cross(d.p[dense_of[poly[(k + 1) % m]]]);
    const double l = n.norm();
    poly_normal.push_back(l > 0 ? V3(n / l) : V3::Zero());
    for (int k = 0; k < m; ++k) {
      auto [it, added] = edge_normal.try_emplace(edge_key(poly[k], poly[(k + 1) % m]), V3::Zero());
      it->second += poly_normal.back();
    }
  }
  std::vector<char> kept(d.p.size(), 0);  // dense vertices that are coarse vertices
  for (int v : dense_of) kept[v] = 1;
  std::unordered_map<std::uint64_t, int> midpoint;
  std::vector<std::uint64_t> feature_keys;
  auto mid = [&](int a, int b) {
    auto [it, inserted] = midpoint.try_emplace(edge_key(a, b), 0);
    if (!inserted) return it->second;
    bool feat = coarse_feature(a, b);
    const int da = dense_of[a], db = dense_of[b];
    const V3 chord_middle = 0.5 * (d.p[da] + d.p[db]);
    V3 x;
    if (!feat)
      x = proj.project(chord_middle, {da, db}, edge_normal[edge_key(a, b)]);
    else if (!proj.chain_middle(std::min(da, db), std::max(da, db), [&](int v) { return kept[v] != 0; }, x))
      x = proj.project_on_feature(chord_middle, std::min(da, db));
    it->second = static_cast<int>(cage.positions.size());
    cage.positions.push_back({x.x(), x.y(), x.z()});
    if (feat) {
      feature_keys.push_back(edge_key(a, it->second));
      feature_keys.push_back(edge_key(it->second, b));
    }
    return it->second;
  };
  for (size_t pi = 0; pi < polygons.size(); ++pi) {
    const auto& poly = polygons[pi];
    int m = static_cast<int>(poly.size());
    V3 centre = V3::Zero();
    std::vector<int> corners;
    for (int v : poly) {
      centre += d.p[dense_of[v]];
      corners.push_back(dense_of[v]);
    }
    V3 x = proj.project(centre / m, corners, poly_normal[pi]);
    int c = static_cast<int>(cage.positions.size());
    cage.positions.push_back({x.x(), x.y(), x.z()});
    std::vector<int> mids(m);
    for (int k = 0; k < m; ++k) mids[k] = mid(poly[k], poly[(k + 1) % m]);
    for (int k = 0; k < m; ++k) {
      cage.face_sizes.push_back(4);
      cage.face_indices.insert(cage.face_indices.end(), {poly[k], mids[k], c, mids[(k + m - 1) % m]});
    }
  }
  std::sort(feature_keys.begin(), feature_keys.end());
  for (auto k : feature_keys) cage.creases.push_back({int(k >> 32), int(k & 0xffffffffu), kInfiniteSharpness});
  for (int v = 0; v < nc; ++v)
    if (fl.kind[dense_of[v]] == 2 && !d.dart[dense_of[v]])  // a fading crease's end is a dart
      cage.corners.push_back({v, kInfiniteSharpness});
  return cage;
}

// Concave corners (docs/remesh.md step 9; core/mesh/corner_sectors.h): each flat sector wider
// than kConcaveSector at a corner of the cage, which the corner rule folds over itself at the
// corner (an L-shaped plane's inner corner), with an edge inside is split by tagging that edge,
// the one nearest the sector's middle, infinitely sharp: two convex sectors, each on the plane.
// The crease ends at the edge's other vertex, a dart. Curved sectors are left (a fan's tip, 300
// degrees around two creases meeting at 60: a crease across a curved surface is a kink, and
// fandisk's fit went 4.5 -> 29 degrees off at the creases beside it). Returns the sectors split;
// the tagged edges go to `added`.
constexpr double kConcaveSector = 170;  // degrees; a T-junction's 180 (a crease ending on another) lies flat too

int split_concave_sectors(MeshInput& cage, std::vector<std::array<int, 2>>& added) {
  // Once: a half of 170 .. 180 degrees (a 270-degree sector of three square quads: 90 + 180) is
  // flat but degenerate at the corner point, not folded; splitting it again cost featuretype 2
  // more pairs of faces touching and 1 crossing.
  int split = 0;
  for (const CornerSector& s : wide_corner_sectors(cage, kConcaveSector)) {
    if (!s.flat || s.middle < 0) continue;
    cage.creases.push_back({s.corner, s.middle, kInfiniteSharpness});
    added.push_back({s.corner, s.middle});
    ++split;
  }
  return split;
}

// Plane edges (QuadRemeshOptions::plane_edges), in edge lengths: planar regions at least this
// wide (plate_holes' side wall, 0.43 h at the automatic size, is a face of the part) end where
// the surface beyond bends tighter than this radius (a fillet the quads cannot follow; 0.6 and
// above took in a fillet of featuretype's and doubled its distance: docs/remesh.md).
constexpr double kPlaneWidth = 0.3;
constexpr double kPlaneRadius = 0.5;

// Checks the cage (manifold, oriented, each component's Euler characteristic and boundary loops
// as the input's) and fills the statistics.
void check_cage(const MeshInput& mesh, QuadRemeshResult& result) {
  QuadRemeshStats& st = result.stats;
  PolyMesh pm;
  try {
    pm = PolyMesh::build(result.cage.num_vertices(), result.cage.face_sizes, result.cage.face_indices);
  } catch (const Error& e) {
    throw Error(ErrorKind::Fit, std::string("quad remesh: the extracted cage is not a valid mesh: ") + e.what());
  }
  Topology ti = topology(mesh.num_vertices(), mesh.face_sizes, mesh.face_indices);
  Topology tc = topology(result.cage.num_vertices(), result.cage.face_sizes, result.cage.face_indices);
  st.euler_input = ti.euler;
  st.euler_cage = tc.euler;
  st.boundaries_input = ti.boundaries;
  st.boundaries_cage = tc.boundaries;
  st.components_input = ti.components;
  st.components_cage = tc.components;
  if (ti.per_component != tc.per_component)
    throw Error(ErrorKind::Fit, "quad remesh: the cage's topology (Euler characteristic " + std::to_string(tc.euler) +
                                    ", " + std::to_string(tc.boundaries) + " boundaries, " +
                                    std::to_string(tc.components) + " components) differs from the mesh's (" +
                                    std::to_string(ti.euler) + ", " + std::to_string(ti.boundaries) + ", " +
                                    std::to_string(ti.components) + ")");
  st.faces = result.cage.num_faces();
  st.vertices = result.cage.num_vertices();
  st.feature_edges = static_cast<int>(result.cage.creases.size() - result.sector_edges.size());
  st.corners = static_cast<int>(result.cage.corners.size());
  std::vector<char> is_corner(result.cage.num_vertices(), 0);
  for (const auto& c : result.cage.corners) is_corner[c.vertex] = 1;
  for (int v = 0; v < pm.num_vertices(); ++v) {
    if (pm.is_unused_vertex(v) || is_corner[v]) continue;
    int regular = pm.is_boundary_vertex(v) ? 3 : 4;
    if (pm.valence(v) != regular) ++st.extraordinary_vertices;
  }
  st.feature_chains_in = result.features.chains + result.features.dropped_short_chains;
  st.feature_chains_kept = result.features.chains;
}

// The size check with a target count (docs/remesh.md step 7). The cage's faces F(s) fall with the
// lattice spacing s about as s^-2 (the lattice's cells), but the lattice's irregularities add
// faces (clusters split where a collapse is refused, unpaired triangles: 0 .. 16 % at s = 2 h on
// the smooth meshes measured, more at coarse sizes), F is noisy in s (+-8 % between nearby
// spacings: the singularities land elsewhere), and feature curves keep vertices of their own
// whatever the spacing. So the first run is at kPrior x 2 h; each next spacing aims at the
// band's middle (kAimCentre x target) from the last run with F ~ s^-2, or, when the last two
// runs lie on both sides of it, by the line through them in log s - log F (slope held within
// 1 .. 3). It stops when the faces are within the band (kAimLow .. 1 x target), after
// kCountAttempts runs, or at a feature floor (two runs above the target, the coarser one 0 .. 3 %
// fewer faces). The spacing stays within 0.7 .. 2.5 x the first. Kept: a run within the
// band; else the one nearest it, an excess over the target counting 4 x a shortfall.
constexpr int kCountAttempts = 5;
constexpr double kPrior = 1.05, kAimLow = 0.9, kAimCentre = 0.95;

class SizeAim {
 public:
  SizeAim(int target, double s0) : target_(target), s0_(s0) {}

  // Records a run; true when it is the best so far.
  bool add(double s, int faces) {
    runs_.push_back({s, faces});
    const double m = miss(faces);
    if (runs_.size() > 1 && !(m < best_miss_)) return false;
    best_miss_ = m;
    return true;
  }

  // Whether to run again; `s` the next spacing.
  bool again(double& s) const {
    const Run& last = runs_.back();
    if (miss(last.faces) == 0 || static_cast<int>(runs_.size()) >= kCountAttempts) return false;
    const double aim = kAimCentre * target_;
    double slope = 2;  // F ~ s^-slope
    if (runs_.size() > 1) {
      const Run& before = runs_[runs_.size() - 2];
      if (last.faces > target_ && before.faces > target_ && last.s > before.s &&
          last.faces <= before.faces && last.faces > 0.97 * before.faces)
        return false;  // a feature floor: a coarser lattice does not help
      const double ds = std::log(last.s / before.s);
      if ((last.faces > aim) != (before.faces > aim) && std::abs(ds) > 1e-6)
        slope = std::clamp(-std::log(double(last.faces) / before.faces) / ds, 1.0, 3.0);
    }
    s = std::clamp(last.s * std::pow(last.faces / aim, 1 / slope), 0.7 * s0_, 2.5 * s0_);
    for (const Run& r : runs_)
      if (std::abs(r.s - s) <= 1e-9 * s) return false;  // at a limit already tried
    return true;
  }

 private:
  struct Run {
    double s;
    int faces;
  };
  // How far `faces` is from the band, relative to the target; an excess counts 4 x.
  double miss(int faces) const {
    const double r = double(faces) / target_;
    return r > 1 ? 4 * (r - 1) : r < kAimLow ? kAimLow - r : 0;
  }
  int target_;
  double s0_;
  std::vector<Run> runs_;
  double best_miss_ = INFINITY;
};

}  // namespace

void set_plane_regions(const MeshInput& mesh, double min_width, FeatureOptions& options) {
  std::vector<Point3> points(mesh.positions.begin(), mesh.positions.end());
  std::vector<int> polygon_of;
  const std::vector<Tri> triangles = fan_triangles(mesh, &polygon_of);
  PlanarRegionOptions po;
  po.min_width = min_width;
  const std::vector<PlanarRegion> regions = detect_planar_regions(points, triangles, po);
  options.plane_widths.clear();
  for (const PlanarRegion& r : regions) options.plane_widths.push_back(r.width);
  std::vector<int> of_triangle(triangles.size(), -1);
  for (std::size_t r = 0; r < regions.size(); ++r)
    for (int t : regions[r].triangles) of_triangle[static_cast<std::size_t>(t)] = static_cast<int>(r);
  std::vector<int>& region = options.plane_of_polygon;
  region.assign(mesh.num_faces(), -2);  // -2: no triangle seen yet
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    int& r = region[static_cast<std::size_t>(polygon_of[t])];
    r = r == -2 || r == of_triangle[t] ? of_triangle[t] : -1;
  }
  for (int& r : region) r = std::max(r, -1);
}

QuadRemeshResult quad_remesh(const MeshInput& mesh, const QuadRemeshOptions& options,
                             const std::function<bool(double)>& progress) {
  if ((options.target_faces > 0) == (options.edge_length > 0) || !std::isfinite(options.edge_length) ||
      options.target_faces < 0 || options.edge_length < 0)
    throw Error(ErrorKind::Settings,
                "quad remesh: exactly one of target faces (> 0) and edge length (> 0) must be given");
  if (!(options.curvature_alignment >= 0) || options.smoothing_iterations < 0)
    throw Error(ErrorKind::Settings, "quad remesh: curvature alignment and smoothing iterations must be >= 0");
  if (mesh.num_faces() == 0) throw Error(ErrorKind::Input, "quad remesh: the mesh has no faces");
  PolyMesh::build(mesh.num_vertices(), mesh.face_sizes, mesh.face_indices);  // manifold, oriented

  QuadRemeshResult result;
  auto check = [&](double fraction) {
    if (progress && !progress(std::clamp(fraction, 0.0, 1.0))) throw CancelSignal{};
  };
  try {
    auto t0 = Clock::now();
    check(0);
    double area = 0;
    make_dense(mesh, FeatureSet{}, area);
    if (!(area > 0)) throw Error(ErrorKind::Input, "quad remesh: the mesh has zero area");
    double h = options.target_faces > 0 ? std::sqrt(area / options.target_faces) : options.edge_length;
    FeatureOptions feature_options = options.features;
    if (feature_options.soft_angle_degrees == 0 && feature_options.soft_reach == 0 && options.soft_features > 0) {
      feature_options.soft_angle_degrees = options.soft_features * feature_options.angle_degrees;
      feature_options.soft_reach = h;
    }
    if (options.plane_edges && feature_options.plane_of_polygon.empty() && feature_options.plane_radius == 0) {
      set_plane_regions(mesh, kPlaneWidth * h, feature_options);
      feature_options.plane_radius = kPlaneRadius * h;
    }
    result.features = detect_features(mesh, feature_options);
    QuadRemeshStats& st = result.stats;
    st.input_vertices = mesh.num_vertices();
    st.input_faces = mesh.num_faces();

    Dense d = make_dense(mesh, result.features, area);
    double s = 2 * h;  // extraction lattice; the final split halves it
    double lmax = s / 4;
    if (area / (lmax * lmax) > 8e6)
      throw Error(ErrorKind::Settings, "quad remesh: the edge length is too small for the mesh's area (over " +
                                           std::to_string(long(area / (h * h))) + " quads)");
    split_long_edges(d, lmax);
    st.dense_vertices = static_cast<int>(d.p.size());
    check(0.05);

    Hierarchy hier;
    {
      Fields dense;
      dense.s = s;
      dense.pin_arcs = options.pin_tight_arcs;
      build_adjacency(d, dense);
      classify(d, dense);
      curvature(d, dense, options.curvature_alignment);
      hier.levels.push_back(std::move(dense));
    }
    build_hierarchy(hier);
    Fields& fl = hier.levels[0];
    int iterations = options.smoothing_iterations > 0 ? options.smoothing_iterations : 30;
    st.field_threads = solve_fields(hier, iterations, true, [&]() { check(0.25); });
    count_singularities(d, hier.levels[0], st);
    // Position field and extraction, and the size check (docs/remesh.md step 7): with a target
    // count (aim_at_target), until the faces are within the band (SizeAim), the spacing corrected
    // from the runs so far, the run nearest the band kept; else once more, with the spacing
    // scaled by the square root of the excess, when the faces clearly exceed the target.
    const bool aim = options.target_faces > 0 && options.aim_at_target;
    if (aim) s *= kPrior;
    SizeAim size_aim(options.target_faces, s);
    MeshInput best_cage;
    QuadRemeshStats best_stats;
    std::optional<Projector> projector;  // the split's search structures: the dense mesh's, built once for all runs
    for (int attempt = 0;; ++attempt) {
      result.cage = MeshInput{};
      auto t_position = Clock::now();
      for (Fields& level : hier.levels) level.s = s;
      st.field_threads = std::max(st.field_threads, solve_fields(hier, iterations, false, [&]() { check(0.5); }));
      st.field_seconds += seconds_since(attempt == 0 ? t0 : t_position);
      auto t1 = Clock::now();
      Collapser col(d, fl, kChainSag);
      if (options.cancel_dislocations) {
        const Translations tr = DislocationCanceller(d, fl).cancel();
        st.position_dislocations = tr.before;
        st.position_dislocations_left = tr.left;
        restretch_positions(fl, tr);
      }
      if (options.align_tight_loops) {
        const std::vector<TightLoop> loops = find_tight_loops(fl, s);
        if (std::any_of(loops.begin(), loops.end(), [](const TightLoop& l) { return l.group >= 0; })) {
          Collapser probe(d, fl, kChainSag);  // the lattice's own choice on each rim
          collapse_to_lattice(d, fl, s, options.cancel_dislocations, probe, check);
          st.tight_loops = anchor_tight_loops(fl, loops, probe.alive, col);
        }
      }
      collapse_to_lattice(d, fl, s, options.cancel_dislocations, col, check);
      std::vector<int> dense_of;
      std::vector<Tri> tris = coarse_triangles(col, fl.n, dense_of);
      auto coarse_feature = [&](int a, int b) { return col.is_feature(dense_of[a], dense_of[b]); };
      if (options.regularize_valence) st.flips = flip_to_regular_valence(d, fl, tris, dense_of, coarse_feature);
      flip_ears(d, fl, tris, dense_of, coarse_feature);  // always: an ear folds the cage
      if (options.flip_chain_slivers)  // before the pairing: a sliver along a bending chain folds the cage
        st.sliver_flips = flip_chain_slivers(d, fl, tris, dense_of, coarse_feature, kChainSliver);
      std::vector<Tri> before_caps;  // the triangles as the size check counts them (below)
      if (options.flip_caps) {  // before the pairing: a cap's corner is degenerate and can turn over
        before_caps = tris;
        st.cap_flips = flip_caps(d, tris, dense_of, coarse_feature, kCapAngle);
      }
      std::vector<std::vector<int>> polygons =
          pair_triangles(d, fl, s, tris, dense_of, coarse_feature, st.coarse_quads);
      // The size check's count (step 7): the faces the cage would have without the caps' flips
      // and the clean-up, so that neither decides whether the extraction runs again: they change
      // the cage where they act, not the spacing of a second run's whole lattice. Each pair of
      // triangles is a quad: 4 x quads + 3 x (triangles - 2 x quads) faces after the split.
      int quads_counted = st.coarse_quads;
      if (st.cap_flips > 0) pair_triangles(d, fl, s, before_caps, dense_of, coarse_feature, quads_counted);
      const int split_faces = 3 * static_cast<int>(tris.size()) - 2 * quads_counted;
      if (!aim) {  // without a target to aim at, one more run only when the faces clearly exceed the spacing's
        const double ratio = split_faces * h * h / area;
        if (attempt == 0 && ratio > 1.3 && !(options.exact_spacing && options.edge_length > 0)) {
          // This run's cage is not kept: the clean-up, the relocation and the split would be
          // thrown away (none of them changes the dense mesh or its fields).
          st.extract_seconds += seconds_since(t1);
          s *= std::sqrt(ratio);
          continue;
        }
      }
      if (options.cleanup) {  // quad-dominant clean-up (core/remesh/quad_cleanup.h, docs/remesh.md step 6b)
        std::vector<V3> positions, normals;
        std::vector<char> corner;
        for (int v : dense_of) {
          positions.push_back(d.p[v]);
          normals.push_back(fl.normal[v]);
          corner.push_back(fl.kind[v] == 2 ? 1 : 0);
        }
        const auto t_cleanup = Clock::now();
        const QuadCleanupStats cs = clean_quad_dominant(polygons, positions, normals, corner, coarse_feature);
        st.cleanup_seconds += seconds_since(t_cleanup);
        st.cleanup_rotations = cs.rotations;
        st.cleanup_merges = cs.merges;
        st.coarse_quads = static_cast<int>(std::count_if(polygons.begin(), polygons.end(),
                                                         [](const std::vector<int>& p) { return p.size() == 4; }));
      }
      st.coarse_triangles = static_cast<int>(polygons.size()) - st.coarse_quads;
      check(0.92);
      if (options.relocate_stuck)  // after the pairing and the clean-up: their counts are kept (step 6c)
        st.relocations = relocate_stuck_vertices(d, fl, s, polygons, dense_of, coarse_feature);
      st.arc_pins = fl.arc_pins;
      if (!projector) projector.emplace(d, fl);
      result.cage = split_into_quads(mesh, d, fl, *projector, polygons, dense_of, coarse_feature);
      st.extract_seconds += seconds_since(t1);
      st.attempts = attempt + 1;
      st.spacing = s;
      if (!aim) break;  // (the one rerun was decided above)
      if (size_aim.add(s, result.cage.num_faces())) {
        best_cage = result.cage;
        best_stats = st;
      }
      if (!size_aim.again(s)) break;
    }
    if (aim && st.attempts > 1) {  // the kept run's cage and counts; the seconds and runs of all
      result.cage = std::move(best_cage);
      best_stats.attempts = st.attempts;
      best_stats.field_seconds = st.field_seconds;
      best_stats.extract_seconds = st.extract_seconds;
      best_stats.cleanup_seconds = st.cleanup_seconds;
      st = best_stats;
    }

    if (options.split_concave_sectors)  // docs/remesh.md step 9
      st.concave_sectors = split_concave_sectors(result.cage, result.sector_edges);
    check_cage(mesh, result);
    check(1);
  } catch (const CancelSignal&) {
    QuadRemeshResult cancelled;
    cancelled.cancelled = true;
    return cancelled;
  }
  return result;
}

}  // namespace subd2nurbs
