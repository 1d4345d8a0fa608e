#include "core/polar/polar_separation.h"

#include <stdexcept>

#include <Eigen/Core>

#include "core/polar/polar_refine.h"
#include "core/util/eigen_point.h"

namespace subd2nurbs {

std::string separation_obstacle(const SubdivLevel& level, int pole) {
  const PolyMesh& m = level.mesh;
  const std::string v = "vertex " + std::to_string(pole);
  const int n = m.vertex_face_count(pole);
  if (n < 3 || m.is_boundary_vertex(pole)) return v + " is not an interior vertex";
  if (level.vertex_sharpness[pole] > 0) return v + " has a corner tag";
  for (int i = 0; i < n; ++i) {
    const int h = m.vertex_corners(pole)[i];
    if (m.face_size(m.corner_face(h)) != 3) return "not all faces at " + v + " are triangles";
    const int r = m.to_vertex(h);
    if (m.is_boundary_vertex(r) || m.valence(r) != 4)
      return "its neighbour vertex " + std::to_string(r) + " is not interior and 4-valent";
    if (level.vertex_sharpness[r] > 0) return "its neighbour vertex " + std::to_string(r) + " has a corner tag";
    bool sharp = false;
    for_each_vertex_edge(m, r, [&](int e, int) { sharp = sharp || level.edge_sharpness[e] > 0; });
    if (sharp) return "an edge at its neighbour vertex " + std::to_string(r) + " is creased";
  }
  return {};
}

SeparatedLevel separate_poles(const SubdivLevel& base, const std::vector<Point3>& positions,
                              const std::vector<int>& poles, double w) {
  using V3 = Eigen::Vector3d;
  const PolyMesh& m = base.mesh;
  for (int p : poles) {
    const std::string why = separation_obstacle(base, p);
    if (!why.empty()) throw std::invalid_argument("separate_poles: vertex " + std::to_string(p) + ": " + why);
  }
  RefinementStep step = refine_once(base);
  std::vector<Point3> x;
  step.stencils.apply(positions, x);
  const PolyMesh& m1 = step.child.mesh;

  // Face points: the degenerate-quad rule at the separated poles' triangles.
  std::vector<char> at_pole(m.num_vertices(), 0);
  for (int p : poles) at_pole[p] = 1;
  std::vector<V3> face_point(m.num_faces());
  for (int f = 0; f < m.num_faces(); ++f) face_point[f] = to_eigen(x[child_of_face(m, f)]);
  for (int p : poles)
    for (int i = 0; i < m.vertex_face_count(p); ++i)
      if (at_pole[m.to_vertex(m.vertex_corners(p)[i])])
        throw std::invalid_argument("separate_poles: vertices " + std::to_string(p) + " and " +
                                    std::to_string(m.to_vertex(m.vertex_corners(p)[i])) +
                                    " are neighbours; separate one of them at a time");
  std::vector<char> touched_vertex(m.num_vertices(), 0), modified_face(m.num_faces(), 0);
  for (int f = 0; f < m.num_faces(); ++f) {
    if (m.face_size(f) != 3) continue;
    for (int i = 0; i < 3; ++i) {
      const int h = m.face_begin(f) + i;
      if (!at_pole[m.corner_vertex(h)]) continue;
      const V3 p0 = to_eigen(positions[m.corner_vertex(h)]);
      face_point[f] = (2 * p0 + to_eigen(positions[m.to_vertex(h)]) + to_eigen(positions[m.corner_vertex(m.prev(h))])) / 4;
      x[child_of_face(m, f)] = to_point(face_point[f]);
      modified_face[f] = 1;
      for (int k = 0; k < 3; ++k) touched_vertex[m.corner_vertex(m.face_begin(f) + k)] = 1;
    }
  }
  // Smooth edge points of every edge of those triangles, smooth vertex points of their ring
  // vertices (interior, untagged: checked above), the BP-weighted pole.
  for (int e = 0; e < m.num_edges(); ++e) {
    const int h = m.edge_corner(e), t = m.twin(h);
    if (t < 0) continue;  // the triangles' edges are interior (their vertices are)
    const int fa = m.corner_face(h), fb = m.corner_face(t);
    if (!modified_face[fa] && !modified_face[fb]) continue;
    const int a = m.edge_vertex(e, 0), b = m.edge_vertex(e, 1);
    x[child_of_edge(m, e)] = to_point((to_eigen(positions[a]) + to_eigen(positions[b]) + face_point[fa] + face_point[fb]) / 4);
  }
  for (int v = 0; v < m.num_vertices(); ++v) {
    if (!touched_vertex[v] || at_pole[v]) continue;
    const int n = m.vertex_face_count(v);
    V3 F = V3::Zero(), R = V3::Zero();
    for (int i = 0; i < n; ++i) F += face_point[m.corner_face(m.vertex_corners(v)[i])];
    for_each_vertex_edge(m, v, [&](int, int other) { R += (to_eigen(positions[v]) + to_eigen(positions[other])) / 2; });
    x[child_of_vertex(m, v)] = to_point((F / n + 2 * R / n + (n - 3) * to_eigen(positions[v])) / n);
  }
  for (int p : poles) {
    V3 mean = V3::Zero();
    for (int i = 0; i < m.vertex_face_count(p); ++i) mean += to_eigen(positions[m.to_vertex(m.vertex_corners(p)[i])]);
    mean /= m.vertex_face_count(p);
    x[child_of_vertex(m, p)] = to_point((1 - w) * to_eigen(positions[p]) + w * mean);
  }

  // Topology: level-1 face h (the child of corner h) at a separated pole splits into two
  // triangles along (P0', F_i).
  SeparatedLevel out;
  std::vector<int> sizes, faces, extra_faces, extra_cage_faces;
  for (int h = 0; h < m1.num_faces(); ++h) {
    const int* fv = m1.face_vertices(h);
    out.cage_face.push_back(m.corner_face(h));
    if (at_pole[m.corner_vertex(h)] && m.face_size(m.corner_face(h)) == 3) {
      // (P0', E_i, F_i, E_i+1) -> (P0', E_i, F_i) here, (P0', F_i, E_i+1) at the end.
      sizes.push_back(3);
      faces.insert(faces.end(), {fv[0], fv[1], fv[2]});
      extra_faces.insert(extra_faces.end(), {fv[0], fv[2], fv[3]});
      extra_cage_faces.push_back(m.corner_face(h));
    } else {
      sizes.push_back(m1.face_size(h));
      faces.insert(faces.end(), fv, fv + m1.face_size(h));
    }
  }
  std::vector<int> face_source(sizes.size());
  for (size_t f = 0; f < face_source.size(); ++f) face_source[f] = static_cast<int>(f);
  sizes.insert(sizes.end(), extra_cage_faces.size(), 3);
  faces.insert(faces.end(), extra_faces.begin(), extra_faces.end());
  face_source.insert(face_source.end(), extra_cage_faces.size(), -1);
  out.cage_face.insert(out.cage_face.end(), extra_cage_faces.begin(), extra_cage_faces.end());
  std::vector<int> identity(m1.num_vertices());
  for (int v = 0; v < m1.num_vertices(); ++v) identity[v] = v;
  out.level = rebuild_level(step.child, identity, m1.num_vertices(), sizes, faces, face_source);
  out.positions = std::move(x);
  return out;
}

}  // namespace subd2nurbs
