#include "converter/occt/shape_check.h"

#include <BRepGProp.hxx>
#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <GProp_GProps.hxx>
#include <Geom2d_Curve.hxx>
#include <Geom_Curve.hxx>
#include <Geom_BSplineSurface.hxx>
#include <Geom_Plane.hxx>
#include <Geom_Surface.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESControl_Reader.hxx>
#include <STEPControl_Reader.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <vector>

#include "converter/occt/occt_util.h"
#include "converter/occt/writers.h"
#include "core/util/constants.h"
#include "io/input_error.h"

namespace subd2nurbs::occt {

TopoDS_Shape read_shape(const std::string& path) {
  const Format format = format_from_path(path);
  // OCCT's readers say little more than "failed" for a missing file; say why.
  if (::access(path.c_str(), R_OK) != 0)
    throw InputError(path, 0, std::string("cannot open: ") + std::strerror(errno));

  TopoDS_Shape shape;
  {
    std::lock_guard<std::mutex> lock(detail::exchange_mutex());
    detail::QuietMessages quiet;
    try {
      switch (format) {
        case Format::Step: {
          STEPControl_Reader reader;
          if (reader.ReadFile(path.c_str()) != IFSelect_RetDone)
            throw InputError(path, 0, "not a readable STEP file");
          reader.TransferRoots();
          shape = reader.OneShape();  // the single root, or a compound of all roots
          break;
        }
        case Format::Iges: {
          IGESControl_Reader reader;
          if (reader.ReadFile(path.c_str()) != IFSelect_RetDone)
            throw InputError(path, 0, "not a readable IGES file");
          reader.TransferRoots();
          shape = reader.OneShape();
          break;
        }
        case Format::Brep: {
          // BRepTools::Read prints "File was not written with this version of the topology"
          // on std::cout (not through the messenger) for a foreign file: look first.
          std::ifstream in(path, std::ios::binary);
          std::string head(256, '\0');
          in.read(&head[0], static_cast<std::streamsize>(head.size()));
          head.resize(static_cast<size_t>(in.gcount()));
          if (head.find("CASCADE Topology V") == std::string::npos)
            throw InputError(path, 0, "not a BREP file (no 'CASCADE Topology' header)");
          BRep_Builder builder;
          if (!BRepTools::Read(shape, path.c_str(), builder))
            throw InputError(path, 0, "not a readable BREP file");
          break;
        }
      }
    } catch (const Standard_Failure& failure) {
      throw InputError(path, 0, "OCCT failed reading it: " + detail::occt_message(failure));
    }
  }
  if (shape.IsNull()) throw InputError(path, 0, "the file holds no shape");
  return shape;
}

namespace {

/// Relative error bound of OCCT's adaptive area and volume integration (faces that
/// `span_properties` does not take).
constexpr double kIntegrationEps = 1e-12;

/// Gauss-Legendre nodes and weights on [0, 1], n points (Newton on P_n from the usual cosine
/// guesses; P_n and P_n-1 by the three-term recurrence).
void gauss_legendre(int n, std::vector<double>& x, std::vector<double>& w) {
  x.assign(static_cast<std::size_t>(n), 0);
  w.assign(static_cast<std::size_t>(n), 0);
  for (int i = 0; i < n; ++i) {
    double t = std::cos(kPi * (i + 0.75) / (n + 0.5)), dp = 1;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1, p1 = t;  // P_0, P_1, ... up to P_n-1, P_n
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2 * k - 1) * t * p1 - (k - 1) * p0) / k;
        p0 = p1, p1 = p2;
      }
      dp = n * (t * p1 - p0) / (t * t - 1);
      const double step = p1 / dp;
      t -= step;
      if (std::abs(step) < 1e-16) break;
    }
    x[static_cast<std::size_t>(i)] = 0.5 * (1 - t);
    w[static_cast<std::size_t>(i)] = 1.0 / ((1 - t * t) * dp * dp);  // 2 / ((1 - t^2) P_n'^2), halved
  }
}

