// The mesh path end to end (issue #28): `subd2nurbs convert MESH.stl` on CAD-like parts built
// here with OCCT (a box with a drilled hole, a closed cylinder, a box with a filleted slot),
// tessellated finely (BRepMesh) and written as STL by the test. Oracles: the exact OCCT solid the
// mesh was made from (distances both ways, sampled; its volume; its planes and its cylinder), the
// mesh's topology (Euler characteristic counted here from the triangles), and for the road rule a
// triangulated quad cage (its conversion must equal the OBJ cage's).
#include <gtest/gtest.h>

#include <BRepAdaptor_Surface.hxx>
#include <BRepTopAdaptor_FClass2d.hxx>
#include <BRepBndLib.hxx>
#include <Bnd_Box.hxx>
#include <ShapeAnalysis_Surface.hxx>
#include <BRepAdaptor_Curve.hxx>
#include <BRepAlgoAPI_Common.hxx>
#include <BRepAlgoAPI_Cut.hxx>
#include <BRepBuilderAPI_MakeFace.hxx>
#include <BRepBuilderAPI_MakePolygon.hxx>
#include <BRepPrimAPI_MakePrism.hxx>
#include <BRepPrimAPI_MakeSphere.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_ListOfShape.hxx>
#include <Geom2d_Curve.hxx>
#include <BRepBuilderAPI_MakeVertex.hxx>
#include <BRepCheck_Analyzer.hxx>
#include <BRepExtrema_DistShapeShape.hxx>
#include <BRepFilletAPI_MakeFillet.hxx>
#include <BRepGProp.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <GProp_GProps.hxx>
#include <Poly_Triangulation.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopLoc_Location.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_Plane.hxx>
#include <GeomLProp_SLProps.hxx>
#include <gp_Ax2.hxx>
#include <gp_Pln.hxx>
#include <gp_Pnt.hxx>
#include <gp_Vec.hxx>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <algorithm>

#include "common/json_text.h"
#include "common/run_command.h"
#include "common/shapes.h"
#include "core/fit/shape_target.h"
#include "io/obj_reader.h"
#include "io/temp_dir.h"

using namespace subd2nurbs;
using namespace subd2nurbs::testing;

namespace {

const std::string kExe = SUBD2NURBS_EXE;

struct Triangles {
  std::vector<gp_Pnt> points;
  std::vector<std::array<int, 3>> triangles;
};

/// The shape's triangulation (BRepMesh, `deflection` in model units), oriented outward, with
/// the faces' shared edge nodes merged by exact position.
Triangles tessellate(const TopoDS_Shape& shape, double deflection) {
  BRepMesh_IncrementalMesh mesher(shape, deflection, false, 0.2, false);
  Triangles t;
  std::map<std::array<double, 3>, int> index;
  for (TopExp_Explorer ex(shape, TopAbs_FACE); ex.More(); ex.Next()) {
    const TopoDS_Face face = TopoDS::Face(ex.Current());
    TopLoc_Location loc;
    const Handle(Poly_Triangulation) tri = BRep_Tool::Triangulation(face, loc);
    if (tri.IsNull()) continue;
    std::vector<int> ids(static_cast<std::size_t>(tri->NbNodes()) + 1);
    for (int i = 1; i <= tri->NbNodes(); ++i) {
      const gp_Pnt p = tri->Node(i).Transformed(loc.Transformation());
      const std::array<double, 3> key{p.X(), p.Y(), p.Z()};
      auto [it, added] = index.emplace(key, static_cast<int>(t.points.size()));
      if (added) t.points.push_back(p);
      ids[static_cast<std::size_t>(i)] = it->second;
    }
    const bool reversed = face.Orientation() == TopAbs_REVERSED;
    for (int i = 1; i <= tri->NbTriangles(); ++i) {
      int a, b, c;
      tri->Triangle(i).Get(a, b, c);
      if (reversed) std::swap(b, c);
      t.triangles.push_back({ids[a], ids[b], ids[c]});
    }
  }
  return t;
}

void write_stl(const Triangles& t, const std::string& path) {
  std::ofstream out(path);
  out.precision(17);
  out << "solid part\n";
  for (const auto& tri : t.triangles) {
    out << " facet normal 0 0 0\n  outer loop\n";
    for (int v : tri) out << "   vertex " << t.points[v].X() << " " << t.points[v].Y() << " " << t.points[v].Z() << "\n";
    out << "  endloop\n endfacet\n";
  }
  out << "endsolid part\n";
}

/// V - E + F of the triangles.
int euler_characteristic(const Triangles& t) {
  std::set<std::pair<int, int>> edges;
  for (const auto& tri : t.triangles)
    for (int k = 0; k < 3; ++k) edges.insert(std::minmax(tri[k], tri[(k + 1) % 3]));
  return static_cast<int>(t.points.size()) - static_cast<int>(edges.size()) + static_cast<int>(t.triangles.size());
}

double diagonal(const Triangles& t) {
  gp_Pnt lo(1e300, 1e300, 1e300), hi(-1e300, -1e300, -1e300);
  for (const gp_Pnt& p : t.points) {
    lo.SetCoord(std::min(lo.X(), p.X()), std::min(lo.Y(), p.Y()), std::min(lo.Z(), p.Z()));
    hi.SetCoord(std::max(hi.X(), p.X()), std::max(hi.Y(), p.Y()), std::max(hi.Z(), p.Z()));
  }
  return lo.Distance(hi);
}

/// Points on every face of `shape`, an n x n grid over each face's parameter range (inside its
/// trimming: B-spline faces of ours are untrimmed; the exact solids' faces are sampled by their
/// triangulation nodes instead, see nodes()).
std::vector<gp_Pnt> grid_points(const TopoDS_Shape& shape, int n) {
  std::vector<gp_Pnt> out;
  for (TopExp_Explorer ex(shape, TopAbs_FACE); ex.More(); ex.Next()) {
    const TopoDS_Face& face = TopoDS::Face(ex.Current());
    const BRepAdaptor_Surface s(face);
    // A planar face (coplanar faces merged, docs/patches.md) is trimmed: its grid is finer and
    // only the points inside its wires count.
    const bool trimmed = s.GetType() == GeomAbs_Plane;
    const int m = trimmed ? 4 * n : n;
    const BRepTopAdaptor_FClass2d inside(face, 1e-9);
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < m; ++j) {
        const double u = s.FirstUParameter() + (s.LastUParameter() - s.FirstUParameter()) * (i + 0.5) / m;
        const double v = s.FirstVParameter() + (s.LastVParameter() - s.FirstVParameter()) * (j + 0.5) / m;
        if (trimmed && inside.Perform(gp_Pnt2d(u, v)) != TopAbs_IN) continue;
        out.push_back(s.Value(u, v));
      }
  }
  return out;
}

struct Distances {
  double max = 0, mean = 0;
};

/// Largest and mean distance from `points` (every `stride`-th) to `shape`.
Distances distances(const std::vector<gp_Pnt>& points, const TopoDS_Shape& shape, std::size_t stride = 1) {
  Distances r;
  int n = 0;
  for (std::size_t i = 0; i < points.size(); i += stride) {
    BRepExtrema_DistShapeShape d(BRepBuilderAPI_MakeVertex(points[i]).Vertex(), shape);
    if (!d.IsDone()) continue;
    r.max = std::max(r.max, d.Value());
    r.mean += d.Value();
    ++n;
  }
  if (n > 0) r.mean /= n;
  return r;
}

/// Largest distance from `points` (every `stride`-th) to the faces of `shape`, each point
/// projected onto the faces whose bounding boxes (enlarged by `reach`) hold it
/// (ShapeAnalysis_Surface keeps a grid per surface, so repeated projections stay cheap). A point
/// near no face counts as `reach`.
double max_distance_to_faces(const std::vector<gp_Pnt>& points, const TopoDS_Shape& shape, double reach,
                             std::size_t stride = 1) {
  struct FaceData {
    Handle(ShapeAnalysis_Surface) surface;
    Bnd_Box box;
  };
  std::vector<FaceData> faces;
  for (TopExp_Explorer ex(shape, TopAbs_FACE); ex.More(); ex.Next()) {
    FaceData f;
    f.surface = new ShapeAnalysis_Surface(BRep_Tool::Surface(TopoDS::Face(ex.Current())));
    BRepBndLib::Add(ex.Current(), f.box);
    f.box.Enlarge(reach);
    faces.push_back(f);
  }
  double worst = 0;
  for (std::size_t i = 0; i < points.size(); i += stride) {
    double best = reach;
    for (FaceData& f : faces) {
      if (f.box.IsOut(points[i])) continue;
      f.surface->ValueOfUV(points[i], 1e-9);
      best = std::min(best, f.surface->Gap());
    }
    worst = std::max(worst, best);
  }
  return worst;
}

double volume(const TopoDS_Shape& s) {
  GProp_GProps g;
  BRepGProp::VolumeProperties(s, g);
  return g.Mass();
}

struct Converted {
  CommandResult run;
  std::string report;
  TopoDS_Shape shape;
  LoadedCage cage;  ///< --keep-cage
};

Converted convert(const std::string& input, TempDir& dir, const std::string& extra = "") {
  Converted c;
  const std::string brep = dir.file("out.brep"), report = dir.file("report.json"), cage = dir.file("cage.obj");
  c.run = run_command(kExe + " convert " + quote(input) + " -o " + quote(brep) + " --report " + quote(report) +
                      " --keep-cage " + quote(cage) + " " + extra);
  if (c.run.exit_code != 0) return c;
  c.report = read_text(report);
  BRep_Builder builder;
  BRepTools::Read(c.shape, brep.c_str(), builder);
  c.cage = read_obj(cage);
  return c;
}

/// `subd2nurbs limit` on the quads of the cage file `cage` (`faces` of them) at (u, v) = (ts[i],
/// ts[j]) on each, i outer: the exact limit points, in that order (asserted: one per query).
std::vector<gp_Pnt> limit_points(const std::string& cage, int faces, const std::vector<double>& ts, TempDir& dir) {
  const std::string queries = dir.file("queries.txt");
  {
    std::ofstream q(queries);
    q.precision(17);
    for (int f = 0; f < faces; ++f)
      for (double u : ts)
        for (double v : ts) q << f << " " << u << " " << v << "\n";
  }
  const CommandResult limit = run_command(kExe + " limit " + quote(cage) + " " + quote(queries));
  EXPECT_EQ(limit.exit_code, 0) << limit.err;
  std::vector<gp_Pnt> points;
  std::istringstream lines(limit.out);
  for (std::string line; std::getline(lines, line);) {
    double x, y, z;
    if (std::istringstream(line) >> x >> y >> z) points.emplace_back(x, y, z);
  }
  EXPECT_EQ(points.size(), static_cast<std::size_t>(faces) * ts.size() * ts.size());
  return points;
}

