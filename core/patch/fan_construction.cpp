#include "core/patch/fan_construction.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

#include "core/patch/quad_frames.h"
#include "core/util/constants.h"

namespace subd2nurbs {

using frames::face_net_index;
using frames::rotation_in_face;
using frames::step_x;
using frames::step_y;

void FanBuilder::add_to_ray_block(int r, const Eigen::Vector3d& d) {
  for (int i : {3, 4}) set_ray(r, i, ray(r, i) + d);
  if (const int s = x_sector(r); s >= 0) { B(s, 3, 1) += d; B(s, 4, 1) += d; }
  if (const int s = y_sector(r); s >= 0) { B(s, 1, 3) += d; B(s, 1, 4) += d; }
}

double FanBuilder::build(const Fan& fan, std::vector<RayKind>& kinds, std::vector<int>& ray_edges) {
  cyclic_ = fan.cyclic;
  const int ns = static_cast<int>(fan.sectors.size());
  B_.resize(ns);
  for (auto& rows : B_)
    for (auto& row : rows) row.fill(Eigen::Vector3d::Zero());
  const int v = fan.v;
  const int n = m_.valence(v);

  // Step 1: regular quads (1,0), (0,1), (1,1) of every sector, from the level-k nets.
  std::vector<std::array<int, 4>> quads(ns);  // frame corners of quads (0,0),(1,0),(0,1),(1,1)
  for (int s = 0; s < ns; ++s) {
    const int q00 = fan.sectors[s];
    const int q10 = step_x(m_, q00), q01 = step_y(m_, q00), q11 = step_y(m_, q10);
    quads[s] = {q00, q10, q01, q11};
    const int qa[4] = {0, 1, 0, 1}, qb[4] = {0, 0, 1, 1};
    for (int q = 3; q >= 1; --q) {
      const int c = quads[s][q];
      const int f = m_.corner_face(c), r = rotation_in_face(m_, c);
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) B(s, 3 * qa[q] + i, 3 * qb[q] + j) = to_eigen(nets_[f * 16 + face_net_index(r, i, j)]);
    }
  }
  const int nr = nR();
  // Keep one value for the two copies of every two-sided ray.
  for (int r = 0; r < nr; ++r)
    if (x_sector(r) >= 0 && y_sector(r) >= 0)
      for (int i = 3; i <= 6; ++i) B(y_sector(r), 0, i) = B(x_sector(r), i, 0);

  // Ray kinds and their level-k edges.
  kinds.assign(nr, RayKind::G1);
  ray_edges.assign(nr, -1);
  for (int r = 0; r < nr; ++r) {
    ray_edges[r] = r < ns ? m_.corner_edge(fan.sectors[r]) : m_.corner_edge(m_.prev(fan.sectors[ns - 1]));
    const bool sharp = L_.sharp(ray_edges[r]);
    if (!cyclic_ && (r == 0 || r == nr - 1)) kinds[r] = RayKind::ExactEnd;
    else if (sharp || fan.mode == FanMode::Approximate) kinds[r] = RayKind::Cut;
  }

  // Step 2: limit data.
  const Eigen::Vector3d p = to_eigen(limit_);
  const Eigen::Vector3d xv = L_.X(v);
  for (int s = 0; s < ns; ++s) B(s, 0, 0) = p;
  // Exact end rays: the crease curve is the cubic B-spline of the crease polygon. Its first
  // Bezier points from the EV are (2v + e)/3 and (v + 2e)/3.
  for (int r = 0; r < nr; ++r) {
    if (kinds[r] != RayKind::ExactEnd) continue;
    const int e = (r == 0) ? m_.to_vertex(fan.sectors[0]) : m_.corner_vertex(m_.prev(fan.sectors[ns - 1]));
    const Eigen::Vector3d xe = L_.X(e);
    set_ray(r, 1, (2 * xv + xe) / 3);
    set_ray(r, 2, (xv + 2 * xe) / 3);
  }
  std::vector<Eigen::Vector3d> q2(nr), q1(nr);
  for (int r = 0; r < nr; ++r) q2[r] = ray(r, 3);

  // Step 3 (closed fans of even valence): vertex enclosure.
  if (fan.mode == FanMode::Smooth && ns % 2 == 0) {
    Eigen::Vector3d A = Eigen::Vector3d::Zero();
    for (int r = 0; r < ns; ++r) A += ((r % 2) ? -1.0 : 1.0) * q2[r];
    A /= ns;
    for (int r = 0; r < ns; ++r) add_to_ray_block(r, -((r % 2) ? -1.0 : 1.0) * A);
    for (int r = 0; r < nr; ++r) q2[r] = ray(r, 3);
  }

