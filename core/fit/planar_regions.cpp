#include "core/fit/planar_regions.h"

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/fit/shape_target.h"
#include "core/limit/limit_evaluator.h"
#include "core/util/vec3.h"

namespace subd2nurbs {
namespace {

using vec3::sub;
using vec3::dot;
using vec3::cross;
using vec3::norm;

struct Plane {
  Point3 point{}, normal{};
  double distance(const Point3& p) const { return std::abs(dot(sub(p, point), normal)); }
};

/// The least-squares plane of `vertices` (their mean; the covariance's smallest eigenvector),
/// oriented along `towards`.
Plane fit_plane(const std::vector<Point3>& points, const std::vector<int>& vertices, const Point3& towards) {
  Plane pl;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int v : vertices) mean += Eigen::Vector3d(points[v][0], points[v][1], points[v][2]);
  mean /= static_cast<double>(vertices.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int v : vertices) {
    const Eigen::Vector3d d = Eigen::Vector3d(points[v][0], points[v][1], points[v][2]) - mean;
    cov += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Eigen::Vector3d n = eig.eigenvectors().col(0);
  if (n.dot(Eigen::Vector3d(towards[0], towards[1], towards[2])) < 0) n = -n;
  pl.point = {mean[0], mean[1], mean[2]};
  pl.normal = {n[0], n[1], n[2]};
  return pl;
}

/// The closest point x to p on every plane of `ids` (p + N^+ (d - N p), N's pseudo-inverse with
/// singular values below 1e-2 of the largest dropped: near-parallel planes); false when x misses
/// a plane by more than 1e-9 x diagonal (parallel planes apart).
bool onto_planes(const std::vector<Plane>& planes, const std::vector<int>& ids, const Point3& p3, double diagonal,
                 Point3& out) {
  const int k = static_cast<int>(ids.size());
  Eigen::MatrixXd N(k, 3);
  Eigen::VectorXd d(k);
  const Eigen::Vector3d p(p3[0], p3[1], p3[2]);
  for (int i = 0; i < k; ++i) {
    const Plane& pl = planes[ids[i]];
    N.row(i) << pl.normal[0], pl.normal[1], pl.normal[2];
    d[i] = dot(pl.normal, pl.point);
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(N, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd sv = svd.singularValues();
  const Eigen::VectorXd rhs = svd.matrixU().transpose() * (d - N * p);
  Eigen::Vector3d x = p;
  for (int i = 0; i < sv.size(); ++i)
    if (sv[i] > 1e-2 * sv[0]) x += svd.matrixV().col(i) * (rhs[i] / sv[i]);
  for (int i = 0; i < k; ++i)
    if (std::abs(N.row(i).dot(x) - d[i]) > 1e-9 * diagonal) return false;
  out = {x[0], x[1], x[2]};
  return true;
}

/// Whether cage face f, on `pl`, turns strictly left at each corner seen from the plane's normal
/// side (a strictly convex polygon, oriented as the region): false for an inverted, folded or
/// non-convex face, whose limit can fold over its neighbours.
bool convex_in_plane(const PolyMesh& m, int f, const std::vector<Point3>& x, const Plane& pl) {
  const int b = m.face_begin(f), n = m.face_size(f);
  for (int i = 0; i < n; ++i) {
    const Point3& p = x[m.corner_vertex(b + (i + n - 1) % n)];
    const Point3& q = x[m.corner_vertex(b + i)];
    const Point3& r = x[m.corner_vertex(b + (i + 1) % n)];
    if (!(dot(cross(sub(q, p), sub(r, q)), pl.normal) > 0)) return false;
  }
  return true;
}

/// The in-plane layout of each region's free vertices (FlattenStats::vertices_free): where the
/// region has faces that are not strictly convex in the plane (the fit moves held vertices freely
/// along their plane, and folds quads there), the free vertices are placed at the average of
/// their edge neighbours (a discrete harmonic map with the other vertices fixed: Tutte's
/// embedding), kept when fewer of the region's faces are then not convex. A free vertex only
/// moves the limit of faces of its own region, within the plane: the limit surface stays the
/// same region of the plane, only its parametrisation changes.
void untangle_regions(const SubdivLevel& cage, const std::vector<int>& face_region, const std::vector<char>& free,
                      const std::vector<int>& vertex_region, const std::vector<Plane>& planes, std::vector<Point3>& x,
                      FlattenStats& s) {
  const PolyMesh& m = cage.mesh;
  const int nf = m.num_faces(), nv = m.num_vertices();
  for (int r = 0; r < static_cast<int>(planes.size()); ++r) {
    std::vector<int> index(nv, -1), vertices;
    for (int v = 0; v < nv; ++v)
      if (free[v] && vertex_region[v] == r) index[v] = static_cast<int>(vertices.size()), vertices.push_back(v);
    if (vertices.empty()) continue;
    s.vertices_free += static_cast<int>(vertices.size());
    std::vector<int> faces;  // the region's faces with a free vertex
    for (int f = 0; f < nf; ++f) {
      if (face_region[f] != r) continue;
      bool any = false;
      for (int h = m.face_begin(f); h < m.face_end(f); ++h) any = any || index[m.corner_vertex(h)] >= 0;
      if (any) faces.push_back(f);
    }
    auto not_convex = [&](const std::vector<Point3>& at) {
      return static_cast<int>(std::count_if(faces.begin(), faces.end(), [&](int f) { return !convex_in_plane(m, f, at, planes[r]); }));
    };
    const int before = not_convex(x);
    s.faces_folded_before += before;
    if (before == 0) continue;
    // The harmonic layout of `set` (free vertices of the region), the others fixed: the
    // Laplacian of the set, the fixed neighbours on the right-hand side (every neighbour of a
    // free vertex is on the plane: it is a vertex of a face of the region). Empty if singular.
    auto layout = [&](const std::vector<int>& set) -> std::vector<Point3> {
      std::vector<int> at(nv, -1);
      for (int i = 0; i < static_cast<int>(set.size()); ++i) at[set[i]] = i;
      const int n = static_cast<int>(set.size());
      std::vector<Eigen::Triplet<double>> entries;
      Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, 3);
      for (int i = 0; i < n; ++i) {
        double degree = 0;
        for_each_vertex_edge(m, set[i], [&](int, int u) {
          degree += 1;
          if (at[u] >= 0) entries.emplace_back(i, at[u], -1.0);
          else for (int k = 0; k < 3; ++k) rhs(i, k) += x[u][k];
        });
        entries.emplace_back(i, i, degree);
      }
      Eigen::SparseMatrix<double> L(n, n);
      L.setFromTriplets(entries.begin(), entries.end());
      const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(L);
      if (solver.info() != Eigen::Success) return {};
      const Eigen::MatrixXd sol = solver.solve(rhs);
      std::vector<Point3> relaxed = x;
      for (int i = 0; i < n; ++i) {
        // Onto the plane again (the solve's rounding).
        Point3 p{sol(i, 0), sol(i, 1), sol(i, 2)};
        const double d = dot(sub(p, planes[r].point), planes[r].normal);
        for (int k = 0; k < 3; ++k) p[k] -= d * planes[r].normal[k];
        relaxed[set[i]] = p;
      }
      return relaxed;
    };
    // A layout is kept when fewer faces are folded and no face that was convex is folded by it:
    // a harmonic map of a region whose outline is not convex (featuretype's letters) can push
    // vertices across the outline, and the limit would then leave the mesh's region.
    auto better = [&](const std::vector<Point3>& relaxed) {
      if (relaxed.empty() || not_convex(relaxed) >= before) return false;
      for (int f : faces)
        if (convex_in_plane(m, f, x, planes[r]) && !convex_in_plane(m, f, relaxed, planes[r])) return false;
      return true;
    };
    // First the whole region's free vertices; else only those near a fold (the vertices of the
    // faces that are not convex, grown by two rings), the fit's layout kept elsewhere.
    std::vector<int> set = vertices;
    std::vector<Point3> relaxed = layout(set);
    if (!better(relaxed)) {
      std::vector<char> active(nv, 0);
      for (int f : faces)
        if (!convex_in_plane(m, f, x, planes[r]))
          for (int h = m.face_begin(f); h < m.face_end(f); ++h) active[m.corner_vertex(h)] = 1;
      for (int ring = 0; ring < 2; ++ring) {
        std::vector<char> grown = active;
        for (int v : vertices)
          if (active[v]) for_each_vertex_edge(m, v, [&](int, int u) { grown[u] = 1; });
        active.swap(grown);
      }
      set.clear();
      for (int v : vertices)
        if (active[v]) set.push_back(v);
      relaxed = layout(set);
    }
    if (better(relaxed)) {
      for (int v : set) x[v] = relaxed[v];
      s.vertices_untangled += static_cast<int>(set.size());
      s.faces_folded_after += not_convex(x);
    } else {
      s.faces_folded_after += before;
    }
  }
}

}  // namespace

std::vector<PlanarRegion> detect_planar_regions(const std::vector<Point3>& points,
                                                const std::vector<std::array<int, 3>>& triangles,
                                                const PlanarRegionOptions& options) {
  const int nt = static_cast<int>(triangles.size());
  std::vector<PlanarRegion> out;
  if (nt == 0) return out;
  Point3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  for (const auto& t : triangles)
    for (int v : t)
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], points[v][k]), hi[k] = std::max(hi[k], points[v][k]);
  const double tol = options.flatness * norm(sub(hi, lo));

