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
    }
    i = j;
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
  corner = find_corners(mesh, result.edges, options.corner_angle_degrees, adjacent);
  for (int v = 0; v < n; ++v)
    if (corner[v]) result.corners.push_back(v);
  result.chains = static_cast<int>(walk_chains(adjacent, corner).size());
  return result;
}

}  // namespace subd2nurbs