/// The checks every mesh conversion must pass, against the exact solid it was tessellated from.
/// Distances: the largest both ways below `max_rel` x the diagonal, our surface's mean distance to
/// the exact solid below `mean_rel` x the diagonal. (The goal, a largest distance of
/// 1e-3 x the diagonal, is met on smooth parts such as the cylinder, not yet at the sharp rims of
/// coarse CAD tessellations: docs/meshes.md "Limits".)
void check_against(const TopoDS_Shape& exact, const Triangles& mesh, const Converted& c, double max_rel,
                   double mean_rel = 1e-3) {
  ASSERT_EQ(c.run.exit_code, 0) << c.run.err;
  const double diag = diagonal(mesh);
  EXPECT_NE(c.report.find("\"mesh\": {"), std::string::npos) << "the mesh path was not taken:\n" << c.run.err;
  // A valid closed solid of about the exact volume.
  EXPECT_TRUE(BRepCheck_Analyzer(c.shape).IsValid());
  TopTools_IndexedMapOfShape solids;
  TopExp::MapShapes(c.shape, TopAbs_SOLID, solids);
  EXPECT_EQ(solids.Extent(), 1);
  const double v_exact = volume(exact), v_ours = volume(c.shape);
  EXPECT_NEAR(v_ours, v_exact, 0.01 * v_exact);
  // The cage: all quads, the mesh's Euler characteristic, closed.
  const MeshInput& cage = c.cage.input;
  for (int n : cage.face_sizes) ASSERT_EQ(n, 4);
  std::set<std::pair<int, int>> edges;
  int off = 0;
  for (int n : cage.face_sizes) {
    for (int k = 0; k < n; ++k) edges.insert(std::minmax(cage.face_indices[off + k], cage.face_indices[off + (k + 1) % n]));
    off += n;
  }
  EXPECT_EQ(cage.num_vertices() - static_cast<int>(edges.size()) + cage.num_faces(), euler_characteristic(mesh));
  // Both ways within the tolerance of the exact solid: our faces' points to it, its mesh's
  // nodes to ours.
  const Distances to_exact = distances(grid_points(c.shape, 5), exact);
  std::vector<gp_Pnt> nodes = mesh.points;
  const double from_exact =
      max_distance_to_faces(nodes, c.shape, 10 * max_rel * diag, std::max<std::size_t>(1, nodes.size() / 400));
  EXPECT_LT(to_exact.max, max_rel * diag) << "relative " << to_exact.max / diag;
  EXPECT_LT(to_exact.mean, mean_rel * diag) << "relative " << to_exact.mean / diag;
  EXPECT_LT(from_exact, max_rel * diag) << "relative " << from_exact / diag;
  std::printf("  %zu triangles -> %d quads, %g B-rep faces; surface->exact max %.3g mean %.3g, exact->surface max %.3g "
              "of the diagonal; volume %.4g vs %.4g; feature angles max %.3g mean %.3g deg off\n",
              mesh.triangles.size(), cage.num_faces(), json_number(c.report, {"brep", "faces"}), to_exact.max / diag,
              to_exact.mean / diag, from_exact / diag, v_ours, v_exact,
              json_number(c.report, {"mesh", "feature_angles", "max_difference_deg"}),
              json_number(c.report, {"mesh", "feature_angles", "mean_difference_deg"}));
  std::printf("  planar faces %g in place of %g faces, %g rejected\n", json_number(c.report, {"brep", "planar_faces"}),
              json_number(c.report, {"brep", "merged_patches"}), json_number(c.report, {"brep", "rejected_planar_faces"}));
}

/// Planar faces stay planar (issue #28): every B-rep face of ours whose n x n grid points all lie
/// within 1e-3 x the diagonal of one plane of the exact solid, inside that face's box, must lie in
/// it within 1e-4 x the diagonal (the goal; the flattening reaches rounding). Such faces must
/// make up at least `min_fraction` of our surface's area (coplanar faces are merged into one
/// planar face, so a count of faces says little). Returns the largest distance over them,
/// relative to the diagonal.
double check_planar_faces(const TopoDS_Shape& exact, const TopoDS_Shape& ours, double diag, double min_fraction) {
  struct ExactPlane {
    gp_Pln plane;
    Bnd_Box box;
  };
  std::vector<ExactPlane> planes;
  for (TopExp_Explorer ex(exact, TopAbs_FACE); ex.More(); ex.Next()) {
    const BRepAdaptor_Surface s(TopoDS::Face(ex.Current()));
    if (s.GetType() != GeomAbs_Plane) continue;
    ExactPlane p{s.Plane(), {}};
    BRepBndLib::Add(ex.Current(), p.box);
    p.box.Enlarge(1e-3 * diag);
    planes.push_back(p);
  }
  int faces = 0, on_planes = 0;
  double worst = 0, area = 0, area_on_planes = 0;
  for (TopExp_Explorer ex(ours, TopAbs_FACE); ex.More(); ex.Next()) {
    ++faces;
    GProp_GProps g;
    BRepGProp::SurfaceProperties(ex.Current(), g);
    area += g.Mass();
    const std::vector<gp_Pnt> pts = grid_points(ex.Current(), 5);
    for (const ExactPlane& p : planes) {
      double far = 0;
      bool inside = true;
      for (const gp_Pnt& q : pts) far = std::max(far, p.plane.Distance(q)), inside = inside && !p.box.IsOut(q);
      if (!inside || far > 1e-3 * diag) continue;
      ++on_planes;
      area_on_planes += g.Mass();
      worst = std::max(worst, far);
      break;
    }
  }
  EXPECT_LT(worst, 1e-4 * diag) << "relative " << worst / diag;
  EXPECT_GE(area_on_planes, min_fraction * area) << area_on_planes << " of " << area;
  std::printf("  %d of %d B-rep faces (%.3g of the area) on planes of the exact solid, within %.3g of the diagonal\n",
              on_planes, faces, area_on_planes / area, worst / diag);
  return worst / diag;
}

TopoDS_Shape box_with_hole() {
  const TopoDS_Shape box = BRepPrimAPI_MakeBox(gp_Pnt(-20, -15, 0), 40, 30, 10).Shape();
  const TopoDS_Shape drill = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, -1), gp::DZ()), 6, 12).Shape();
  return BRepAlgoAPI_Cut(box, drill).Shape();
}

TEST(MeshPath, BoxWithDrilledHole) {
  TempDir dir;
  const TopoDS_Shape exact = box_with_hole();
  const Triangles mesh = tessellate(exact, 0.01);
  ASSERT_EQ(euler_characteristic(mesh), 0);  // genus 1
  const std::string stl = dir.file("part.stl");
  write_stl(mesh, stl);
  const Converted c = convert(stl, dir, "--target-faces 300");
  // Within 2e-3 x the diagonal both ways (the hole's rims, circles of radius 6 against a cage
  // spacing of ~7, are followed by chain vertices of their own: docs/remesh.md step 4; before
  // that, 3e-3).
  check_against(exact, mesh, c, 2e-3);
  // The sharp edges kept: the normal jump across the cage's feature curves is the mesh's
  // dihedral there (90 degrees at the box's and the hole's rims), everywhere within 3 degrees
  // (the goal; before the rims were followed, 14 degrees at a rim).
  EXPECT_GT(json_number(c.report, {"mesh", "feature_angles", "samples"}), 0);
  EXPECT_LT(json_number(c.report, {"mesh", "feature_angles", "max_difference_deg"}), 3.0);
  EXPECT_LT(json_number(c.report, {"mesh", "feature_angles", "mean_difference_deg"}), 1.0);
  // The box's planar faces (with the hole's rims) are flat.
  check_planar_faces(exact, c.shape, diagonal(mesh), 0.3);
  EXPECT_LT(json_number(c.report, {"mesh", "planar", "flatness_after"}), 1e-12);
}

/// A box 100 x 60 x 20 whose four bottom edges are rounded with radius 2 (plate_holes' bottom
/// outline in small: a fillet tangent to the bottom and to the walls, narrower than the cage's
/// quads, ~7.8 at 300 quads). Without plane edges the bottom's quads along the fillet took it in
/// smoothly: the bottom's outer ring was neither flat nor one face. The planes now end at the
/// fillet's tangent lines (features: docs/remesh.md "Plane edges"), so the bottom is one planar
/// face covering the exact solid's flat bottom, and the walls' planar faces reach down to the
/// fillet.
TEST(MeshPath, NarrowFilletEndsItsPlanes) {
  TempDir dir;
  const TopoDS_Shape box = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 100, 60, 20).Shape();
  BRepFilletAPI_MakeFillet fillet(box);
  for (TopExp_Explorer ex(box, TopAbs_EDGE); ex.More(); ex.Next()) {
    const TopoDS_Edge e = TopoDS::Edge(ex.Current());
    const gp_Pnt a = BRep_Tool::Pnt(TopExp::FirstVertex(e)), b = BRep_Tool::Pnt(TopExp::LastVertex(e));
    if (a.Z() == 0 && b.Z() == 0) fillet.Add(2.0, e);
  }
  const TopoDS_Shape exact = fillet.Shape();
  ASSERT_TRUE(BRepCheck_Analyzer(exact).IsValid());
  const Triangles mesh = tessellate(exact, 0.01);
  const std::string stl = dir.file("rounded.stl");
  write_stl(mesh, stl);
  const Converted c = convert(stl, dir, "--target-faces 300");
  check_against(exact, mesh, c, 2e-3);
  EXPECT_GT(json_number(c.report, {"mesh", "features", "plane_edges"}), 0);
  // The bottom: one planar face in z = 0 covering the exact solid's flat bottom, 96 x 56: its
  // area within that of a band of the distance tolerance along the bottom's outline (its edges
  // are the fitted crease curves along the fillet's tangent lines).
  double bottom = 0;
  int bottom_faces = 0;
  for (TopExp_Explorer ex(c.shape, TopAbs_FACE); ex.More(); ex.Next()) {
    const BRepAdaptor_Surface sf(TopoDS::Face(ex.Current()));
    if (sf.GetType() != GeomAbs_Plane || std::abs(sf.Plane().Location().Z()) > 1e-9 ||
        std::abs(std::abs(sf.Plane().Axis().Direction().Z()) - 1) > 1e-12)
      continue;
    GProp_GProps g;
    BRepGProp::SurfaceProperties(ex.Current(), g);
    bottom += g.Mass();
    ++bottom_faces;
  }
  std::printf("  rounded box: %d bottom planar face(s) of area %.6g (exact flat bottom 5376), %g plane edges, %g B-rep faces\n",
              bottom_faces, bottom, json_number(c.report, {"mesh", "features", "plane_edges"}),
              json_number(c.report, {"brep", "faces"}));
  EXPECT_EQ(bottom_faces, 1);
  EXPECT_NEAR(bottom, 96.0 * 56.0, 2 * (96.0 + 56.0) * 2e-3 * diagonal(mesh));
  check_planar_faces(exact, c.shape, diagonal(mesh), 0.8);
}