  std::vector<Point3> normal(nt);  // area-weighted (twice the area)
  std::vector<double> area(nt);
  double total_area = 0;
  for (int t = 0; t < nt; ++t) {
    const auto& tr = triangles[t];
    normal[t] = cross(sub(points[tr[1]], points[tr[0]]), sub(points[tr[2]], points[tr[0]]));
    area[t] = 0.5 * norm(normal[t]);
    total_area += area[t];
  }
  // Edge neighbours: (min, max, triangle) sorted, equal keys adjacent.
  struct EdgeRef {
    int a, b, t;
  };
  std::vector<EdgeRef> refs;
  refs.reserve(3 * static_cast<std::size_t>(nt));
  for (int t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = triangles[t][k], b = triangles[t][(k + 1) % 3];
      refs.push_back({std::min(a, b), std::max(a, b), t});
    }
  std::sort(refs.begin(), refs.end(),
            [](const EdgeRef& x, const EdgeRef& y) { return std::tie(x.a, x.b, x.t) < std::tie(y.a, y.b, y.t); });
  // Per triangle side k: the neighbouring triangles across it.
  std::vector<std::vector<int>> across(3 * static_cast<std::size_t>(nt));
  for (std::size_t i = 0; i < refs.size();) {
    std::size_t j = i;
    while (j < refs.size() && refs[j].a == refs[i].a && refs[j].b == refs[i].b) ++j;
    for (std::size_t p = i; p < j; ++p)
      for (std::size_t q = i; q < j; ++q) {
        if (p == q || refs[p].t == refs[q].t) continue;
        const int t = refs[p].t;
        for (int k = 0; k < 3; ++k) {
          const int a = triangles[t][k], b = triangles[t][(k + 1) % 3];
          if (std::min(a, b) == refs[p].a && std::max(a, b) == refs[p].b)
            across[3 * static_cast<std::size_t>(t) + k].push_back(refs[q].t);
        }
      }
    i = j;
  }

