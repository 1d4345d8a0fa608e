#include "core/analysis/mesh_stats.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

namespace subd2nurbs {

bool is_automatic_corner(const SubdivLevel& level, int v) {
  return level.vertex_sharpness[v] >= kInfiniteSharpness &&
         is_sharpened_by_tagging(level.mesh, level.options.boundary, v);
}

namespace {

/// Follows every boundary loop once. The boundary halfedge leaving a boundary vertex is the
/// first corner of its fan, so the loop continues from to_vertex(h) with that vertex's
/// first corner.
int count_boundary_loops(const PolyMesh& m) {
  std::vector<char> seen(m.num_edges(), 0);
  int loops = 0;
  for (int e = 0; e < m.num_edges(); ++e) {
    if (!m.is_boundary_edge(e) || seen[e]) continue;
    ++loops;
    int h = m.edge_corner(e);
    while (!seen[m.corner_edge(h)]) {
      seen[m.corner_edge(h)] = 1;
      h = m.vertex_corners(m.to_vertex(h))[0];
    }
  }
  return loops;
}

/// Groups of faces connected through shared edges (union-find over faces).
int count_components(const PolyMesh& m) {
  std::vector<int> parent(m.num_faces());
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int f) {
    while (parent[f] != f) f = parent[f] = parent[parent[f]];
    return f;
  };
  int components = m.num_faces();
  for (int h = 0; h < m.num_corners(); ++h) {
    if (m.twin(h) < 0) continue;
    const int a = root(m.corner_face(h)), b = root(m.corner_face(m.twin(h)));
    if (a != b) {
      parent[a] = b;
      --components;
    }
  }
  return components;
}

}  // namespace

MeshStats compute_stats(const SubdivLevel& level, const std::vector<Point3>& positions) {
  const PolyMesh& m = level.mesh;
  if (static_cast<int>(positions.size()) != m.num_vertices())
    throw std::invalid_argument("compute_stats: " + std::to_string(positions.size()) +
                                " positions for " + std::to_string(m.num_vertices()) +
                                " vertices");
  MeshStats s;
  s.vertices = m.num_vertices();
  s.faces = m.num_faces();
  s.edges = m.num_edges();
  s.corners = m.num_corners();

  for (int f = 0; f < m.num_faces(); ++f) {
    ++s.face_sizes[m.face_size(f)];
    if (f < static_cast<int>(level.face_hole.size()) && level.face_hole[f]) ++s.holes;
  }

  for (int e = 0; e < m.num_edges(); ++e) {
    if (m.is_boundary_edge(e)) {
      ++s.boundary_edges;
      continue;
    }
    const double sharpness = level.edge_sharpness[e];
    if (sharpness >= kInfiniteSharpness) ++s.infinite_crease_edges;
    else if (sharpness > 0) ++s.semi_sharp_crease_edges;
  }
  s.boundary_loops = count_boundary_loops(m);

  int used = 0;
  bool first = true;
  for (int v = 0; v < m.num_vertices(); ++v) {
    if (m.is_unused_vertex(v)) {
      ++s.unused_vertices;
      continue;
    }
    ++used;
    const int valence = m.valence(v);
    ++s.valences[valence];
    const bool boundary = m.is_boundary_vertex(v);
    const bool corner = m.is_topological_corner(v);
    if (boundary) ++s.boundary_vertices;
    if (corner) ++s.topological_corners;
    if (level.vertex_sharpness[v] > 0 && !is_automatic_corner(level, v)) ++s.corner_vertices;
    if (boundary ? (!corner && valence != 3) : valence != 4) ++s.extraordinary_vertices;

    const Point3& p = positions[v];
    for (int k = 0; k < 3; ++k) {
      s.bounds.min[k] = first ? p[k] : std::min(s.bounds.min[k], p[k]);
      s.bounds.max[k] = first ? p[k] : std::max(s.bounds.max[k], p[k]);
    }
    first = false;
  }
  s.bounds.diagonal = std::hypot(s.bounds.max[0] - s.bounds.min[0],
                                 s.bounds.max[1] - s.bounds.min[1],
                                 s.bounds.max[2] - s.bounds.min[2]);

  s.components = count_components(m);
  s.euler_characteristic = used - s.edges + s.faces;
  s.closed = s.boundary_edges == 0;
  return s;
}

}  // namespace subd2nurbs