/// A stepped block (an L-shaped profile extruded, a hole drilled through the lower step): its
/// nine planar faces stay planar.
TEST(MeshPath, SteppedBlockStaysPlanar) {
  TempDir dir;
  const TopoDS_Shape block = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 40, 24, 16).Shape();
  const TopoDS_Shape step = BRepPrimAPI_MakeBox(gp_Pnt(20, -1, 8), 21, 26, 9).Shape();
  const TopoDS_Shape drill = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(30, 12, -1), gp::DZ()), 4, 20).Shape();
  const TopoDS_Shape exact = BRepAlgoAPI_Cut(BRepAlgoAPI_Cut(block, step).Shape(), drill).Shape();
  const Triangles mesh = tessellate(exact, 0.01);
  ASSERT_EQ(euler_characteristic(mesh), 0);  // genus 1
  const std::string stl = dir.file("stepped.stl");
  write_stl(mesh, stl);
  const Converted c = convert(stl, dir, "--target-faces 300");
  check_against(exact, mesh, c, 2e-2);
  check_planar_faces(exact, c.shape, diagonal(mesh), 0.5);
  EXPECT_GE(json_number(c.report, {"mesh", "planar", "regions_used"}), 8);
}

/// Concave corners (docs/remesh.md step 9): an L-shaped profile extruded, whose front and back
/// faces each have an inner corner of 270 degrees where the concave edge ends. The corner rule
/// folds such a sector over itself at the corner (the faces' normals there face into the block),
/// so the remesher splits it with a crease. Checked against the exact solid, with the B-spline
/// faces kept: every point of our faces, sampled on grids graded towards the faces' corners, that
/// lies on one of the block's planes faces the way that plane's outward normal does; the two
/// concave sectors, and only they, are split; no faces cross or touch. (Without the split: no
/// sector split, and 6 of 13 125 samples, at the two inner corners, face into the block.)
TEST(MeshPath, ConcaveCornersDoNotFold) {
  TempDir dir;
  const TopoDS_Shape block = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 40, 24, 16).Shape();
  const TopoDS_Shape step = BRepPrimAPI_MakeBox(gp_Pnt(20, -1, 8), 21, 26, 9).Shape();
  const TopoDS_Shape exact = BRepAlgoAPI_Cut(block, step).Shape();
  const Triangles mesh = tessellate(exact, 0.01);
  const std::string stl = dir.file("l_block.stl");
  write_stl(mesh, stl);
  // B-spline faces kept (coplanar faces merged into one planar face would hide a fold).
  const Converted c = convert(stl, dir, "--target-faces 300 --planar-faces keep");
  check_against(exact, mesh, c, 2e-2);
  const double diag = diagonal(mesh);
  EXPECT_EQ(json_number(c.report, {"mesh", "cage", "concave_sectors"}), 2);
  EXPECT_EQ(json_number(c.report, {"self_intersection", "touching_face_pairs"}), 0);
  EXPECT_EQ(json_number(c.report, {"self_intersection", "crossing_face_pairs"}), 0);

  struct ExactPlane {
    gp_Pln plane;
    gp_Vec outward;
    Bnd_Box box;
  };
  std::vector<ExactPlane> planes;
  for (TopExp_Explorer ex(exact, TopAbs_FACE); ex.More(); ex.Next()) {
    const TopoDS_Face& f = TopoDS::Face(ex.Current());
    const gp_Pln pl = BRepAdaptor_Surface(f).Plane();
    gp_Vec n(pl.Axis().Direction());
    if (!pl.Direct()) n.Reverse();  // a left-handed frame: its normal is -Z
    if (f.Orientation() == TopAbs_REVERSED) n.Reverse();
    ExactPlane e{pl, n, {}};
    BRepBndLib::Add(f, e.box);
    e.box.Enlarge(1e-3 * diag);
    planes.push_back(e);
  }
  ASSERT_EQ(planes.size(), 8u);
  const std::vector<double> graded = {0, 1e-3, 4e-3, 0.01, 0.02, 0.04, 0.07, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5};
  std::vector<double> ts = graded;
  for (const double t : graded)
    if (t < 0.5) ts.push_back(1 - t);
  int samples = 0, folded = 0;
  for (TopExp_Explorer ex(c.shape, TopAbs_FACE); ex.More(); ex.Next()) {
    const TopoDS_Face& face = TopoDS::Face(ex.Current());
    const BRepAdaptor_Surface s(face);
    const BRepTopAdaptor_FClass2d inside(face, 1e-9);
    for (const double tu : ts)
      for (const double tv : ts) {
        const double u = s.FirstUParameter() + (s.LastUParameter() - s.FirstUParameter()) * tu;
        const double v = s.FirstVParameter() + (s.LastVParameter() - s.FirstVParameter()) * tv;
        if (s.GetType() == GeomAbs_Plane && inside.Perform(gp_Pnt2d(u, v)) != TopAbs_IN) continue;
        gp_Pnt q;
        gp_Vec du, dv;
        s.D1(u, v, q, du, dv);
        gp_Vec n = du.Crossed(dv);
        if (n.Magnitude() < 1e-12) continue;
        if (face.Orientation() == TopAbs_REVERSED) n.Reverse();
        bool on_plane = false, agrees = false;
        for (const ExactPlane& e : planes) {
          if (e.box.IsOut(q) || e.plane.Distance(q) > 1e-3 * diag) continue;
          on_plane = true;
          agrees = agrees || n.Normalized().Dot(e.outward) > 0.5;
        }
        samples += on_plane;
        if (on_plane && !agrees) {
          if (folded++ < 5)
            std::printf("  folded: (%.4g, %.4g, %.4g) normal (%.3f, %.3f, %.3f)\n", q.X(), q.Y(), q.Z(),
                        n.Normalized().X(), n.Normalized().Y(), n.Normalized().Z());
        }
      }
  }
  EXPECT_GT(samples, 10000);
  EXPECT_EQ(folded, 0) << "of " << samples << " samples on the block's planes";
  std::printf("  %d samples on the block's planes, %d facing against them\n", samples, folded);
}

/// Walls narrower than a cage edge (issue #28; docs/fitting.md "Planar regions"): a 60 x 40 x 3
/// slab with a hole of radius 5 drilled through, converted with ~6-unit quads, so its four side
/// walls (3 high) are one quad between the sharp top and bottom rims. Such a wall's faces depend
/// only on the rims' crease vertices; held on the wall's plane (and the rim vertices on both
/// planes: on their line), every B-rep face on a side wall must be exactly planar: all its poles
/// within 1e-12 x the diagonal of the exact wall plane, the flat faces together covering the
/// walls' area. The drilled hole's wall (3 high, a faceted cylinder) stays on the cylinder.
TEST(MeshPath, ThinSlabWallsAreExactlyPlanar) {
  TempDir dir;
  const double a = 30, b = 20, h = 3;
  const TopoDS_Shape slab = BRepPrimAPI_MakeBox(gp_Pnt(-a, -b, 0), 2 * a, 2 * b, h).Shape();
  const TopoDS_Shape drill = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(8, 0, -1), gp::DZ()), 5, h + 2).Shape();
  const TopoDS_Shape exact = BRepAlgoAPI_Cut(slab, drill).Shape();
  const Triangles mesh = tessellate(exact, 0.01);
  ASSERT_EQ(euler_characteristic(mesh), 0);  // genus 1
  const std::string stl = dir.file("slab.stl");
  write_stl(mesh, stl);
  const Converted c = convert(stl, dir, "--target-faces 150");
  check_against(exact, mesh, c, 1e-2);
  const double diag = diagonal(mesh);
  // The cage's edges are longer than the walls are high (else the test would not test narrow
  // walls): measured along the feature curves (the rims), whose vertices the untangling of the
  // planar regions leaves where the fit put them (docs/meshes.md "Folds in planar regions").
  const MeshInput& cage = c.cage.input;
  double length = 0;
  int edges = 0;
  for (const CreaseTag& t : cage.creases) {
    const auto& p = cage.positions[t.v0];
    const auto& q = cage.positions[t.v1];
    length += std::hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]);
    ++edges;
  }
  ASSERT_GT(edges, 0);
  ASSERT_GT(length / edges, 1.3 * h);
  // The walls: x = +-a, y = +-b. A B-rep face of ours on one of them: its points all within
  // 1e-3 x the diagonal of the wall's plane and its normal at its middle within 10 degrees of the
  // wall's (not a strip of the top or the bottom along a rim).
  const gp_Pln walls[4] = {gp_Pln(gp_Pnt(a, 0, 0), gp::DX()), gp_Pln(gp_Pnt(-a, 0, 0), gp::DX()),
                           gp_Pln(gp_Pnt(0, b, 0), gp::DY()), gp_Pln(gp_Pnt(0, -b, 0), gp::DY())};
  double flat_area = 0, worst = 0;
  int wall_faces = 0;
  for (TopExp_Explorer ex(c.shape, TopAbs_FACE); ex.More(); ex.Next()) {
    const TopoDS_Face face = TopoDS::Face(ex.Current());
    const std::vector<gp_Pnt> pts = grid_points(face, 5);
    for (const gp_Pln& wall : walls) {
      double far = 0;
      for (const gp_Pnt& q : pts) far = std::max(far, wall.Distance(q));
      if (far > 1e-3 * diag) continue;
      const Handle(Geom_Surface) surface = BRep_Tool::Surface(face);
      const BRepAdaptor_Surface ad(face);
      GeomLProp_SLProps props(surface, 0.5 * (ad.FirstUParameter() + ad.LastUParameter()),
                              0.5 * (ad.FirstVParameter() + ad.LastVParameter()), 1, 1e-9);
      if (!props.IsNormalDefined() || std::abs(props.Normal().Dot(wall.Axis().Direction())) < std::cos(10 * M_PI / 180))
        continue;
      ++wall_faces;
      double pole_far = 0;
      if (const Handle(Geom_BSplineSurface) bs = Handle(Geom_BSplineSurface)::DownCast(surface)) {
        for (int i = 1; i <= bs->NbUPoles(); ++i)
          for (int j = 1; j <= bs->NbVPoles(); ++j) pole_far = std::max(pole_far, wall.Distance(bs->Pole(i, j)));
      } else if (const Handle(Geom_Plane) pl = Handle(Geom_Plane)::DownCast(surface)) {
        // A merged planar face: its plane's origin and normal against the wall's.
        pole_far = std::max(wall.Distance(pl->Location()), (1 - std::abs(pl->Axis().Direction().Dot(wall.Axis().Direction()))) * diag);
      } else {
        pole_far = INFINITY;
      }
      worst = std::max(worst, pole_far);
      GProp_GProps g;
      BRepGProp::SurfaceProperties(face, g);
      if (pole_far <= 1e-12 * diag) flat_area += g.Mass();
      break;
    }
  }
  EXPECT_GE(wall_faces, 4);
  EXPECT_LT(worst, 1e-12 * diag) << "relative " << worst / diag;
  const double wall_area = 2 * (2 * a + 2 * b) * h;
  EXPECT_NEAR(flat_area, wall_area, 0.02 * wall_area);
  std::printf("  %d B-rep faces on the side walls, poles within %.3g of the diagonal of the walls' planes; flat area "
              "%.4g of %.4g\n",
              wall_faces, worst / diag, flat_area, wall_area);
}

