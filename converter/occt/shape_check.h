// Reading a B-rep file back and measuring a shape: counts, validity, area / volume, and how
// well the faces meet along their shared edges. Used by the tests and by `subd2nurbs --report`.
#pragma once

#include <TopoDS_Shape.hxx>

#include <string>
#include <vector>

namespace subd2nurbs::occt {

/// Reads a STEP, IGES or BREP file (format by extension, see format_from_path) into one shape
/// (a compound when the file holds several roots).
/// \throw InputError (io/input_error.h) naming the file when it cannot be read or holds no
///        shape; std::invalid_argument for an unknown extension.
TopoDS_Shape read_shape(const std::string& path);

struct ShapeSummary {
  int solids = 0, shells = 0, faces = 0, edges = 0;  ///< distinct sub-shapes
  int free_edges = 0;  ///< non-degenerate edges bounding only one face (open boundary)
  bool valid = false;  ///< BRepCheck_Analyzer found no defect
  std::string check_message;  ///< BRepCheck's findings, one per line (empty when valid)
  /// Total face area and solid volume (0 without solids). A face that is its B-spline
  /// surface's whole parameter rectangle (ours are) is integrated by Gauss rules on each knot
  /// span: the volume exactly for a polynomial surface, the area to about 1e-9 relative (1.2e-7
  /// on a valence-256 fan); any other face by OCCT's adaptive integrators (relative
  /// bound 1e-12), which take minutes on faces of thousands of spans.
  double area = 0;
  double volume = 0;
  int span_faces = 0;  ///< face occurrences integrated by the span rules
  /// Largest distance, over the sampled shared edges and parameters, between the two faces'
  /// points (surface at the edge's pcurve) and the edge's 3D curve.
  double max_gap = 0;
  /// Largest angle between the two faces' normals (oriented by the faces' orientation, so
  /// outward for a consistently oriented shell) at the sampled points: 0 across smooth
  /// edges, the dihedral turn across a crease (90 on a box).
  double max_normal_angle_deg = 0;
  int shared_edges_sampled = 0;  ///< edges measured for max_gap / max_normal_angle_deg
};

/// Summarizes `shape`, measuring every edge that bounds exactly two faces (or one face twice,
/// as a seam) at `samples_per_edge` (>= 2) parameters including the ends.
/// `mass_properties` = false skips the area and volume integration (left 0), which is most
/// of the cost on many-span faces.
ShapeSummary summarize(const TopoDS_Shape& shape, int samples_per_edge = 16, bool mass_properties = true);

/// The same, but measures only the given edges of `shape` (e.g. BrepResult::curve_edges of
/// the smooth curves); counts, validity, area and volume are still of the whole shape.
/// Null entries and edges not shared by two faces are skipped.
ShapeSummary summarize(const TopoDS_Shape& shape, const std::vector<TopoDS_Shape>& edges,
                       int samples_per_edge = 16, bool mass_properties = true);

}  // namespace subd2nurbs::occt
