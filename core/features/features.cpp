#include "core/features/features.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>

#include "core/util/constants.h"
#include "core/util/error.h"
#include "core/util/vec3.h"

namespace subd2nurbs {
namespace {

using Vec = std::array<double, 3>;

using vec3::cross;
using vec3::dot;
using vec3::norm;
using vec3::sub;

// Newell normal of a polygon (not normalised; zero for a degenerate face).
Vec face_normal(const MeshInput& mesh, int begin, int size) {
  Vec n{0, 0, 0};
  for (int k = 0; k < size; ++k) {
    const Vec& a = mesh.positions[mesh.face_indices[begin + k]];
    const Vec& b = mesh.positions[mesh.face_indices[begin + (k + 1) % size]];
    n[0] += (a[1] - b[1]) * (a[2] + b[2]);
    n[1] += (a[2] - b[2]) * (a[0] + b[0]);
    n[2] += (a[0] - b[0]) * (a[1] + b[1]);
  }
  return n;
}

struct Graph {
  std::vector<std::vector<int>> adjacent;  // per vertex, the feature edges' other ends (sorted)
};

// Corners of a feature graph: degree != 2, or a turn sharper than the corner angle.
std::vector<char> find_corners(const MeshInput& mesh, const std::vector<std::array<int, 2>>& edges,
                               double corner_angle, std::vector<std::vector<int>>& adjacent) {
  int n = mesh.num_vertices();
  adjacent.assign(n, {});
  for (const auto& e : edges) {
    adjacent[e[0]].push_back(e[1]);
    adjacent[e[1]].push_back(e[0]);
  }
  std::vector<char> corner(n, 0);
  double cos_limit = std::cos(corner_angle * kPi / 180.0);
  for (int v = 0; v < n; ++v) {
    auto& adj = adjacent[v];
    std::sort(adj.begin(), adj.end());
    if (adj.empty()) continue;
    if (adj.size() != 2) {
      corner[v] = 1;
      continue;
    }
    Vec d0 = sub(mesh.positions[v], mesh.positions[adj[0]]);
    Vec d1 = sub(mesh.positions[adj[1]], mesh.positions[v]);
    double l = norm(d0) * norm(d1);
    if (l > 0 && dot(d0, d1) < cos_limit * l) corner[v] = 1;
  }
  return corner;
}

// Walks the feature graph into chains: each chain is a list of vertices (closed loops repeat the
// first vertex at the end).
std::vector<std::vector<int>> walk_chains(const std::vector<std::vector<int>>& adjacent,
                                          const std::vector<char>& corner) {
  int n = static_cast<int>(adjacent.size());
  std::vector<std::vector<char>> used(n);
  for (int v = 0; v < n; ++v) used[v].assign(adjacent[v].size(), 0);
  auto mark = [&](int a, int b) {
    auto ia = std::lower_bound(adjacent[a].begin(), adjacent[a].end(), b) - adjacent[a].begin();
    auto ib = std::lower_bound(adjacent[b].begin(), adjacent[b].end(), a) - adjacent[b].begin();
    used[a][ia] = used[b][ib] = 1;
  };
  std::vector<std::vector<int>> chains;
  auto follow = [&](int start, int k) {
    std::vector<int> chain{start};
    int prev = start, cur = adjacent[start][k];
    mark(prev, cur);
    chain.push_back(cur);
    while (!corner[cur] && cur != start) {
      int next = -1;
      for (size_t j = 0; j < adjacent[cur].size(); ++j)
        if (!used[cur][j]) next = adjacent[cur][j];
      if (next < 0) break;
      mark(cur, next);
      prev = cur;
      cur = next;
      chain.push_back(cur);
    }
    chains.push_back(std::move(chain));
  };
  for (int v = 0; v < n; ++v)
    if (corner[v])
      for (size_t k = 0; k < adjacent[v].size(); ++k)
        if (!used[v][k]) follow(v, static_cast<int>(k));
  for (int v = 0; v < n; ++v)
    for (size_t k = 0; k < adjacent[v].size(); ++k)
      if (!used[v][k]) follow(v, static_cast<int>(k));
  return chains;
}

// Distance from x to the line through a and b (to a if they coincide).
double line_distance(const Vec& x, const Vec& a, const Vec& b) {
  const Vec ab = sub(b, a);
  const double l = norm(ab);
  return l > 0 ? norm(cross(sub(x, a), ab)) / l : norm(sub(x, a));
}

double segment_distance(const Vec& x, const Vec& a, const Vec& b) {
  const Vec ab = sub(b, a);
  const double l = dot(ab, ab);
  const double t = l > 0 ? std::clamp(dot(sub(x, a), ab) / l, 0.0, 1.0) : 0.0;
  return norm(sub(x, Vec{a[0] + t * ab[0], a[1] + t * ab[1], a[2] + t * ab[2]}));
}

struct BentEdge {
  int a, b;
  double angle;  // degrees
  int sign = 0;  // +1 convex, -1 concave (set for the fading edges only)
};

// The soft features (FeatureOptions::soft_angle_degrees): from `bent` (interior edges that are not
// sharp, bending by at least half the soft angle), added to the sorted `edges` (protect: 0).
void add_soft_features(const MeshInput& mesh, const FeatureOptions& options, const std::vector<BentEdge>& bent,
                       std::vector<std::array<int, 2>>& edges, std::vector<char>& protect) {
  const int n = mesh.num_vertices();
  const auto& p = mesh.positions;
  const double reach = options.soft_reach;
  std::vector<std::vector<int>> at(n);  // bent edges per vertex
  for (int i = 0; i < static_cast<int>(bent.size()); ++i) at[bent[i].a].push_back(i), at[bent[i].b].push_back(i);
  // vertex neighbours (all edges) for the search within reach
  std::vector<std::vector<int>> nb(n);
  int begin = 0;
  for (int size : mesh.face_sizes) {
    for (int k = 0; k < size; ++k) {
      const int a = mesh.face_indices[begin + k], b = mesh.face_indices[begin + (k + 1) % size];
      nb[a].push_back(b);
      nb[b].push_back(a);
    }
    begin += size;
  }
  auto direction = [&](const BentEdge& e) {
    Vec d = sub(p[e.b], p[e.a]);
    const double l = norm(d);
    return l > 0 ? Vec{d[0] / l, d[1] / l, d[2] / l} : Vec{0, 0, 0};
  };
  auto middle = [&](const BentEdge& e) {
    return Vec{0.5 * (p[e.a][0] + p[e.b][0]), 0.5 * (p[e.a][1] + p[e.b][1]), 0.5 * (p[e.a][2] + p[e.b][2])};
  };
  std::vector<int> stamp(n, -1);
  std::vector<char> accepted(bent.size(), 0);
  std::vector<int> queue;
  for (int i = 0; i < static_cast<int>(bent.size()); ++i) {
    const BentEdge& e = bent[i];
    if (e.angle < options.soft_angle_degrees) continue;
    const Vec d = direction(e), m = middle(e);
    bool concentrated = true;
    std::vector<int> visit{e.a, e.b};
    stamp[e.a] = stamp[e.b] = i;
    for (size_t h = 0; h < visit.size() && concentrated; ++h) {
      for (int g : at[visit[h]]) {
        const BentEdge& o = bent[g];
        if (g == i || o.angle < 0.5 * e.angle) continue;
        if (segment_distance(m, p[o.a], p[o.b]) > reach) continue;
        const Vec r = sub(middle(o), m);
        const double along = dot(r, d);
        const Vec off{r[0] - along * d[0], r[1] - along * d[1], r[2] - along * d[2]};
        if (std::abs(dot(direction(o), d)) > 0.9 && norm(off) < 0.1 * reach) continue;  // continues it
        concentrated = false;
        break;
      }
      for (int w : nb[visit[h]])  // over the edges that pass within reach (long slivers too)
        if (stamp[w] != i && segment_distance(m, p[visit[h]], p[w]) <= reach) stamp[w] = i, visit.push_back(w);
    }
    if (concentrated) accepted[i] = 1, queue.push_back(i);
  }
  // grown along their lines through edges above the soft angle
  for (size_t h = 0; h < queue.size(); ++h) {
    const BentEdge& e = bent[queue[h]];
    const Vec d = direction(e);
    for (int v : {e.a, e.b})
      for (int g : at[v]) {
        if (accepted[g] || bent[g].angle < options.soft_angle_degrees) continue;
        if (std::abs(dot(direction(bent[g]), d)) < 0.9) continue;
        accepted[g] = 1;
        queue.push_back(g);
      }
  }
  // A soft line that continues a sharp feature curve (a crease fading out below the feature
  // angle) is dropped whole: an infinitely sharp crease cannot follow a fading one.
  std::vector<std::vector<Vec>> sharp_at(n);  // directions of the sharp edges at each vertex
  for (const auto& e : edges) {
    Vec d = sub(p[e[1]], p[e[0]]);
    const double l = norm(d);
    if (!(l > 0)) continue;
    d = {d[0] / l, d[1] / l, d[2] / l};
    sharp_at[e[0]].push_back(d);
    sharp_at[e[1]].push_back(d);
  }
  std::vector<int> component(bent.size(), -1);
  for (int i = 0; i < static_cast<int>(bent.size()); ++i) {
    if (!accepted[i] || component[i] >= 0) continue;
    std::vector<int> members{i};
    component[i] = i;
    bool continues = false;
    for (size_t h = 0; h < members.size(); ++h) {
      const BentEdge& e = bent[members[h]];
      const Vec d = direction(e);
      for (int v : {e.a, e.b}) {
        for (const Vec& sd : sharp_at[v]) continues |= std::abs(dot(sd, d)) > 0.9;
        for (int g : at[v])
          if (accepted[g] && component[g] < 0) component[g] = i, members.push_back(g);
      }
    }
    if (continues)
      for (int g : members) accepted[g] = 0;
  }
  for (int i = 0; i < static_cast<int>(bent.size()); ++i)
    if (accepted[i]) {
      const std::array<int, 2> e{std::min(bent[i].a, bent[i].b), std::max(bent[i].a, bent[i].b)};
      const auto it = std::lower_bound(edges.begin(), edges.end(), e);
      protect.insert(protect.begin() + (it - edges.begin()), 0);
      edges.insert(it, e);
    }
}

// Continues each open chain end of `edges` (a vertex on one feature edge) along its line through
// the `fading` edges (the straightest continuation, within 30 degrees of the chain's last edge),
// up to another feature curve (then a junction) or to where the bend falls below the fade angle
// (then a dart: recorded, sorted, in `darts`). Returns the number of edges added; `edges` stays sorted.
template <class BendSign, class IsTagged>
int continue_fading_chains(const MeshInput& mesh, const std::vector<BentEdge>& fading, BendSign&& bend_sign,
                           IsTagged&& is_tagged, std::vector<std::array<int, 2>>& edges, std::vector<int>& darts) {
  const int n = mesh.num_vertices();
  const auto& p = mesh.positions;
  std::vector<std::vector<int>> feature_at(n), fading_at(n);
  for (const auto& e : edges) feature_at[e[0]].push_back(e[1]), feature_at[e[1]].push_back(e[0]);
  for (int i = 0; i < static_cast<int>(fading.size()); ++i)
    fading_at[fading[i].a].push_back(i), fading_at[fading[i].b].push_back(i);
  auto unit = [&](int a, int b) {
    Vec d = sub(p[b], p[a]);
    const double l = norm(d);
    return l > 0 ? Vec{d[0] / l, d[1] / l, d[2] / l} : Vec{0, 0, 0};
  };
  const double kAlong = std::cos(30.0 * kPi / 180.0);  // an edge within 30 degrees of the line continues it
  std::vector<std::array<int, 2>> added;
  std::vector<char> taken(fading.size(), 0);
  std::vector<int> ends;  // the chains' open ends before any is continued
  for (int v = 0; v < n; ++v)
    if (feature_at[v].size() == 1 && !is_tagged(v, feature_at[v][0])) ends.push_back(v);  // a user's crease ends where it ends
  for (int end : ends) {
    if (feature_at[end].size() != 1) continue;  // joined by a chain continued before
    int prev = feature_at[end][0], cur = end;
    const int sign = bend_sign(prev, cur);  // the curve's: convex or concave
    double last = 180;                      // the bend of the last edge taken
    std::vector<int> walk;                  // the fading edges taken, in order
    bool joined = false;
    while (!joined && walk.size() < fading.size()) {
      const Vec d = unit(prev, cur);
      int best = -1, next = -1;
      double best_cos = kAlong;
      for (int g : fading_at[cur]) {
        if (taken[g]) continue;
        const int w = fading[g].a == cur ? fading[g].b : fading[g].a;
        const double c = dot(unit(cur, w), d);
        if (c > best_cos) best_cos = c, best = g, next = w;
      }
      // A crease fades: the straightest continuation bends the same way, by less than the edge
      // before it (noise on a smooth part neither keeps its sign nor falls steadily; a tight
      // smooth bend of a scan keeps its angle: with 1 degree of slack, Blub's scan gained 225
      // such edges and its fit took 10 x longer).
      if (best < 0 || fading[best].sign != sign || !(fading[best].angle < last)) break;
      // ... and the bend is the crease's, not the surface's: no other edge at either end (but
      // those continuing the line) bends as much (the facets of a coarse sphere bend alike).
      bool concentrated = true;
      for (int v : {cur, next})
        for (int g : fading_at[v]) {
          if (g == best || fading[g].angle < fading[best].angle) continue;
          const int w = fading[g].a == v ? fading[g].b : fading[g].a;
          if (w == prev || std::abs(dot(unit(v, w), d)) > kAlong) continue;  // along the line
          concentrated = false;
        }
      // Where it is not, the crease has sunk into the facets' own bends: that edge is its last.
      const bool last_edge = !concentrated;
      last = fading[best].angle;
      joined = !feature_at[next].empty();  // the crease runs on into another feature curve: a junction
      taken[best] = 1;
      walk.push_back(best);
      prev = cur, cur = next;
      if (last_edge) break;
    }
    if (walk.empty()) continue;
    for (int g : walk) {
      added.push_back({std::min(fading[g].a, fading[g].b), std::max(fading[g].a, fading[g].b)});
      feature_at[fading[g].a].push_back(fading[g].b), feature_at[fading[g].b].push_back(fading[g].a);
    }
    if (!joined) darts.push_back(cur);
  }
  // A dart that a later chain ran into is a junction (or a point of that chain), not an end.
  darts.erase(std::remove_if(darts.begin(), darts.end(), [&](int v) { return feature_at[v].size() != 1; }), darts.end());
  edges.insert(edges.end(), added.begin(), added.end());
  std::sort(edges.begin(), edges.end());
  std::sort(darts.begin(), darts.end());
  return static_cast<int>(added.size());
}

// Plane edges: a plane is at least this many times as wide as the polygon beyond its edge.
constexpr double kPlaneOverFacet = 3;

}  // namespace

FeatureSet detect_features(const MeshInput& mesh, const FeatureOptions& options) {
  int n = mesh.num_vertices();
  // Every edge with its faces, sorted by key so that the result is independent of hashing.
  struct EdgeFace {
    std::int64_t key;
    int face;
  };
  std::vector<EdgeFace> ef;
  std::vector<Vec> normals(mesh.num_faces()), centre(mesh.num_faces(), Vec{0, 0, 0});
  int begin = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    int size = mesh.face_sizes[f];
    normals[f] = face_normal(mesh, begin, size);
    for (int k = 0; k < size; ++k)
      for (int c = 0; c < 3; ++c) centre[f][c] += mesh.positions[mesh.face_indices[begin + k]][c] / size;
    for (int k = 0; k < size; ++k) {
      int a = mesh.face_indices[begin + k], b = mesh.face_indices[begin + (k + 1) % size];
      ef.push_back({std::int64_t(std::min(a, b)) * n + std::max(a, b), f});
    }
    begin += size;
  }
  std::sort(ef.begin(), ef.end(), [](const EdgeFace& x, const EdgeFace& y) {
    return x.key != y.key ? x.key < y.key : x.face < y.face;
  });
  // Which way the edge from vertex a between faces f and g bends: +1 convex (g's centre below f's
  // plane), -1 concave, 0 flat.
  auto faces_bend_sign = [&](int a, int f, int g) {
    const double h = dot(normals[f], sub(centre[g], mesh.positions[a]));
    return h < 0 ? 1 : h > 0 ? -1 : 0;
  };
  // ... of the edge (a, b), looked up: 0 on the boundary.
  auto bend_sign = [&](int a, int b) {
    const std::int64_t key = std::int64_t(std::min(a, b)) * n + std::max(a, b);
    const auto it = std::lower_bound(ef.begin(), ef.end(), key, [](const EdgeFace& x, std::int64_t k) { return x.key < k; });
    if (it == ef.end() || it + 1 == ef.end() || it->key != key || (it + 1)->key != key) return 0;
    return faces_bend_sign(a, it->face, (it + 1)->face);
  };
  std::vector<std::int64_t> tagged;
  for (const auto& c : mesh.creases)
    if (c.sharpness >= kInfiniteSharpness && c.v0 != c.v1 && c.v0 >= 0 && c.v1 >= 0 && c.v0 < n && c.v1 < n)
      tagged.push_back(std::int64_t(std::min(c.v0, c.v1)) * n + std::max(c.v0, c.v1));
  std::sort(tagged.begin(), tagged.end());