TEST(MeshPath, CylinderSideStaysOnTheCylinder) {
  TempDir dir;
  const double r = 5, h = 20;
  const TopoDS_Shape exact = BRepPrimAPI_MakeCylinder(r, h).Shape();
  const Triangles mesh = tessellate(exact, 0.005);
  const std::string stl = dir.file("cylinder.stl");
  write_stl(mesh, stl);
  const Converted c = convert(stl, dir, "--target-faces 250");
  check_against(exact, mesh, c, 2e-3, 2e-4);
  // Points of our surface away from the caps: on the cylinder within the tolerance.
  const double diag = diagonal(mesh);
  double worst = 0;
  for (const gp_Pnt& p : grid_points(c.shape, 7))
    if (p.Z() > 0.1 * h && p.Z() < 0.9 * h) worst = std::max(worst, std::abs(std::hypot(p.X(), p.Y()) - r));
  EXPECT_LT(worst, 2e-3 * diag) << "relative " << worst / diag;
}

TEST(MeshPath, BoxWithFilletedSlot) {
  TempDir dir;
  const TopoDS_Shape box = BRepPrimAPI_MakeBox(gp_Pnt(-20, -10, 0), 40, 20, 12).Shape();
  const TopoDS_Shape slot = BRepPrimAPI_MakeBox(gp_Pnt(-25, -4, 6), 50, 8, 10).Shape();
  const TopoDS_Shape cut = BRepAlgoAPI_Cut(box, slot).Shape();
  // Fillet the slot's two bottom edges (the edges along x at z = 6, y = +-4).
  BRepFilletAPI_MakeFillet fillet(cut);
  for (TopExp_Explorer ex(cut, TopAbs_EDGE); ex.More(); ex.Next()) {
    const TopoDS_Edge e = TopoDS::Edge(ex.Current());
    TopoDS_Vertex a, b;
    TopExp::Vertices(e, a, b);
    const gp_Pnt pa = BRep_Tool::Pnt(a), pb = BRep_Tool::Pnt(b);
    if (std::abs(pa.Z() - 6) < 1e-9 && std::abs(pb.Z() - 6) < 1e-9 && std::abs(std::abs(pa.Y()) - 4) < 1e-9 &&
        std::abs(pa.Y() - pb.Y()) < 1e-9)
      fillet.Add(2.0, e);
  }
  ASSERT_EQ(fillet.NbContours(), 2);
  const TopoDS_Shape exact = fillet.Shape();
  const Triangles mesh = tessellate(exact, 0.01);
  const std::string stl = dir.file("slot.stl");
  write_stl(mesh, stl);
  const Converted c = convert(stl, dir, "--target-faces 400");
  check_against(exact, mesh, c, 2e-2);
}

// --- The size chosen by the fit tolerance (docs/meshes.md "Size chosen by the fit tolerance") ---

/// A capsule: the cylinder of radius r around the z axis from z = 0 to z = L, closed by two
/// hemispheres. The oracle of the size rule's tests: the exact distance of a point to it.
struct Capsule {
  double L = 20, r = 1;
  double distance(const gp_Pnt& p) const {
    const double z = std::clamp(p.Z(), 0.0, L);
    return std::abs(std::hypot(p.X(), p.Y(), p.Z() - z) - r);
  }
  gp_Pnt point(double z, double radius, double angle) const {
    return gp_Pnt(radius * std::cos(angle), radius * std::sin(angle), z);
  }
  /// Its triangulation with every vertex on it: `around` vertices per ring, `along` steps along
  /// the cylinder, `cap` rings per hemisphere; every other ring turned by half a step, so the
  /// triangles do not pair back into quads (the mesh road by the rule).
  Triangles mesh(int around, int along, int cap) const {
    std::vector<std::pair<double, double>> rings;  // (z, radius)
    for (int i = 1; i <= cap; ++i) {
      const double phi = -M_PI / 2 + M_PI / 2 * i / cap;
      rings.emplace_back(r * std::sin(phi), r * std::cos(phi));
    }
    for (int i = 1; i < along; ++i) rings.emplace_back(L * i / along, r);
    for (int i = 0; i < cap; ++i) {
      const double phi = M_PI / 2 * i / cap;
      rings.emplace_back(L + r * std::sin(phi), r * std::cos(phi));
    }
    Triangles t;
    t.points.emplace_back(0, 0, -r);
    for (std::size_t k = 0; k < rings.size(); ++k)
      for (int j = 0; j < around; ++j)
        t.points.push_back(point(rings[k].first, rings[k].second, 2 * M_PI * (j + 0.5 * (k % 2)) / around));
    const int top = static_cast<int>(t.points.size());
    t.points.emplace_back(0, 0, L + r);
    for (int j = 0; j < around; ++j) t.triangles.push_back({0, 1 + (j + 1) % around, 1 + j});
    for (int k = 0; k + 1 < static_cast<int>(rings.size()); ++k) {
      const int a = 1 + k * around, b = a + around;
      for (int j = 0; j < around; ++j) {
        const int j1 = (j + 1) % around;
        if (k % 2 == 0) {
          t.triangles.push_back({a + j, a + j1, b + j});
          t.triangles.push_back({a + j1, b + j1, b + j});
        } else {
          t.triangles.push_back({a + j, a + j1, b + j1});
          t.triangles.push_back({a + j, b + j1, b + j});
        }
      }
    }
    const int last = 1 + (static_cast<int>(rings.size()) - 1) * around;
    for (int j = 0; j < around; ++j) t.triangles.push_back({last + j, last + (j + 1) % around, top});
    return t;
  }
  /// The largest distance of the mesh's triangles from the capsule (their chord error), sampled
  /// at 28 barycentric points per triangle.
  double chord_error(const Triangles& t) const {
    double worst = 0;
    for (const auto& tri : t.triangles)
      for (int i = 0; i <= 6; ++i)
        for (int j = 0; i + j <= 6; ++j) {
          const double a = i / 6.0, b = j / 6.0, c = 1 - a - b;
          const gp_Pnt& p = t.points[tri[0]];
          const gp_Pnt& q = t.points[tri[1]];
          const gp_Pnt& w = t.points[tri[2]];
          worst = std::max(worst, distance(gp_Pnt(a * p.X() + b * q.X() + c * w.X(), a * p.Y() + b * q.Y() + c * w.Y(),
                                                  a * p.Z() + b * q.Z() + c * w.Z())));
        }
    return worst;
  }
  /// Points on it: `n` around, along the cylinder at the same spacing, and on the hemispheres.
  std::vector<gp_Pnt> samples(int n) const {
    std::vector<gp_Pnt> out;
    const int along = static_cast<int>(std::ceil(L / (2 * M_PI * r / n)));
    for (int i = 0; i <= along; ++i)
      for (int j = 0; j < n; ++j) out.push_back(point(L * i / along, r, 2 * M_PI * j / n));
    for (int i = 1; i <= n / 4; ++i) {
      const double phi = M_PI / 2 * i / (n / 4);
      for (int j = 0; j < n; ++j) {
        out.push_back(point(L + r * std::sin(phi), r * std::cos(phi), 2 * M_PI * j / n));
        out.push_back(point(-r * std::sin(phi), r * std::cos(phi), 2 * M_PI * j / n));
      }
    }
    return out;
  }
};

/// One number per round of the report's mesh.size.rounds: the values of `key` in order.
std::vector<double> round_values(const std::string& report, const std::string& key) {
  std::vector<double> out;
  const std::size_t begin = report.find("\"rounds\": [");
  const std::size_t end = report.find(']', begin);
  if (begin == std::string::npos || end == std::string::npos) return out;
  for (std::size_t at = report.find("\"" + key + "\": ", begin); at < end; at = report.find("\"" + key + "\": ", at + 1))
    out.push_back(std::strtod(report.c_str() + at + key.size() + 4, nullptr));
  return out;
}

/// The capsule's mesh (6 528 triangles), its diagonal and its chord error.
struct CapsuleCase {
  Capsule shape;
  Triangles mesh = shape.mesh(48, 45, 12);
  double diag = diagonal(mesh);
  double chord = shape.chord_error(mesh);
};

/// `subd2nurbs convert STL -o DIR/NAME.json --report DIR/NAME.report.json -q ARGS`, expected to
/// succeed: the report's text.
std::string convert_with_report(const TempDir& dir, const std::string& stl, const std::string& name,
                                const std::string& args) {
  const CommandResult r = run_command(kExe + " convert " + quote(stl) + " -o " + quote(dir.file(name + ".json")) +
                                      " --report " + quote(dir.file(name + ".report.json")) + " -q " + args);
  EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.err;
  return read_text(dir.file(name + ".report.json"));
}

/// The size rule makes the cage finer until the fit tolerance is met (issue #28 item 3). The
/// tolerance asked for is 0.7 x the distance the automatic size reaches (the report of a run with
/// fit_tolerance 0), so the automatic size misses it whatever the remesher does. With it the kept
/// cage is finer and meets it, checked against the exact capsule: our surface (the B-rep, dense
/// grids on its faces) within the tolerance + the mesh's chord error + the conversion's own
/// tolerance (1e-5) of the capsule, and the capsule (dense samples) as close to our surface.
TEST(MeshPath, FitToleranceRefinesTheCageUntilMet) {
  TempDir dir;
  const CapsuleCase k;
  const std::string stl = dir.file("capsule.stl");
  write_stl(k.mesh, stl);
  const CommandResult first = run_command(kExe + " convert " + quote(stl) + " -o " + quote(dir.file("a.json")) +
                                          " --report " + quote(dir.file("a.report.json")) + " -q --fit-tolerance 0");
  ASSERT_EQ(first.exit_code, 0) << first.err;
  const std::string first_report = read_text(dir.file("a.report.json"));
  const double automatic = std::max(json_number(first_report, {"mesh", "fit", "after", "limit_to_target", "max"}),
                                    json_number(first_report, {"mesh", "fit", "after", "target_to_limit", "max"}));
  const double tolerance = 0.7 * automatic;
  // The fit follows the mesh's facets only to about half their chord error.
  ASSERT_GT(tolerance * k.diag, 1.5 * k.chord) << "the mesh is too coarse for the test";

  TempDir out;
  char arg[64];
  std::snprintf(arg, sizeof arg, "--fit-tolerance %.6g --tolerance 1e-5", tolerance);
  const Converted c = convert(stl, out, arg);
  ASSERT_EQ(c.run.exit_code, 0) << c.run.err;
  EXPECT_NE(c.report.find("\"rule\": \"fit_tolerance\""), std::string::npos);
  const std::vector<double> quads = round_values(c.report, "quads");
  ASSERT_GE(quads.size(), 2u);
  ASSERT_LE(quads.size(), 3u);
  EXPECT_NE(c.report.find("\"tolerance_met\": true"), std::string::npos) << c.report;
  const int kept = static_cast<int>(json_number(c.report, {"mesh", "size", "kept_round"}));
  ASSERT_GE(kept, 1);
  EXPECT_GT(quads[static_cast<std::size_t>(kept)], quads[0]);
  EXPECT_EQ(c.cage.input.num_faces(), quads[static_cast<std::size_t>(kept)]);
  EXPECT_EQ(quads[0], json_number(first_report, {"mesh", "cage", "faces"}));  // round 1: the automatic size

  // The oracle: the exact capsule, both ways.
  const double bound = tolerance * k.diag + k.chord + 1e-5 * k.diag;
  double to_exact = 0;
  for (const gp_Pnt& p : grid_points(c.shape, 12)) to_exact = std::max(to_exact, k.shape.distance(p));
  const std::vector<gp_Pnt> samples = k.shape.samples(96);
  const double from_exact = max_distance_to_faces(samples, c.shape, 10 * bound, 3);
  EXPECT_LT(to_exact, bound) << "relative " << to_exact / k.diag;
  EXPECT_LT(from_exact, bound) << "relative " << from_exact / k.diag;
  std::printf("  capsule: automatic %g quads at %.3g; fit tolerance %.3g: rounds", quads[0], automatic, tolerance);
  for (double q : quads) std::printf(" %g", q);
  std::printf(", kept %g quads; to the capsule %.3g, from it %.3g of the diagonal (bound %.3g, chord error %.3g)\n",
              quads[static_cast<std::size_t>(kept)], to_exact / k.diag, from_exact / k.diag, bound / k.diag,
              k.chord / k.diag);
}