  // Step 4: the tangent oval q1 and the G1 coefficient c.
  double c = 0;
  const bool fourier = fan.mode == FanMode::Smooth || fan.mode == FanMode::Dart ||
                       (fan.mode == FanMode::Approximate && cyclic_);
  if (fourier) {
    // Approximate closed fans (valence 2, cone points) take the same tangent oval without the
    // G1 claim: at valence 2 it makes the two corners degenerate (collinear rays) like the
    // limit's own parametrization, instead of folding one sector over the other.
    c = fan.mode == FanMode::Approximate ? 0.0 : std::cos(2 * kPi / ns);
    Eigen::Vector3d E1 = Eigen::Vector3d::Zero(), E2 = Eigen::Vector3d::Zero();
    for (int r = 0; r < ns; ++r) {
      E1 += std::cos(2 * kPi * r / ns) * q2[r];
      E2 += std::sin(2 * kPi * r / ns) * q2[r];
    }
    E1 /= ns;
    E2 /= ns;
    if (fan.mode == FanMode::Smooth) {
      // Limit normal from the tangent masks (docs/math.md 2.2).
      const double cn = std::cos(2 * kPi / ns), An = 1 + cn + std::cos(kPi / ns) * std::sqrt(2 * (9 + cn));
      Eigen::Vector3d T1 = Eigen::Vector3d::Zero(), T2 = Eigen::Vector3d::Zero();
      for (int r = 0; r < ns; ++r) {
        const int h = fan.sectors[r];
        const Eigen::Vector3d e = L_.X(m_.to_vertex(h)) - xv, d = L_.X(m_.corner_vertex(m_.next(m_.next(h)))) - xv;
        const double t0 = 2 * kPi * r / ns, t1 = 2 * kPi * (r + 1) / ns;
        T1 += An * std::cos(t0) * e + (std::cos(t0) + std::cos(t1)) * d;
        T2 += An * std::sin(t0) * e + (std::sin(t0) + std::sin(t1)) * d;
      }
      const Eigen::Vector3d N = T1.cross(T2).normalized();
      E1 -= E1.dot(N) * N;
      E2 -= E2.dot(N) * N;
    }
    for (int r = 0; r < nr; ++r)
      q1[r] = p + std::cos(2 * kPi * r / ns) * E1 + std::sin(2 * kPi * r / ns) * E2;
  } else if (fan.mode == FanMode::Crease && ns >= 2) {
    const int k = ns;
    const double psi = kPi / k;
    c = std::cos(psi);
    const Eigen::Vector3d E1 = 1.5 * (ray(0, 1) - p);
    // Exact cross-boundary tangent for the standard rules (docs/math.md 2.3), to fix the plane.
    const double c2k = std::cos(2 * kPi / (2 * k));
    const double A = 1 + c2k + std::cos(kPi / (2 * k)) * std::sqrt(2 * (9 + c2k));
    const double lam = (5 + c2k + std::cos(kPi / (2 * k)) * std::sqrt(2 * (9 + c2k))) / 16;
    Eigen::Vector3d t2 = Eigen::Vector3d::Zero();
    double Se = 0, Sd = 0;
    for (int i = 0; i < k; ++i) {
      const int h = fan.sectors[i];
      if (i >= 1) {
        const double w = A * std::sin(i * psi);
        t2 += w * (L_.X(m_.to_vertex(h)) - xv);
        Se += w;
      }
      const double w = std::sin(i * psi) + std::sin((i + 1) * psi);
      t2 += w * (L_.X(m_.corner_vertex(m_.next(m_.next(h)))) - xv);
      Sd += w;
    }
    const double beta = (A * std::sin(psi) / 2 + 2 * std::sin(psi) - Se - Sd) / (8 * lam - 2);
    t2 += beta * (L_.X(m_.to_vertex(fan.sectors[0])) - xv);
    t2 += beta * (L_.X(m_.corner_vertex(m_.prev(fan.sectors[k - 1]))) - xv);
    const Eigen::Vector3d N = E1.cross(t2).normalized();
    // E2: least-squares fit of the interior rays' targets (p + q2)/2.
    Eigen::Vector3d num = Eigen::Vector3d::Zero();
    double den = 0;
    for (int r = 1; r < k; ++r) {
      const double sr = std::sin(r * psi);
      num += sr * ((p + q2[r]) / 2 - p - std::cos(r * psi) * E1);
      den += sr * sr;
    }
    Eigen::Vector3d E2 = num / den;
    E2 -= E2.dot(N) * N;
    for (int r = 0; r < nr; ++r) q1[r] = p + std::cos(r * psi) * E1 + std::sin(r * psi) * E2;
  } else if (fan.mode == FanMode::Corner) {
    const int k = ns;
    const double psi = kPi / (2 * k);
    c = std::cos(psi);
    const Eigen::Vector3d a = 1.5 * (ray(0, 1) - p), b = 1.5 * (ray(k, 1) - p);
    for (int r = 0; r < nr; ++r)
      q1[r] = p + (std::sin((k - r) * psi) * a + std::sin(r * psi) * b) / std::sin(k * psi);
  } else {
    for (int r = 0; r < nr; ++r) q1[r] = (p + q2[r]) / 2;
  }