  std::vector<int> order(nt);
  for (int t = 0; t < nt; ++t) order[t] = t;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return area[a] > area[b]; });
  std::vector<int> owner(nt, -1);  // region (kept or not) that took the triangle
  std::vector<int> mark(nt, -1);
  int grown = 0;
  std::vector<int> vmark(points.size(), -1);
  auto grow = [&](int seed, const Plane& pl, int stamp) {
    std::vector<int> members{seed};
    mark[seed] = stamp;
    for (std::size_t i = 0; i < members.size(); ++i) {
      const int t = members[i];
      for (int k = 0; k < 3; ++k)
        for (int u : across[3 * static_cast<std::size_t>(t) + k]) {
          if (owner[u] >= 0 || mark[u] == stamp || area[u] <= 0) continue;
          const auto& tr = triangles[u];
          if (pl.distance(points[tr[0]]) > tol || pl.distance(points[tr[1]]) > tol || pl.distance(points[tr[2]]) > tol)
            continue;
          mark[u] = stamp;
          members.push_back(u);
        }
    }
    std::sort(members.begin(), members.end());
    return members;
  };
  auto region_vertices = [&](const std::vector<int>& members, int stamp) {
    std::vector<int> vs;
    for (int t : members)
      for (int v : triangles[t])
        if (vmark[v] != stamp) vmark[v] = stamp, vs.push_back(v);
    return vs;
  };
  int stamp = 0;
  for (int seed : order) {
    if (owner[seed] >= 0 || !(area[seed] > 0)) continue;
    const double len = norm(normal[seed]);
    Plane plane;
    const auto& st = triangles[seed];
    plane.point = {(points[st[0]][0] + points[st[1]][0] + points[st[2]][0]) / 3,
                   (points[st[0]][1] + points[st[1]][1] + points[st[2]][1]) / 3,
                   (points[st[0]][2] + points[st[1]][2] + points[st[2]][2]) / 3};
    plane.normal = {normal[seed][0] / len, normal[seed][1] / len, normal[seed][2] / len};
    std::vector<int> members = grow(seed, plane, stamp++);
    for (int round = 0; round < 4; ++round) {
      Point3 towards{0, 0, 0};
      for (int t : members)
        for (int k = 0; k < 3; ++k) towards[k] += normal[t][k];
      const std::vector<int> vs = region_vertices(members, stamp++);
      const Plane refit = fit_plane(points, vs, towards);
      double dev = 0;
      for (int v : vs) dev = std::max(dev, refit.distance(points[v]));
      if (dev > tol) break;
      std::vector<int> again = grow(seed, refit, stamp++);
      plane = refit;
      if (again == members) break;
      members = std::move(again);
    }
    const int id = grown++;
    for (int t : members) owner[t] = id;
    PlanarRegion r;
    r.point = plane.point;
    r.normal = plane.normal;
    double perimeter = 0;
    for (int t : members) {
      r.area += area[t];
      for (int k = 0; k < 3; ++k) {
        bool inside = false;
        for (int u : across[3 * static_cast<std::size_t>(t) + k]) inside = inside || owner[u] == id;
        if (!inside) perimeter += norm(sub(points[triangles[t][(k + 1) % 3]], points[triangles[t][k]]));
      }
    }
    r.width = perimeter > 0 ? 2 * r.area / perimeter : INFINITY;
    for (int v : region_vertices(members, stamp++)) r.deviation = std::max(r.deviation, plane.distance(points[v]));
    r.deviation /= std::max(norm(sub(hi, lo)), 1e-300);
    if (r.area < options.min_area * total_area || r.width < options.min_width) continue;
    r.triangles = std::move(members);
    out.push_back(std::move(r));
  }
  return out;
}