/// fit_tolerance 0 is the automatic size alone: the same cage as that size given as
/// --target-faces (one round); a size the user gives is obeyed, one round, whatever the tolerance;
/// a first round far within the tolerance is tried once coarser, and the cage kept meets it
/// (against the exact capsule).
/// --aim-at-target (the settings table's aim_at_target) reaches the remesher: the cage has no more
/// quads than asked for and not far fewer (the request is the oracle; the aim is 0.9 .. 1.0 x, the
/// nearest run kept otherwise, a shortfall counted 4 x an excess: the capsule at 200 keeps 154 of
/// five runs' counts; QuadRemesh.TargetCountIsMet tests the core's band on smoother sizes), where
/// the same request without it leaves more (so the check is able to fail).
TEST(MeshPath, AimAtTargetHonoursTheCount) {
  TempDir dir;
  const CapsuleCase k;
  const std::string stl = dir.file("capsule.stl");
  write_stl(k.mesh, stl);
  auto quads = [&](const std::string& name, const std::string& args) {
    return json_number(convert_with_report(dir, stl, name, args), {"mesh", "cage", "faces"});
  };
  for (const int n : {200, 400}) {
    const double loose = quads("loose", "--target-faces " + std::to_string(n));
    const double aimed = quads("aimed", "--target-faces " + std::to_string(n) + " --aim-at-target");
    EXPECT_GT(loose, n) << "the request without aiming was met already: the test cannot fail";
    EXPECT_LE(aimed, n);
    EXPECT_GE(aimed, 0.75 * n);
    std::printf("  %d quads asked: %g without aiming, %g aiming\n", n, loose, aimed);
  }
}

/// --exact-spacing (the settings table's exact_spacing) reaches the remesher: with --edge-length L
/// the report's cage has one run at the lattice spacing 2 L (the request is the oracle), where
/// without it the drilled box runs again at a coarser spacing for one of the lengths at least
/// (so the check is able to fail).
TEST(MeshPath, ExactSpacingIsTheEdgeLengthAskedFor) {
  TempDir dir;
  const std::string stl = dir.file("part.stl");
  write_stl(tessellate(box_with_hole(), 0.01), stl);
  int reruns = 0;
  for (const double length : {4.0, 6.0, 8.0}) {
    const std::string size = "--edge-length " + std::to_string(length);
    const std::string loose = convert_with_report(dir, stl, "loose", size);
    const std::string exact = convert_with_report(dir, stl, "exact", size + " --exact-spacing");
    reruns += json_number(loose, {"mesh", "cage", "attempts"}) == 2;
    EXPECT_EQ(json_number(exact, {"mesh", "cage", "attempts"}), 1);
    EXPECT_NEAR(json_number(exact, {"mesh", "cage", "spacing"}), 2 * length, 1e-9 * length);
    std::printf("  edge length %g: %g runs at spacing %g without, %g quads; %g quads exact\n", length,
                json_number(loose, {"mesh", "cage", "attempts"}), json_number(loose, {"mesh", "cage", "spacing"}),
                json_number(loose, {"mesh", "cage", "faces"}), json_number(exact, {"mesh", "cage", "faces"}));
  }
  EXPECT_GE(reruns, 1) << "no second run without --exact-spacing: the test cannot fail";
}

TEST(MeshPath, FitToleranceOffGivenSizeAndCoarsening) {
  TempDir dir;
  const CapsuleCase k;
  const std::string stl = dir.file("capsule.stl");
  write_stl(k.mesh, stl);
  auto run = [&](const std::string& name, const std::string& args) {
    return convert_with_report(dir, stl, name, "--keep-cage " + quote(dir.file(name + ".obj")) + " " + args);
  };
  const std::string off = run("off", "--fit-tolerance 0");
  EXPECT_NE(off.find("\"rule\": \"automatic\""), std::string::npos);
  EXPECT_EQ(round_values(off, "quads").size(), 1u);
  // The automatic size is the documented one: quads of 1/25 of the diagonal over the mesh's area.
  double area = 0;
  for (const auto& t : k.mesh.triangles) {
    const gp_Vec u(k.mesh.points[t[0]], k.mesh.points[t[1]]), v(k.mesh.points[t[0]], k.mesh.points[t[2]]);
    area += 0.5 * u.Crossed(v).Magnitude();
  }
  const int automatic = static_cast<int>(json_number(off, {"mesh", "target_faces"}));
  EXPECT_NEAR(automatic, area / std::pow(k.diag / 25, 2), 1.0);
  const std::string given = run("given", "--target-faces " + std::to_string(automatic));
  EXPECT_NE(given.find("\"rule\": \"given\""), std::string::npos);
  const LoadedCage a = read_obj(dir.file("off.obj")), b = read_obj(dir.file("given.obj"));
  ASSERT_EQ(a.input.num_faces(), b.input.num_faces());
  EXPECT_EQ(a.input.face_indices, b.input.face_indices);
  ASSERT_EQ(a.input.positions.size(), b.input.positions.size());
  double moved = 0;
  for (std::size_t i = 0; i < a.input.positions.size(); ++i)
    for (int c = 0; c < 3; ++c) moved = std::max(moved, std::abs(a.input.positions[i][c] - b.input.positions[i][c]));
  EXPECT_LT(moved, 1e-12 * k.diag);

  // A given size with a tolerance it misses: one round, that size.
  const std::string small = run("small", "--target-faces 60 --fit-tolerance 1e-5");
  EXPECT_NE(small.find("\"rule\": \"given\""), std::string::npos);
  const std::vector<double> small_targets = round_values(small, "target_faces");
  ASSERT_EQ(small_targets.size(), 1u);
  EXPECT_EQ(small_targets[0], 60);

  // Far within the tolerance: once coarser; the kept cage meets the tolerance and has no more
  // quads than the first; checked on its limit surface against the capsule below.
  const double d0 = std::max(json_number(off, {"mesh", "fit", "after", "limit_to_target", "max"}),
                             json_number(off, {"mesh", "fit", "after", "target_to_limit", "max"}));
  char arg[64];
  std::snprintf(arg, sizeof arg, "--fit-tolerance %.6g", 3 * d0);
  const std::string coarse = run("coarse", arg);
  const std::vector<double> quads = round_values(coarse, "quads"), targets = round_values(coarse, "target_faces");
  ASSERT_EQ(quads.size(), 2u) << coarse;
  EXPECT_LT(targets[1], targets[0]);
  const int kept = static_cast<int>(json_number(coarse, {"mesh", "size", "kept_round"}));
  const LoadedCage kept_cage = read_obj(dir.file("coarse.obj"));
  EXPECT_EQ(kept_cage.input.num_faces(), quads[static_cast<std::size_t>(kept)]);
  EXPECT_LE(kept_cage.input.num_faces(), quads[0]);
  EXPECT_NE(coarse.find("\"tolerance_met\": true"), std::string::npos) << coarse;
  // The kept cage's exact limit surface (`subd2nurbs limit`, 5 x 5 points per quad) within the
  // tolerance + the mesh's chord error of the capsule.
  const std::vector<gp_Pnt> points =
      limit_points(dir.file("coarse.obj"), kept_cage.input.num_faces(), {0.1, 0.3, 0.5, 0.7, 0.9}, dir);
  ASSERT_EQ(points.size(), 25u * static_cast<std::size_t>(kept_cage.input.num_faces()));
  double worst = 0;
  for (const gp_Pnt& p : points) worst = std::max(worst, k.shape.distance(p));
  EXPECT_LT(worst, 3 * d0 * k.diag + k.chord) << "relative " << worst / k.diag;
  std::printf("  capsule: automatic %d quads at %.3g; fit tolerance %.3g: rounds %g, %g quads, kept %g; its limit within "
              "%.3g of the diagonal of the capsule\n",
              automatic, d0, 3 * d0, quads[0], quads[1], quads[static_cast<std::size_t>(kept)], worst / k.diag);
}

/// A fan-like tip (issue #28, fandisk's worst spot; docs/meshes.md "Limits"): a wedge whose two
/// planar side walls meet at 20 degrees, topped by a sphere, so that at the top of the apex two
/// sharp rims (sphere against wall) meet at an acute angle and the curved top between them is a
/// narrow wedge, one cage quad wide at the tip. Oracle: the exact solid's surfaces, analytic
/// here. At points along every sharp edge of our B-rep (away from the solid's corners), the
/// angle between the two faces' normals must be the exact dihedral there (the angle between the
/// two exact surfaces' outward normals at that point) within 3 degrees. Before the fit held the
/// crease sides' normals (core/fit/shape_fit.h crease_normal_weight), the tip's quad, sheared
/// into the wedge, was off by 8.6 degrees (now 2.75). Only the tip's third of the wedge is checked:
/// its far end is another case (below).
/// The outward normals of an edge's two faces at its curve parameter u (their surfaces' D1 at the
/// pcurves' points); false where either vanishes.
bool normals_across(const TopoDS_Edge& e, const TopTools_ListOfShape& faces, double u, gp_Vec normal[2]) {
  int side = 0;
  for (const TopoDS_Shape& fs : faces) {
    const TopoDS_Face f = TopoDS::Face(fs);
    double a, b;
    const Handle(Geom2d_Curve) pc = BRep_Tool::CurveOnSurface(e, f, a, b);
    const gp_Pnt2d uv = pc->Value(u);
    gp_Pnt q;
    gp_Vec du, dv;
    BRepAdaptor_Surface(f).D1(uv.X(), uv.Y(), q, du, dv);
    normal[side] = du.Crossed(dv);
    if (f.Orientation() == TopAbs_REVERSED) normal[side].Reverse();
    if (++side == 2) break;
  }
  return side == 2 && normal[0].Magnitude() >= 1e-12 && normal[1].Magnitude() >= 1e-12;
}