  double cos_limit = std::cos(options.angle_degrees * kPi / 180.0);
  const bool soft = options.soft_angle_degrees > 0 && options.soft_reach > 0 &&
                    options.soft_angle_degrees < options.angle_degrees;
  std::vector<BentEdge> bent;  // interior edges that are not sharp, bending by half the soft angle or more
  std::vector<std::array<int, 2>> edges;
  std::vector<char> protect;  // boundary or tagged: never dropped
  const bool fade = options.fade_angle_degrees > 0 && options.fade_angle_degrees < options.angle_degrees;
  std::vector<BentEdge> fading;  // interior edges that are not sharp, bending by more than the fade angle
  // Plane edges (options.plane_of_polygon): an edge between polygon f (in a planar region) and g.
  const bool planes = !options.plane_of_polygon.empty() && options.plane_radius > 0;
  if (planes && static_cast<int>(options.plane_of_polygon.size()) != mesh.num_faces())
    throw Error(ErrorKind::Settings, "features: plane_of_polygon has " + std::to_string(options.plane_of_polygon.size()) +
                                         " entries for " + std::to_string(mesh.num_faces()) + " polygons");
  const std::vector<int>& region = options.plane_of_polygon;
  const std::vector<double>& region_width = options.plane_widths;
  std::vector<int> face_begin(mesh.num_faces() + 1, 0);
  for (int f = 0; f < mesh.num_faces(); ++f) face_begin[f + 1] = face_begin[f] + mesh.face_sizes[f];
  std::vector<std::int64_t> plane_keys;  // added after the soft features (a plane edge may be one, grown along its line)
  auto plane_edge = [&](int a, int b, int f, int g) {
    if (region[f] == region[g]) return false;
    const Vec &nf = normals[f], &ng = normals[g];
    const double bend = std::atan2(norm(cross(nf, ng)), dot(nf, ng));  // radians
    if (!(bend >= kPi / 180)) return false;
    // The plane `in` ends at the edge if the polygon beyond, `out`, is much narrower across the
    // edge than the plane is wide (a fillet's facet, not the next facet of a faceted cylinder,
    // which is as wide as this one) and the surface turns on it with a radius below plane_radius.
    auto ends = [&](int in, int out) {
      if (region[in] < 0 || region[in] >= static_cast<int>(region_width.size())) return false;
      double width = 0;  // out's width across the edge: its farthest vertex from the edge's line
      for (int k = face_begin[out]; k < face_begin[out + 1]; ++k)
        width = std::max(width, line_distance(mesh.positions[mesh.face_indices[k]], mesh.positions[a], mesh.positions[b]));
      return width * kPlaneOverFacet <= region_width[region[in]] && width < 2 * bend * options.plane_radius;
    };
    return ends(f, g) || ends(g, f);
  };
  for (size_t i = 0; i < ef.size();) {
    size_t j = i;
    while (j < ef.size() && ef[j].key == ef[i].key) ++j;
    if (j - i > 2)
      throw Error(ErrorKind::Input, "edge " + std::to_string(ef[i].key / n) + "-" + std::to_string(ef[i].key % n) +
                                        " is on " + std::to_string(j - i) + " faces: the mesh is not manifold");
    bool is_tagged = std::binary_search(tagged.begin(), tagged.end(), ef[i].key);
    bool sharp = j - i == 1 || is_tagged;
    if (!sharp) {
      const Vec& a = normals[ef[i].face];
      const Vec& b = normals[ef[i + 1].face];
      double l = norm(a) * norm(b);
      sharp = l > 0 && dot(a, b) < cos_limit * l;
      if (!sharp && planes && plane_edge(int(ef[i].key / n), int(ef[i].key % n), ef[i].face, ef[i + 1].face))
        plane_keys.push_back(ef[i].key);
    }
    if (sharp) {
      edges.push_back({int(ef[i].key / n), int(ef[i].key % n)});
      protect.push_back(j - i == 1 || is_tagged);
    } else if (soft || fade) {
      const Vec& a = normals[ef[i].face];
      const Vec& b = normals[ef[i + 1].face];
      const double l = norm(a) * norm(b);
      const double angle = l > 0 ? std::acos(std::clamp(dot(a, b) / l, -1.0, 1.0)) * 180.0 / kPi : 0.0;
      BentEdge e{int(ef[i].key / n), int(ef[i].key % n), angle};
      if (soft && angle >= 0.5 * options.soft_angle_degrees) bent.push_back(e);
      if (fade && angle > options.fade_angle_degrees) e.sign = faces_bend_sign(e.a, ef[i].face, ef[i + 1].face), fading.push_back(e);
    }
    i = j;
  }
  if (soft) add_soft_features(mesh, options, bent, edges, protect);
  int plane_edges = 0;
  for (std::int64_t key : plane_keys) {
    const std::array<int, 2> e{int(key / n), int(key % n)};
    const auto it = std::lower_bound(edges.begin(), edges.end(), e);
    if (it != edges.end() && *it == e) continue;  // a soft feature already
    protect.insert(protect.begin() + (it - edges.begin()), 0);
    edges.insert(it, e);
    ++plane_edges;
  }

