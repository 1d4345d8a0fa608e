#include "core/patch/patch_builder.h"

#include "core/polar/polar_separation.h"
#include "core/patch/quad_frames.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace subd2nurbs {

const char* to_string(FanMode mode) {
  switch (mode) {
    case FanMode::Smooth: return "smooth";
    case FanMode::Dart: return "dart";
    case FanMode::Crease: return "crease";
    case FanMode::Corner: return "corner";
    case FanMode::Approximate: return "approximate";
  }
  return "?";
}

namespace {

using V3 = Eigen::Vector3d;
constexpr double kPi = 3.14159265358979323846;

V3 v3(const Point3& p) { return V3(p[0], p[1], p[2]); }
Point3 pt(const V3& v) { return {v.x(), v.y(), v.z()}; }

using frames::face_net_index;
using frames::rotation_in_face;
using frames::step_x;
using frames::step_y;

// ---- the level-k mesh: sharp edges, vertex rules, fans ------------------------------------

struct LevelView {
  const SubdivLevel& level;
  const PolyMesh& m;
  const std::vector<Point3>& x;

  bool sharp(int e) const {
    return m.is_boundary_edge(e) || level.edge_sharpness[e] >= kInfiniteSharpness;
  }
  // The ray along corner c's edge, leaving corner_vertex(c).
  bool sharp_ray_out(int c) const { return sharp(m.corner_edge(c)); }
  // The ray along prev(c)'s edge, i.e. the other edge of c's face at corner_vertex(c).
  bool sharp_ray_in(int c) const { return sharp(m.corner_edge(m.prev(c))); }
  // Counter-clockwise neighbour face's corner at the same vertex (across the "in" ray).
  int ccw(int c) const { return sharp_ray_in(c) ? -1 : m.twin(m.prev(c)); }
  int cw(int c) const { return sharp_ray_out(c) ? -1 : m.next(m.twin(c)); }

  // Faces in the fan (between sharp edges) that contains corner c; -1 if cyclic.
  int fan_size(int c) const {
    int n = 1;
    for (int d = ccw(c); d != -1; d = ccw(d)) {
      if (d == c) return -1;
      ++n;
    }
    for (int d = cw(c); d != -1; d = cw(d)) ++n;
    return n;
  }

  bool regular_corner(int c) const {
    const int v = m.corner_vertex(c);
    switch (vertex_rule(level, v)) {
      case VertexRule::Smooth: return !m.is_boundary_vertex(v) && m.valence(v) == 4;
      case VertexRule::Crease: return fan_size(c) == 2;
      case VertexRule::Corner: return fan_size(c) == 1;
      case VertexRule::Dart: return false;
    }
    return false;
  }
  V3 X(int v) const { return v3(x[v]); }
};

// ---- regular patches (MATH.md 6.1 with the phantom points of 1.2) -------------------------

const double kM[4][4] = {{1.0 / 6, 4.0 / 6, 1.0 / 6, 0},
                         {0, 4.0 / 6, 2.0 / 6, 0},
                         {0, 2.0 / 6, 4.0 / 6, 0},
                         {0, 1.0 / 6, 4.0 / 6, 1.0 / 6}};

// Bezier net (face frame) of a quad whose four corners are regular for it.
void regular_net(const LevelView& L, int f, Point3* net) {
  const PolyMesh& m = L.m;
  const int h0 = m.face_begin(f);
  V3 G[4][4];      // G[x+1][y+1], x, y in -1..2
  bool have[4][4] = {};
  auto set = [&](int x, int y, int v) { G[x + 1][y + 1] = L.X(v); have[x + 1][y + 1] = true; };
  // Corners (0,0), (1,0), (1,1), (0,1).
  const int cx[4] = {0, 1, 1, 0}, cy[4] = {0, 0, 1, 1};
  for (int i = 0; i < 4; ++i) set(cx[i], cy[i], m.corner_vertex(h0 + i));
  // Outer rows across each open side i (edge of corner h_i, from corner i to corner i+1).
  // In the neighbour across the edge, next(next(t)) is next to corner i, prev(t) to corner i+1.
  // Outward step of side i: side 0 -> (0,-1), 1 -> (+1,0), 2 -> (0,+1), 3 -> (-1,0).
  const int ox[4] = {0, 1, 0, -1}, oy[4] = {-1, 0, 1, 0};
  bool open[4];
  for (int i = 0; i < 4; ++i) {
    const int h = h0 + i;
    open[i] = !L.sharp(m.corner_edge(h));
    if (!open[i]) continue;
    const int t = m.twin(h);
    const int a = i, b = (i + 1) % 4;
    set(cx[a] + ox[i], cy[a] + oy[i], m.corner_vertex(m.next(m.next(t))));
    set(cx[b] + ox[i], cy[b] + oy[i], m.corner_vertex(m.prev(t)));
  }
  // Diagonal points at smooth 4-valent corners: two faces around the corner.
  for (int i = 0; i < 4; ++i) {
    const int h = h0 + i;
    const int prev_side = (i + 3) % 4;
    if (!open[i] || !open[prev_side]) continue;
    const int opposite = m.twin(m.prev(m.twin(m.prev(h))));  // two faces counter-clockwise
    set(cx[i] + ox[i] + ox[prev_side], cy[i] + oy[i] + oy[prev_side],
        m.corner_vertex(m.next(m.next(opposite))));
  }
  // Phantom points: first the rows beside the four corners, then the diagonals. A missing
  // x = -1 or 2 point reflects in x; otherwise (missing y row) it reflects in y.
  auto phantom = [&](int x, int y) {
    if (have[x + 1][y + 1]) return;
    if (x == -1) G[0][y + 1] = 2 * G[1][y + 1] - G[2][y + 1];
    else if (x == 2) G[3][y + 1] = 2 * G[2][y + 1] - G[1][y + 1];
    else if (y == -1) G[x + 1][0] = 2 * G[x + 1][1] - G[x + 1][2];
    else G[x + 1][3] = 2 * G[x + 1][2] - G[x + 1][1];
    have[x + 1][y + 1] = true;
  };
  for (int t = 0; t <= 1; ++t) {
    phantom(-1, t); phantom(2, t); phantom(t, -1); phantom(t, 2);
  }
  for (int x : {-1, 2})
    for (int y : {-1, 2}) {
      const bool x_side_sharp = (x == -1) ? !open[3] : !open[1];
      if (x_side_sharp) {
        G[x + 1][y + 1] = (x == -1) ? 2 * G[1][y + 1] - G[2][y + 1] : 2 * G[2][y + 1] - G[1][y + 1];
        have[x + 1][y + 1] = true;
      } else if (!have[x + 1][y + 1]) {  // the x side is open: reflect across the y side
        G[x + 1][y + 1] = (y == -1) ? 2 * G[x + 1][1] - G[x + 1][2] : 2 * G[x + 1][2] - G[x + 1][1];
        have[x + 1][y + 1] = true;
      }
    }
  // B = M G M^T
  V3 T[4][4];
  for (int i = 0; i < 4; ++i)
    for (int b = 0; b < 4; ++b) {
      T[i][b] = V3::Zero();
      for (int a = 0; a < 4; ++a) T[i][b] += kM[i][a] * G[a][b];
    }
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      V3 s = V3::Zero();
      for (int b = 0; b < 4; ++b) s += kM[j][b] * T[i][b];
      net[i * 4 + j] = pt(s);
    }
}

