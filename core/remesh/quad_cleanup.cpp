#include "core/remesh/quad_cleanup.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <unordered_map>
#include <utility>

#include "core/util/constants.h"

namespace subd2nurbs {
namespace {

using V3 = Eigen::Vector3d;
using Poly = std::vector<int>;

std::uint64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}

// The cage's valence excess and irregular-vertex count, compared lexicographically.
struct Energy {
  int excess = 0, irregular = 0;
  Energy operator+(const Energy& o) const { return {excess + o.excess, irregular + o.irregular}; }
  Energy operator-(const Energy& o) const { return {excess - o.excess, irregular - o.irregular}; }
  bool operator<(const Energy& o) const { return excess != o.excess ? excess < o.excess : irregular < o.irregular; }
};

// One change: faces f and g replaced by nf and ng (ng empty: g removed, a merge).
struct Op {
  int f = -1, g = -1;
  Poly nf, ng;
};

class Cleaner {
 public:
  Cleaner(std::vector<Poly>& polygons, const std::vector<V3>& positions, const std::vector<V3>& normals,
          const std::vector<char>& corner, const std::function<bool(int, int)>& is_feature,
          const QuadCleanupOptions& options)
      : faces_(polygons), p_(positions), n_(normals), corner_(corner), feature_(is_feature), opt_(options) {
    valence_.assign(p_.size(), 0);
    boundary_.assign(p_.size(), 0);
    for (size_t i = 0; i < faces_.size(); ++i) add_face(static_cast<int>(i));
    on_curve_.assign(p_.size(), 0);
    for (const auto& [key, e] : edges_) {
      const int a = int(key >> 32), b = int(key & 0xffffffffu);
      if (e[0] < 0 || e[1] < 0) boundary_[a] = boundary_[b] = 1;
      if (e[0] < 0 || e[1] < 0 || feature_(a, b)) on_curve_[a] = on_curve_[b] = 1;
    }
    cos_normal_ = std::cos(opt_.max_normal_degrees * kPi / 180);
  }

  Energy total() const {
    Energy e;
    for (size_t v = 0; v < p_.size(); ++v)
      if (valence_[v] > 0) e = e + vertex_energy(static_cast<int>(v), 0);
    for (const Poly& f : faces_)
      if (!f.empty()) e = e + face_energy(static_cast<int>(f.size()));
    return e;
  }

  void run(QuadCleanupStats& st) {
    for (int pass = 0; pass < opt_.max_passes; ++pass) {
      int changed = 0;
      for (int f = 0; f < static_cast<int>(faces_.size()); ++f) changed += rotate_around(f, st);
      if (opt_.walk_depth > 0)
        for (int t = 0; t < static_cast<int>(faces_.size()); ++t)
          if (faces_[t].size() == 3) changed += walk(t, st);
      if (changed == 0) break;
    }
    faces_.erase(std::remove_if(faces_.begin(), faces_.end(), [](const Poly& f) { return f.empty(); }), faces_.end());
  }

 private:
  std::vector<Poly>& faces_;
  const std::vector<V3>& p_;
  const std::vector<V3>& n_;
  const std::vector<char>& corner_;
  const std::function<bool(int, int)>& feature_;
  const QuadCleanupOptions& opt_;
  std::unordered_map<std::uint64_t, std::array<int, 2>> edges_;  // edge -> its faces (-1: none); lookups only
  std::vector<int> valence_;
  std::vector<char> boundary_;  // fixed: only interior edges change
  std::vector<char> on_curve_;  // on a boundary or feature edge (fixed too)
  double cos_normal_ = 0.5;

  Energy vertex_energy(int v, int change) const {
    if (corner_[v]) return {};
    const int e = std::abs(valence_[v] + change - (boundary_[v] ? 3 : 4));
    return {e, e > 0 ? 1 : 0};
  }
  static Energy face_energy(int size) { return {std::abs(size - 4), size != 4 ? 1 : 0}; }

