#include "converter/occt/brep_builder.h"

#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <BRepCheck_Analyzer.hxx>
#include <BRepCheck_Wire.hxx>
#include <Geom2d_BSplineCurve.hxx>
#include <Geom2d_Line.hxx>
#include <Geom_BSplineCurve.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_Plane.hxx>
#include <GeomAdaptor_Surface.hxx>
#include <Precision.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColStd_Array2OfReal.hxx>
#include <TColgp_Array1OfPnt.hxx>
#include <TColgp_Array1OfPnt2d.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <TopExp.hxx>
#include <TopTools_DataMapOfShapeInteger.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Shell.hxx>
#include <TopoDS_Solid.hxx>
#include <TopoDS_Vertex.hxx>
#include <TopoDS_Wire.hxx>
#include <gp_Ax3.hxx>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include "converter/occt/occt_util.h"
#include "core/patch/planar_faces.h"
#include "core/util/tolerances.h"

namespace subd2nurbs::occt {

using detail::guarded;

double brep_tolerance(double model_size) {
  const double tol = 1e-9 * model_size;
  // Precision::Confusion() (1e-7) is the smallest distance OCCT's algorithms tell apart; a
  // smaller tolerance is not honoured by BRepCheck and friends anyway.
  return std::isfinite(tol) && tol > Precision::Confusion() ? tol : Precision::Confusion();
}

namespace {

gp_Pnt to_pnt(const Point3& p) { return gp_Pnt(p[0], p[1], p[2]); }

/// Knots and multiplicities as OCCT arrays (1-based, like everything in OCCT).
void to_occt(const KnotVector& kv, TColStd_Array1OfReal& knots, TColStd_Array1OfInteger& mults) {
  knots.Resize(1, static_cast<int>(kv.knots.size()), false);
  mults.Resize(1, static_cast<int>(kv.mults.size()), false);
  for (size_t i = 0; i < kv.knots.size(); ++i) {
    knots(static_cast<int>(i) + 1) = kv.knots[i];
    mults(static_cast<int>(i) + 1) = kv.mults[i];
  }
}

/// Checks a knot vector against the PatchSet conventions (clamped, non-periodic) so that the
/// error names the patch instead of surfacing as a bare Standard_ConstructionError.
void check_knots(const KnotVector& kv, int degree, int num_poles, const char* what, int patch) {
  auto fail = [&](const std::string& why) {
    throw ExportError("patch", patch, std::string(what) + ": " + why);
  };
  if (kv.periodic) fail("periodic knot vectors are not supported (PatchSet patches are clamped)");
  if (kv.knots.size() < 2 || kv.knots.size() != kv.mults.size())
    fail("needs at least two distinct knots and one multiplicity per knot");
  for (size_t i = 1; i < kv.knots.size(); ++i)
    if (!(kv.knots[i] > kv.knots[i - 1])) fail("knots are not strictly increasing");
  if (kv.num_poles(degree) != num_poles)
    fail("knots give " + std::to_string(kv.num_poles(degree)) + " poles, but there are " +
         std::to_string(num_poles));
}

Handle(Geom_BSplineSurface) make_surface(const NurbsPatch& patch, int index) {
  if (patch.num_poles_u < 2 || patch.num_poles_v < 2 ||
      patch.poles.size() != static_cast<size_t>(patch.num_poles_u) * patch.num_poles_v)
    throw ExportError("patch", index, "pole count does not match num_poles_u x num_poles_v");
  if (!patch.weights.empty() && patch.weights.size() != patch.poles.size())
    throw ExportError("patch", index, "weights must be empty or one per pole");
  check_knots(patch.knots_u, patch.degree_u, patch.num_poles_u, "u knots", index);
  check_knots(patch.knots_v, patch.degree_v, patch.num_poles_v, "v knots", index);

  return guarded("surface", index, [&] {
    TColgp_Array2OfPnt poles(1, patch.num_poles_u, 1, patch.num_poles_v);
    for (int i = 0; i < patch.num_poles_u; ++i)
      for (int j = 0; j < patch.num_poles_v; ++j) poles(i + 1, j + 1) = to_pnt(patch.pole(i, j));
    TColStd_Array1OfReal uknots, vknots;
    TColStd_Array1OfInteger umults, vmults;
    to_occt(patch.knots_u, uknots, umults);
    to_occt(patch.knots_v, vknots, vmults);
    if (patch.weights.empty())
      return new Geom_BSplineSurface(poles, uknots, vknots, umults, vmults, patch.degree_u,
                                     patch.degree_v);
    TColStd_Array2OfReal weights(1, patch.num_poles_u, 1, patch.num_poles_v);
    for (int i = 0; i < patch.num_poles_u; ++i)
      for (int j = 0; j < patch.num_poles_v; ++j)
        weights(i + 1, j + 1) = patch.weights[static_cast<size_t>(i) * patch.num_poles_v + j];
    return new Geom_BSplineSurface(poles, weights, uknots, vknots, umults, vmults,
                                   patch.degree_u, patch.degree_v);
  });
}

/// A face whose surface closes onto itself along a seam (the same curve on its sides 1 and 3:
/// closed in u; on sides 0 and 2: closed in v; a packed cylinder's side, a torus, a polar cap)
/// gets its surface made periodic in that direction, as OCCT's own closed faces are: the same
/// poles and knots but the repeated pole row, i.e. the same surface, and the same parameter
/// range, so the pcurves along the sides (the seam's two lines at the range's ends) are those
/// of the clamped surface. OCCT's offset and shell algorithms extend a face's surface before
/// intersecting it with its neighbours; a clamped closed B-spline is taken whole (both ends of
/// the seam, wrapping round), a periodic one over the face's own range plus a margin
/// (BRepOffset_Tool::EnLargeFace), which is what lets a cut-then-shell through a wrapping
/// face succeed (docs/downstream.md).
void make_closed_periodic(const NurbsPatch& patch, const Handle(Geom_BSplineSurface)& surface, int index) {
  guarded("surface", index, [&] {
    if (patch.curves[1] >= 0 && patch.curves[1] == patch.curves[3] && surface->IsUClosed())
      surface->SetUPeriodic();
    if (patch.curves[0] >= 0 && patch.curves[0] == patch.curves[2] && surface->IsVClosed())
      surface->SetVPeriodic();
  });
}

/// The 3D curve of an edge: the curve's poles with its knots mapped affinely onto `range`
/// (the edge's parameter range, see edge_parameter_range), so the same curve, reparametrized linearly.
Handle(Geom_BSplineCurve) make_curve(const BoundaryCurve& curve, int index, int patch,
                                     std::pair<double, double> range) {
  const int n = static_cast<int>(curve.poles.size());
  if (n < 2) throw ExportError("edge", patch, "curve " + std::to_string(index) + " has < 2 poles");
  check_knots(curve.knots, curve.degree, n, ("curve " + std::to_string(index)).c_str(), patch);
  return guarded("edge", patch, [&] {
    TColgp_Array1OfPnt poles(1, n);
    for (int i = 0; i < n; ++i) poles(i + 1) = to_pnt(curve.poles[static_cast<size_t>(i)]);
    TColStd_Array1OfReal knots;
    TColStd_Array1OfInteger mults;
    to_occt(curve.knots, knots, mults);
    const double k0 = curve.knots.knots.front(), k1 = curve.knots.knots.back();
    const int nk = knots.Upper();
    if (range.first != k0 || range.second != k1) {
      const double scale = (range.second - range.first) / (k1 - k0);
      for (int i = 1; i <= nk; ++i) knots(i) = range.first + (knots(i) - k0) * scale;
      knots(1) = range.first;  // the ends exactly, whatever the rounding
      knots(nk) = range.second;
      for (int i = 2; i <= nk; ++i)
        if (!(knots(i) > knots(i - 1)))
          throw ExportError("edge", patch, "curve " + std::to_string(index) +
                                               ": knots collapse when mapped onto the face's parameters");
    }
    return new Geom_BSplineCurve(poles, knots, mults, curve.degree);
  });
}

/// The parameter rectangle of a patch: first and last knot in u and v ([0,1]^2 by convention,
/// but nothing here depends on that).
struct Domain {
  double u0, u1, v0, v1;
};

/// Start and end of side `side` in the (u, v) domain, traversed counter-clockwise.
std::pair<gp_Pnt2d, gp_Pnt2d> side_ends(const Domain& d, int side) {
  const gp_Pnt2d c[4] = {{d.u0, d.v0}, {d.u1, d.v0}, {d.u1, d.v1}, {d.u0, d.v1}};
  return {c[side], c[(side + 1) % 4]};
}

/// The pcurve of a straight segment from `a` (at parameter t0) to `b` (at t1), parametrized
/// so that its parameter is t. A Geom2d_Line has unit speed, so it only fits when |b - a|
/// equals t1 - t0 (the usual case: [0,1] curve on a [0,1]^2 side); otherwise a degree-1
/// B-spline does the same job with any speed.
Handle(Geom2d_Curve) segment(const gp_Pnt2d& a, const gp_Pnt2d& b, double t0, double t1) {
  const gp_Vec2d ab(a, b);
  const double length = ab.Magnitude();
  if (length > 0 && std::abs(length - (t1 - t0)) <= 1e-14 * (t1 - t0)) {
    const gp_Dir2d dir(ab);
    // Line point at parameter t is origin + t * dir, so the origin sits at -t0 from a.
    return new Geom2d_Line(gp_Pnt2d(a.XY() - t0 * dir.XY()), dir);
  }
  TColgp_Array1OfPnt2d poles(1, 2);
  poles(1) = a;
  poles(2) = b;
  TColStd_Array1OfReal knots(1, 2);
  knots(1) = t0;
  knots(2) = t1;
  TColStd_Array1OfInteger mults(1, 2);
  mults(1) = mults(2) = 2;
  return new Geom2d_BSplineCurve(poles, knots, mults, 1);
}

/// Signed volume enclosed by the faces' surfaces, each over its whole parameter rectangle
/// and with its normal X_u x X_v: V = 1/3 sum of the integrals of (X - c) . (X_u x X_v).
/// Per knot span the integrand of a bicubic polynomial patch has degree 8 in u and in v, so
/// 5-point Gauss-Legendre is exact (rational patches: very nearly so). About 20x cheaper
/// than BRepGProp::VolumeProperties, which matters at 10k faces; only its sign is used.
double signed_volume(const std::vector<Handle(Geom_BSplineSurface)>& surfaces, const gp_XYZ& c) {
  static const double node[5] = {-0.9061798459386640, -0.5384693101056831, 0.0,
                                  0.5384693101056831, 0.9061798459386640};
  static const double weight[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889,
                                   0.4786286704993665, 0.2369268850561891};
  double volume = 0;
  for (const Handle(Geom_BSplineSurface)& s : surfaces) {
    // The adaptor caches each span's polynomial between evaluations (a packed face has many).
    GeomAdaptor_Surface adaptor(s);
    for (int iu = 1; iu < s->NbUKnots(); ++iu) {
      const double u0 = s->UKnot(iu), hu = (s->UKnot(iu + 1) - u0) / 2;
      for (int iv = 1; iv < s->NbVKnots(); ++iv) {
        const double v0 = s->VKnot(iv), hv = (s->VKnot(iv + 1) - v0) / 2;
        for (int a = 0; a < 5; ++a)
          for (int b = 0; b < 5; ++b) {
            gp_Pnt x;
            gp_Vec xu, xv;
            adaptor.D1(u0 + hu * (1 + node[a]), v0 + hv * (1 + node[b]), x, xu, xv);
            volume += weight[a] * weight[b] * hu * hv * (x.XYZ() - c).Dot(xu.Crossed(xv).XYZ());
          }
      }
    }
  }
  return volume / 3;
}

/// A split side (patch_set.h) must be a chain of listed curve uses from the side's first
/// corner to its last, covering [0, 1] in order.
void check_split_side(const PatchSet& ps, int p, int side) {
  const NurbsPatch& patch = ps.patches[p];
  auto fail = [&](const std::string& why) {
    throw ExportError("topology", p, "split side " + std::to_string(side) + ": " + why);
  };
  int at = patch.corners[side];
  double t = 0;
  for (const SidePiece& q : patch.split_sides[side]) {
    if (q.curve < 0 || q.curve >= static_cast<int>(ps.curves.size())) fail("curve index out of range");
    const BoundaryCurve& curve = ps.curves[q.curve];
    bool listed = false;
    for (const CurveUse& use : curve.uses)
      listed |= use.patch == p && use.side == side && use.reversed == q.reversed && use.t0 == q.t0 &&
                use.t1 == q.t1;
    if (!listed) fail("curve " + std::to_string(q.curve) + " does not list this piece among its uses");
    if (q.t0 != t || !(q.t1 > q.t0)) fail("pieces do not cover [0, 1] in order");
    if ((q.reversed ? curve.corner1 : curve.corner0) != at) fail("pieces do not form a chain of corners");
    at = q.reversed ? curve.corner0 : curve.corner1;
    t = q.t1;
  }
  if (t != 1 || at != patch.corners[(side + 1) % 4]) fail("pieces do not end at the side's last corner");
}

/// One use of a curve by a patch side, remembered until the edge gets its pcurves.
struct PendingUse {
  bool reversed;
  Handle(Geom2d_Curve) pcurve;
};

/// Topology checks that OCCT would not report, or only as a crash: each patch side must name a
/// curve whose use list contains exactly this (patch, side, reversed), and whose end corners are
/// the side's corners in the right order; a curve has at most two uses, each made by a side.
/// \throw ExportError ("topology")
void check_topology(const PatchSet& ps) {
  const int num_patches = static_cast<int>(ps.patches.size());
  const int num_curves = static_cast<int>(ps.curves.size());
  const int num_corners = static_cast<int>(ps.corners.size());
  std::vector<int> uses_seen(num_curves, 0);
  for (int p = 0; p < num_patches; ++p) {
    const NurbsPatch& patch = ps.patches[p];
    for (int side = 0; side < 4; ++side) {
      const int c0 = patch.corners[side], c1 = patch.corners[(side + 1) % 4];
      if (c0 < 0 || c0 >= num_corners || c1 < 0 || c1 >= num_corners)
        throw ExportError("topology", p, "corner index out of range at side " +
                                             std::to_string(side));
      const int k = patch.curves[side];
      if (k < 0 && !patch.split_sides[side].empty()) {
        check_split_side(ps, p, side);
        for (const SidePiece& q : patch.split_sides[side]) ++uses_seen[q.curve];
        continue;
      }
      if (k < 0) {
        if (c0 != c1)
          throw ExportError("topology", p, "side " + std::to_string(side) +
                                               " has no curve but is not collapsed to a corner");
        continue;  // degenerate side
      }
      if (k >= num_curves)
        throw ExportError("topology", p, "curve index out of range at side " + std::to_string(side));
      const BoundaryCurve& curve = ps.curves[k];
      const bool rev = patch.curve_reversed[side];
      bool listed = false;
      for (const CurveUse& use : curve.uses)
        listed |= use.patch == p && use.side == side && use.reversed == rev;
      if (!listed)
        throw ExportError("topology", p, "curve " + std::to_string(k) + " does not list side " +
                                             std::to_string(side) + " among its uses");
      if ((rev ? curve.corner1 : curve.corner0) != c0 || (rev ? curve.corner0 : curve.corner1) != c1)
        throw ExportError("topology", p, "curve " + std::to_string(k) +
                                             " does not join the corners of side " +
                                             std::to_string(side));
      ++uses_seen[k];
    }
  }
  for (int k = 0; k < num_curves; ++k) {
    if (ps.curves[k].uses.size() > 2)
      throw ExportError("topology", ps.curves[k].uses[0].patch,
                        "curve " + std::to_string(k) + " has more than two uses (non-manifold)");
    if (uses_seen[k] != static_cast<int>(ps.curves[k].uses.size()))
      throw ExportError("topology", ps.curves[k].uses.empty() ? -1 : ps.curves[k].uses[0].patch,
                        "curve " + std::to_string(k) + " lists uses that no patch side makes");
  }
}

/// The B-rep's vertices (one per corner) and 3D edges (one per curve, with its parameter range),
/// each made once and shared by the faces.
struct SharedTopology {
  std::vector<TopoDS_Vertex> vertices;
  std::vector<TopoDS_Edge> edges;
  std::vector<std::pair<double, double>> edge_range;
};

/// The parameter range of curve k's edge, as OCCT gives the edges it builds on a face (e.g.
/// BRepBuilderAPI_MakeFace, BRepPrimAPI_MakeTorus): the range of the face's own parameter
/// along the iso-line the edge runs on, so that the edge's pcurve is a unit-speed Geom2d_Line
/// (OCCT's offset, shell and boolean algorithms recognise iso-lines by it). Taken from a use
/// where the curve runs the way the parameter increases (the coordinates of its ends), else
/// [0, length] from the first use. The other use's side has the same length wherever the two
/// faces give a coarse quad the same parameter length (per-quad and packed faces: one unit per
/// quad); where not (a polar cap's [0, 1] side against its ring of quads), that pcurve is a
/// straight degree-1 B-spline (see segment).
std::pair<double, double> edge_parameter_range(const PatchSet& ps, int k) {
  const BoundaryCurve& curve = ps.curves[k];
  std::pair<double, double> fallback{0, 0};
  for (size_t i = 0; i < curve.uses.size(); ++i) {
    const CurveUse& use = curve.uses[i];
    const NurbsPatch& patch = ps.patches[use.patch];
    const Domain d{patch.knots_u.knots.front(), patch.knots_u.knots.back(),
                   patch.knots_v.knots.front(), patch.knots_v.knots.back()};
    const auto [a, b] = side_ends(d, use.side);
    auto at = [&](double t) { return gp_Pnt2d(a.XY() + t * (b.XY() - a.XY())); };
    const gp_Pnt2d start = at(use.reversed ? use.t1 : use.t0), end = at(use.reversed ? use.t0 : use.t1);
    const bool along_u = use.side % 2 == 0;  // sides 0 and 2 run along u, 1 and 3 along v
    const double c0 = along_u ? start.X() : start.Y(), c1 = along_u ? end.X() : end.Y();
    if (c1 > c0) return {c0, c1};
    if (i == 0) fallback = {0, c0 - c1};
  }
  if (!(fallback.second > 0)) throw ExportError("edge", curve.uses[0].patch,
                                                "curve " + std::to_string(k) + " has zero length in its face");
  return fallback;
}

SharedTopology make_vertices_and_edges(const PatchSet& ps, BRep_Builder& builder, double tol) {
  const int num_curves = static_cast<int>(ps.curves.size());
  const int num_corners = static_cast<int>(ps.corners.size());
  SharedTopology t;
  std::vector<TopoDS_Vertex>& vertices = t.vertices;
  std::vector<TopoDS_Edge>& edges = t.edges;
  std::vector<std::pair<double, double>>& edge_range = t.edge_range;
  vertices.resize(num_corners);
  guarded("vertex", -1, [&] {
    for (int c = 0; c < num_corners; ++c)
      builder.MakeVertex(vertices[c], to_pnt(ps.corners[c].position), tol);
  });
  edges.resize(num_curves);
  edge_range.resize(num_curves);
  for (int k = 0; k < num_curves; ++k) {
    const BoundaryCurve& curve = ps.curves[k];
    if (curve.uses.empty()) continue;
    const int patch = curve.uses[0].patch;
    Handle(Geom_BSplineCurve) c3d = make_curve(curve, k, patch, edge_parameter_range(ps, k));
    guarded("edge", patch, [&] {
      builder.MakeEdge(edges[k], c3d, tol);
      // The start vertex is FORWARD and the end vertex REVERSED in its edge; for a closed
      // curve (corner0 == corner1) the same vertex appears twice, once each way.
      builder.Add(edges[k], vertices[curve.corner0].Oriented(TopAbs_FORWARD));
      builder.Add(edges[k], vertices[curve.corner1].Oriented(TopAbs_REVERSED));
      edge_range[k] = {c3d->FirstParameter(), c3d->LastParameter()};
    });
  }
  return t;
}

/// The face of patch p on `surface`: its wire of the shared edges (split sides one edge per
/// piece, collapsed sides a degenerated edge), each edge given its straight pcurve along the
/// side (two for a seam).
void make_face(const PatchSet& ps, int p, const Handle(Geom_BSplineSurface)& surface, SharedTopology& shared,
               BRep_Builder& builder, double tol, TopoDS_Face& face) {
  const NurbsPatch& patch = ps.patches[p];
  std::vector<TopoDS_Vertex>& vertices = shared.vertices;
  std::vector<TopoDS_Edge>& edges = shared.edges;
  const std::vector<std::pair<double, double>>& edge_range = shared.edge_range;
  Domain d;
  surface->Bounds(d.u0, d.u1, d.v0, d.v1);
  builder.MakeFace(face, surface, tol);

  // pcurves of this patch per curve (two for a seam).
  std::vector<std::pair<int, PendingUse>> pending;
  std::array<std::vector<TopoDS_Edge>, 4> side_edges;
  for (int side = 0; side < 4; ++side) {
    const auto [start, end] = side_ends(d, side);
    const int k = patch.curves[side];
    if (k < 0 && !patch.split_sides[side].empty()) {
      // A side made of several curves (a polar cap's boundary): one edge per piece, each
      // with the straight pcurve over its part [t0, t1] of the side.
      auto at = [&](double t) { return gp_Pnt2d(start.XY() + t * (end.XY() - start.XY())); };
      for (const SidePiece& q : patch.split_sides[side]) {
        const auto [s0, s1] = edge_range[q.curve];
        const gp_Pnt2d a = at(q.reversed ? q.t1 : q.t0), b = at(q.reversed ? q.t0 : q.t1);
        pending.push_back({q.curve, {q.reversed, segment(a, b, s0, s1)}});
        side_edges[side].push_back(
            TopoDS::Edge(edges[q.curve].Oriented(q.reversed ? TopAbs_REVERSED : TopAbs_FORWARD)));
      }
      continue;
    }
    if (k < 0) {
      // Collapsed side (e.g. the pole of a polar cap): a degenerated edge, which has no 3D
      // curve, only the pcurve along the side and the one vertex at both ends.
      side_edges[side].emplace_back();
      TopoDS_Edge& e = side_edges[side].back();
      builder.MakeEdge(e);
      const double length = gp_Vec2d(start, end).Magnitude();
      builder.UpdateEdge(e, segment(start, end, 0, length), face, tol);
      builder.Add(e, vertices[patch.corners[side]].Oriented(TopAbs_FORWARD));
      builder.Add(e, vertices[patch.corners[side]].Oriented(TopAbs_REVERSED));
      builder.Range(e, 0, length);
      builder.Degenerated(e, Standard_True);
      continue;
    }
    // The pcurve runs from the side point where s = s0 to the one where s = s1: the side's
    // start unless the side traverses the curve backwards.
    const bool rev = patch.curve_reversed[side];
    const auto [s0, s1] = edge_range[k];
    pending.push_back({k, {rev, segment(rev ? end : start, rev ? start : end, s0, s1)}});
    // In the wire the edge runs the way the side does: against the curve when reversed.
    side_edges[side].push_back(TopoDS::Edge(edges[k].Oriented(rev ? TopAbs_REVERSED : TopAbs_FORWARD)));
  }

  for (size_t a = 0; a < pending.size(); ++a) {
    const int k = pending[a].first;
    size_t b = a + 1;
    while (b < pending.size() && pending[b].first != k) ++b;
    if (b < pending.size()) {
      // Seam: the same edge bounds this face twice. OCCT stores both pcurves together, the
      // first for the edge's FORWARD occurrence in the face, the second for REVERSED.
      const PendingUse& u = pending[a].second;
      const PendingUse& w = pending[b].second;
      if (u.reversed == w.reversed)
        throw ExportError("topology", p, "curve " + std::to_string(k) +
                                             " is used twice in the same direction");
      builder.UpdateEdge(edges[k], u.reversed ? w.pcurve : u.pcurve,
                         u.reversed ? u.pcurve : w.pcurve, face, tol);
      pending.erase(pending.begin() + static_cast<long>(b));
    } else {
      builder.UpdateEdge(edges[k], pending[a].second.pcurve, face, tol);
    }
  }

  TopoDS_Wire wire;
  builder.MakeWire(wire);
  for (const auto& list : side_edges)
    for (const TopoDS_Edge& e : list) builder.Add(wire, e);
  wire.Closed(Standard_True);
  builder.Add(face, wire);
  // The wire is the boundary of the whole parameter rectangle.
  builder.NaturalRestriction(face, Standard_True);
}

/// The planar face of a set of coplanar patches (core/patch/planar_faces.h): a Geom_Plane with
/// the set's boundary loops of the shared edges. Each edge's pcurve on the plane is its 3D
/// B-spline with the poles projected onto the plane's axes: the curve lies in the plane, so the
/// projection is the curve itself, with its own parameter (SameParameter by construction).
void make_planar_face(const PlanarFace& f, SharedTopology& shared, BRep_Builder& builder, double tol,
                      TopoDS_Face& face) {
  const gp_Ax3 axes(to_pnt(f.origin), gp_Dir(f.normal[0], f.normal[1], f.normal[2]),
                    gp_Dir(f.x_axis[0], f.x_axis[1], f.x_axis[2]));
  const gp_XYZ origin = axes.Location().XYZ(), x = axes.XDirection().XYZ(), y = axes.YDirection().XYZ();
  builder.MakeFace(face, new Geom_Plane(axes), tol);
  for (const std::vector<LoopCurve>& loop : f.loops) {
    TopoDS_Wire wire;
    builder.MakeWire(wire);
    for (const LoopCurve& c : loop) {
      TopoDS_Edge& edge = shared.edges[c.curve];
      double first = 0, last = 0;
      Handle(Geom_BSplineCurve) curve = Handle(Geom_BSplineCurve)::DownCast(BRep_Tool::Curve(edge, first, last));
      if (curve.IsNull()) throw ExportError("planar face", f.patches.front(), "curve " + std::to_string(c.curve) +
                                                                              " has no B-spline curve");
      TColgp_Array1OfPnt2d poles(1, curve->NbPoles());
      for (int i = 1; i <= curve->NbPoles(); ++i) {
        const gp_XYZ d = curve->Pole(i).XYZ() - origin;
        poles(i) = gp_Pnt2d(d.Dot(x), d.Dot(y));
      }
      TColStd_Array1OfReal knots(1, curve->NbKnots());
      TColStd_Array1OfInteger mults(1, curve->NbKnots());
      curve->Knots(knots);
      curve->Multiplicities(mults);
      builder.UpdateEdge(edge, new Geom2d_BSplineCurve(poles, knots, mults, curve->Degree()), face, tol);
      builder.Add(wire, edge.Oriented(c.reversed ? TopAbs_REVERSED : TopAbs_FORWARD));
    }
    wire.Closed(Standard_True);
    builder.Add(face, wire);
  }
}

/// One shell per connected component of the faces, a solid (outward) where the component has
/// no open boundary curve; several components as a compound. Fills result.shape and its counts.
void assemble(const PatchSet& ps, const std::vector<TopoDS_Face>& faces,
              const std::vector<Handle(Geom_BSplineSurface)>& surfaces, BRep_Builder& builder, BrepResult& result) {
  const int num_patches = static_cast<int>(ps.patches.size());
  std::vector<int> parent(num_patches);
  for (int p = 0; p < num_patches; ++p) parent[p] = p;
  auto find = [&](int p) {
    while (parent[p] != p) p = parent[p] = parent[parent[p]];
    return p;
  };
  std::vector<char> open_component(num_patches, 0);
  for (const BoundaryCurve& c : ps.curves) {
    if (c.uses.size() == 2) parent[find(c.uses[0].patch)] = find(c.uses[1].patch);
  }
  for (const BoundaryCurve& c : ps.curves)
    if (c.uses.size() == 1) open_component[find(c.uses[0].patch)] = 1;
  std::vector<int> roots;
  std::vector<std::vector<int>> members(num_patches);
  for (int p = 0; p < num_patches; ++p) {
    const int r = find(p);
    if (members[r].empty()) roots.push_back(r);
    members[r].push_back(p);
  }
  std::vector<TopoDS_Shape> parts;
  result.is_solid = !roots.empty();
  for (int r : roots) {
    TopoDS_Shell shell;
    guarded("shell", members[r].front(), [&] {
      builder.MakeShell(shell);
      for (int p : members[r])
        if (!faces[p].IsNull()) builder.Add(shell, faces[p]);  // null: inside a planar face
      shell.Closed(BRep_Tool::IsClosed(shell));
    });
    if (open_component[r]) {
      result.is_solid = false;
      ++result.num_shells;
      parts.push_back(shell);
      continue;
    }
    guarded("solid", members[r].front(), [&] {
      TopoDS_Solid solid;
      builder.MakeSolid(solid);
      builder.Add(solid, shell);
      // The faces' normals follow the cage, which may be oriented inward. The volume
      // integral is signed by the normals: negative means inside out, and reversing the
      // shell turns every face around. Centred on the corners' mean to limit round-off.
      std::vector<Handle(Geom_BSplineSurface)> component_surfaces;
      gp_XYZ centre(0, 0, 0);
      int n_corners = 0;
      for (int p : members[r]) {
        component_surfaces.push_back(surfaces[p]);
        for (int c : ps.patches[p].corners) { centre += to_pnt(ps.corners[c].position).XYZ(); ++n_corners; }
      }
      centre /= std::max(1, n_corners);
      if (signed_volume(component_surfaces, centre) < 0) {
        builder.MakeSolid(solid);
        builder.Add(solid, shell.Reversed());
      }
      ++result.num_solids;
      ++result.num_shells;
      parts.push_back(solid);
    });
  }
  if (parts.size() == 1) {
    result.shape = parts.front();
  } else {
    guarded("compound", -1, [&] {
      TopoDS_Compound compound;
      builder.MakeCompound(compound);
      for (const TopoDS_Shape& part : parts) builder.Add(compound, part);
      result.shape = compound;
    });
  }
}

/// Counts the result's faces, edges and vertices and checks it with BRepCheck, naming faces and
/// edges by patch and curve in its messages.
void count_and_check(const std::vector<TopoDS_Face>& faces, const std::vector<TopoDS_Edge>& edges, BrepResult& result) {
  const int num_patches = static_cast<int>(faces.size());
  const int num_curves = static_cast<int>(edges.size());
  guarded("check", -1, [&] {
    TopTools_IndexedMapOfShape map;
    TopExp::MapShapes(result.shape, TopAbs_FACE, map);
    result.num_faces = map.Extent();
    map.Clear();
    TopExp::MapShapes(result.shape, TopAbs_EDGE, map);
    result.num_edges = map.Extent();
    map.Clear();
    TopExp::MapShapes(result.shape, TopAbs_VERTEX, map);
    result.num_vertices = map.Extent();

    // Name faces and edges by patch and curve index in BRepCheck's messages.
    TopTools_DataMapOfShapeInteger face_patch, edge_curve;
    for (int p = 0; p < num_patches; ++p)
      if (!faces[p].IsNull()) face_patch.Bind(faces[p], p);
    for (int k = 0; k < num_curves; ++k)
      if (!edges[k].IsNull()) edge_curve.Bind(edges[k], k);
    auto namer = [&](const TopoDS_Shape& s) -> std::string {
      if (s.ShapeType() == TopAbs_FACE && face_patch.IsBound(s))
        return "face of patch " + std::to_string(face_patch(s));
      if (s.ShapeType() == TopAbs_EDGE && edge_curve.IsBound(s))
        return "edge of curve " + std::to_string(edge_curve(s));
      return "";
    };
    result.valid = detail::check_shape(result.shape, result.check_message, namer);
  });
}

}  // namespace

BrepResult build_brep(const PatchSet& ps, const std::function<void(double)>& progress, const BrepOptions& options) {
  BrepResult result;
  const double tol = brep_tolerance(ps.model_size);
  result.tolerance = tol;
  const int num_patches = static_cast<int>(ps.patches.size());
  const int num_curves = static_cast<int>(ps.curves.size());
  if (num_patches == 0) throw ExportError("input", -1, "the PatchSet has no patches");
  check_topology(ps);

  BRep_Builder builder;
  SharedTopology shared = make_vertices_and_edges(ps, builder, tol);
  std::vector<TopoDS_Face> faces(num_patches);
  std::vector<Handle(Geom_BSplineSurface)> surfaces(num_patches);
  // Coplanar patches become one planar face each (exactly: their poles lie on the plane).
  PlanarFaces planar;
  if (options.merge_planar) planar = find_planar_faces(ps, tolerances::kSameSurface);
  else planar.face_of_patch.assign(num_patches, -1);
  result.split_planar_sets = planar.split;
  constexpr int kMaxPlanarSplits = 4;
  // A planar face stands in the face list at its lowest patch; its other patches have none.
  // It is made first and checked alone (BRepCheck): where the set's boundary crosses itself in
  // the plane (a surface folded over itself), its patches are written as they are instead.
  // A refused set whose loops cross (patches overlapping in the plane) is split at the crossings
  // (core/patch/planar_faces.h, split_planar_face) and its parts are tried in turn, appended to
  // the list; the patches left out are written as they are.
  std::vector<char> on_loop(num_curves, 0);
  std::vector<int> rounds(planar.faces.size(), 0);  // per planar face: splits it comes from
  for (size_t i = 0; i < planar.faces.size(); ++i) {
    const PlanarFace f = planar.faces[i];  // a copy: parts are appended below
    TopoDS_Face& face = faces[f.patches.front()];
    bool ok = false;
    std::vector<int> intersecting;  // loop curves whose edges BRepCheck finds intersecting
    guarded("planar face", f.patches.front(), [&] {
      make_planar_face(f, shared, builder, tol, face);
      ok = BRepCheck_Analyzer(face).IsValid();
      if (ok) return;
      for (TopExp_Explorer w(face, TopAbs_WIRE); w.More(); w.Next()) {
        TopoDS_Edge e1, e2;
        BRepCheck_Wire check(TopoDS::Wire(w.Current()));
        if (check.SelfIntersect(face, e1, e2) != BRepCheck_SelfIntersectingWire) continue;
        for (const auto& loop : f.loops)
          for (const LoopCurve& c : loop)
            if (shared.edges[c.curve].IsSame(e1) || shared.edges[c.curve].IsSame(e2)) intersecting.push_back(c.curve);
      }
      for (const auto& loop : f.loops)  // take the pcurves on the plane off the edges again
        for (const LoopCurve& c : loop) builder.UpdateEdge(shared.edges[c.curve], Handle(Geom2d_Curve)(), face, tol);
      face.Nullify();
    });
    if (!ok) {
      for (int p : f.patches) planar.face_of_patch[p] = -1;
      std::vector<PlanarFace> parts;
      if (rounds[i] < kMaxPlanarSplits) parts = split_planar_face(ps, f, intersecting);
      if (parts.empty()) {
        ++result.rejected_planar_faces;
        continue;
      }
      ++result.split_planar_sets;
      for (PlanarFace& part : parts) {
        for (int p : part.patches) planar.face_of_patch[p] = static_cast<int>(planar.faces.size());
        planar.faces.push_back(std::move(part));
        rounds.push_back(rounds[i] + 1);
      }
      continue;
    }
    for (const auto& loop : f.loops)
      for (const LoopCurve& c : loop) on_loop[c.curve] = 1;
    result.merged_patches += static_cast<int>(f.patches.size());
    for (int p : f.patches) result.folded_planar_patches += planar.folded_patch[p];
    ++result.planar_faces;
  }
  const int step = std::max(1, num_patches / 100);
  for (int p = 0; p < num_patches; ++p) {
    surfaces[p] = make_surface(ps.patches[p], p);
    if (planar.face_of_patch[p] < 0) {
      if (options.periodic_closed_faces) make_closed_periodic(ps.patches[p], surfaces[p], p);
      guarded("face", p, [&] { make_face(ps, p, surfaces[p], shared, builder, tol, faces[p]); });
    }
    if (progress && ((p + 1) % step == 0 || p + 1 == num_patches))
      progress(static_cast<double>(p + 1) / num_patches);
  }

  // Curves inside a planar face bound no face any more: no edge of the shape.
  for (int k = 0; k < num_curves; ++k) {
    if (shared.edges[k].IsNull() || on_loop[k]) continue;
    bool inside = !ps.curves[k].uses.empty();
    for (const CurveUse& u : ps.curves[k].uses) inside = inside && planar.face_of_patch[u.patch] >= 0;
    if (inside) shared.edges[k].Nullify();
  }

  // Every pcurve was made with the curve's own parameter, so all representations share one
  // range and agree pointwise: SameRange and SameParameter hold by construction (BRepCheck
  // verifies the latter by sampling against the edge tolerance).
  for (int k = 0; k < num_curves; ++k) {
    if (shared.edges[k].IsNull()) continue;
    guarded("edge", ps.curves[k].uses[0].patch, [&] {
      builder.Range(shared.edges[k], shared.edge_range[k].first, shared.edge_range[k].second);
      builder.SameRange(shared.edges[k], Standard_True);
      builder.SameParameter(shared.edges[k], Standard_True);
    });
  }

  // A cage may have several components (catmark_cubes_infsharp is four cubes). BRepCheck
  // rejects a shell whose faces are not connected, so each component gets its own shell.
  assemble(ps, faces, surfaces, builder, result);
  count_and_check(faces, shared.edges, result);
  result.curve_edges.assign(shared.edges.begin(), shared.edges.end());
  return result;
}

}  // namespace subd2nurbs::occt