// ---- fans around irregular vertices (MATH.md 5.3, and the open variant of 5.6) ------------

enum class RayKind : unsigned char {
  G1,           ///< smooth ray between two sectors: exactly G1
  Cut,          ///< two sectors, constructed quadratic, no G1 claim (dart's sharp ray, approx.)
  ExactEnd,     ///< end of an open fan: a sharp edge whose limit curve is known exactly
};

struct Fan {
  int v = -1;
  std::vector<int> sectors;  ///< corner at v of each sector's quad (0,0), counter-clockwise
  bool cyclic = false;
  FanMode mode = FanMode::Smooth;
};

class FanBuilder {
 public:
  FanBuilder(const LevelView& L, const std::vector<Point3>& limit, std::vector<Point3>& nets)
      : L_(L), m_(L.m), limit_(limit), nets_(nets) {}

  // Builds the fan's nets; returns the G1 coefficient c and fills ray kinds.
  double build(const Fan& fan, std::vector<RayKind>& kinds, std::vector<int>& ray_edges);

 private:
  V3& B(int s, int i, int j) { return B_[s][i][j]; }
  int nS() const { return static_cast<int>(B_.size()); }
  int nR() const { return cyclic_ ? nS() : nS() + 1; }
  // Sector owning ray r as its x axis (-1 for the end ray of an open fan).
  int x_sector(int r) const { return r < nS() ? r : -1; }
  // Sector owning ray r as its y axis (-1 for ray 0 of an open fan).
  int y_sector(int r) const { return cyclic_ ? (r + nS() - 1) % nS() : r - 1; }
  V3 ray(int r, int i) {
    const int s = x_sector(r);
    return s >= 0 ? B(s, i, 0) : B(y_sector(r), 0, i);
  }
  void set_ray(int r, int i, const V3& p) {
    if (const int s = x_sector(r); s >= 0) B(s, i, 0) = p;
    if (const int s = y_sector(r); s >= 0) B(s, 0, i) = p;
  }
  void add_to_ray_block(int r, const V3& d);

  const LevelView& L_;
  const PolyMesh& m_;
  const std::vector<Point3>& limit_;
  std::vector<Point3>& nets_;
  bool cyclic_ = false;
  std::vector<std::array<std::array<V3, 7>, 7>> B_;
};

void FanBuilder::add_to_ray_block(int r, const V3& d) {
  for (int i : {3, 4}) set_ray(r, i, ray(r, i) + d);
  if (const int s = x_sector(r); s >= 0) { B(s, 3, 1) += d; B(s, 4, 1) += d; }
  if (const int s = y_sector(r); s >= 0) { B(s, 1, 3) += d; B(s, 1, 4) += d; }
}

