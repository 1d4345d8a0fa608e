// Edges as OCCT builds its own (issue 33): the pcurve of every face edge is a unit-speed
// Geom2d_Line in the face's own parameters (as BRepBuilderAPI_MakeFace / BRepPrimAPI_MakeTorus
// make them), the edge's range is the face parameter's range along it, a seam has two such
// lines; and the cut-flat-then-shell that failed on a packed (closed) torus face works.
#include <gtest/gtest.h>

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepCheck_Analyzer.hxx>
#include <BRepGProp.hxx>
#include <BRepOffsetAPI_MakeThickSolid.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRep_Tool.hxx>
#include <GProp_GProps.hxx>
#include <Geom2d_Line.hxx>
#include <Geom_Curve.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_Plane.hxx>
#include <Geom_Surface.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <TopoDS.hxx>

#include <algorithm>
#include <cmath>

#include "converter/occt/brep_builder.h"
#include "occt/synthetic_patch_sets.h"

namespace subd2nurbs::occt {
namespace {

using testing::bspline_torus;
using testing::unit_cube;

/// The PatchSet as the packing writes it: each patch's knots map one unit per knot span (one
/// unit per coarse quad: a packed face of 8 x 6 quads has the domain [0, 8] x [0, 6]), and
/// every curve's knots lie on [0, 1] (CurveUse::side_parameter: s in [0, 1]) whatever the
/// parameter length of the sides it runs along. (bspline_torus itself gives the patches and the
/// curves the same knots on [0, 1], which would hide what build_brep does with the edges.)
PatchSet as_packed(PatchSet ps) {
  auto unit_spans = [](KnotVector& kv) {
    for (size_t i = 0; i < kv.knots.size(); ++i) kv.knots[i] = static_cast<double>(i);
  };
  for (NurbsPatch& p : ps.patches) {
    unit_spans(p.knots_u);
    unit_spans(p.knots_v);
  }
  for (BoundaryCurve& c : ps.curves) {
    const double k0 = c.knots.knots.front(), k1 = c.knots.knots.back();
    for (double& k : c.knots.knots) k = (k - k0) / (k1 - k0);
  }
  return ps;
}

/// Checks every (edge, face) pair of `shape`: the pcurve is a Geom2d_Line over exactly the
/// edge's range, and the edge's 3D curve and the surface at the pcurve agree pointwise with
/// the same parameter (sampled), to rounding. Returns the number of pcurves checked.
int check_pcurves(const TopoDS_Shape& shape, double size) {
  int checked = 0;
  for (TopExp_Explorer fx(shape, TopAbs_FACE); fx.More(); fx.Next()) {
    const TopoDS_Face& face = TopoDS::Face(fx.Current());
    const Handle(Geom_Surface) surface = BRep_Tool::Surface(face);
    for (TopExp_Explorer ex(face, TopAbs_EDGE); ex.More(); ex.Next()) {
      const TopoDS_Edge& edge = TopoDS::Edge(ex.Current());
      if (BRep_Tool::Degenerated(edge)) continue;
      double e0, e1, c0, c1;
      BRep_Tool::Range(edge, e0, e1);
      const Handle(Geom_Curve) c3d = BRep_Tool::Curve(edge, c0, c1);
      double p0, p1;
      const Handle(Geom2d_Curve) pc = BRep_Tool::CurveOnSurface(edge, face, p0, p1);
      EXPECT_FALSE(pc.IsNull());
      if (pc.IsNull()) continue;
      EXPECT_TRUE(pc->IsKind(STANDARD_TYPE(Geom2d_Line))) << pc->DynamicType()->Name();
      EXPECT_EQ(p0, e0);
      EXPECT_EQ(p1, e1);
      for (int i = 0; i <= 8; ++i) {
        const double t = e0 + (e1 - e0) * i / 8;
        const gp_Pnt2d uv = pc->Value(t);
        EXPECT_LT(c3d->Value(t).Distance(surface->Value(uv.X(), uv.Y())), 1e-12 * size) << t;
      }
      // The face parameter along the iso-line runs at unit speed: the pcurve's direction is
      // an axis of the (u, v) plane.
      const gp_Vec2d d = pc->DN(e0, 1);
      EXPECT_NEAR(std::abs(d.X()) + std::abs(d.Y()), 1.0, 1e-15);
      EXPECT_TRUE(d.X() == 0 || d.Y() == 0);
      ++checked;
    }
  }
  return checked;
}

TEST(Pcurves, AreUnitSpeedLinesInTheFacesOwnParameters) {
  for (const auto& split : std::vector<std::pair<int, int>>{{8, 6}, {2, 2}, {1, 1}, {4, 1}}) {
    SCOPED_TRACE(std::to_string(split.first) + " x " + std::to_string(split.second));
    const PatchSet ps = as_packed(bspline_torus(split.first, split.second));
    const BrepResult r = build_brep(ps);
    ASSERT_TRUE(r.valid) << r.check_message;
    // Each face has four sides, each side one pcurve (a seam counts in both of its sides).
    EXPECT_EQ(check_pcurves(r.shape, ps.model_size), 4 * r.num_faces);
  }
  const PatchSet cube = as_packed(unit_cube());
  EXPECT_EQ(check_pcurves(build_brep(cube).shape, cube.model_size), 24);
}

// A one-face torus (closed in u and v, two seams, one vertex: a packed periodic face) is cut
// flat by a half-space box, and the flat faces are removed by BRepOffsetAPI_MakeThickSolid:
// with B-spline pcurves on [0, 1] OCCT built a wrong, invalid solid (issue 33: volume 7.92
// instead of 1.75 on catmark_torus); with OCCT's own kind of edges it is a valid shell whose
// volume is the kept area A times the thickness t to first order: the wall between the
// surface and its inward offset has volume A t - t^2 (integral of H) + O(t^3), and |H| <=
// (1 / r + 1 / (R - r)) / 2 = 0.75 on this torus (R = 3, r = 1), so within 7.5 % at t = 0.1.
TEST(Pcurves, ClosedTorusFaceCutFlatThenShelled) {
  for (const auto& split : std::vector<std::pair<int, int>>{{1, 1}, {2, 2}}) {
    SCOPED_TRACE(std::to_string(split.first) + " x " + std::to_string(split.second));
    const BrepResult r = build_brep(as_packed(bspline_torus(split.first, split.second)));
    ASSERT_TRUE(r.valid) << r.check_message;
    // The torus (R = 3, r = 1, axis z): everything above z = 0.3 cut off.
    BRepAlgoAPI_Cut cut(r.shape, BRepPrimAPI_MakeBox(gp_Pnt(-5, -5, 0.3), gp_Pnt(5, 5, 2)).Shape());
    ASSERT_TRUE(cut.IsDone());
    TopTools_ListOfShape flats;
    double kept_area = 0;
    for (TopExp_Explorer fx(cut.Shape(), TopAbs_FACE); fx.More(); fx.Next()) {
      const TopoDS_Face& f = TopoDS::Face(fx.Current());
      GProp_GProps a;
      BRepGProp::SurfaceProperties(f, a);
      if (BRep_Tool::Surface(f)->IsKind(STANDARD_TYPE(Geom_Plane)))
        flats.Append(f);
      else
        kept_area += a.Mass();
    }
    ASSERT_EQ(flats.Extent(), 1);  // an annulus
    const double t = 0.1;
    BRepOffsetAPI_MakeThickSolid thick;
    thick.MakeThickSolidByJoin(cut.Shape(), flats, -t, 1e-6);
    ASSERT_TRUE(thick.IsDone());
    EXPECT_TRUE(BRepCheck_Analyzer(thick.Shape()).IsValid());
    GProp_GProps v;
    BRepGProp::VolumeProperties(thick.Shape(), v);
    EXPECT_NEAR(v.Mass(), kept_area * t, 0.08 * kept_area * t);
  }
}


// A face that closes onto itself (the one-face torus: seams in u and v) gets a periodic
// surface in each closed direction, as OCCT's own closed faces: the same surface (sampled
// against the clamped B-spline the PatchSet gives, BrepOptions::periodic_closed_faces = false)
// over the same parameter range, so the pcurves are the same lines.
TEST(Pcurves, ClosedFacesArePeriodicWithTheSameSurface) {
  const PatchSet ps = as_packed(bspline_torus(1, 1));
  BrepOptions clamped_options;
  clamped_options.periodic_closed_faces = false;
  const BrepResult periodic = build_brep(ps), clamped = build_brep(ps, {}, clamped_options);
  ASSERT_TRUE(periodic.valid) << periodic.check_message;
  ASSERT_TRUE(clamped.valid) << clamped.check_message;
  TopExp_Explorer fp(periodic.shape, TopAbs_FACE), fc(clamped.shape, TopAbs_FACE);
  ASSERT_TRUE(fp.More() && fc.More());
  const auto sp = Handle(Geom_BSplineSurface)::DownCast(BRep_Tool::Surface(TopoDS::Face(fp.Current())));
  const auto sc = Handle(Geom_BSplineSurface)::DownCast(BRep_Tool::Surface(TopoDS::Face(fc.Current())));
  ASSERT_FALSE(sp.IsNull() || sc.IsNull());
  EXPECT_TRUE(sp->IsUPeriodic());
  EXPECT_TRUE(sp->IsVPeriodic());
  EXPECT_FALSE(sc->IsUPeriodic());
  EXPECT_FALSE(sc->IsVPeriodic());
  double a0, a1, b0, b1, c0, c1, d0, d1;
  sp->Bounds(a0, a1, b0, b1);
  sc->Bounds(c0, c1, d0, d1);
  EXPECT_EQ(a0, c0);
  EXPECT_EQ(a1, c1);
  EXPECT_EQ(b0, d0);
  EXPECT_EQ(b1, d1);
  for (int i = 0; i <= 20; ++i)
    for (int j = 0; j <= 20; ++j) {
      const double u = c0 + (c1 - c0) * i / 20, v = d0 + (d1 - d0) * j / 20;
      EXPECT_LT(sp->Value(u, v).Distance(sc->Value(u, v)), 1e-12 * ps.model_size) << u << " " << v;
    }
  EXPECT_EQ(check_pcurves(periodic.shape, ps.model_size), 4);
}

}  // namespace
}  // namespace subd2nurbs::occt