std::vector<int> limit_support(const SubdivLevel& cage, int f) {
  const PolyMesh& m = cage.mesh;
  std::vector<int> faces;
  for (int h = m.face_begin(f); h < m.face_end(f); ++h) {
    const int v = m.corner_vertex(h);
    const int* fan = m.vertex_corners(v);
    const int k = m.vertex_face_count(v);
    int i0 = -1, sharp = 0;
    for (int i = 0; i < k; ++i) {
      if (fan[i] == h) i0 = i;
      if (cage.infinitely_sharp(m.corner_edge(fan[i]))) ++sharp;
    }
    if (m.is_boundary_vertex(v)) ++sharp;  // the last face's incoming edge, on the boundary
    if (sharp < 2) {
      for (int i = 0; i < k; ++i) faces.push_back(m.corner_face(fan[i]));
      continue;
    }
    // The sector of f at v: the faces reached from f around v without crossing a sharp edge
    // (the edge between fan faces i and i + 1 is the one of prev(fan[i])).
    faces.push_back(f);
    for (int i = i0;;) {
      if (cage.infinitely_sharp(m.corner_edge(m.prev(fan[i])))) break;
      i = (i + 1) % k;
      if (i == i0) break;
      faces.push_back(m.corner_face(fan[i]));
    }
    for (int i = i0;;) {
      if (cage.infinitely_sharp(m.corner_edge(fan[i]))) break;
      i = (i + k - 1) % k;
      if (i == i0) break;
      faces.push_back(m.corner_face(fan[i]));
    }
  }
  std::vector<int> out;
  for (int g : faces)
    for (int h = m.face_begin(g); h < m.face_end(g); ++h) out.push_back(m.corner_vertex(h));
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

PlanarConstraints planar_constraints(const SubdivLevel& cage, const std::vector<Point3>& on_mesh,
                                     const std::vector<Point3>& points, const std::vector<std::array<int, 3>>& triangles,
                                     const std::vector<PlanarRegion>& regions, double diagonal,
                                     const FlattenOptions& options) {
  const PolyMesh& m = cage.mesh;
  const int nf = m.num_faces(), nv = m.num_vertices();
  if (static_cast<int>(on_mesh.size()) != nv) throw std::invalid_argument("planar_constraints: one position per cage vertex");
  PlanarConstraints pc;
  pc.face_region.assign(nf, -1);
  pc.vertex_regions.assign(nv, {});
  if (regions.empty() || triangles.empty() || !(diagonal > 0)) return pc;
  std::vector<int> triangle_region(triangles.size(), -1);
  for (int r = 0; r < static_cast<int>(regions.size()); ++r)
    for (int t : regions[r].triangles) triangle_region[t] = r;
  std::vector<Plane> planes(regions.size());
  for (std::size_t r = 0; r < regions.size(); ++r) planes[r] = {regions[r].point, regions[r].normal};

  // The faces of each region.
  const ClosestPointTree tree(points, triangles);
  const double on_plane = options.on_plane * diagonal;
  std::vector<std::vector<int>> support(nf);
  for (int f = 0; f < nf; ++f) {
    if (cage.face_hole[f]) continue;
    Point3 c{0, 0, 0};
    for (int h = m.face_begin(f); h < m.face_end(f); ++h)
      for (int k = 0; k < 3; ++k) c[k] += on_mesh[m.corner_vertex(h)][k] / m.face_size(f);
    const int t = tree.closest(c).element;
    const int r = t >= 0 ? triangle_region[t] : -1;
    if (r < 0) continue;
    bool on = true;
    for (int h = m.face_begin(f); h < m.face_end(f) && on; ++h) on = planes[r].distance(on_mesh[m.corner_vertex(h)]) <= on_plane;
    if (!on) continue;
    // The whole support on the plane (not only the face): else the face's limit depends on
    // vertices off the region (across a thin wall, along a fillet that leaves the plane).
    std::vector<int> sup = limit_support(cage, f);
    if (!std::all_of(sup.begin(), sup.end(), [&](int v) { return planes[r].distance(on_mesh[v]) <= on_plane; })) {
      ++pc.faces_off_plane;
      continue;
    }
    pc.face_region[f] = r;
    support[f] = std::move(sup);
  }

  // Planes per vertex; faces whose vertices' planes do not meet near them are given up, until all meet.
  const double max_move = options.max_move * diagonal;
  for (;;) {
    auto& vr = pc.vertex_regions;
    for (auto& x : vr) x.clear();
    for (int f = 0; f < nf; ++f)
      if (pc.face_region[f] >= 0)
        for (int v : support[f]) vr[v].push_back(pc.face_region[f]);
    std::vector<char> bad(nv, 0);
    bool any_bad = false;
    for (int v = 0; v < nv; ++v) {
      std::sort(vr[v].begin(), vr[v].end());
      vr[v].erase(std::unique(vr[v].begin(), vr[v].end()), vr[v].end());
      if (vr[v].empty()) continue;
      Point3 x;
      if (!onto_planes(planes, vr[v], on_mesh[v], diagonal, x) || norm(sub(x, on_mesh[v])) > max_move) bad[v] = 1, any_bad = true;
    }
    if (!any_bad) break;
    for (int f = 0; f < nf; ++f) {
      if (pc.face_region[f] < 0) continue;
      if (std::any_of(support[f].begin(), support[f].end(), [&](int v) { return bad[v] != 0; }))
        pc.face_region[f] = -1, ++pc.faces_dropped;
    }
  }
  return pc;
}

FlattenStats flatten_planar_regions(const SubdivLevel& cage, const PlanarConstraints& constraints,
                                    std::vector<Point3>& positions, const std::vector<PlanarRegion>& regions,
                                    double diagonal, const FlattenOptions& options) {
  const PolyMesh& m = cage.mesh;
  const int nf = m.num_faces(), nv = m.num_vertices();
  if (static_cast<int>(positions.size()) != nv || static_cast<int>(constraints.vertex_regions.size()) != nv ||
      static_cast<int>(constraints.face_region.size()) != nf)
    throw std::invalid_argument("flatten_planar_regions: one position per cage vertex");
  FlattenStats s;
  s.regions = static_cast<int>(regions.size());
  s.face_region = constraints.face_region;
  s.faces_off_plane = constraints.faces_off_plane;
  s.faces_dropped = constraints.faces_dropped;
  std::vector<Plane> planes(regions.size());
  for (std::size_t r = 0; r < regions.size(); ++r) planes[r] = {regions[r].point, regions[r].normal};
  std::vector<Point3> moved = positions;
  for (int v = 0; v < nv; ++v) {
    if (constraints.vertex_regions[v].empty()) continue;
    Point3 x;
    if (!onto_planes(planes, constraints.vertex_regions[v], positions[v], diagonal, x)) continue;  // not for planar_constraints' planes
    moved[v] = x;
    const double move = norm(sub(x, positions[v]));
    if (move > 0) ++s.vertices_moved;
    s.max_move = std::max(s.max_move, move / diagonal);
  }
  // The free vertices: smooth (no sharp edge, not on a boundary), held by one region, and in the
  // limit support of that region's faces only.
  std::vector<int> vertex_region(nv, -1);
  for (int v = 0; v < nv; ++v)
    if (constraints.vertex_regions[v].size() == 1) vertex_region[v] = constraints.vertex_regions[v][0];
  std::vector<char> free(nv, 0);
  for (int v = 0; v < nv; ++v)
    free[v] = vertex_region[v] >= 0 && !m.is_boundary_vertex(v) && !m.is_unused_vertex(v) &&
              vertex_rule(cage, v) == VertexRule::Smooth;
  for (int f = 0; f < nf; ++f)
    for (int v : limit_support(cage, f))
      if (cage.face_hole[f] || constraints.face_region[f] != vertex_region[v]) free[v] = 0;
  untangle_regions(cage, constraints.face_region, free, vertex_region, planes, moved, s);

  // The flatness of the regions' faces before and after.
  std::vector<char> used(regions.size(), 0);
  for (int f = 0; f < nf; ++f)
    if (s.face_region[f] >= 0) ++s.faces, used[s.face_region[f]] = 1;
  s.regions_used = static_cast<int>(std::count(used.begin(), used.end(), 1));
  if (s.faces > 0) {
    const LimitEvaluator before(cage, positions), after(cage, moved);
    const int n = std::max(2, options.samples);
    for (int f = 0; f < nf; ++f) {
      if (s.face_region[f] < 0) continue;
      const Plane& pl = planes[s.face_region[f]];
      const int subs = m.face_size(f) == 4 ? 1 : m.face_size(f);
      for (int sub = 0; sub < subs; ++sub)
        for (int i = 0; i < n; ++i)
          for (int j = 0; j < n; ++j) {
            const double u = static_cast<double>(i) / (n - 1), w = static_cast<double>(j) / (n - 1);
            try {
              s.flatness_before = std::max(s.flatness_before, pl.distance(before.evaluate_point(f, sub, u, w).p) / diagonal);
              s.flatness_after = std::max(s.flatness_after, pl.distance(after.evaluate_point(f, sub, u, w).p) / diagonal);
            } catch (const std::domain_error&) {
            }
          }
    }
  }
  positions = std::move(moved);
  return s;
}

FlattenStats flatten_planar_regions(const SubdivLevel& cage, const std::vector<Point3>& on_mesh,
                                    std::vector<Point3>& positions, const std::vector<Point3>& points,
                                    const std::vector<std::array<int, 3>>& triangles,
                                    const std::vector<PlanarRegion>& regions, double diagonal,
                                    const FlattenOptions& options) {
  const PlanarConstraints pc = planar_constraints(cage, on_mesh, points, triangles, regions, diagonal, options);
  return flatten_planar_regions(cage, pc, positions, regions, diagonal, options);
}

std::vector<ShapeFitOptions::VertexPlane> vertex_planes(const PlanarConstraints& constraints,
                                                        const std::vector<PlanarRegion>& regions) {
  std::vector<ShapeFitOptions::VertexPlane> out;
  for (int v = 0; v < static_cast<int>(constraints.vertex_regions.size()); ++v)
    for (int r : constraints.vertex_regions[v]) out.push_back({v, regions[r].normal, dot(regions[r].normal, regions[r].point)});
  return out;
}

}  // namespace subd2nurbs
