#include "core/eval/quality.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/nurbs/nurbs_eval.h"
#include "core/util/constants.h"
#include "core/util/parallel.h"
#include "core/util/tolerances.h"
#include "core/util/vec3.h"

namespace subd2nurbs {

namespace {

using vec3::dot;
using vec3::sub;
using vec3::norm;

double angle_deg(const Point3& a, const Point3& b) {
  const double na = norm(a), nb = norm(b);
  if (!(na > 0 && nb > 0)) return 0;
  // atan2 of |a x b| and a.b: accurate for small angles too.
  const Point3 c = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  return std::atan2(norm(c), dot(a, b)) * 180.0 / kPi;
}

/// The limit's unit normal at p: from the first derivatives (evaluate_point, which skips the
/// second derivatives and curvature where the face is regular or Stam's; unit_normal), else,
/// where they are (nearly) parallel, as at an extraordinary vertex, evaluate()'s normal, which
/// has its fallback there.
Point3 limit_normal(const LimitEvaluator& L, const LimitParam& p) {
  const LimitPoint q = L.evaluate_point(p.face, p.sub, p.u, p.v);
  SurfaceDerivs d;
  d.du = q.du;
  d.dv = q.dv;
  const Point3 n = unit_normal(d);
  if (n[0] != 0 || n[1] != 0 || n[2] != 0) return n;
  return L.evaluate(p.face, p.sub, p.u, p.v).normal;
}

/// Level-a face of a patch.
int coarse_face(const PatchBuild& b, int patch) { return b.coarse_face.at(static_cast<size_t>(patch)); }

/// Closest point on the limit surface near `p` (Gauss-Newton in p's face, parameters clamped
/// to [0,1]^2). The search stops once a step would move the point by less than `stop` (model
/// units): the distance cannot drop by more than that. `at_p`: the limit at p when the caller
/// has it already.
double closest_distance(const LimitEvaluator& L, LimitParam p, const Point3& x, double stop,
                        const LimitSample* at_p = nullptr) {
  LimitPoint q = at_p ? LimitPoint{at_p->p, at_p->du, at_p->dv} : L.evaluate_point(p.face, p.sub, p.u, p.v);
  double best = norm(sub(q.p, x));
  for (int it = 0; it < 12 && best > 0; ++it) {
    const Point3 r = sub(q.p, x);
    const double a11 = dot(q.du, q.du), a12 = dot(q.du, q.dv), a22 = dot(q.dv, q.dv);
    const double b1 = -dot(q.du, r), b2 = -dot(q.dv, r);
    const double det = a11 * a22 - a12 * a12;
    if (!(std::abs(det) > 0)) break;
    const double du = (b1 * a22 - b2 * a12) / det, dv = (a11 * b2 - a12 * b1) / det;
    const double nu = std::clamp(p.u + du, 0.0, 1.0), nv = std::clamp(p.v + dv, 0.0, 1.0);
    if (nu == p.u && nv == p.v) break;
    const double su = nu - p.u, sv = nv - p.v;  // the step taken, in model space below
    const Point3 step{su * q.du[0] + sv * q.dv[0], su * q.du[1] + sv * q.dv[1], su * q.du[2] + sv * q.dv[2]};
    if (norm(step) < stop) break;
    p.u = nu;
    p.v = nv;
    q = L.evaluate_point(p.face, p.sub, p.u, p.v);
    const double d = norm(sub(q.p, x));
    if (d >= best) {
      if (std::abs(du) + std::abs(dv) < 1e-14) break;
    }
    best = std::min(best, d);
    if (std::abs(du) + std::abs(dv) < 1e-14) break;
  }
  return best;
}

/// Parameters along one side of a sample grid.
using Parameters = SmallVector<double, 16>;

/// A surface's values at a quad's sample grid (s_i, t_j), out[i * nt + j]. of_s[i] and of_t[j]
/// are the surface parameters that follow the quad's s and t: the first and second one, or,
/// `turned` (a quarter turn between the quad and the surface), the second and first.
/// grid(us, nu, vs, nv, o) fills o[a * nv + b] with the values at (us[a], vs[b]).
template <class T, class Grid>
void on_quad_grid(bool turned, const Parameters& of_s, const Parameters& of_t, Grid&& grid, std::vector<T>& out) {
  const int ns = static_cast<int>(of_s.size()), nt = static_cast<int>(of_t.size());
  out.resize(static_cast<size_t>(ns) * nt);
  if (!turned) {
    grid(of_s.data(), ns, of_t.data(), nt, out.data());
    return;
  }
  thread_local std::vector<T> by_t;  // by_t[j * ns + i]: (t_j, s_i)
  by_t.resize(out.size());
  grid(of_t.data(), nt, of_s.data(), ns, by_t.data());
  for (int i = 0; i < ns; ++i)
    for (int j = 0; j < nt; ++j) out[static_cast<size_t>(i) * nt + j] = by_t[static_cast<size_t>(j) * ns + i];
}

/// True where `face` over the cell [u, u+1] x [v, v+1] is one polynomial of degree <= 3 in
/// each parameter: not rational, no knot strictly inside the cell.
bool polynomial_cell(const NurbsPatch& face, int u, int v) {
  if (!face.weights.empty() || face.degree_u > 3 || face.degree_v > 3) return false;
  const auto knot_inside = [](const KnotVector& kv, double lo) {  // knots are increasing
    const double* next = std::upper_bound(kv.knots.begin(), kv.knots.end(), lo);
    return next != kv.knots.end() && *next < lo + 1;
  };
  return !knot_inside(face.knots_u, u) && !knot_inside(face.knots_v, v);
}

/// The surfaces measured: the quad patches themselves, or the exported faces holding them,
/// each with its knots expanded once.
class MeasuredSurfaces {
 public:
  MeasuredSurfaces(const PatchBuild& b, const PackedSet* exported) : exported_(exported) {
    const PatchSet& set = exported ? exported->set : b.set;
    faces_.reserve(set.patches.size());
    for (const NurbsPatch& p : set.patches) faces_.emplace_back(p);
  }
  /// The surface at quad patch `pi`'s parameters (s, t), with derivatives up to `order` (in
  /// the exported face's parameters).
  SurfaceDerivs at(int pi, double s, double t, int order) const {
    if (!exported_) return faces_[static_cast<size_t>(pi)].derivs(s, t, order);
    const PatchPlace& place = exported_->place[static_cast<size_t>(pi)];
    double u, v;
    place_parameters(place, s, t, u, v);
    return faces_[static_cast<size_t>(place.patch)].derivs(u, v, order);
  }
  /// The surface's points at quad patch `pi`'s grid (s_i, t_j), out[i * t.size() + j], from one
  /// grid evaluation (one basis evaluation per parameter instead of two per point). A quad's
  /// cell in an exported face is turned by quarter turns, so the image of the grid is a grid.
  void points(int pi, const SampleGrid& g, std::vector<Point3>& out) const {
    const PatchEvaluator* face = &faces_[static_cast<size_t>(pi)];
    bool turned = false;
    Parameters of_s = g.s, of_t = g.t;
    if (exported_) {
      const PatchPlace& place = exported_->place[static_cast<size_t>(pi)];
      face = &faces_[static_cast<size_t>(place.patch)];
      turned = (place.rotation & 1) != 0;  // s runs along v, t along u
      double u, v;
      for (size_t i = 0; i < g.s.size(); ++i) {
        place_parameters(place, g.s[i], g.t[0], u, v);
        of_s[i] = turned ? v : u;
      }
      for (size_t j = 0; j < g.t.size(); ++j) {
        place_parameters(place, g.s[0], g.t[j], u, v);
        of_t[j] = turned ? u : v;
      }
    }
    on_quad_grid(turned, of_s, of_t,
                 [&](const double* us, int nu, const double* vs, int nv, Point3* o) { face->grid(us, nu, vs, nv, o); },
                 out);
  }