  void add_face(int id) {
    const Poly& f = faces_[id];
    for (size_t k = 0; k < f.size(); ++k) {
      const int a = f[k], b = f[(k + 1) % f.size()];
      auto [it, inserted] = edges_.try_emplace(edge_key(a, b), std::array<int, 2>{-1, -1});
      if (inserted) ++valence_[a], ++valence_[b];
      (it->second[0] < 0 ? it->second[0] : it->second[1]) = id;
    }
  }
  void remove_face(int id) {
    const Poly& f = faces_[id];
    for (size_t k = 0; k < f.size(); ++k) {
      const int a = f[k], b = f[(k + 1) % f.size()];
      auto it = edges_.find(edge_key(a, b));
      (it->second[0] == id ? it->second[0] : it->second[1]) = -1;
      if (it->second[0] < 0 && it->second[1] < 0) {
        edges_.erase(it);
        --valence_[a], --valence_[b];
      }
    }
  }
  int across(int f, int a, int b) const {
    auto it = edges_.find(edge_key(a, b));
    if (it == edges_.end()) return -1;
    return it->second[0] == f ? it->second[1] : it->second[0];
  }

  // Applies op and returns the op that undoes it.
  Op apply(const Op& op) {
    Op undo{op.f, op.g, faces_[op.f], faces_[op.g]};
    remove_face(op.f);
    remove_face(op.g);
    faces_[op.f] = op.nf;
    faces_[op.g] = op.ng;
    add_face(op.f);
    if (!op.ng.empty()) add_face(op.g);
    return undo;
  }
  void revert(const Op& undo) {
    remove_face(undo.f);
    if (!faces_[undo.g].empty()) remove_face(undo.g);
    faces_[undo.f] = undo.nf;
    faces_[undo.g] = undo.ng;
    add_face(undo.f);
    add_face(undo.g);
  }

  V3 newell(const Poly& f) const {
    V3 n = V3::Zero();
    for (size_t k = 0; k < f.size(); ++k) n += p_[f[k]].cross(p_[f[(k + 1) % f.size()]]);
    return n;
  }
  // A new face: convex with corner sines >= the minimum, facing within the angle of `ref` (the
  // old faces' normal) and of its corners' surface normals.
  // The smallest corner sine of a face (about its Newell normal; -1 if degenerate or not convex);
  // curve_only: at its vertices on a feature curve or the boundary only (1 if none).
  double worst_sine(const Poly& f, bool curve_only = false) const {
    V3 n = newell(f);
    const double ln = n.norm();
    if (!(ln > 0)) return -1;
    n /= ln;
    const size_t m = f.size();
    double worst = 1;
    for (size_t k = 0; k < m; ++k) {
      const V3 a = p_[f[(k + 1) % m]] - p_[f[k]], b = p_[f[(k + m - 1) % m]] - p_[f[k]];
      const double la = a.norm(), lb = b.norm();
      if (!(la > 0) || !(lb > 0)) return -1;
      if (curve_only && !on_curve_[f[k]]) continue;
      worst = std::min(worst, a.cross(b).dot(n) / (la * lb));
    }
    return worst;
  }
  bool good_face(const Poly& f, const V3& ref, double min_sine, double curve_sine) const {
    V3 n = newell(f);
    const double ln = n.norm();
    if (!(ln > 0)) return false;
    n /= ln;
    if (n.dot(ref) <= cos_normal_ * ref.norm()) return false;
    V3 mean = V3::Zero();
    for (int v : f) mean += n_[v];
    if (n.dot(mean) <= cos_normal_ * mean.norm()) return false;
    return worst_sine(f) >= min_sine && worst_sine(f, true) >= curve_sine;
  }