double FanBuilder::build(const Fan& fan, std::vector<RayKind>& kinds, std::vector<int>& ray_edges) {
  cyclic_ = fan.cyclic;
  const int ns = static_cast<int>(fan.sectors.size());
  B_.resize(ns);
  for (auto& rows : B_)
    for (auto& row : rows) row.fill(V3::Zero());
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
        for (int j = 0; j < 4; ++j) B(s, 3 * qa[q] + i, 3 * qb[q] + j) = v3(nets_[f * 16 + face_net_index(r, i, j)]);
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
  const V3 p = v3(limit_[v]);
  const V3 xv = L_.X(v);
  for (int s = 0; s < ns; ++s) B(s, 0, 0) = p;
  // Exact end rays: the crease curve is the cubic B-spline of the crease polygon. Its first
  // Bezier points from the EV are (2v + e)/3 and (v + 2e)/3.
  for (int r = 0; r < nr; ++r) {
    if (kinds[r] != RayKind::ExactEnd) continue;
    const int e = (r == 0) ? m_.to_vertex(fan.sectors[0]) : m_.corner_vertex(m_.prev(fan.sectors[ns - 1]));
    const V3 xe = L_.X(e);
    set_ray(r, 1, (2 * xv + xe) / 3);
    set_ray(r, 2, (xv + 2 * xe) / 3);
  }
  std::vector<V3> q2(nr), q1(nr);
  for (int r = 0; r < nr; ++r) q2[r] = ray(r, 3);

  // Step 3 (closed fans of even valence): vertex enclosure.
  if (fan.mode == FanMode::Smooth && ns % 2 == 0) {
    V3 A = V3::Zero();
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
    V3 E1 = V3::Zero(), E2 = V3::Zero();
    for (int r = 0; r < ns; ++r) {
      E1 += std::cos(2 * kPi * r / ns) * q2[r];
      E2 += std::sin(2 * kPi * r / ns) * q2[r];
    }
    E1 /= ns;
    E2 /= ns;
    if (fan.mode == FanMode::Smooth) {
      // Limit normal from the tangent masks (MATH.md 1.4).
      const double cn = std::cos(2 * kPi / ns), An = 1 + cn + std::cos(kPi / ns) * std::sqrt(2 * (9 + cn));
      V3 T1 = V3::Zero(), T2 = V3::Zero();
      for (int r = 0; r < ns; ++r) {
        const int h = fan.sectors[r];
        const V3 e = L_.X(m_.to_vertex(h)) - xv, d = L_.X(m_.corner_vertex(m_.next(m_.next(h)))) - xv;
        const double t0 = 2 * kPi * r / ns, t1 = 2 * kPi * (r + 1) / ns;
        T1 += An * std::cos(t0) * e + (std::cos(t0) + std::cos(t1)) * d;
        T2 += An * std::sin(t0) * e + (std::sin(t0) + std::sin(t1)) * d;
      }
      const V3 N = T1.cross(T2).normalized();
      E1 -= E1.dot(N) * N;
      E2 -= E2.dot(N) * N;
    }
    for (int r = 0; r < nr; ++r)
      q1[r] = p + std::cos(2 * kPi * r / ns) * E1 + std::sin(2 * kPi * r / ns) * E2;
  } else if (fan.mode == FanMode::Crease && ns >= 2) {
    const int k = ns;
    const double psi = kPi / k;
    c = std::cos(psi);
    const V3 E1 = 1.5 * (ray(0, 1) - p);
    // Exact cross-boundary tangent for the standard rules (MATH.md 1.5), to fix the plane.
    const double c2k = std::cos(2 * kPi / (2 * k));
    const double A = 1 + c2k + std::cos(kPi / (2 * k)) * std::sqrt(2 * (9 + c2k));
    const double lam = (5 + c2k + std::cos(kPi / (2 * k)) * std::sqrt(2 * (9 + c2k))) / 16;
    V3 t2 = V3::Zero();
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
    const V3 N = E1.cross(t2).normalized();
    // E2: least-squares fit of the interior rays' targets (p + q2)/2.
    V3 num = V3::Zero();
    double den = 0;
    for (int r = 1; r < k; ++r) {
      const double sr = std::sin(r * psi);
      num += sr * ((p + q2[r]) / 2 - p - std::cos(r * psi) * E1);
      den += sr * sr;
    }
    V3 E2 = num / den;
    E2 -= E2.dot(N) * N;
    for (int r = 0; r < nr; ++r) q1[r] = p + std::cos(r * psi) * E1 + std::sin(r * psi) * E2;
  } else if (fan.mode == FanMode::Corner) {
    const int k = ns;
    const double psi = kPi / (2 * k);
    c = std::cos(psi);
    const V3 a = 1.5 * (ray(0, 1) - p), b = 1.5 * (ray(k, 1) - p);
    for (int r = 0; r < nr; ++r)
      q1[r] = p + (std::sin((k - r) * psi) * a + std::sin(r * psi) * b) / std::sin(k * psi);
  } else {
    for (int r = 0; r < nr; ++r) q1[r] = (p + q2[r]) / 2;
  }

  // Steps 5 and 6: first edge segment = degree-raised quadratic (p, q1, q2), C1 at q2.
  std::vector<V3> b1(nr), b2(nr);
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
    const V3 b4 = 2 * q2[r] - b2[r];
    const V3 delta = b4 - ray(r, 4);
    set_ray(r, 4, b4);
    if (const int s = x_sector(r); s >= 0) B(s, 4, 1) += delta;
    if (const int s = y_sector(r); s >= 0) B(s, 1, 4) += delta;
  }

  // Step 7: twists. T_s + T_{s-1} = R_r across every G1 ray r between sectors s-1 and s.
  std::vector<V3> target(ns), T(ns);
  for (int s = 0; s < ns; ++s) {
    const int h = fan.sectors[s];
    target[s] = (n * xv + 2 * L_.X(m_.to_vertex(h)) + 2 * L_.X(m_.corner_vertex(m_.prev(h))) +
                 L_.X(m_.corner_vertex(m_.next(m_.next(h))))) / (n + 5);
  }
  auto R = [&](int r) { return V3(2 * b1[r] + (4 * c / 9) * (q2[r] - q1[r])); };
  const bool closed_chain = cyclic_ && std::all_of(kinds.begin(), kinds.end(), [](RayKind k) { return k == RayKind::G1; });
  if (closed_chain) {
    if (ns % 2 == 1) {
      for (int s = 0; s < ns; ++s) {
        V3 sum = V3::Zero();
        for (int r = 0; r < ns; ++r) sum += ((r % 2) ? -1.0 : 1.0) * R(((s - r) % ns + ns) % ns);
        T[s] = sum / 2;
      }
    } else {
      T[0] = V3::Zero();
      for (int s = 1; s < ns; ++s) T[s] = R(s) - T[s - 1];
      V3 w = V3::Zero();
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
      std::vector<V3> C{V3::Zero()};
      for (;;) {
        const int next_s = cyclic_ ? (run.back() + 1) % ns : run.back() + 1;
        const int r = cyclic_ ? next_s : run.back() + 1;  // ray between run.back() and next_s
        if (static_cast<int>(run.size()) + done >= ns || next_s >= ns || kinds[r] != RayKind::G1) break;
        C.push_back(R(r) - C.back());
        run.push_back(next_s);
      }
      V3 t0 = V3::Zero();
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
      const V3 X = 2 * B(sx, 3, 1) - B(sx, 4, 1);
      const V3 Y = 2 * B(sy, 1, 3) - B(sy, 1, 4);
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
        for (int j = 0; j < 4; ++j) nets_[f * 16 + face_net_index(r, i, j)] = pt(B(s2, 3 * qa[q] + i, 3 * qb[q] + j));
    }
  }
  return c;
}