TEST(MeshPath, AcuteFeatureCornerKeepsItsDihedral) {
  TempDir dir;
  const double deg = M_PI / 180, half = 10 * deg, L = 40, R = 22;
  const gp_Pnt c(20, 0, -5);
  BRepBuilderAPI_MakePolygon tri(gp_Pnt(0, 0, 0), gp_Pnt(L, L * std::tan(half), 0), gp_Pnt(L, -L * std::tan(half), 0), true);
  const TopoDS_Shape prism = BRepPrimAPI_MakePrism(BRepBuilderAPI_MakeFace(tri.Wire()).Face(), gp_Vec(0, 0, 30)).Shape();
  const TopoDS_Shape exact = BRepAlgoAPI_Common(prism, BRepPrimAPI_MakeSphere(c, R).Shape()).Shape();
  ASSERT_TRUE(BRepCheck_Analyzer(exact).IsValid());
  // The exact surfaces: outward normal and distance at a point.
  struct Surface {
    gp_Dir normal_at(const gp_Pnt& p) const { return sphere ? gp_Dir(gp_Vec(centre, p)) : n; }
    double distance(const gp_Pnt& p) const {
      return sphere ? std::abs(p.Distance(centre) - radius) : std::abs(gp_Vec(n).Dot(gp_Vec(origin, p)));
    }
    bool sphere = false;
    gp_Dir n{0, 0, 1};
    gp_Pnt origin, centre;
    double radius = 0;
  };
  std::vector<Surface> surfaces(5);
  surfaces[0].n = gp_Dir(0, 0, -1);                                     // bottom
  surfaces[1].n = gp_Dir(-std::sin(half), std::cos(half), 0);           // wall y > 0
  surfaces[2].n = gp_Dir(-std::sin(half), -std::cos(half), 0);          // wall y < 0
  surfaces[3].n = gp_Dir(1, 0, 0);                                      // far wall
  surfaces[3].origin = gp_Pnt(L, 0, 0);
  surfaces[4].sphere = true;                                            // top
  surfaces[4].centre = c;
  surfaces[4].radius = R;
  std::vector<gp_Pnt> corners;
  for (TopExp_Explorer ex(exact, TopAbs_VERTEX); ex.More(); ex.Next()) corners.push_back(BRep_Tool::Pnt(TopoDS::Vertex(ex.Current())));

  const Triangles mesh = tessellate(exact, 0.02);
  const std::string stl = dir.file("tip.stl");
  write_stl(mesh, stl);
  const Converted c1 = convert(stl, dir, "--target-faces 300");
  ASSERT_EQ(c1.run.exit_code, 0) << c1.run.err;
  const double diag = diagonal(mesh);
  EXPECT_TRUE(BRepCheck_Analyzer(c1.shape).IsValid());
  EXPECT_NEAR(volume(c1.shape), volume(exact), 0.01 * volume(exact));

  TopTools_IndexedDataMapOfShapeListOfShape edge_faces;
  TopExp::MapShapesAndAncestors(c1.shape, TopAbs_EDGE, TopAbs_FACE, edge_faces);
  int samples = 0, near_tip = 0;
  double worst = 0, worst_all = 0;  // within 0.3 L of the tip; anywhere
  gp_Pnt worst_at, worst_all_at;
  for (int i = 1; i <= edge_faces.Extent(); ++i) {
    const TopoDS_Edge e = TopoDS::Edge(edge_faces.FindKey(i));
    const TopTools_ListOfShape& faces = edge_faces.FindFromIndex(i);
    if (faces.Extent() != 2 || BRep_Tool::Degenerated(e)) continue;
    const BRepAdaptor_Curve curve(e);
    for (int k = 1; k < 8; ++k) {
      const double t = curve.FirstParameter() + k / 8.0 * (curve.LastParameter() - curve.FirstParameter());
      const gp_Pnt p = curve.Value(t);
      gp_Vec normal[2];
      if (!normals_across(e, faces, t, normal)) continue;
      const double ours = normal[0].Angle(normal[1]) / deg;
      if (ours < 20) continue;  // a smooth seam between our faces (exact dihedral 0 inside a face)
      // The two exact surfaces through p; skipped near the solid's corners (a third one near).
      bool at_corner = false;
      for (const gp_Pnt& v : corners) at_corner = at_corner || v.Distance(p) < 0.01 * diag;
      std::vector<std::pair<double, int>> d;
      for (int s = 0; s < 5; ++s) d.push_back({surfaces[s].distance(p), s});
      std::sort(d.begin(), d.end());
      if (at_corner || d[2].first < 4 * std::max(d[1].first, 1e-3 * diag)) continue;
      const double dihedral = surfaces[d[0].second].normal_at(p).Angle(surfaces[d[1].second].normal_at(p)) / deg;
      ++samples;
      if (std::abs(ours - dihedral) > worst_all) worst_all = std::abs(ours - dihedral), worst_all_at = p;
      if (p.X() > 0.3 * L) continue;
      ++near_tip;
      if (std::abs(ours - dihedral) > worst) worst = std::abs(ours - dihedral), worst_at = p;
    }
  }
  std::printf("  acute tip: %d sharp-edge samples, %d within 0.3 L of the tip: normal angle within %.3g deg of the exact "
              "dihedral there (worst at %.3g %.3g %.3g), %.3g deg anywhere (at %.3g %.3g %.3g); report: %.3g / %.3g deg "
              "against the mesh, %g B-rep faces\n",
              samples, near_tip, worst, worst_at.X(), worst_at.Y(), worst_at.Z(), worst_all, worst_all_at.X(),
              worst_all_at.Y(), worst_all_at.Z(), json_number(c1.report, {"mesh", "feature_angles", "max_difference_deg"}),
              json_number(c1.report, {"mesh", "feature_angles", "mean_difference_deg"}), json_number(c1.report, {"brep", "faces"}));
  EXPECT_GT(samples, 100);
  EXPECT_GT(near_tip, 30);
  EXPECT_LT(worst, 3.0) << "at " << worst_at.X() << " " << worst_at.Y() << " " << worst_at.Z();
  // Not checked elsewhere (printed): at the far end the sphere comes down to 0.9 .. 4 above the
  // bottom (walls lower than a cage quad), and the far bottom edge and the low walls' rims are
  // off by up to ~15 degrees with or without the crease normals (docs/meshes.md "Limits").
}

/// A block [-1, 1] x [-1, 2] x [0, 1] roofed by a tent along x = 0 whose height fades smoothly
/// (smoothstep) to nothing at y = 1.5: z = 1 + k(y) (1.2 - |x|), k = 0.5 for y <= 0. The ridge is
/// a crease between the normals (-/+k, -1.2 k', 1): 53 degrees at y <= 0, 30 at y = 0.63, fading
/// to 0 at 1.5,
/// the shape of a crease where a CAD part's surfaces become tangent (fandisk has two). Tessellated
/// here (grids of 0.05), written as STL.
Triangles fading_ridge_block() {
  auto k = [](double y) {
    const double t = std::clamp(y / 1.5, 0.0, 1.0);
    return 0.5 * (1 - t * t * (3 - 2 * t));
  };
  auto top = [&](double x, double y) { return 1 + k(y) * (1.2 - std::abs(x)); };
  Triangles t;
  std::map<std::array<double, 3>, int> index;
  auto id = [&](const gp_Pnt& p) {
    const auto [it, added] = index.try_emplace({p.X(), p.Y(), p.Z()}, static_cast<int>(t.points.size()));
    if (added) t.points.push_back(p);
    return it->second;
  };
  const gp_Pnt centre(0, 0.5, 0.5);
  // A grid of f(u, v), u, v in [0, 1], each quad two triangles, turned to face away from the centre.
  auto grid = [&](const std::function<gp_Pnt(double, double)>& f, int nu, int nv) {
    for (int i = 0; i < nu; ++i)
      for (int j = 0; j < nv; ++j) {
        const gp_Pnt a = f(double(i) / nu, double(j) / nv), b = f(double(i + 1) / nu, double(j) / nv);
        const gp_Pnt c = f(double(i + 1) / nu, double(j + 1) / nv), d = f(double(i) / nu, double(j + 1) / nv);
        for (const auto& tri : {std::array<gp_Pnt, 3>{a, b, c}, std::array<gp_Pnt, 3>{a, c, d}}) {
          const gp_Vec n = gp_Vec(tri[0], tri[1]).Crossed(gp_Vec(tri[0], tri[2]));
          const gp_Vec out(centre, tri[0]);
          std::array<int, 3> v{id(tri[0]), id(tri[1]), id(tri[2])};
          if (n.Dot(out) < 0) std::swap(v[1], v[2]);
          t.triangles.push_back(v);
        }
      }
  };
  grid([&](double u, double v) { const double x = 2 * u - 1, y = 3 * v - 1; return gp_Pnt(x, y, top(x, y)); }, 40, 60);
  grid([&](double u, double v) { const double x = 2 * u - 1, y = 3 * v - 1; return gp_Pnt(x, y, 0); }, 40, 60);
  for (const double x : {-1.0, 1.0})
    grid([&](double u, double v) { const double y = 3 * u - 1; return gp_Pnt(x, y, v * top(x, y)); }, 60, 20);
  for (const double y : {-1.0, 2.0})
    grid([&](double u, double v) { const double x = 2 * u - 1; return gp_Pnt(x, y, v * top(x, y)); }, 40, 20);
  return t;
}

/// The fading ridge above through the mesh path: the ridge's chain is continued below the feature
/// angle as long as it fades and ends in a dart (the report's fading end), and the B-rep's normal
/// angle across its crease follows the exact dihedral within 3 degrees all along,
/// down to where the crease fades below 5 degrees. Before fading creases were followed the chain
/// ended at 30 degrees in a corner: the surface held a full crease to there and none beyond.
TEST(MeshPath, FadingCreaseFollowsItsDihedral) {
  TempDir dir;
  const Triangles mesh = fading_ridge_block();
  ASSERT_EQ(euler_characteristic(mesh), 2);
  const std::string stl = dir.file("ridge.stl");
  write_stl(mesh, stl);
  const Converted c = convert(stl, dir);
  ASSERT_EQ(c.run.exit_code, 0) << c.run.err;
  EXPECT_TRUE(BRepCheck_Analyzer(c.shape).IsValid());
  EXPECT_EQ(json_number(c.report, {"mesh", "features", "fading_ends"}), 1);
  EXPECT_GT(json_number(c.report, {"mesh", "features", "faded_edges"}), 5);
  auto k = [](double y) {
    const double t = std::clamp(y / 1.5, 0.0, 1.0);
    return 0.5 * (1 - t * t * (3 - 2 * t));
  };
  const double deg = M_PI / 180;
  TopTools_IndexedDataMapOfShapeListOfShape edge_faces;
  TopExp::MapShapesAndAncestors(c.shape, TopAbs_EDGE, TopAbs_FACE, edge_faces);
  int samples = 0;
  double worst = 0, worst_y = 0, last_y = -1;  // last_y: the farthest sample on the ridge
  for (int i = 1; i <= edge_faces.Extent(); ++i) {
    const TopoDS_Edge e = TopoDS::Edge(edge_faces.FindKey(i));
    const TopTools_ListOfShape& faces = edge_faces.FindFromIndex(i);
    if (faces.Extent() != 2 || BRep_Tool::Degenerated(e)) continue;
    const BRepAdaptor_Curve curve(e);
    for (int s = 1; s < 16; ++s) {
      const double u = curve.FirstParameter() + s / 16.0 * (curve.LastParameter() - curve.FirstParameter());
      gp_Pnt p;
      gp_Vec tangent;
      curve.D1(u, p, tangent);
      // on the ridge and along it (not an edge between faces that crosses it), away from the
      // wall at y = -1 (a corner there)
      if (std::abs(p.X()) > 0.02 || p.Z() < 1.05 || p.Y() < -0.8) continue;
      if (!(std::abs(tangent.Y()) > 0.9 * std::hypot(tangent.X(), tangent.Y()))) continue;  // seen from above
      gp_Vec normal[2];
      if (!normals_across(e, faces, u, normal)) continue;
      // the exact normals either side of the ridge, (-/+k, -1.2 k', 1): the tent also slopes along y
      const double y = p.Y(), t = std::clamp(y / 1.5, 0.0, 1.0);
      const double slope_y = y > 0 && y < 1.5 ? -1.2 * 0.5 * 6 * t * (1 - t) / 1.5 : 0.0;
      const double exact = gp_Vec(-k(y), slope_y, 1).Angle(gp_Vec(k(y), slope_y, 1)) / deg;
      if (exact < 5) continue;
      const double ours = normal[0].Angle(normal[1]) / deg;
      ++samples;
      last_y = std::max(last_y, p.Y());
      if (std::abs(ours - exact) > worst) worst = std::abs(ours - exact), worst_y = p.Y();
    }
  }
  std::printf("  fading ridge: %d samples on the ridge up to y = %.3g (5 deg at y = 1.22), normal angle within %.3g deg "
              "of the exact dihedral (worst at y = %.3g); report: %g feature edges, %g faded, %g fading end(s), "
              "feature angles %.3g deg max against the mesh, %g B-rep faces\n",
              samples, last_y, worst, worst_y, json_number(c.report, {"mesh", "features", "edges"}),
              json_number(c.report, {"mesh", "features", "faded_edges"}),
              json_number(c.report, {"mesh", "features", "fading_ends"}),
              json_number(c.report, {"mesh", "feature_angles", "max_difference_deg"}), json_number(c.report, {"brep", "faces"}));
  EXPECT_GT(samples, 30);
  EXPECT_GT(last_y, 1.0);  // the crease runs on below 30 degrees (y = 0.63), to below 11 (y = 1.0)
  EXPECT_LT(worst, 3.0) << "at y = " << worst_y;
}