/// Adds the area and the signed volume contribution (1/3 of the integral of x . n dA, n the
/// face's outward normal) of a face that is its B-spline surface's whole parameter rectangle,
/// by Gauss-Legendre rules on every knot span (see the rule's comment below). Returns false,
/// adding nothing, for any other face: not a B-spline surface, more than one wire, or an edge
/// whose pcurve leaves the rectangle's border (a trimmed face).
bool span_properties(const TopoDS_Face& face, double& area, double& volume) {
  const Handle(Geom_BSplineSurface) surface = Handle(Geom_BSplineSurface)::DownCast(BRep_Tool::Surface(face));
  if (surface.IsNull()) return false;
  double u0 = 0, u1 = 0, v0 = 0, v1 = 0;
  surface->Bounds(u0, u1, v0, v1);
  const double tu = 1e-9 * (u1 - u0), tv = 1e-9 * (v1 - v0);
  int wires = 0;
  for (TopExp_Explorer w(face, TopAbs_WIRE); w.More(); w.Next()) ++wires;
  if (wires != 1) return false;
  for (TopExp_Explorer it(face, TopAbs_EDGE); it.More(); it.Next()) {
    double first = 0, last = 0;
    const Handle(Geom2d_Curve) pcurve = BRep_Tool::CurveOnSurface(TopoDS::Edge(it.Current()), face, first, last);
    if (pcurve.IsNull()) return false;
    for (const double f : {0.0, 0.25, 0.5, 0.75, 1.0}) {
      const gp_Pnt2d uv = pcurve->Value(first + f * (last - first));
      const bool on_u = std::abs(uv.X() - u0) <= tu || std::abs(uv.X() - u1) <= tu;
      const bool on_v = std::abs(uv.Y() - v0) <= tv || std::abs(uv.Y() - v1) <= tv;
      if (!on_u && !on_v) return false;
    }
  }
  // The rule: ceil(3p / 2) points per direction integrate the volume integrand of a polynomial
  // surface of degree p exactly; 3 more (8 more for a rational surface, whose spans are often
  // a quarter circle wide) for the area, whose integrand |Su x Sv| is not a polynomial. Measured:
  // 7 s against OCCT's 230 s on a valence-256 fan of 1536 faces; the area within 1e-9 of the
  // closed forms of OCCT's sphere and torus made B-splines (test Summarize.*), 1.2e-7 of
  // OCCT's adaptive value on the valence-256 fan, whose innermost spans' area element is a fractional power of the distance
  // to the centre.
  const bool rational = surface->IsURational() || surface->IsVRational();
  const int nu = (3 * surface->UDegree() + 1) / 2 + (rational ? 8 : 3);
  const int nv = (3 * surface->VDegree() + 1) / 2 + (rational ? 8 : 3);
  std::vector<double> xu, wu, xv, wv;
  gauss_legendre(nu, xu, wu);
  gauss_legendre(nv, xv, wv);
  double a = 0, vol = 0;
  const TColStd_Array1OfReal& uk = surface->UKnots();
  const TColStd_Array1OfReal& vk = surface->VKnots();
  for (int i = uk.Lower(); i < uk.Upper(); ++i)
    for (int j = vk.Lower(); j < vk.Upper(); ++j) {
      const double ua = uk(i), du = uk(i + 1) - uk(i), va = vk(j), dv = vk(j + 1) - vk(j);
      if (!(du > 0 && dv > 0)) continue;
      for (int p = 0; p < nu; ++p)
        for (int q = 0; q < nv; ++q) {
          gp_Pnt x;
          gp_Vec su, sv;
          surface->D1(ua + xu[static_cast<std::size_t>(p)] * du, va + xv[static_cast<std::size_t>(q)] * dv, x, su, sv);
          const gp_Vec n = su.Crossed(sv);
          const double weight = wu[static_cast<std::size_t>(p)] * wv[static_cast<std::size_t>(q)] * du * dv;
          a += weight * n.Magnitude();
          vol += weight * (x.X() * n.X() + x.Y() * n.Y() + x.Z() * n.Z()) / 3;
        }
    }
  area += a;
  volume += face.Orientation() == TopAbs_REVERSED ? -vol : vol;
  return true;
}

/// One occurrence of an edge in a face's wires, with orientations composed from the top
/// shape down (so a face of a reversed shell is REVERSED here, and its normal is flipped).
struct EdgeUse {
  int face;  ///< index into the face map
  TopoDS_Edge edge;
};

