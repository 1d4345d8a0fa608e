#include "core/features/features.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>

#include "core/util/constants.h"
#include "core/util/error.h"

namespace subd2nurbs {
namespace {

using Vec = std::array<double, 3>;

Vec sub(const Vec& a, const Vec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(const Vec& a) { return std::sqrt(dot(a, a)); }

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

double segment_distance(const Vec& x, const Vec& a, const Vec& b) {
  const Vec ab = sub(b, a);
  const double l = dot(ab, ab);
  const double t = l > 0 ? std::clamp(dot(sub(x, a), ab) / l, 0.0, 1.0) : 0.0;
  return norm(sub(x, Vec{a[0] + t * ab[0], a[1] + t * ab[1], a[2] + t * ab[2]}));
}

struct BentEdge {
  int a, b;
  double angle;  // degrees
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

}  // namespace

FeatureSet detect_features(const MeshInput& mesh, const FeatureOptions& options) {
  int n = mesh.num_vertices();
  // Every edge with its faces, sorted by key so that the result is independent of hashing.
  struct EdgeFace {
    std::int64_t key;
    int face;
  };
  std::vector<EdgeFace> ef;
  std::vector<Vec> normals(mesh.num_faces());
  int begin = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    int size = mesh.face_sizes[f];
    normals[f] = face_normal(mesh, begin, size);
    for (int k = 0; k < size; ++k) {
      int a = mesh.face_indices[begin + k], b = mesh.face_indices[begin + (k + 1) % size];
      ef.push_back({std::int64_t(std::min(a, b)) * n + std::max(a, b), f});
    }
    begin += size;
  }
  std::sort(ef.begin(), ef.end(), [](const EdgeFace& x, const EdgeFace& y) {
    return x.key != y.key ? x.key < y.key : x.face < y.face;
  });
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
    }
    if (sharp) {
      edges.push_back({int(ef[i].key / n), int(ef[i].key % n)});
      protect.push_back(j - i == 1 || is_tagged);
    } else if (soft) {
      const Vec& a = normals[ef[i].face];
      const Vec& b = normals[ef[i + 1].face];
      const double l = norm(a) * norm(b);
      const double angle = l > 0 ? std::acos(std::clamp(dot(a, b) / l, -1.0, 1.0)) * 180.0 / kPi : 0.0;
      if (angle >= 0.5 * options.soft_angle_degrees) bent.push_back({int(ef[i].key / n), int(ef[i].key % n), angle});
    }
    i = j;
  }
  if (soft) add_soft_features(mesh, options, bent, edges, protect);

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
  corner = find_corners(mesh, result.edges, options.corner_angle_degrees, adjacent);
  for (int v = 0; v < n; ++v)
    if (corner[v]) result.corners.push_back(v);
  result.chains = static_cast<int>(walk_chains(adjacent, corner).size());
  return result;
}

}  // namespace subd2nurbs