/// Fandisk (12 946 triangles) with the defaults, against the input mesh itself: the report's
/// two-sided distance (our surface's samples to the mesh's triangles, the mesh's vertices to our
/// surface) and the normal angle across every kept feature curve against the mesh's dihedral at
/// the nearest feature edge of the mesh. The goals: <= 300 B-rep faces and 1e-3 x the
/// diagonal both ways (met since the size is chosen by the fit tolerance, 1e-3 by default: since
/// its fading creases are followed the automatic size's 670 quads reach 0.97e-3; before, 1.14e-3
/// there and ~1 100 quads in a second round) and 3
/// degrees (not met: 11.7 degrees at the finer size, 4.5 at the automatic one; docs/meshes.md
/// "Limits"), so that bound guards what is reached
/// (before the split's projection fix and the soft features: 82 degrees, a quad folded across the
/// bottom rim; before the crease normals: 7.1 degrees at the automatic size, at the fan's tip
/// where two feature curves meet at 19 degrees, 11.7 at the finer size).
TEST(MeshPath, FandiskFollowsTheMesh) {
  TempDir dir;
  const Converted c = convert(std::string(SUBD2NURBS_TEST_DATA_DIR) + "/mesh/fandisk.off", dir);
  ASSERT_EQ(c.run.exit_code, 0) << c.run.err;
  EXPECT_TRUE(BRepCheck_Analyzer(c.shape).IsValid());
  EXPECT_LE(json_number(c.report, {"brep", "faces"}), 300);
  const double to_mesh = json_number(c.report, {"mesh", "fit", "after", "limit_to_target", "max"});
  const double from_mesh = json_number(c.report, {"mesh", "fit", "after", "target_to_limit", "max"});
  const double angle_max = json_number(c.report, {"mesh", "feature_angles", "max_difference_deg"});
  const double angle_mean = json_number(c.report, {"mesh", "feature_angles", "mean_difference_deg"});
  EXPECT_LE(to_mesh, 1e-3);
  EXPECT_LE(from_mesh, 1e-3);
  EXPECT_NE(c.report.find("\"tolerance_met\": true"), std::string::npos);
  // The conversion met its tolerance (1e-4 of the model size): no warning that it was capped
  // (its estimate asked for 16 levels at the rim's rounded corners, met at 12).
  EXPECT_LE(json_number(c.report, {"deviation", "relative"}), 1e-4);
  EXPECT_EQ(c.run.err.find("extra levels at some fan"), std::string::npos) << c.run.err;
  EXPECT_GT(json_number(c.report, {"mesh", "feature_angles", "samples"}), 500);
  EXPECT_LT(angle_max, 15.0);
  EXPECT_LT(angle_mean, 0.5);
  EXPECT_EQ(c.run.err.find("feature curve folds"), std::string::npos) << c.run.err;
  // Its planes' inner corners are split (docs/remesh.md step 9): the surface neither crosses nor
  // touches itself (47 pairs of faces touching at 6 corners before).
  EXPECT_GE(json_number(c.report, {"mesh", "cage", "concave_sectors"}), 6);
  EXPECT_EQ(json_number(c.report, {"self_intersection", "touching_face_pairs"}), 0);
  EXPECT_EQ(json_number(c.report, {"self_intersection", "crossing_face_pairs"}), 0);
  std::printf("  fandisk: %zu rounds, %d quads, %g B-rep faces, to the mesh %.3g, from the mesh %.3g of the diagonal, "
              "feature angles max %.3g mean %.3g deg off\n",
              round_values(c.report, "quads").size(), c.cage.input.num_faces(), json_number(c.report, {"brep", "faces"}),
              to_mesh, from_mesh, angle_max, angle_mean);
}

/// A folded feature curve warns (docs/meshes.md "Folded creases"): fandisk at 720 target faces,
/// where the extraction leaves two cage vertices 0.005 apart beside a crease (a quad turned
/// over), and the surface's normals across that crease are ~140 degrees off the mesh's dihedral
/// of ~20 there. The warning names the worst point; the report gives it too.
TEST(MeshPath, FoldedCreaseWarns) {
  TempDir dir;
  const Converted c = convert(std::string(SUBD2NURBS_TEST_DATA_DIR) + "/mesh/fandisk.off", dir, "--target-faces 720");
  ASSERT_EQ(c.run.exit_code, 0) << c.run.err;
  const double angle_max = json_number(c.report, {"mesh", "feature_angles", "max_difference_deg"});
  // If a change of the remesher no longer folds at this size, pick a size that does (a sweep
  // of --target-faces shows them): this test is about the warning, not the draw.
  ASSERT_GT(angle_max, 20.0) << "fandisk at 720 no longer folds";
  EXPECT_NE(c.run.err.find("warning: a feature curve folds"), std::string::npos) << c.run.err;
  EXPECT_NE(c.report.find("\"where\": ["), std::string::npos);
  std::printf("  fandisk at 720: feature angle error %.3g deg\n", angle_max);
}

/// Slivers along a chain (docs/remesh.md step 5): fandisk at 1050 target faces had a coarse
/// triangle with a small angle between a feature edge and another edge at a crease vertex; where
/// the chain bends away from its chord the split quad between them turned over and the fit
/// folded the crease, 140 degrees off the mesh's dihedral. Flipped open before the pairing, the
/// crease follows the mesh (the oracle: the mesh's dihedral at its nearest feature edge).
TEST(MeshPath, SliverAlongAChainIsFlippedOpen) {
  TempDir dir;
  const Converted c = convert(std::string(SUBD2NURBS_TEST_DATA_DIR) + "/mesh/fandisk.off", dir, "--target-faces 1050");
  ASSERT_EQ(c.run.exit_code, 0) << c.run.err;
  EXPECT_GE(json_number(c.report, {"mesh", "cage", "sliver_flips"}), 1);
  const double angle_max = json_number(c.report, {"mesh", "feature_angles", "max_difference_deg"});
  EXPECT_LT(angle_max, 10.0);
  EXPECT_EQ(c.run.err.find("feature curve folds"), std::string::npos) << c.run.err;
  std::printf("  fandisk at 1050: feature angle error %.3g deg\n", angle_max);
}

/// `cage`'s exact limit (its `faces` quads) sampled n x n per quad by `subd2nurbs limit` (the
/// points at (i / n, j / n), borders included) and triangulated, two triangles per grid cell.
Triangles limit_grid_mesh(const std::string& cage, int faces, int n, TempDir& dir) {
  std::vector<double> ts;
  for (int i = 0; i <= n; ++i) ts.push_back(double(i) / n);
  Triangles mesh;
  mesh.points = limit_points(cage, faces, ts, dir);
  EXPECT_EQ(mesh.points.size(), size_t(faces) * (n + 1) * (n + 1));
  for (int f = 0; f < faces; ++f)
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const int a = f * (n + 1) * (n + 1) + i * (n + 1) + j, b = a + n + 1;
        mesh.triangles.push_back({a, b, b + 1});
        mesh.triangles.push_back({a, b + 1, a + 1});
      }
  return mesh;
}