  std::vector<std::vector<int>> adjacent;
  std::vector<char> corner = find_corners(mesh, edges, options.corner_angle_degrees, adjacent);
  FeatureSet result;
  // Drop short isolated open chains (both ends dangling) made only of dihedral edges.
  std::vector<std::int64_t> dropped;
  for (const auto& chain : walk_chains(adjacent, corner)) {
    int first = chain.front(), last = chain.back();
    int length = static_cast<int>(chain.size()) - 1;
    if (first == last || length >= options.min_chain_edges) continue;
    if (adjacent[first].size() != 1 || adjacent[last].size() != 1) continue;
    bool keep = false;
    for (size_t k = 0; k + 1 < chain.size(); ++k) {
      std::int64_t key = std::int64_t(std::min(chain[k], chain[k + 1])) * n + std::max(chain[k], chain[k + 1]);
      auto it = std::lower_bound(edges.begin(), edges.end(), std::array<int, 2>{int(key / n), int(key % n)});
      if (protect[it - edges.begin()]) keep = true;
    }
    if (keep) continue;
    ++result.dropped_short_chains;
    for (size_t k = 0; k + 1 < chain.size(); ++k)
      dropped.push_back(std::int64_t(std::min(chain[k], chain[k + 1])) * n + std::max(chain[k], chain[k + 1]));
  }
  std::sort(dropped.begin(), dropped.end());
  for (const auto& e : edges)
    if (!std::binary_search(dropped.begin(), dropped.end(), std::int64_t(e[0]) * n + e[1])) result.edges.push_back(e);
  auto is_tagged = [&](int a, int b) {
    return std::binary_search(tagged.begin(), tagged.end(), std::int64_t(std::min(a, b)) * n + std::max(a, b));
  };
  result.plane_edges = plane_edges;
  if (fade) result.faded_edges = continue_fading_chains(mesh, fading, bend_sign, is_tagged, result.edges, result.darts);
  corner = find_corners(mesh, result.edges, options.corner_angle_degrees, adjacent);
  for (int v = 0; v < n; ++v)
    if (corner[v]) result.corners.push_back(v);
  result.chains = static_cast<int>(walk_chains(adjacent, corner).size());
  return result;
}

}  // namespace subd2nurbs
