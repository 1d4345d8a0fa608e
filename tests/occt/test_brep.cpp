// PatchSet -> B-rep (build_brep) and its measurement (summarize), on hand-built PatchSets
// with known answers: a unit cube (volume 1, area 6), a B-spline torus split three ways
// (the same surface, so the same area and volume), open patches.
#include <gtest/gtest.h>

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepBuilderAPI_NurbsConvert.hxx>
#include <BRepGProp.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <BRepPrimAPI_MakeTorus.hxx>
#include <GProp_GProps.hxx>
#include <TopAbs_ShapeEnum.hxx>

#include <cmath>
#include <vector>

#include "converter/occt/brep_builder.h"
#include "converter/occt/shape_check.h"
#include "occt/synthetic_patch_sets.h"

namespace subd2nurbs::occt {
namespace {

using testing::bspline_torus;
using testing::open_patch;
using testing::triangle_with_collapsed_side;
using testing::unit_cube;

TEST(BuildBrep, UnitCubeIsAValidSolidOfVolumeOne) {
  const PatchSet ps = unit_cube();
  const BrepResult r = build_brep(ps);
  EXPECT_TRUE(r.valid) << r.check_message;
  EXPECT_TRUE(r.is_solid);
  EXPECT_EQ(r.shape.ShapeType(), TopAbs_SOLID);
  EXPECT_EQ(r.num_faces, 6);
  EXPECT_EQ(r.num_edges, 12);
  EXPECT_EQ(r.num_vertices, 8);

  const ShapeSummary s = summarize(r.shape);
  EXPECT_TRUE(s.valid) << s.check_message;
  EXPECT_EQ(s.solids, 1);
  EXPECT_EQ(s.shells, 1);
  EXPECT_EQ(s.faces, 6);
  EXPECT_EQ(s.edges, 12);
  EXPECT_EQ(s.free_edges, 0);
  EXPECT_NEAR(s.volume, 1.0, 1e-9);
  EXPECT_NEAR(s.area, 6.0, 1e-9);
  EXPECT_EQ(s.shared_edges_sampled, 12);
  EXPECT_LT(s.max_gap, 1e-12);
  // Outward normals of two cube faces meet at 90 degrees along every edge.
  EXPECT_NEAR(s.max_normal_angle_deg, 90.0, 1e-9);
}

TEST(BuildBrep, InwardCageStillGivesAPositiveSolid) {
  const BrepResult r = build_brep(unit_cube(/*inward=*/true));
  EXPECT_TRUE(r.valid) << r.check_message;
  ASSERT_TRUE(r.is_solid);
  const ShapeSummary s = summarize(r.shape);
  EXPECT_NEAR(s.volume, 1.0, 1e-9);
  EXPECT_NEAR(s.area, 6.0, 1e-9);
  EXPECT_NEAR(s.max_normal_angle_deg, 90.0, 1e-9);  // still outward on both sides
}

TEST(BuildBrep, TorusOfBezierPatchesIsSmoothAndClosed) {
  const PatchSet ps = bspline_torus(8, 6);  // one Bezier patch per net cell
  ASSERT_EQ(ps.patches.size(), 48u);
  const BrepResult r = build_brep(ps);
  EXPECT_TRUE(r.valid) << r.check_message;
  EXPECT_TRUE(r.is_solid);
  EXPECT_EQ(r.num_faces, 48);
  EXPECT_EQ(r.num_edges, 96);
  EXPECT_EQ(r.num_vertices, 48);  // V - E + F = 0: a torus

  const ShapeSummary s = summarize(r.shape);
  EXPECT_TRUE(s.valid) << s.check_message;
  EXPECT_EQ(s.free_edges, 0);
  EXPECT_EQ(s.shared_edges_sampled, 96);
  EXPECT_LT(s.max_gap, 1e-10 * ps.model_size);
  EXPECT_LT(s.max_normal_angle_deg, 1e-6);
  EXPECT_GT(s.volume, 0);
}

// The same B-spline surface cut into 48, 4 or 1 patches must have the same area and volume;
// the 1 x 1 split is one face closed onto itself by two seams (one vertex, two edges).
TEST(BuildBrep, TorusSplitsAgreeAndSeamsWork) {
  const ShapeSummary cells = summarize(build_brep(bspline_torus(8, 6)).shape);
  for (const auto& split : std::vector<std::pair<int, int>>{{2, 2}, {1, 1}, {4, 1}}) {
    SCOPED_TRACE(std::to_string(split.first) + " x " + std::to_string(split.second));
    const PatchSet ps = bspline_torus(split.first, split.second);
    const BrepResult r = build_brep(ps);
    EXPECT_TRUE(r.valid) << r.check_message;
    EXPECT_TRUE(r.is_solid);
    const int faces = split.first * split.second;
    EXPECT_EQ(r.num_faces, faces);
    EXPECT_EQ(r.num_edges, 2 * faces);
    EXPECT_EQ(r.num_vertices, faces);
    const ShapeSummary s = summarize(r.shape);
    EXPECT_TRUE(s.valid) << s.check_message;
    EXPECT_EQ(s.free_edges, 0);
    EXPECT_EQ(s.shared_edges_sampled, 2 * faces);  // seams are measured face against itself
    EXPECT_LT(s.max_gap, 1e-10 * ps.model_size);
    EXPECT_LT(s.max_normal_angle_deg, 1e-6);
    EXPECT_NEAR(s.area, cells.area, 1e-9 * cells.area);
    EXPECT_NEAR(s.volume, cells.volume, 1e-9 * cells.volume);
  }
}

TEST(BuildBrep, OpenPatchIsAShellWithFourFreeEdges) {
  const BrepResult r = build_brep(open_patch());
  EXPECT_TRUE(r.valid) << r.check_message;
  EXPECT_FALSE(r.is_solid);
  EXPECT_EQ(r.shape.ShapeType(), TopAbs_SHELL);
  const ShapeSummary s = summarize(r.shape);
  EXPECT_EQ(s.solids, 0);
  EXPECT_EQ(s.shells, 1);
  EXPECT_EQ(s.faces, 1);
  EXPECT_EQ(s.edges, 4);
  EXPECT_EQ(s.free_edges, 4);
  EXPECT_EQ(s.shared_edges_sampled, 0);
  EXPECT_EQ(s.volume, 0);
  EXPECT_GT(s.area, 2.0);  // the flat rectangle is 2; the bump adds a little
  EXPECT_LT(s.area, 2.1);
}

TEST(BuildBrep, CollapsedSideBecomesADegeneratedEdge) {
  const BrepResult r = build_brep(triangle_with_collapsed_side());
  EXPECT_TRUE(r.valid) << r.check_message;
  EXPECT_EQ(r.num_faces, 1);
  EXPECT_EQ(r.num_edges, 4);  // three curves and the degenerated edge at the apex
  EXPECT_EQ(r.num_vertices, 3);
  const ShapeSummary s = summarize(r.shape);
  EXPECT_EQ(s.free_edges, 3);  // the degenerated edge is no boundary
  EXPECT_NEAR(s.area, 0.5, 1e-12);
}

// The measurement can fail: a pole moved off a shared side opens a gap between the faces,
// and BRepCheck sees the edge's curve leave the moved face.
TEST(BuildBrep, MovedPoleOnASharedSideIsDetected) {
  PatchSet ps = bspline_torus(8, 6);
  const double shift = 1e-3 * ps.model_size;
  NurbsPatch& p = ps.patches[0];
  p.pole(p.num_poles_u - 1, 1)[2] += shift;  // side 1 (u = 1), second pole
  const BrepResult r = build_brep(ps);
  EXPECT_FALSE(r.valid);
  EXPECT_NE(r.check_message.find("InvalidCurveOnSurface"), std::string::npos) << r.check_message;
  EXPECT_NE(r.check_message.find("face of patch 0"), std::string::npos) << r.check_message;
  const ShapeSummary s = summarize(r.shape);
  // The side moves by shift * B_1(t) (Bernstein), whose maximum is 4/9 at t = 1/3; the
  // samples t = k/15 include t = 1/3.
  EXPECT_NEAR(s.max_gap, shift * 4.0 / 9.0, 1e-9 * shift);
  EXPECT_GT(s.max_gap, 1e-10 * ps.model_size);
}

TEST(BuildBrep, SummarizeCanMeasureChosenEdgesOnly) {
  const PatchSet ps = unit_cube();
  const BrepResult r = build_brep(ps);
  ASSERT_EQ(r.curve_edges.size(), ps.curves.size());
  const ShapeSummary two = summarize(r.shape, {r.curve_edges[0], r.curve_edges[3]});
  EXPECT_EQ(two.shared_edges_sampled, 2);
  EXPECT_EQ(two.faces, 6);  // counts stay those of the whole shape
  const ShapeSummary none = summarize(r.shape, std::vector<TopoDS_Shape>{});
  EXPECT_EQ(none.shared_edges_sampled, 0);
  EXPECT_EQ(none.max_normal_angle_deg, 0);
}

TEST(BuildBrep, ReportsProgressUpToOne) {
  std::vector<double> seen;
  build_brep(bspline_torus(8, 6), [&](double f) { seen.push_back(f); });
  ASSERT_FALSE(seen.empty());
  EXPECT_LE(seen.size(), 101u);
  for (size_t i = 1; i < seen.size(); ++i) EXPECT_GT(seen[i], seen[i - 1]);
  EXPECT_EQ(seen.back(), 1.0);
}

TEST(BuildBrep, InconsistentPatchSetsThrowNamingThePatch) {
  {
    PatchSet ps = unit_cube();
    ps.patches[2].curves[1] = 99;
    try {
      build_brep(ps);
      FAIL() << "no exception";
    } catch (const ExportError& e) {
      EXPECT_EQ(e.stage, "topology");
      EXPECT_EQ(e.patch, 2);
    }
  }
  {
    PatchSet ps = unit_cube();
    ps.patches[4].knots_u.mults = {3, 4};  // one pole short
    try {
      build_brep(ps);
      FAIL() << "no exception";
    } catch (const ExportError& e) {
      EXPECT_EQ(e.stage, "patch");
      EXPECT_EQ(e.patch, 4);
      EXPECT_NE(std::string(e.what()).find("patch 4"), std::string::npos) << e.what();
    }
  }
  {
    PatchSet ps = unit_cube();
    ps.curves[5].uses.pop_back();  // a side that its curve does not list
    EXPECT_THROW(build_brep(ps), ExportError);
  }
  EXPECT_THROW(build_brep(PatchSet{}), ExportError);
}


// summarize's area and volume against closed forms: OCCT's sphere and torus made B-spline
// surfaces (rational, whole rectangles with seams and collapsed sides: the span rules), and a
// box with a hole drilled through (trimmed planes: OCCT's adaptive integrators); and the span
// rules against OCCT's adaptive integrators on the polynomial B-spline torus.
TEST(Summarize, AreaAndVolumeMatchClosedForms) {
  const double pi = std::acos(-1.0);
  const TopoDS_Shape sphere = BRepBuilderAPI_NurbsConvert(BRepPrimAPI_MakeSphere(2.0).Shape()).Shape();
  const ShapeSummary s = summarize(sphere);
  EXPECT_EQ(s.span_faces, s.faces);
  EXPECT_NEAR(s.volume, 4.0 / 3.0 * pi * 8.0, 1e-10 * 32.0);
  EXPECT_NEAR(s.area, 4.0 * pi * 4.0, 1e-9 * 16.0 * pi);

  const TopoDS_Shape torus = BRepBuilderAPI_NurbsConvert(BRepPrimAPI_MakeTorus(3.0, 1.0).Shape()).Shape();
  const ShapeSummary t = summarize(torus);
  EXPECT_EQ(t.span_faces, t.faces);
  EXPECT_NEAR(t.volume, 2.0 * pi * pi * 3.0, 1e-10 * 60.0);
  EXPECT_NEAR(t.area, 4.0 * pi * pi * 3.0, 1e-9 * 120.0);

  const TopoDS_Shape drilled =
      BRepAlgoAPI_Cut(BRepPrimAPI_MakeBox(gp_Pnt(-2, -2, 0), 4, 4, 4).Shape(), BRepPrimAPI_MakeCylinder(1.0, 4.0).Shape())
          .Shape();
  const ShapeSummary d = summarize(drilled);
  EXPECT_EQ(d.span_faces, 0);  // planes and a cylinder: no B-spline surface
  EXPECT_NEAR(d.volume, 64.0 - pi * 4.0, 1e-9 * 64.0);
  EXPECT_NEAR(d.area, 4 * 16.0 + 2 * (16.0 - pi) + 2 * pi * 4.0, 1e-9 * 100.0);

  const TopoDS_Shape bspline = build_brep(bspline_torus(8, 6)).shape;
  const ShapeSummary b = summarize(bspline);
  EXPECT_EQ(b.span_faces, b.faces);
  GProp_GProps volume, area;
  BRepGProp::VolumeProperties(bspline, volume, 1e-12);
  BRepGProp::SurfaceProperties(bspline, area, 1e-12);
  EXPECT_NEAR(b.volume, volume.Mass(), 1e-12 * volume.Mass());
  EXPECT_NEAR(b.area, area.Mass(), 1e-9 * area.Mass());
}

}  // namespace
}  // namespace subd2nurbs::occt