// Fans of irregular vertex v: maximal runs of faces between sharp rays (one cyclic fan if it
// has no sharp ray). Fans that are regular for all their faces are skipped.
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
    Fan fan{v, {}, true, FanMode::Smooth};
    for (int i = 0; i < nf; ++i) fan.sectors.push_back(cs[i]);
    const int n = nf;
    fan.mode = (rule == VertexRule::Smooth && n >= 3) ? FanMode::Smooth : FanMode::Approximate;
    if (rule == VertexRule::Smooth && n == 4) return out;  // regular
    out.push_back(fan);
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

// ---- merging the level-k Bezier nets of a coarse quad into one B-spline (MATH.md 5.4) ------

// Knot vector on [0,1] with N uniform spans; interior multiplicity 2 at 1/N, 2/N if low,
// at (N-1)/N, (N-2)/N if high, else 1. Ends clamped (multiplicity 4).
KnotVector coarse_knots(int N, bool low, bool high) {
  KnotVector kv;
  for (int i = 0; i <= N; ++i) {
    kv.knots.push_back(static_cast<double>(i) / N);
    int mult = (i == 0 || i == N) ? 4 : 1;
    if (i > 0 && i < N && ((low && i <= 2) || (high && i >= N - 2))) mult = 2;
    kv.mults.push_back(mult);
  }
  return kv;
}

// For pole i of a clamped cubic with flat knots U and N uniform spans of width 1/N: the span
// whose polynomial piece is used, and the blossom weights on that span's 4 Bezier points.
struct PoleFromBezier {
  int span;
  double w[4];
};
std::vector<PoleFromBezier> blossom_rows(const std::vector<double>& U, int N) {
  const int np = static_cast<int>(U.size()) - 4;
  std::vector<PoleFromBezier> rows(np);
  for (int i = 0; i < np; ++i) {
    const double a1 = U[i + 1], a2 = U[i + 2], a3 = U[i + 3];
    int span = std::min(N - 1, static_cast<int>(std::floor(a2 * N + 0.5)));
    if (static_cast<double>(span + 1) / N > U[i + 4] + 1e-12) --span;  // keep inside the support
    span = std::max(0, span);
    const double lo = static_cast<double>(span) / N;
    double w[4] = {1, 0, 0, 0};
    int deg = 0;
    for (double a : {a1, a2, a3}) {
      const double s = (a - lo) * N;
      for (int q = deg + 1; q >= 0; --q) w[q] = (q <= deg ? w[q] * (1 - s) : 0) + (q > 0 ? w[q - 1] * s : 0);
      ++deg;
    }
    rows[i].span = span;
    std::copy(w, w + 4, rows[i].w);
  }
  return rows;
}

