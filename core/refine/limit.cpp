// Limit positions of vertices (docs/math.md section 2; OpenSubdiv's catmarkScheme.h limit masks).
#include <Eigen/Dense>

#include "core/refine/refiner.h"

namespace subd2nurbs {

namespace {

/// True when every vertex of the level has a closed-form limit mask: all faces quads and
/// no semi-sharp edge or vertex.
bool has_closed_form_limits(const SubdivLevel& level) {
  return level.mesh.all_quads() && level.max_semi_sharpness() == 0.0;
}

/// The limit mask of a smooth interior vertex of valence n >= 3 between quads:
/// p = (n^2 v + 4 sum e_r + sum d_r) / (n (n + 5)), e_r its edge neighbours, d_r the corners
/// opposite it.
struct SmoothLimitMask {
  double vertex, edge, diagonal;
  explicit SmoothLimitMask(int valence) {
    const double n = valence;
    diagonal = 1.0 / (n * (n + 5.0));
    edge = 4.0 * diagonal;
    vertex = 1.0 - n * (edge + diagonal);
  }
};

}  // namespace

std::vector<double> ring_limit_weights(int n, int sharp) {
  const int N = 2 * n + 1;
  if (sharp < 0 && n > kDenseValence) {
    // A smooth vertex: the closed form (SmoothLimitMask), the left eigenvector solved for below
    // to rounding (the solve is O(n^3): 7 s at valence 1000; up to kDenseValence it is kept,
    // bit for bit what every conversion made so far).
    const SmoothLimitMask w(n);
    std::vector<double> l(N);
    l[0] = w.vertex;
    for (int r = 0; r < n; ++r) {
      l[1 + r] = w.edge;
      l[1 + n + r] = w.diagonal;
    }
    return l;
  }
  auto E = [](int r) { return 1 + r; };
  auto D = [n](int r) { return 1 + n + r; };
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(N, N);
  auto face_point = [&](int row, int r, double w) {  // w * centre of quad (v, e_r, d_r, e_{r+1})
    S(row, 0) += w / 4;
    S(row, E(r)) += w / 4;
    S(row, D(r)) += w / 4;
    S(row, E((r + 1) % n)) += w / 4;
  };
  const double nn = n;
  S(0, 0) = (nn - 2) / nn;
  for (int r = 0; r < n; ++r) {
    S(0, E(r)) += 1 / (nn * nn);
    face_point(0, r, 1 / (nn * nn));
  }
  for (int r = 0; r < n; ++r) {
    if (r == sharp) {
      S(E(r), 0) = 0.5;
      S(E(r), E(r)) = 0.5;
    } else {
      S(E(r), 0) += 0.25;
      S(E(r), E(r)) += 0.25;
      face_point(E(r), r, 0.25);
      face_point(E(r), (r + n - 1) % n, 0.25);
    }
    face_point(D(r), r, 1.0);
  }
  // Solve l^T (S - I) = 0 with sum(l) = 1: replace one equation by the normalisation.
  Eigen::MatrixXd A = (S - Eigen::MatrixXd::Identity(N, N)).transpose();
  A.row(0).setOnes();
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(N);
  rhs(0) = 1;
  Eigen::VectorXd l = A.fullPivLu().solve(rhs);
  return std::vector<double>(l.data(), l.data() + N);
}

namespace {

StencilTable closed_form_limit_stencils(const SubdivLevel& level) {
  const PolyMesh& m = level.mesh;
  StencilTable t;
  t.num_sources = m.num_vertices();
  for (int v = 0; v < m.num_vertices(); ++v) {
    auto add = [&](int s, double w) {
      t.indices.push_back(s);
      t.weights.push_back(w);
    };
    const int nf = m.vertex_face_count(v);
    VertexRule rule = nf == 0 ? VertexRule::Corner : vertex_rule(level, v);
    // Darts and smooth valence-2 vertices have no closed-form mask: solve for the exact one.
    // (OpenSubdiv approximates them by the smooth mask and by the vertex itself.)
    if (rule == VertexRule::Dart || (rule == VertexRule::Smooth && nf == 2)) {
      const int* c = m.vertex_corners(v);
      int sharp = -1;
      if (rule == VertexRule::Dart)
        for (int i = 0; i < nf; ++i)
          if (level.edge_sharpness[m.corner_edge(c[i])] > 0.0f) sharp = i;
      const std::vector<double> w = ring_limit_weights(nf, sharp);
      add(v, w[0]);
      for (int i = 0; i < nf; ++i) {
        add(m.to_vertex(c[i]), w[1 + i]);
        add(m.corner_vertex(m.next(m.next(c[i]))), w[1 + nf + i]);
      }
      t.offsets.push_back(static_cast<int>(t.indices.size()));
      continue;
    }
    switch (rule) {
      case VertexRule::Dart:
      case VertexRule::Smooth: {
        const SmoothLimitMask w(nf);  // d_r opposite v in each quad
        add(v, w.vertex);
        const int* c = m.vertex_corners(v);
        for (int i = 0; i < nf; ++i) {
          add(m.to_vertex(c[i]), w.edge);
          add(m.corner_vertex(m.next(m.next(c[i]))), w.diagonal);
        }
        break;
      }
      case VertexRule::Crease: {  // p = (b0 + 4 v + b1) / 6 over the two sharp edges
        add(v, 2.0 / 3.0);
        for_each_vertex_edge(m, v, [&](int e, int other) {
          if (level.edge_sharpness[e] > 0.0f) add(other, 1.0 / 6.0);
        });
        break;
      }
      case VertexRule::Corner:
        add(v, 1.0);
        break;
    }
    t.offsets.push_back(static_cast<int>(t.indices.size()));
  }
  return t;
}

}  // namespace

StencilTable limit_stencils(const SubdivLevel& level) {
  if (has_closed_form_limits(level)) return closed_form_limit_stencils(level);
  // No closed form here (n-gons, or semi-sharp features still active): the limit of a vertex
  // is the limit of its vertex-child, so refine once and compose.
  RefinementStep step = refine_once(level);
  StencilTable child_limits = limit_stencils(step.child);
  StencilTable vertex_children;
  vertex_children.num_sources = child_limits.num_sources;
  for (int v = 0; v < level.mesh.num_vertices(); ++v) {
    const int r = child_of_vertex(level.mesh, v);
    for (int k = child_limits.offsets[r]; k < child_limits.offsets[r + 1]; ++k) {
      vertex_children.indices.push_back(child_limits.indices[k]);
      vertex_children.weights.push_back(child_limits.weights[k]);
    }
    vertex_children.offsets.push_back(static_cast<int>(vertex_children.indices.size()));
  }
  return vertex_children.compose(step.stencils);
}

}  // namespace subd2nurbs