/// A scan of a smooth surface is remeshed without folds: bob's exact limit surface (Keenan
/// Crane's cage, tests/data/mesh, 334 quads, genus 1), sampled 10 x 10 per quad by `subd2nurbs
/// limit` and triangulated, is remeshed at 668 quads (twice the cage) and fitted. The oracle: the
/// exact limit of a cage whose limit is smooth and embedded crosses itself nowhere, and the scan
/// lies on it. Before the remesher's collapses kept faces from turning over (docs/remesh.md step
/// 4) coarse triangles faced away from the surface there, and the fitted surface crossed itself
/// (6 pairs of faces) at a knot 2.6e-3 of the diagonal from the scan.
/// And the fitted limit follows bob's: the fit runs until it stops gaining (docs/meshes.md step
/// 4). The oracle: bob's exact limit, sampled 40 x 40 per quad and triangulated (its chords sag
/// 16 x less than the scan's); the fitted limit's points (5 x 5 per quad) are within 4e-4 of the
/// diagonal of it (3.1e-4; with the fit stopped after 10 iterations, as before the sixteenth
/// session, 5.9e-4; the issue asks 1e-4, docs/meshes.md "Measured against bob's true limit").
/// Those points miss one spot: at a valence-7 vertex of this cage the scan is 9.5e-4 from the
/// fitted limit (6.8e-4 after 10 iterations), which `from_scan` (the scan's points, all on bob's
/// limit, to the fitted limit) bounds.
TEST(MeshPath, LimitScanDoesNotFold) {
  TempDir dir;
  const std::string cage = std::string(SUBD2NURBS_TEST_DATA_DIR) + "/mesh/bob_controlmesh.obj";
  const int faces = read_obj(cage).input.num_faces();
  const Triangles scan = limit_grid_mesh(cage, faces, 10, dir);
  ASSERT_FALSE(HasFailure());
  write_stl(scan, dir.file("scan.stl"));
  const Converted c = convert(dir.file("scan.stl"), dir, "--input mesh --target-faces 668 -q");
  ASSERT_EQ(c.run.exit_code, 0) << c.run.err;
  EXPECT_EQ(json_number(c.report, {"self_intersection", "crossing_face_pairs"}), 0) << c.run.err;
  EXPECT_EQ(json_number(c.report, {"self_intersection", "touching_face_pairs"}), 0) << c.run.err;
  const double to_scan = json_number(c.report, {"mesh", "fit", "after", "limit_to_target", "max"});
  const double from_scan = json_number(c.report, {"mesh", "fit", "after", "target_to_limit", "max"});
  EXPECT_LE(to_scan, 1e-3);
  EXPECT_LE(from_scan, 1e-3);
  // The exact limit, triangulated 40 x 40 per quad, and the fitted cage's limit at 5 x 5 points per quad.
  const Triangles fine = limit_grid_mesh(cage, faces, 40, dir);
  ASSERT_FALSE(HasFailure());
  std::vector<Point3> fine_points;
  for (const gp_Pnt& p : fine.points) fine_points.push_back({p.X(), p.Y(), p.Z()});
  const subd2nurbs::ClosestPointTree exact(fine_points, fine.triangles);
  Bnd_Box box;
  for (const gp_Pnt& p : scan.points) box.Add(p);
  const double diagonal = std::sqrt(box.SquareExtent());
  const std::vector<gp_Pnt> fitted =
      limit_points(dir.file("cage.obj"), c.cage.input.num_faces(), {0.1, 0.3, 0.5, 0.7, 0.9}, dir);
  ASSERT_EQ(fitted.size(), 25u * static_cast<std::size_t>(c.cage.input.num_faces()));
  double worst = 0;
  for (const gp_Pnt& p : fitted) worst = std::max(worst, exact.closest({p.X(), p.Y(), p.Z()}).distance2);
  worst = std::sqrt(worst) / diagonal;
  EXPECT_LE(worst, 4e-4);
  std::printf("  bob's limit scan: %d quads, to the scan %.3g, from the scan %.3g, to bob's limit %.3g of the diagonal\n",
              c.cage.input.num_faces(), to_scan, from_scan, worst);
}

/// Ears across walls one quad high (docs/remesh.md step 5, "Ears"): featuretype.STL, a machined
/// part of steps and pockets whose walls are 0.25 and 0.75 high against a cage spacing of ~0.2,
/// has coarse triangles along a rim where it rounds a corner in plan, whose third vertex is on
/// the other rim of the wall. Left as they were, their split quads lay along the rim, folded
/// over onto the top, and the fitted surface crossed itself (7 pairs of faces). The oracle: the
/// part is a solid, so its surface crosses itself nowhere. (The count of crossing pairs is the
/// extraction's draw at this size; if another change of the remesher makes one elsewhere, look
/// at where the report's `self_intersection` puts it before changing this test.)
TEST(MeshPath, MachinedPartDoesNotCrossItself) {
  TempDir dir;
  const Converted c = convert(std::string(SUBD2NURBS_TEST_DATA_DIR) + "/mesh/featuretype.STL", dir, "-q");
  ASSERT_EQ(c.run.exit_code, 0) << c.run.err;
  EXPECT_TRUE(BRepCheck_Analyzer(c.shape).IsValid());
  EXPECT_EQ(json_number(c.report, {"self_intersection", "crossing_face_pairs"}), 0) << c.run.err;
  std::printf("  featuretype: %d quads, %g B-rep faces, %g pairs of faces touching\n", c.cage.input.num_faces(),
              json_number(c.report, {"brep", "faces"}), json_number(c.report, {"self_intersection", "touching_face_pairs"}));
}

/// Caps (docs/remesh.md step 5, "Caps"): plate_holes.STL, a plate with holes, has coarse
/// triangles in its top plane with an angle near 180 degrees (a vertex almost on the opposite
/// edge). Their split quads were degenerate, the fit slid the vertex across the edge in the plane,
/// and 12 faces of the top folded over each other (27 pairs of faces touching). Flipped before the
/// pairing, the plate is a valid solid whose surface crosses itself nowhere (the oracle: the part
/// is a solid) in no more than the 150 B-rep faces. Nor does it touch itself: at a
/// countersunk hole a 170 degree cap had only slivers to flip to (a partner 65 mm across the
/// top), which the smallest-angle rule refused; the largest angle falling takes it (3 pairs of
/// faces touching there before, and the crease folded 84 degrees off the mesh's dihedral). As for
/// the machined part above, the counts are the extraction's draw at this size; look at the
/// report's `self_intersection` before changing this test.
TEST(MeshPath, CapsInAPlaneAreFlipped) {
  TempDir dir;
  const Converted c = convert(std::string(SUBD2NURBS_TEST_DATA_DIR) + "/mesh/plate_holes.STL", dir, "-q");
  ASSERT_EQ(c.run.exit_code, 0) << c.run.err;
  EXPECT_TRUE(BRepCheck_Analyzer(c.shape).IsValid());
  EXPECT_GE(json_number(c.report, {"mesh", "cage", "cap_flips"}), 1);
  EXPECT_EQ(json_number(c.report, {"self_intersection", "crossing_face_pairs"}), 0) << c.run.err;
  EXPECT_EQ(json_number(c.report, {"self_intersection", "touching_face_pairs"}), 0) << c.run.err;
  EXPECT_LE(json_number(c.report, {"brep", "faces"}), 150);
  std::printf("  plate_holes: %d quads, %g extraordinary vertices, %g B-rep faces\n", c.cage.input.num_faces(),
              json_number(c.report, {"mesh", "cage", "extraordinary_vertices"}), json_number(c.report, {"brep", "faces"}));
}

/// A fan of an ear and a chord triangle along a rim (docs/remesh.md step 5, "Ears"): fandisk at
/// 500 target faces had coarse triangles with all their vertices on one rim where it bends over
/// three coarse edges, lying on the wrong side of it; their split quads turned over and the fit
/// folded the crease, 90 degrees off the mesh's dihedral, with faces crossing. Flipped like
/// ears, the crease follows the mesh (the oracle: the mesh's dihedral at its nearest feature
/// edge) and the surface crosses and touches itself nowhere (fandisk is a solid).
TEST(MeshPath, ChordFanAlongARimIsFlippedOpen) {
  TempDir dir;
  const Converted c = convert(std::string(SUBD2NURBS_TEST_DATA_DIR) + "/mesh/fandisk.off", dir, "--target-faces 500");
  ASSERT_EQ(c.run.exit_code, 0) << c.run.err;
  const double angle_max = json_number(c.report, {"mesh", "feature_angles", "max_difference_deg"});
  EXPECT_LT(angle_max, 15.0);
  EXPECT_EQ(c.run.err.find("feature curve folds"), std::string::npos) << c.run.err;
  EXPECT_EQ(json_number(c.report, {"self_intersection", "crossing_face_pairs"}), 0) << c.run.err;
  EXPECT_EQ(json_number(c.report, {"self_intersection", "touching_face_pairs"}), 0) << c.run.err;
  std::printf("  fandisk at 500: feature angle error %.3g deg\n", angle_max);
}

/// A triangulated quad cage (each quad split along a diagonal) takes the cage road: `info` says
/// so, and its conversion equals the OBJ cage's.
TEST(MeshPath, TriangulatedQuadCageStaysACage) {
  TempDir dir;
  const MeshInput ring = torus(12, 8);
  Triangles t;
  for (const auto& p : ring.positions) t.points.emplace_back(p[0], p[1], p[2]);
  const std::string obj = dir.file("ring.obj");
  {
    std::ofstream out(obj);
    out.precision(17);
    for (const auto& p : ring.positions) out << "v " << p[0] << " " << p[1] << " " << p[2] << "\n";
    for (int f = 0; f < ring.num_faces(); ++f) {
      const int* q = ring.face_indices.data() + 4 * f;
      out << "f " << q[0] + 1 << " " << q[1] + 1 << " " << q[2] + 1 << " " << q[3] + 1 << "\n";
      t.triangles.push_back({q[0], q[1], q[2]});
      t.triangles.push_back({q[0], q[2], q[3]});
    }
  }
  const std::string stl = dir.file("ring.stl");
  write_stl(t, stl);
  const CommandResult info = run_command(kExe + " info " + quote(stl));
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.out.find("path         cage: its 192 triangles pair back into quads"), std::string::npos) << info.out;
  const CommandResult a = run_command(kExe + " convert " + quote(stl) + " -o " + quote(dir.file("a.json")) + " -q");
  const CommandResult b = run_command(kExe + " convert " + quote(obj) + " -o " + quote(dir.file("b.json")) + " -q");
  ASSERT_EQ(a.exit_code, 0) << a.err;
  ASSERT_EQ(b.exit_code, 0) << b.err;
  // The same patches up to the last digits of the STL's text coordinates: the same counts.
  const std::string ja = read_text(dir.file("a.json")), jb = read_text(dir.file("b.json"));
  EXPECT_EQ(std::count(ja.begin(), ja.end(), '{'), std::count(jb.begin(), jb.end(), '{'));
  // Declared a mesh, the same file is remeshed.
  const CommandResult as_mesh = run_command(kExe + " info " + quote(stl) + " --input mesh");
  EXPECT_NE(as_mesh.out.find("path         mesh: the input was declared a mesh"), std::string::npos) << as_mesh.out;
}

/// A dense triangle mesh that does not pair back takes the mesh road; `--input cage` overrides.
TEST(MeshPath, DenseTriangleMeshIsAMesh) {
  TempDir dir;
  const Triangles mesh = tessellate(box_with_hole(), 0.05);
  const std::string stl = dir.file("c.stl");
  write_stl(mesh, stl);
  const CommandResult info = run_command(kExe + " info " + quote(stl));
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.out.find("path         mesh: its " + std::to_string(mesh.triangles.size()) + " triangles do not pair back"),
            std::string::npos)
      << info.out;
  const CommandResult as_cage = run_command(kExe + " info " + quote(stl) + " --input cage");
  EXPECT_NE(as_cage.out.find("path         cage: the input was declared a cage"), std::string::npos) << as_cage.out;
  // The mesh settings' rules, before any work, naming the flag; nothing written.
  const std::string out = dir.file("never.step");
  for (const auto& [args, words] : {std::pair<std::string, std::string>{"--target-faces -3", "--target-faces must be >= 0"},
                                    {"--edge-length -1", "--edge-length must be a number >= 0"},
                                    {"--feature-angle 200", "--feature-angle must be between 0 and 180"},
                                    {"--fit-tolerance -1e-3", "--fit-tolerance must be a number from 0"},
                                    {"--fit-tolerance 1", "--fit-tolerance must be a number from 0"},
                                    {"--fit-to " + quote(stl), "--fit-to fits a cage"}}) {
    const CommandResult bad = run_command(kExe + " convert " + quote(stl) + " -o " + quote(out) + " " + args);
    EXPECT_EQ(bad.exit_code, 1) << args << "\n" << bad.err;
    EXPECT_NE(bad.err.find(words), std::string::npos) << args << "\n" << bad.err;
  }
  EXPECT_FALSE(std::ifstream(out).good());
}

}  // namespace
