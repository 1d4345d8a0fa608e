#include "converter/occt/shape_check.h"

#include <BRepGProp.hxx>
#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <BRep_Tool.hxx>
#include <GProp_GProps.hxx>
#include <Geom2d_Curve.hxx>
#include <Geom_Curve.hxx>
#include <Geom_Surface.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESControl_Reader.hxx>
#include <STEPControl_Reader.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>

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

/// Relative error bound for area and volume integration.
constexpr double kIntegrationEps = 1e-12;

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

    // The adaptive integrators, with a relative error bound: the fixed-order ones use the
    // same number of Gauss points per face whatever its number of knot spans, so a face of
    // many spans comes out visibly wrong (5e-5 relative for the 1-face B-spline torus).
    if (mass_properties) {
    GProp_GProps area;
    BRepGProp::SurfaceProperties(shape, area, kIntegrationEps);
    s.area = area.Mass();
    }
    if (mass_properties && s.solids > 0) {
      GProp_GProps volume;
      BRepGProp::VolumeProperties(shape, volume, kIntegrationEps);
      s.volume = volume.Mass();
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