/// Point and orientation-corrected normal of `face` at parameter t of `edge`'s pcurve on it.
struct SidePoint {
  gp_Pnt point;
  gp_Vec normal;  ///< zero where the surface is singular (e.g. a collapsed side)
};

class FaceSide {
 public:
  FaceSide(const TopoDS_Face& face, const TopoDS_Edge& edge) {
    // CurveOnSurface takes the edge as it occurs in the face; for a seam the orientation
    // selects which of the two pcurves is meant (it undoes the face's own orientation).
    pcurve_ = BRep_Tool::CurveOnSurface(edge, face, first_, last_);
    surface_ = BRep_Tool::Surface(face);  // with the face's location applied
    reversed_ = face.Orientation() == TopAbs_REVERSED;
  }
  bool ok() const { return !pcurve_.IsNull() && !surface_.IsNull(); }

  /// Evaluates at the fraction `f` in [0, 1] of the pcurve's range.
  SidePoint at(double f) const {
    const gp_Pnt2d uv = pcurve_->Value(first_ + f * (last_ - first_));
    SidePoint out;
    gp_Vec du, dv;
    surface_->D1(uv.X(), uv.Y(), out.point, du, dv);
    out.normal = du.Crossed(dv);
    const double scale = du.Magnitude() * dv.Magnitude();
    if (!(scale > 0) || out.normal.Magnitude() <= 1e-12 * scale) out.normal = gp_Vec();
    if (reversed_) out.normal.Reverse();
    return out;
  }

 private:
  Handle(Geom2d_Curve) pcurve_;
  Handle(Geom_Surface) surface_;
  double first_ = 0, last_ = 0;
  bool reversed_ = false;
};

/// Angle between two non-zero vectors in degrees; atan2 stays accurate for tiny angles where
/// acos of a dot product floors at about 1e-6 degrees.
double angle_deg(const gp_Vec& a, const gp_Vec& b) {
  const gp_Vec na = a.Normalized(), nb = b.Normalized();
  return std::atan2(na.Crossed(nb).Magnitude(), na.Dot(nb)) * 180.0 / kPi;
}