  // Steps 5 and 6: first edge segment = degree-raised quadratic (p, q1, q2), C1 at q2.
  std::vector<Eigen::Vector3d> b1(nr), b2(nr);
  for (int r = 0; r < nr; ++r) {
    if (kinds[r] == RayKind::ExactEnd) {
      b1[r] = ray(r, 1);
      b2[r] = ray(r, 2);
      continue;
    }
    b1[r] = (p + 2 * q1[r]) / 3;
    b2[r] = (2 * q1[r] + q2[r]) / 3;
    set_ray(r, 1, b1[r]);
    set_ray(r, 2, b2[r]);
    const Eigen::Vector3d b4 = 2 * q2[r] - b2[r];
    const Eigen::Vector3d delta = b4 - ray(r, 4);
    set_ray(r, 4, b4);
    if (const int s = x_sector(r); s >= 0) B(s, 4, 1) += delta;
    if (const int s = y_sector(r); s >= 0) B(s, 1, 4) += delta;
  }

  // Step 7: twists. T_s + T_{s-1} = R_r across every G1 ray r between sectors s-1 and s.
  std::vector<Eigen::Vector3d> target(ns), T(ns);
  for (int s = 0; s < ns; ++s) {
    const int h = fan.sectors[s];
    target[s] = (n * xv + 2 * L_.X(m_.to_vertex(h)) + 2 * L_.X(m_.corner_vertex(m_.prev(h))) +
                 L_.X(m_.corner_vertex(m_.next(m_.next(h))))) / (n + 5);
  }
  auto R = [&](int r) { return Eigen::Vector3d(2 * b1[r] + (4 * c / 9) * (q2[r] - q1[r])); };
  const bool closed_chain = cyclic_ && std::all_of(kinds.begin(), kinds.end(), [](RayKind k) { return k == RayKind::G1; });
  if (closed_chain) {
    if (ns % 2 == 1) {
      for (int s = 0; s < ns; ++s) {
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        for (int r = 0; r < ns; ++r) sum += ((r % 2) ? -1.0 : 1.0) * R(((s - r) % ns + ns) % ns);
        T[s] = sum / 2;
      }
    } else {
      T[0] = Eigen::Vector3d::Zero();
      for (int s = 1; s < ns; ++s) T[s] = R(s) - T[s - 1];
      Eigen::Vector3d w = Eigen::Vector3d::Zero();
      for (int s = 0; s < ns; ++s) w += ((s % 2) ? -1.0 : 1.0) * (target[s] - T[s]);
      w /= ns;
      for (int s = 0; s < ns; ++s) T[s] += ((s % 2) ? -1.0 : 1.0) * w;
    }
  } else {
    // Open chains: maximal runs of sectors joined by G1 rays. Within a run starting at sector
    // s0, T_s = (-1)^(s-s0) T_s0 + C_s; T_s0 minimises the distance to the targets.
    // Find a ray that is not G1 to start from (there is one: the fan is open or cut).
    int start = 0;
    while (start < nr && kinds[start] == RayKind::G1) ++start;
    int s = cyclic_ ? start % ns : 0;
    int done = 0;
    while (done < ns) {
      std::vector<int> run{s};
      std::vector<Eigen::Vector3d> C{Eigen::Vector3d::Zero()};
      for (;;) {
        const int next_s = cyclic_ ? (run.back() + 1) % ns : run.back() + 1;
        const int r = cyclic_ ? next_s : run.back() + 1;  // ray between run.back() and next_s
        if (static_cast<int>(run.size()) + done >= ns || next_s >= ns || kinds[r] != RayKind::G1) break;
        C.push_back(R(r) - C.back());
        run.push_back(next_s);
      }
      Eigen::Vector3d t0 = Eigen::Vector3d::Zero();
      for (size_t i = 0; i < run.size(); ++i) t0 += ((i % 2) ? -1.0 : 1.0) * (target[run[i]] - C[i]);
      t0 /= static_cast<double>(run.size());
      for (size_t i = 0; i < run.size(); ++i) T[run[i]] = ((i % 2) ? -1.0 : 1.0) * t0 + C[i];
      done += static_cast<int>(run.size());
      s = cyclic_ ? (run.back() + 1) % ns : run.back() + 1;
    }
  }
  for (int s2 = 0; s2 < ns; ++s2) B(s2, 1, 1) = T[s2];