KnotVector reversed(const KnotVector& kv) {
  KnotVector r;
  for (size_t i = kv.knots.size(); i-- > 0;) {
    r.knots.push_back(1.0 - kv.knots[i]);
    r.mults.push_back(kv.mults[i]);
  }
  r.knots.front() = 0.0;
  r.knots.back() = 1.0;
  return r;
}

/// The model size: the bounding-box diagonal of the cage's points (not empty).
double bounding_diagonal(const std::vector<Point3>& positions) {
  V3 lo = v3(positions[0]), hi = lo;
  for (const Point3& q : positions) {
    lo = lo.cwiseMin(v3(q));
    hi = hi.cwiseMax(v3(q));
  }
  return (hi - lo).norm();
}

/// PatchOptions::separate_poles: the separating first step at the poles that need it, then
/// the ordinary build of that level-1 cage. False (and `out` untouched) if no pole needs it.
bool build_with_separated_poles(const SubdivLevel& base, const std::vector<Point3>& positions,
                                const PatchOptions& options, PatchBuild& out) {
  const PolyMesh& m = base.mesh;
  const PolarDetection polar = detect_polar_structures(base);
  std::vector<int> chosen;
  std::vector<RejectedPole> left;
  std::vector<char> taken(m.num_vertices(), 0);
  for (const RejectedPole& r : polar.rejected) {
    bool ok = (r.kind == RejectedPole::Kind::LowValence || r.kind == RejectedPole::Kind::TooClose) &&
              separation_obstacle(base, r.vertex).empty();
    for (int i = 0; ok && i < m.vertex_face_count(r.vertex); ++i) ok = !taken[m.to_vertex(m.vertex_corners(r.vertex)[i])];
    if (ok) {
      chosen.push_back(r.vertex);
      taken[r.vertex] = 1;
    } else {
      left.push_back(r);
    }
  }
  if (chosen.empty()) return false;
  const SeparatedLevel sl = separate_poles(base, positions, chosen);
  PatchOptions once = options;
  once.separate_poles = false;
  out = build_patches(sl.level, sl.positions, once);
  for (NurbsPatch& p : out.set.patches) {
    for (int& f : p.base_faces) f = sl.cage_face[f];
    std::sort(p.base_faces.begin(), p.base_faces.end());
    p.base_faces.erase(std::unique(p.base_faces.begin(), p.base_faces.end()), p.base_faces.end());
  }
  out.info.separated_poles = chosen;
  out.info.rejected_poles = left;  // the level-1 cage has no other all-triangle vertices
  out.set.model_size = bounding_diagonal(positions);  // of the cage, not of its level 1
  return true;
}

}  // namespace