 private:
  const PackedSet* exported_;
  std::vector<PatchEvaluator> faces_;
};

/// The limit at quad patch `pi`'s grid (s_i, t_j), out[i * t.size() + j], through
/// Where a quad's sample grid (s_i, t_j) lies on the limit: patch_to_limit turns and scales a
/// quad's parameters, so each limit parameter follows one of s and t.
struct LimitGrid {
  LimitParam at;        ///< the face, sub-face and parameters of (s_0, t_0)
  bool turned = false;  ///< u follows t, v follows s
  Parameters of_s, of_t;

  LimitGrid(const PatchBuild& b, int pi, const SampleGrid& g) : at(patch_to_limit(b, pi, g.s[0], g.t[0])) {
    turned = patch_to_limit(b, pi, g.s[1], g.t[0]).u == at.u;
    for (double s : g.s) {
      const LimitParam l = patch_to_limit(b, pi, s, g.t[0]);
      of_s.push_back(turned ? l.v : l.u);
    }
    for (double t : g.t) {
      const LimitParam l = patch_to_limit(b, pi, g.s[0], t);
      of_t.push_back(turned ? l.u : l.v);
    }
  }
  /// The limit parameters of sample (s_i, t_j): patch_to_limit(b, pi, s_i, t_j).
  LimitParam param(size_t i, size_t j) const {
    LimitParam l = at;
    l.u = turned ? of_t[j] : of_s[i];
    l.v = turned ? of_s[i] : of_t[j];
    return l;
  }
  /// The limit at the grid, out[i * t.size() + j] at param(i, j) (LimitEvaluator::evaluate_grid).
  void evaluate(const LimitEvaluator& limit, std::vector<LimitSample>& out) const {
    on_quad_grid(turned, of_s, of_t,
                 [&](const double* us, int nu, const double* vs, int nv, LimitSample* o) {
                   limit.evaluate_grid(at.face, at.sub, us, nu, vs, nv, o);
                 },
                 out);
  }
};

/// Samples reduced in order: counts, sums and maxima, with the rules of the report (the worst
/// distance is the first sample reaching it, the largest |H| the last). Merging reductions in
/// order gives the reduction of the concatenated samples.
struct PatchSamples {
  bool polynomial = false;
  int polynomial_patches = 0;
  int samples = 0;
  double distance_sum = 0, parametric_sum = 0, distance_max = 0, parametric_max = 0;
  DeviationSample worst;  // patch -1: no sample yet
  CurvatureSummary curvature;  // its means are set at the end, from the sums
  double abs_mean_sum = 0, mean2_sum = 0;