  // Step 8: the second cross row beside every ray.
  for (int r = 0; r < nr; ++r) {
    const int sx = x_sector(r), sy = y_sector(r);
    if (kinds[r] == RayKind::G1) {
      const Eigen::Vector3d X = 2 * B(sx, 3, 1) - B(sx, 4, 1);
      const Eigen::Vector3d Y = 2 * B(sy, 1, 3) - B(sy, 1, 4);
      B(sx, 2, 1) = b2[r] + (X - Y) / 2;
      B(sy, 1, 2) = b2[r] - (X - Y) / 2;
      B(sx, 3, 1) = (B(sx, 2, 1) + B(sx, 4, 1)) / 2;
      B(sy, 1, 3) = (B(sy, 1, 2) + B(sy, 1, 4)) / 2;
    } else {
      if (sx >= 0) B(sx, 2, 1) = 2 * B(sx, 3, 1) - B(sx, 4, 1);
      if (sy >= 0) B(sy, 1, 2) = 2 * B(sy, 1, 3) - B(sy, 1, 4);
    }
  }
  // Step 9: the far corner of the EV patch.
  for (int s2 = 0; s2 < ns; ++s2) B(s2, 2, 2) = 2 * B(s2, 2, 3) - B(s2, 2, 4);

  // Step 10: write quads (0,0), (1,0), (0,1) back into the level-k nets.
  for (int s2 = 0; s2 < ns; ++s2) {
    const int qa[3] = {0, 1, 0}, qb[3] = {0, 0, 1};
    for (int q = 0; q < 3; ++q) {
      const int cq = quads[s2][q];
      const int f = m_.corner_face(cq), r = rotation_in_face(m_, cq);
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) nets_[f * 16 + face_net_index(r, i, j)] = to_point(B(s2, 3 * qa[q] + i, 3 * qb[q] + j));
    }
  }
  return c;
}

std::vector<Fan> fans_at(const LevelView& L, int v) {
  const PolyMesh& m = L.m;
  std::vector<Fan> out;
  const int* cs = m.vertex_corners(v);
  const int nf = m.vertex_face_count(v);
  if (nf == 0) return out;
  const VertexRule rule = vertex_rule(L.level, v);
  int sharp_start = -1;
  for (int i = 0; i < nf; ++i)
    if (L.sharp_ray_out(cs[i])) { sharp_start = i; break; }
  if (sharp_start < 0) {
    if (rule == VertexRule::Smooth && nf == 4) return out;  // regular
    Fan fan{v, {}, true, (rule == VertexRule::Smooth && nf >= 3) ? FanMode::Smooth : FanMode::Approximate};
    fan.sectors.assign(cs, cs + nf);
    out.push_back(std::move(fan));
    return out;
  }
  if (rule == VertexRule::Dart) {
    Fan fan{v, {}, true, nf >= 3 ? FanMode::Dart : FanMode::Approximate};
    for (int i = 0; i < nf; ++i) fan.sectors.push_back(cs[(sharp_start + i) % nf]);
    out.push_back(fan);
    return out;
  }
  // Open fans: start at every corner whose out ray is sharp.
  for (int i = 0; i < nf; ++i) {
    const int c0 = cs[(sharp_start + i) % nf];
    if (!L.sharp_ray_out(c0)) continue;
    Fan fan{v, {c0}, false, FanMode::Approximate};
    for (int d = L.ccw(c0); d != -1; d = L.ccw(d)) fan.sectors.push_back(d);
    const int k = static_cast<int>(fan.sectors.size());
    if (rule == VertexRule::Crease) {
      if (k == 2) continue;  // regular crease side
      fan.mode = FanMode::Crease;
    } else if (rule == VertexRule::Corner) {
      if (k == 1) continue;  // regular corner
      fan.mode = FanMode::Corner;
    }
    out.push_back(fan);
  }
  return out;
}

}  // namespace subd2nurbs