PatchBuild build_patches(const SubdivLevel& base, const std::vector<Point3>& positions,
                         const PatchOptions& options) {
  if (static_cast<int>(positions.size()) != base.mesh.num_vertices())
    throw std::invalid_argument("build_patches: one position per cage vertex expected");
  if (options.polar && options.separate_poles) {
    PatchBuild separated;
    if (build_with_separated_poles(base, positions, options, separated)) return separated;
  }
  PatchBuild out;
  PatchBuildInfo& info = out.info;
  // Polar structures: their cap faces make no Catmull-Clark patch.
  std::vector<char> cap_face(base.mesh.num_faces(), 0);
  if (options.polar) {
    PolarDetection polar = detect_polar_structures(base);
    info.rejected_poles = std::move(polar.rejected);
    for (PolarStructure& s : polar.structures) {
      for (int f : s.cap_faces) cap_face[f] = 1;
      CapInfo ci;
      ci.structure = std::move(s);
      info.caps.push_back(std::move(ci));
    }
  }
  bool quads = true;
  for (int f = 0; f < base.mesh.num_faces(); ++f)
    quads = quads && (cap_face[f] || base.mesh.face_size(f) == 4);  // holes too: as before
  info.coarse_level = quads ? 0 : 1;
  int k = info.coarse_level + 2 + std::max(0, options.extra_levels);

  // Refine until level k is reached and no semi-sharp sharpness is left.
  auto semi_sharp_left = [](const SubdivLevel& l) {
    for (float s : l.edge_sharpness) if (s > 0 && s < kInfiniteSharpness) return true;
    for (float s : l.vertex_sharpness) if (s > 0 && s < kInfiniteSharpness) return true;
    return false;
  };
  out.refinement.levels.push_back(base);
  std::vector<Point3> x = positions;
  const int k_cap = std::max(k, info.coarse_level + std::max(2, options.max_levels_above_coarse));
  for (int lvl = 0; lvl < k || (lvl < k_cap && semi_sharp_left(out.refinement.levels.back())); ++lvl) {
    RefinementStep step = refine_once(out.refinement.levels.back());
    std::vector<Point3> y;
    step.stencils.apply(x, y);
    x.swap(y);
    out.refinement.levels.push_back(std::move(step.child));
    out.refinement.steps.push_back(std::move(step.stencils));
  }
  k = static_cast<int>(out.refinement.levels.size()) - 1;
  info.level = k;
  {  // At the cap, what is still semi-sharp becomes a sharp crease.
    SubdivLevel& last = out.refinement.levels.back();
    for (float& s : last.edge_sharpness)
      if (s > 0 && s < kInfiniteSharpness) { s = static_cast<float>(kInfiniteSharpness); ++info.sharpened_edges; }
    for (float& s : last.vertex_sharpness)
      if (s > 0 && s < kInfiniteSharpness) { s = static_cast<float>(kInfiniteSharpness); ++info.sharpened_vertices; }
  }
  const int a = info.coarse_level, d = k - a, N = 1 << d;
  std::vector<char> capped_a;  // level-a faces inside polar caps
  const SubdivLevel& lk = out.refinement.levels[k];
  const PolyMesh& mk = lk.mesh;
  out.level_positions = x;
  LevelView L{lk, mk, out.level_positions};

  // Level-k faces inside polar caps (level t+1 face h is the child of level-t corner h).
  std::vector<char> capped = cap_face;
  for (int t = 0; t < k; ++t) {
    const PolyMesh& mt = out.refinement.levels[t].mesh;
    std::vector<char> next(mt.num_corners());
    for (int h = 0; h < mt.num_corners(); ++h) next[h] = capped[mt.corner_face(h)];
    capped.swap(next);
    if (t + 1 == a) capped_a = capped;
  }
  if (a == 0) capped_a = cap_face;

  // Limit positions of level-k vertices (closed-form masks: nothing semi-sharp is left).
  std::vector<Point3> limit;
  limit_stencils(lk).apply(out.level_positions, limit);

  // Regular nets.
  std::vector<Point3>& nets = out.level_nets;
  nets.assign(static_cast<size_t>(mk.num_faces()) * 16, Point3{});
  std::vector<char> zone(mk.num_faces(), 0);  // quad (0,0) of a fan
  for (int f = 0; f < mk.num_faces(); ++f) {
    bool regular = true;
    for (int h = mk.face_begin(f); h < mk.face_end(f); ++h) regular = regular && L.regular_corner(h);
    if (regular) regular_net(L, f, &nets[static_cast<size_t>(f) * 16]);
    else zone[f] = 1;
  }
  // Fans at irregular vertices (all are children of level-a vertices, 4 apart at level k).
  // What each fan says of its rays, per level-k edge. A sharp ray between two fans of one
  // vertex is recorded twice (C0 both times); every other ray belongs to one fan.
  struct RayRecord {
    int fan = -1;
    Continuity continuity = Continuity::C2;
    double c = 0;
  };
  std::vector<RayRecord> ray_of_edge(mk.num_edges());
  std::vector<char> covered(mk.num_faces(), 0);
  FanBuilder fb(L, limit, nets);
  const int va = out.refinement.levels[a].mesh.num_vertices();
  for (int v = 0; v < va; ++v) {
    for (const Fan& fan : fans_at(L, v)) {
      bool inside_cap = true;  // the pole of a polar cap: no Catmull-Clark patch there
      for (int c : fan.sectors) inside_cap = inside_cap && capped[mk.corner_face(c)];
      if (inside_cap) continue;
      std::vector<RayKind> kinds;
      std::vector<int> ray_edges;
      IrregularFan rec;
      rec.vertex = v;
      rec.base_vertex = v < base.mesh.num_vertices() ? v : -1;
      rec.mode = fan.mode;
      rec.valence = mk.valence(v);
      rec.sectors = static_cast<int>(fan.sectors.size());
      rec.c = fb.build(fan, kinds, ray_edges);
      info.fans.push_back(rec);
      for (int c : fan.sectors) covered[mk.corner_face(c)] = 1;
      for (size_t r = 0; r < kinds.size(); ++r)
        ray_of_edge[ray_edges[r]] = {static_cast<int>(info.fans.size()) - 1,
                                     kinds[r] == RayKind::G1 ? Continuity::G1 : Continuity::C0, rec.c};
    }
  }
  for (int f = 0; f < mk.num_faces(); ++f)
    if (zone[f] && !covered[f] && !capped[f])
      throw std::logic_error("patch builder: level-" + std::to_string(k) + " face " + std::to_string(f) +
                             " has an irregular corner that no fan covers");

  // Coarse quads: the grid of level-k frame corners inside each, by following child faces.
  const SubdivLevel& la = out.refinement.levels[a];
  const PolyMesh& ma = la.mesh;
  PatchSet& ps = out.set;
  std::vector<int> corner_of_vertex(ma.num_vertices(), -1);
  std::vector<int> curve_of_edge(ma.num_edges(), -1);
  const int dx[4] = {0, 1, 1, 0}, dy[4] = {0, 0, 1, 1};
  for (int F = 0; F < ma.num_faces(); ++F) {
    if (la.face_hole[F] || capped_a[F]) continue;
    std::vector<int> grid{ma.face_begin(F)};  // frame corners, row-major [y][x]
    int size = 1;
    for (int t = 0; t < d; ++t) {
      const PolyMesh& mp = out.refinement.levels[a + t].mesh;
      const PolyMesh& mc = out.refinement.levels[a + t + 1].mesh;
      std::vector<int> next(static_cast<size_t>(4) * size * size);
      for (int y = 0; y < size; ++y)
        for (int xx = 0; xx < size; ++xx) {
          const int c = grid[y * size + xx];
          const int P = mp.corner_face(c), r = rotation_in_face(mp, c);
          for (int j = 0; j < 4; ++j) {
            const int child_face = mp.face_begin(P) + (r + j) % mp.face_size(P);
            const int child_corner = mc.face_begin(child_face) + (4 - j) % 4;
            next[(2 * y + dy[j]) * 2 * size + 2 * xx + dx[j]] = child_corner;
          }
        }
      grid.swap(next);
      size *= 2;
    }
    // Corners with a fan construction decide the double knots.
    auto zone_at = [&](int gx, int gy) { return zone[mk.corner_face(grid[gy * N + gx])] != 0; };
    const bool z00 = zone_at(0, 0), z10 = zone_at(N - 1, 0), z11 = zone_at(N - 1, N - 1), z01 = zone_at(0, N - 1);
    NurbsPatch patch;
    patch.kind = (z00 || z10 || z11 || z01) ? PatchKind::Pccm : PatchKind::RegularBSpline;
    patch.knots_u = coarse_knots(N, z00 || z01, z10 || z11);
    patch.knots_v = coarse_knots(N, z00 || z10, z01 || z11);
    const auto Uf = patch.knots_u.flat(), Vf = patch.knots_v.flat();
    const auto ru = blossom_rows(Uf, N), rv = blossom_rows(Vf, N);
    patch.num_poles_u = static_cast<int>(ru.size());
    patch.num_poles_v = static_cast<int>(rv.size());
    patch.poles.resize(static_cast<size_t>(patch.num_poles_u) * patch.num_poles_v);
    for (int i = 0; i < patch.num_poles_u; ++i)
      for (int j = 0; j < patch.num_poles_v; ++j) {
        const int c = grid[rv[j].span * N + ru[i].span];
        const int f = mk.corner_face(c), r = rotation_in_face(mk, c);
        V3 s = V3::Zero();
        for (int q = 0; q < 4; ++q)
          for (int w = 0; w < 4; ++w)
            s += ru[i].w[q] * rv[j].w[w] * v3(nets[static_cast<size_t>(f) * 16 + face_net_index(r, q, w)]);
        patch.pole(i, j) = pt(s);
      }
    patch.base_faces.push_back(a == 0 ? F : base.mesh.corner_face(F));  // level-1 face F = child of corner F
    info.sub_corners.push_back(grid);
    (patch.kind == PatchKind::Pccm ? info.pccm_patches : info.regular_patches)++;

    const int pi = static_cast<int>(ps.patches.size());
    // Corners and boundary curves.
    for (int i = 0; i < 4; ++i) {
      const int va_i = ma.corner_vertex(ma.face_begin(F) + i);
      if (corner_of_vertex[va_i] < 0) {
        corner_of_vertex[va_i] = static_cast<int>(ps.corners.size());
        PatchCorner pc;
        pc.base_vertex = va_i < base.mesh.num_vertices() ? va_i : -1;
        const int ui = (i == 1 || i == 2) ? patch.num_poles_u - 1 : 0;  // corner i of the domain
        const int vi = (i == 2 || i == 3) ? patch.num_poles_v - 1 : 0;
        pc.position = patch.pole(ui, vi);
        ps.corners.push_back(pc);
      }
      patch.corners[i] = corner_of_vertex[va_i];
    }
    for (int side = 0; side < 4; ++side) {
      const int e = ma.corner_edge(ma.face_begin(F) + side);
      if (curve_of_edge[e] < 0) {
        curve_of_edge[e] = static_cast<int>(ps.curves.size());
        BoundaryCurve bc;
        bc.corner0 = patch.corners[side];
        bc.corner1 = patch.corners[(side + 1) % 4];
        const int nu = patch.num_poles_u, nv = patch.num_poles_v;
        switch (side) {
          case 0: bc.knots = patch.knots_u; for (int i = 0; i < nu; ++i) bc.poles.push_back(patch.pole(i, 0)); break;
          case 1: bc.knots = patch.knots_v; for (int j = 0; j < nv; ++j) bc.poles.push_back(patch.pole(nu - 1, j)); break;
          case 2: bc.knots = reversed(patch.knots_u); for (int i = nu; i-- > 0;) bc.poles.push_back(patch.pole(i, nv - 1)); break;
          default: bc.knots = reversed(patch.knots_v); for (int j = nv; j-- > 0;) bc.poles.push_back(patch.pole(0, j)); break;
        }
        ps.curves.push_back(std::move(bc));
        ps.curves.back().uses.push_back({pi, side, false});
      } else {
        BoundaryCurve& bc = ps.curves[curve_of_edge[e]];
        bc.uses.push_back({pi, side, bc.corner0 != patch.corners[side]});
      }
      patch.curves[side] = curve_of_edge[e];
      patch.curve_reversed[side] = ps.curves[curve_of_edge[e]].uses.back().reversed;
    }
    ps.patches.push_back(std::move(patch));
  }

  // Polar caps, after their neighbours: the boundary curves exist by now.
  std::vector<char> cap_boundary_edge(ma.num_edges(), 0);
  for (CapInfo& ci : info.caps) {
    const PolarStructure& st = ci.structure;
    ci.input = polar_net_of(st, positions);
    ci.cap = build_polar_cap(ci.input, options.cap);
    NurbsPatch patch = polar_cap_patch(ci.cap, a);
    patch.base_faces = st.cap_faces;
    const int pi = static_cast<int>(ps.patches.size());
    // Corners: the pole at (0,0) and (0,1); ring 2's spoke 0 at (1,0) and (1,1).
    const int pole_corner = static_cast<int>(ps.corners.size());
    ps.corners.push_back({ci.cap.centre, st.pole});
    const int rim_corner = corner_of_vertex[st.rings[1][0]];  // level-a index = cage index
    if (rim_corner < 0) throw std::logic_error("patch builder: polar cap without neighbour patches");
    patch.corners = {pole_corner, rim_corner, rim_corner, pole_corner};
    // The seam at spoke 0, used by sides 0 and 2.
    BoundaryCurve seam;
    seam.corner0 = pole_corner;
    seam.corner1 = rim_corner;
    seam.knots = patch.knots_u;
    for (int i = 0; i < patch.num_poles_u; ++i) seam.poles.push_back(patch.pole(i, 0));
    seam.uses = {{pi, 0, false}, {pi, 2, true}};
    seam.continuity = Continuity::C2;
    const int seam_curve = static_cast<int>(ps.curves.size());
    ps.curves.push_back(std::move(seam));
    patch.curves = {seam_curve, -1, seam_curve, -1};
    patch.curve_reversed = {false, false, true, false};
    // Side 1 (u = 1, v from 0 to 1): the level-a edges along ring 2, spoke 0 onwards.
    const int n = st.valence, pieces = n << a;
    int q = 0;
    for (int j = 0; j < n; ++j) {
      const int v0 = st.rings[1][j], v1 = st.rings[1][(j + 1) % n];
      const int e0 = base.mesh.find_edge(v0, v1);
      std::vector<int> level_edges{e0};
      if (a == 1) {  // the two halves: child edge 2e is the half at edge_vertex(e, 0)
        const bool v0_first = base.mesh.edge_vertex(e0, 0) == v0;
        level_edges = {2 * e0 + (v0_first ? 0 : 1), 2 * e0 + (v0_first ? 1 : 0)};
      }
      int at = corner_of_vertex[v0];
      for (int e : level_edges) {
        const int k_curve = curve_of_edge[e];
        if (k_curve < 0) throw std::logic_error("patch builder: polar cap boundary edge without a curve");
        BoundaryCurve& bc = ps.curves[k_curve];
        SidePiece piece;
        piece.curve = k_curve;
        piece.reversed = bc.corner0 != at;
        piece.t0 = static_cast<double>(q) / pieces;
        piece.t1 = static_cast<double>(q + 1) / pieces;
        at = piece.reversed ? bc.corner0 : bc.corner1;
        bc.uses.push_back({pi, 1, piece.reversed, piece.t0, piece.t1});
        patch.split_sides[1].push_back(piece);
        cap_boundary_edge[e] = 1;
        ++q;
      }
    }
    ci.patch = pi;
    info.sub_corners.emplace_back();
    ps.patches.push_back(std::move(patch));
  }

  // Continuity claims per coarse edge, and the rays of irregular vertices.
  ps.closed = true;
  for (int e = 0; e < ma.num_edges(); ++e) {
    const int ci = curve_of_edge[e];
    if (ci < 0) continue;
    BoundaryCurve& bc = ps.curves[ci];
    if (bc.uses.size() < 2) {
      bc.continuity = Continuity::Boundary;
      ps.closed = false;
      continue;
    }
    // Sharp if any of its level-k pieces is (semi-sharp creases made sharp at the level cap
    // count: the patches are built with them).
    bool sharp = false;
    for (int ek = e << d; ek < (e + 1) << d; ++ek) sharp = sharp || L.sharp(ek);
    if (sharp) {
      bc.continuity = Continuity::C0;
      continue;
    }
    if (cap_boundary_edge[e]) {
      // C2 in geometry, but the cap's parameter is an affine image of the neighbours'
      // (MATH.md 4.2: x_u = 2^-s x_U), so derivatives are not equal: claimed G1.
      bc.continuity = Continuity::G1;
      continue;
    }
    bc.continuity = Continuity::C2;
    // The level-k edge of this coarse edge at each end vertex.
    for (int end = 0; end < 2; ++end) {
      const int v = ma.edge_vertex(e, end);
      // Walk down the levels: the half of the edge at v.
      int ek = e;
      for (int t = a; t < k; ++t) {
        const PolyMesh& mp = out.refinement.levels[t].mesh;
        ek = 2 * ek + (mp.edge_vertex(ek, 0) == v ? 0 : 1);
      }
      const RayRecord& rr = ray_of_edge[ek];
      if (rr.fan < 0) continue;
      if (static_cast<int>(rr.continuity) < static_cast<int>(bc.continuity)) bc.continuity = rr.continuity;
      RayCurve ray;
      ray.curve = ci;
      ray.vertex_at_start = corner_of_vertex[v] == bc.corner0;
      ray.fan = rr.fan;
      ray.continuity = rr.continuity;
      ray.c = rr.c;
      info.rays.push_back(ray);
    }
  }

  if (!positions.empty()) ps.model_size = bounding_diagonal(positions);
  return out;
}

}  // namespace subd2nurbs