  PatchSamples() {
    curvature.min_k = HUGE_VAL;
    curvature.max_k = -HUGE_VAL;
  }

  void add(const DeviationSample& d, const LimitSample& L) {
    ++samples;
    distance_sum += d.distance;
    parametric_sum += d.parametric;
    parametric_max = std::max(parametric_max, d.parametric);
    if (d.distance > distance_max || worst.patch < 0) {
      distance_max = std::max(distance_max, d.distance);
      if (d.distance >= distance_max) worst = d;
    }
    if (!(L.exact_derivatives && std::isfinite(L.k1) && std::isfinite(L.k2))) return;
    CurvatureSummary& c = curvature;
    ++c.samples;
    c.min_k = std::min(c.min_k, L.k2);
    c.max_k = std::max(c.max_k, L.k1);
    c.max_abs_gauss = std::max(c.max_abs_gauss, std::abs(L.gauss));
    if (std::abs(L.mean) >= c.max_abs_mean) {
      c.max_abs_mean = std::abs(L.mean);
      c.where_max_abs_mean = d;
      c.where_max_abs_mean.point = L.p;
    }
    abs_mean_sum += std::abs(L.mean);
    mean2_sum += L.mean * L.mean;
  }

  void merge(const PatchSamples& o) {
    polynomial_patches += o.polynomial_patches + (o.polynomial ? 1 : 0);
    if (o.samples == 0) return;
    samples += o.samples;
    distance_sum += o.distance_sum;
    parametric_sum += o.parametric_sum;
    parametric_max = std::max(parametric_max, o.parametric_max);
    if (o.distance_max > distance_max || worst.patch < 0) {
      distance_max = std::max(distance_max, o.distance_max);
      worst = o.worst;
    }
    const CurvatureSummary& oc = o.curvature;
    if (oc.samples == 0) return;
    CurvatureSummary& c = curvature;
    c.samples += oc.samples;
    c.min_k = std::min(c.min_k, oc.min_k);
    c.max_k = std::max(c.max_k, oc.max_k);
    c.max_abs_gauss = std::max(c.max_abs_gauss, oc.max_abs_gauss);
    if (oc.max_abs_mean >= c.max_abs_mean) {
      c.max_abs_mean = oc.max_abs_mean;
      c.where_max_abs_mean = oc.where_max_abs_mean;
    }
    abs_mean_sum += o.abs_mean_sum;
    mean2_sum += o.mean2_sum;
  }
};

}  // namespace

LimitParam patch_to_limit(const PatchBuild& b, int patch, double s, double t) {
  if (patch < 0 || patch >= static_cast<int>(b.set.patches.size()))
    throw std::out_of_range("patch_to_limit: no patch " + std::to_string(patch));
  if (b.set.patches[static_cast<size_t>(patch)].kind == PatchKind::PolarCap)
    throw std::invalid_argument("patch_to_limit: patch " + std::to_string(patch) +
                                " is a polar cap (not a piece of the Catmull-Clark limit)");
  const int F = coarse_face(b, patch);
  if (b.info.coarse_level == 0) return {F, 0, s, t};
  const PolyMesh& m0 = b.refinement.levels[0].mesh;
  const int g = m0.corner_face(F);  // level-1 face F is the child of base corner F
  const int k = F - m0.face_begin(g);
  if (m0.face_size(g) != 4) return {g, k, s, t};
  // A quarter of a quad: the child frame at corner k (docs/limit.md, refiner.h layout).
  switch (k) {
    case 0: return {g, 0, s / 2, t / 2};
    case 1: return {g, 0, 1 - t / 2, s / 2};
    case 2: return {g, 0, 1 - s / 2, 1 - t / 2};
    default: return {g, 0, t / 2, 1 - s / 2};
  }
}

double limit_distance(const PatchBuild& b, const LimitEvaluator& limit, int patch, double s, double t) {
  const LimitParam lp = patch_to_limit(b, patch, s, t);
  const Point3 x = evaluate(b.set.patches[static_cast<size_t>(patch)], s, t).p;
  return closest_distance(limit, lp, x, tolerances::kSameSurface * b.set.model_size);
}

bool sampled_as_polynomial(const PatchBuild& b, const LimitEvaluator& limit, int patch, const PackedSet* exported) {
  const NurbsPatch& p = b.set.patches.at(static_cast<size_t>(patch));
  if (p.kind == PatchKind::PolarCap) return false;
  const LimitParam at = patch_to_limit(b, patch, 0.5, 0.5);
  if (!limit.is_polynomial(at.face, at.sub)) return false;
  if (!exported) return polynomial_cell(p, 0, 0);
  const PatchPlace& place = exported->place.at(static_cast<size_t>(patch));
  return polynomial_cell(exported->set.patches.at(static_cast<size_t>(place.patch)), place.u, place.v);
}

std::vector<SampleGrid> quality_sample_grids(const PatchBuild& b, int patch, int n, bool polynomial) {
  std::vector<SampleGrid> out(1);
  if (polynomial) n = std::min(n, kPolynomialSamples);
  for (int i = 0; i < n; ++i) out[0].s.push_back(static_cast<double>(i) / (n - 1));
  out[0].t = out[0].s;
  const NurbsPatch& p = b.set.patches.at(static_cast<size_t>(patch));
  if (p.kind != PatchKind::Pccm) return out;
  // Construction Q changes the surface only in the level-k quads next to an irregular corner,
  // 2^-(k-a) of the patch wide: a few rings of samples, halving towards each corner.
  int zone_level = b.info.coarse_level;
  for (const PatchLeaf& l : b.leaves.at(static_cast<size_t>(patch)))
    if (l.zone) zone_level = std::max(zone_level, l.level);
  const int depth = zone_level - b.info.coarse_level + 1;
  const double w[4] = {0.2, 0.45, 0.7, 0.95};
  for (int m = 1; m <= depth; ++m) {
    const double h = std::ldexp(1.0, -m);
    std::vector<double> low, high;  // h w from the corner at 0, and from the corner at 1
    for (double x : w) {
      low.push_back(h * x);
      high.push_back(1 - h * x);
    }
    // Corners (0,0), (1,0), (1,1), (0,1).
    out.push_back({low, low});
    out.push_back({high, low});
    out.push_back({high, high});
    out.push_back({low, high});
  }
  return out;
}

std::vector<std::array<double, 2>> quality_sample_parameters(const PatchBuild& b, int patch, int n, bool polynomial) {
  std::vector<std::array<double, 2>> out;
  for (const SampleGrid& g : quality_sample_grids(b, patch, n, polynomial))
    for (double s : g.s)
      for (double t : g.t) out.push_back({s, t});
  return out;
}

QualityReport measure_quality(const PatchBuild& b, const LimitEvaluator& limit,
                              const ContinuityReport& continuity, int n, const PackedSet* exported) {
  return measure_quality(b, limit, continuity, n, exported, compare_vertex_curvature(limit));
}

QualityReport measure_quality(const PatchBuild& b, const LimitEvaluator& limit, const ContinuityReport& continuity,
                              int n, const PackedSet* exported, const VertexCurvatureComparison& quadric) {
  if (n < 2) throw std::invalid_argument("measure_quality: at least 2 samples per side");
  QualityReport q;
  q.samples_per_side = n;
  const PatchSet& ps = b.set;
  q.patch_max.assign(ps.patches.size(), 0.0);
  // The patches are sampled in parallel, a block at a time, each reduced on its own in sample
  // order (PatchSamples); the patches are then combined in patch order by the same rules, so the
  // report does not depend on the threads.
  const int num_patches = static_cast<int>(ps.patches.size());
  const MeasuredSurfaces measured_surface(b, exported);
  const double same_surface = tolerances::kSameSurface * ps.model_size;
  constexpr int kBlock = 4096;
  std::vector<PatchSamples> block(kBlock);
  PatchSamples all;
  for (int first = 0; first < num_patches; first += kBlock) {
    const int count = std::min(kBlock, num_patches - first);
    parallel_for(count, [&](int i) {
      const int pi = first + i;
      PatchSamples& out = block[i];
      out = PatchSamples{};
      if (ps.patches[pi].kind == PatchKind::PolarCap) return;
      // Each grid of samples (quality_sample_grids) is one grid evaluation of the surface and
      // one of the limit, in the order of quality_sample_parameters.
      thread_local std::vector<Point3> grid;
      thread_local std::vector<LimitSample> limit_samples;
      out.polynomial = sampled_as_polynomial(b, limit, pi, exported);
      for (const SampleGrid& g : quality_sample_grids(b, pi, n, out.polynomial)) {
        measured_surface.points(pi, g, grid);
        const LimitGrid on_limit(b, pi, g);
        on_limit.evaluate(limit, limit_samples);
        for (size_t k = 0; k < grid.size(); ++k) {
          DeviationSample d;
          d.patch = pi;
          d.s = g.s[k / g.t.size()];
          d.t = g.t[k % g.t.size()];
          d.point = grid[k];
          const LimitSample& L = limit_samples[k];
          d.parametric = norm(sub(d.point, L.p));
          // The closest-point distance is at most the same-parameter one; searching for it only
          // pays where the patch is not the limit itself (Construction Q reparametrizes). It
          // starts from the limit sample at the same parameters.
          d.limit = on_limit.param(k / g.t.size(), k % g.t.size());
          d.distance = d.parametric > same_surface
                           ? std::min(d.parametric, closest_distance(limit, d.limit, d.point, same_surface, &L))
                           : d.parametric;
          out.add(d, L);
        }
      }
    });
    for (int i = 0; i < count; ++i) {
      if (ps.patches[first + i].kind == PatchKind::PolarCap) {  // Bi-cubic polar, not Catmull-Clark: not measured
        ++q.polar_patches;
        continue;
      }
      q.patch_max[first + i] = block[i].distance_max;
      all.merge(block[i]);
    }
  }
  q.polynomial_patches = all.polynomial_patches;
  q.deviation_samples = all.samples;
  q.deviation_max = all.distance_max;
  q.parametric_max = all.parametric_max;
  q.worst = all.worst;
  if (q.deviation_samples > 0) {
    q.deviation_mean = all.distance_sum / q.deviation_samples;
    q.parametric_mean = all.parametric_sum / q.deviation_samples;
  }
  CurvatureSummary& cs = q.curvature;
  cs = all.curvature;
  if (cs.samples > 0) {
    cs.mean_abs_mean = all.abs_mean_sum / cs.samples;
    cs.rms_mean = std::sqrt(all.mean2_sum / cs.samples);
  } else {
    cs.min_k = cs.max_k = 0;
  }

  // Edges: the patches' joins against the limit's behaviour across the same edges.
  const int a = b.info.coarse_level;
  const SubdivLevel& La = b.refinement.levels[a];
  for (const BoundaryCurve& c : ps.curves)
    if (c.uses.size() == 1) ++q.boundary_edges;
  const int m = 24;
  // Each shared curve's limit normal jump is measured in parallel, then taken in curve order.
  const int num_curves = static_cast<int>(continuity.curves.size());
  std::vector<EdgeQuality> measured(num_curves);
  std::vector<char> measured_ok(num_curves, 0);
  parallel_for(num_curves, [&](int ci) {
    const CurveMeasure& cm = continuity.curves[ci];
      // The quads' own curves (several where exported faces joined coarse edges): their uses
    // give the coarse edge and the limit's parameters.
    const std::vector<int> one{cm.curve};
    const std::vector<int>& sources = exported ? exported->source_curves[cm.curve] : one;
    for (int k : sources) {
      const BoundaryCurve& c = ps.curves[k];
      if (c.uses.size() != 2) return;
      if (ps.patches[c.uses[0].patch].kind == PatchKind::PolarCap ||
          ps.patches[c.uses[1].patch].kind == PatchKind::PolarCap)
        return;  // a polar cap's side: the limit there is BP subdivision's
    }
    EdgeQuality& e = measured[ci];
    measured_ok[ci] = 1;
    e.curve = cm.curve;
    e.claimed = cm.claimed;
    e.gap = cm.gap;
    e.normal_jump_deg = cm.normal_angle_deg;
    for (int k : sources) {
      const BoundaryCurve& c = ps.curves[k];
      const CurveUse& u0 = c.uses[0];
      const int F = coarse_face(b, u0.patch);
      const int edge = La.mesh.corner_edge(La.mesh.face_begin(F) + u0.side);
      const bool crease = La.edge_sharpness[edge] >= static_cast<float>(kInfiniteSharpness);
      e.expected = crease ? "crease" : "smooth";
      for (int i = 0; i < m; ++i) {
        const double s = (i + 0.5) / m;  // interior samples: the curve's ends may be singular
        Point3 pn[2], ln[2];
        for (int w = 0; w < 2; ++w) {
          const CurveUse& use = c.uses[w];
          double pu, pv;
          side_parameters(use.side, use.reversed ? 1 - s : s, pu, pv);
          pn[w] = unit_normal(measured_surface.at(use.patch, pu, pv, 1));
          if (crease) ln[w] = limit_normal(limit, patch_to_limit(b, use.patch, pu, pv));
        }
        // Across an edge that is not infinitely sharp the limit is tangent-plane continuous at
        // every interior point of the edge (docs/math.md 11.2): its normal jump there is 0.
        const double pj = angle_deg(pn[0], pn[1]), lj = crease ? angle_deg(ln[0], ln[1]) : 0.0;
        e.limit_normal_jump_deg = std::max(e.limit_normal_jump_deg, lj);
        e.normal_jump_error_deg = std::max(e.normal_jump_error_deg, std::abs(pj - lj));
      }
    }
  });
  for (int ci = 0; ci < num_curves; ++ci) {
    if (!measured_ok[ci]) continue;
    const EdgeQuality& e = measured[ci];
    const bool crease = std::string(e.expected) == "crease";
    (crease ? q.crease_edges : q.smooth_edges)++;
    q.max_gap = std::max(q.max_gap, e.gap);
    if (!crease) q.max_smooth_normal_jump_deg = std::max(q.max_smooth_normal_jump_deg, e.normal_jump_deg);
    q.max_normal_jump_error_deg = std::max(q.max_normal_jump_error_deg, e.normal_jump_error_deg);
    if ((crease && e.claimed != Continuity::C0) || (!crease && e.claimed == Continuity::C0))
      ++q.class_mismatches;
    q.edges.push_back(e);
  }
  q.quadric = quadric;
  return q;
}

}  // namespace subd2nurbs