  // The energy change of op (faces f, g -> nf, ng) from the valences of the edges it removes and adds.
  Energy delta(const Op& op) const {
    std::vector<std::pair<int, int>> change;  // vertex, valence change
    auto edge_set = [](const Poly& f, std::vector<std::uint64_t>& out) {
      for (size_t k = 0; k < f.size(); ++k) out.push_back(edge_key(f[k], f[(k + 1) % f.size()]));
    };
    std::vector<std::uint64_t> before, after;
    edge_set(faces_[op.f], before);
    edge_set(faces_[op.g], before);
    edge_set(op.nf, after);
    edge_set(op.ng, after);
    std::sort(before.begin(), before.end());
    before.erase(std::unique(before.begin(), before.end()), before.end());
    std::sort(after.begin(), after.end());
    after.erase(std::unique(after.begin(), after.end()), after.end());
    std::vector<std::uint64_t> gone, added;
    std::set_difference(before.begin(), before.end(), after.begin(), after.end(), std::back_inserter(gone));
    std::set_difference(after.begin(), after.end(), before.begin(), before.end(), std::back_inserter(added));
    for (auto k : gone) change.push_back({int(k >> 32), -1}), change.push_back({int(k & 0xffffffffu), -1});
    for (auto k : added) change.push_back({int(k >> 32), 1}), change.push_back({int(k & 0xffffffffu), 1});
    std::sort(change.begin(), change.end());
    Energy d;
    for (size_t i = 0; i < change.size();) {
      int v = change[i].first, c = 0;
      for (; i < change.size() && change[i].first == v; ++i) c += change[i].second;
      const Energy dv = vertex_energy(v, c) - vertex_energy(v, 0);
      // a vertex on a feature curve or the boundary never gets more irregular: the faces beside
      // the curve keep one side each (a face bent around it makes the crease's limit normal poor)
      if (on_curve_[v] && dv.excess > 0) return {1 << 20, 0};
      d = d + dv;
    }
    d = d + face_energy(static_cast<int>(op.nf.size())) - face_energy(static_cast<int>(faces_[op.f].size())) -
        face_energy(static_cast<int>(faces_[op.g].size()));
    if (!op.ng.empty()) d = d + face_energy(static_cast<int>(op.ng.size()));
    return d;
  }

  // The ways to re-split the union of faces f and g (sharing the interior non-feature edge a-b,
  // a -> b in f) into faces of the same sizes, or two triangles into one quad; only valid ones.
  // far_from >= 0: only re-splits whose triangle does not contain that vertex (a walk's step).
  void alternatives(int f, int g, int a, int b, std::vector<Op>& out, int far_from = -1) const {
    const Poly &F = faces_[f], &G = faces_[g];
    int shared = 0;
    for (int x : F) shared += static_cast<int>(std::count(G.begin(), G.end(), x));
    if (shared != 2) return;  // the union is not a simple polygon
    const int nf = static_cast<int>(F.size()), ng = static_cast<int>(G.size());
    int i = 0, j = 0;
    while (!(F[i] == a && F[(i + 1) % nf] == b)) ++i;
    while (!(G[j] == b && G[(j + 1) % ng] == a)) ++j;
    Poly P;  // b ... a along f, then g's vertices strictly between a and b
    for (int k = 1; k <= nf; ++k) P.push_back(F[(i + k) % nf]);
    for (int k = 2; k < ng; ++k) P.push_back(G[(j + k) % ng]);
    const int n = static_cast<int>(P.size());
    const V3 ref = newell(F).normalized() + newell(G).normalized();
    // new faces: at least the minimum sine, and no worse than the old pair's worst or keep_sine
    const double min_sine =
        std::max(opt_.min_corner_sine, std::min(opt_.keep_sine, std::min(worst_sine(F), worst_sine(G))));
    // at feature-curve and boundary vertices: no worse than the old faces there, or curve_sine
    // (a face meeting a crease at a small angle makes the crease's limit normal ill-conditioned)
    const double curve_sine = std::max(
        min_sine, std::min(opt_.curve_sine, std::min(worst_sine(F, true), worst_sine(G, true))));
    auto piece = [&](int from, int to) {
      Poly q;
      for (int k = from;; k = (k + 1) % n) {
        q.push_back(P[k]);
        if (k == to) break;
      }
      return q;
    };
    // two triangles into a quad: held to the pairing's minimum only (as the extraction's own pairs)
    if (nf == 3 && ng == 3 && good_face(P, ref, opt_.min_corner_sine, curve_sine)) out.push_back({f, g, P, {}});
    for (int p = 0; p < n; ++p)
      for (int q = p + 2; q < n; ++q) {
        if (p == 0 && q == n - 1) continue;   // adjacent
        if (p == 0 && q == nf - 1) continue;  // the edge a-b itself
        Poly x = piece(p, q), y = piece(q, p);
        const int sx = static_cast<int>(x.size()), sy = static_cast<int>(y.size());
        if (!((sx == nf && sy == ng) || (sx == ng && sy == nf))) continue;
        if (edges_.count(edge_key(P[p], P[q]))) continue;  // would duplicate an edge
        if (sx != nf) std::swap(x, y);
        if (far_from >= 0) {
          const Poly& tri = x.size() == 3 ? x : y;
          if (std::count(tri.begin(), tri.end(), far_from)) continue;
        }
        if (!good_face(x, ref, min_sine, curve_sine) || !good_face(y, ref, min_sine, curve_sine)) continue;
        out.push_back({f, g, std::move(x), std::move(y)});
      }
  }