ShapeSummary summarize_impl(const TopoDS_Shape& shape, const std::vector<TopoDS_Shape>* only,
                            int samples, bool mass_properties) {
  samples = std::max(samples, 2);
  ShapeSummary s;
  if (shape.IsNull()) return s;
  detail::guarded("summary", -1, [&] {
    TopTools_IndexedMapOfShape map;
    TopExp::MapShapes(shape, TopAbs_SOLID, map);
    s.solids = map.Extent();
    map.Clear();
    TopExp::MapShapes(shape, TopAbs_SHELL, map);
    s.shells = map.Extent();

    // MapShapes keeps the first occurrence of each face with its composed orientation.
    TopTools_IndexedMapOfShape faces, edges;
    TopExp::MapShapes(shape, TopAbs_FACE, faces);
    TopExp::MapShapes(shape, TopAbs_EDGE, edges);
    s.faces = faces.Extent();
    s.edges = edges.Extent();

    std::vector<std::vector<EdgeUse>> uses(static_cast<size_t>(edges.Extent()) + 1);
    for (int f = 1; f <= faces.Extent(); ++f)
      for (TopExp_Explorer it(faces(f), TopAbs_EDGE); it.More(); it.Next())
        uses[edges.FindIndex(it.Current())].push_back({f, TopoDS::Edge(it.Current())});

    std::vector<bool> wanted(uses.size(), only == nullptr);
    if (only != nullptr)
      for (const TopoDS_Shape& e : *only)
        if (!e.IsNull()) {
          const int index = edges.FindIndex(e);
          if (index > 0) wanted[index] = true;
        }

    for (int e = 1; e <= edges.Extent(); ++e) {
      const TopoDS_Edge& edge = TopoDS::Edge(edges(e));
      if (BRep_Tool::Degenerated(edge)) continue;
      if (uses[e].size() == 1) ++s.free_edges;
      if (uses[e].size() != 2 || !wanted[e]) continue;

      const FaceSide a(TopoDS::Face(faces(uses[e][0].face)), uses[e][0].edge);
      const FaceSide b(TopoDS::Face(faces(uses[e][1].face)), uses[e][1].edge);
      if (!a.ok() || !b.ok()) continue;
      double first = 0, last = 0;
      const Handle(Geom_Curve) curve = BRep_Tool::Curve(edge, first, last);
      // Samples go by the same fraction of each representation's range: for SameParameter
      // edges (ours) that is the same parameter everywhere.
      for (int k = 0; k < samples; ++k) {
        const double f = static_cast<double>(k) / (samples - 1);
        const SidePoint pa = a.at(f), pb = b.at(f);
        double gap = pa.point.Distance(pb.point);
        if (!curve.IsNull()) {
          const gp_Pnt pc = curve->Value(first + f * (last - first));
          gap = std::max({gap, pa.point.Distance(pc), pb.point.Distance(pc)});
        }
        s.max_gap = std::max(s.max_gap, gap);
        if (pa.normal.Magnitude() > 0 && pb.normal.Magnitude() > 0)
          s.max_normal_angle_deg = std::max(s.max_normal_angle_deg, angle_deg(pa.normal, pb.normal));
      }
      ++s.shared_edges_sampled;
    }

    // Area and volume: Gauss rules per knot span on the faces that are whole B-spline
    // surfaces (span_properties); planar faces in closed form from their area; the others by
    // OCCT's adaptive integrators, with a relative error bound (its fixed-order ones use the
    // same number of Gauss points per face whatever its number of knot spans: 5e-5 relative
    // error on the 1-face B-spline torus). Every occurrence of a face counts, as in BRepGProp.
    // The volume of a single face is only defined against a reference point: ours is the
    // origin, while BRepGProp takes the shape's rough barycentre. So BRepGProp's volume is used
    // only when it covers the whole shape (or no part of the shape is measured by our rules).
    if (mass_properties) {
      double area = 0, volume = 0;
      TopoDS_Compound rest;
      BRep_Builder builder;
      builder.MakeCompound(rest);
      bool any_rest = false, curved_rest = false;
      for (TopExp_Explorer it(shape, TopAbs_FACE); it.More(); it.Next()) {
        const TopoDS_Face& face = TopoDS::Face(it.Current());
        if (span_properties(face, area, volume)) {
          ++s.span_faces;
          continue;
        }
        builder.Add(rest, face);
        any_rest = true;
        const Handle(Geom_Plane) plane = Handle(Geom_Plane)::DownCast(BRep_Tool::Surface(face));
        if (plane.IsNull() || !face.Location().IsIdentity()) {
          curved_rest = true;
          continue;
        }
        // On a plane X . n is constant: the face's volume (1/3) int X . n dA is (1/3) (o . n) A.
        GProp_GProps a;
        BRepGProp::SurfaceProperties(face, a, kIntegrationEps);
        const gp_Ax3 axes = plane->Position();
        const double side = axes.Direct() == (face.Orientation() != TopAbs_REVERSED) ? 1.0 : -1.0;
        volume += side * axes.Location().XYZ().Dot(axes.Direction().XYZ()) * a.Mass() / 3;
      }
      if (any_rest) {
        GProp_GProps a;
        BRepGProp::SurfaceProperties(rest, a, kIntegrationEps);
        area += a.Mass();
        if (s.solids > 0 && curved_rest) {
          GProp_GProps v;
          BRepGProp::VolumeProperties(s.span_faces > 0 ? shape : TopoDS_Shape(rest), v, kIntegrationEps);
          volume = v.Mass();
        }
      }
      s.area = area;
      if (s.solids > 0) s.volume = volume;
    }
    s.valid = detail::check_shape(shape, s.check_message);
  });
  return s;
}

}  // namespace

ShapeSummary summarize(const TopoDS_Shape& shape, int samples_per_edge, bool mass_properties) {
  return summarize_impl(shape, nullptr, samples_per_edge, mass_properties);
}

ShapeSummary summarize(const TopoDS_Shape& shape, const std::vector<TopoDS_Shape>& edges,
                       int samples_per_edge, bool mass_properties) {
  return summarize_impl(shape, &edges, samples_per_edge, mass_properties);
}

}  // namespace subd2nurbs::occt