  // The best improving re-split across one of f's edges, applied; returns 1 if one was.
  int rotate_around(int f, QuadCleanupStats& st) {
    if (faces_[f].empty()) return 0;
    const Poly F = faces_[f];
    for (size_t k = 0; k < F.size(); ++k) {
      const int a = F[k], b = F[(k + 1) % F.size()];
      const int g = across(f, a, b);
      if (g < 0 || feature_(a, b)) continue;
      std::vector<Op> ops;
      alternatives(f, g, a, b, ops);
      int best = -1;
      Energy best_delta;
      for (size_t i = 0; i < ops.size(); ++i) {
        Energy dl = delta(ops[i]);
        if (dl < best_delta) best_delta = dl, best = static_cast<int>(i);
      }
      if (best < 0) continue;
      apply(ops[best]);
      if (ops[best].ng.empty()) ++st.merges; else ++st.rotations;
      return 1;
    }
    return 0;
  }

  // Depth-first search over a triangle's moves (re-splits with a quad that carry it away from its
  // apex) ending anywhere or in a merge with another triangle; the best sequence is applied when
  // it lowers the energy.
  struct Walk {
    Energy total;
    std::vector<Op> path;
  };
  void search(int t, int depth, int previous, const Energy& sum, std::vector<Op>& path, Walk& best) {
    const Poly T = faces_[t];
    for (int k = 0; k < 3; ++k) {
      const int a = T[k], b = T[(k + 1) % 3];
      const int u = across(t, a, b);
      if (u < 0 || feature_(a, b) || faces_[u].size() != 3) continue;
      std::vector<Op> ops;
      alternatives(t, u, a, b, ops);
      for (const Op& op : ops)
        if (op.ng.empty()) {
          Energy total = sum + delta(op);
          if (total < best.total || (!(best.total < total) && path.size() + 1 < best.path.size())) {
            best.total = total;
            best.path = path;
            best.path.push_back(op);
          }
        }
    }
    if (!path.empty() && (sum < best.total || (!(best.total < sum) && path.size() < best.path.size()))) {
      best.total = sum;
      best.path = path;
    }
    if (depth == 0) return;
    for (int k = 0; k < 3; ++k) {
      const int a = T[k], b = T[(k + 1) % 3], apex = T[(k + 2) % 3];
      const int q = across(t, a, b);
      if (q < 0 || q == previous || feature_(a, b) || faces_[q].size() != 4) continue;
      std::vector<Op> ops;
      alternatives(t, q, a, b, ops, apex);
      for (const Op& op : ops) {
        const Energy d = delta(op);
        const Op undo = apply(op);
        path.push_back(op);
        search(t, depth - 1, q, sum + d, path, best);
        path.pop_back();
        revert(undo);
      }
    }
  }

  int walk(int t, QuadCleanupStats& st) {
    Walk best;
    std::vector<Op> path;
    search(t, opt_.walk_depth, -1, Energy{}, path, best);
    if (!(best.total < Energy{}) || best.path.empty()) return 0;
    for (const Op& op : best.path) {
      apply(op);
      if (op.ng.empty()) ++st.merges; else ++st.rotations;
    }
    ++st.walks;
    return 1;
  }
};

}  // namespace

QuadCleanupStats clean_quad_dominant(std::vector<std::vector<int>>& polygons, const std::vector<Eigen::Vector3d>& positions,
                                     const std::vector<Eigen::Vector3d>& normals, const std::vector<char>& corner,
                                     const std::function<bool(int, int)>& is_feature,
                                     const QuadCleanupOptions& options) {
  QuadCleanupStats st;
  Cleaner c(polygons, positions, normals, corner, is_feature, options);
  Energy e0 = c.total();
  st.excess_before = e0.excess;
  st.irregular_before = e0.irregular;
  c.run(st);
  Cleaner after(polygons, positions, normals, corner, is_feature, options);
  Energy e1 = after.total();
  st.excess_after = e1.excess;
  st.irregular_after = e1.irregular;
  return st;
}

}  // namespace subd2nurbs
