// PatchSet -> OCCT B-rep, built topology-first: one vertex per PatchSet corner, one edge per
// BoundaryCurve, one face per patch. Shared edges are made once and used by both faces, so no
// sewing is needed (sewing 10k faces takes ~5 s, building them shared ~0.1 s).
#pragma once

#include <TopoDS_Shape.hxx>

#include <functional>
#include <string>
#include <vector>

#include "converter/occt/export_error.h"
#include "core/nurbs/patch_set.h"

namespace subd2nurbs::occt {

struct BrepResult {
  /// A TopoDS_Solid or TopoDS_Shell for a connected cage; for several connected components a
  /// TopoDS_Compound of one solid (closed component, oriented outward) or shell (open) each.
  TopoDS_Shape shape;
  bool is_solid = false;   ///< every component is closed and became a solid
  int num_solids = 0, num_shells = 0;  ///< per component: a solid counts as one of each
  int num_faces = 0, num_edges = 0, num_vertices = 0;  ///< distinct sub-shapes of `shape`
  bool valid = false;      ///< BRepCheck_Analyzer found no defect
  std::string check_message;  ///< BRepCheck's findings, one per line (empty when valid)
  /// The edge made for each PatchSet::curves entry (null for an unused curve), so that a caller
  /// can measure chosen edges, e.g. only the smooth ones, with summarize(shape, edges).
  std::vector<TopoDS_Shape> curve_edges;
  double tolerance = 0;    ///< vertex / edge / face tolerance used (model units)
  int planar_faces = 0;    ///< planar faces made of coplanar patches (BrepOptions::merge_planar)
  int merged_patches = 0;  ///< patches inside those planar faces
  int folded_planar_patches = 0;  ///< of those, patches folded over themselves in the plane (the face is the region its loops enclose)
  int rejected_planar_faces = 0;  ///< coplanar sets whose planar face BRepCheck rejected (a boundary
                                  ///< crossing itself): written one face per patch instead
  int split_planar_sets = 0;  ///< coplanar sets whose loops crossed in the plane (patches overlapping: a
                              ///< fold): the patches along the crossings left out, the rest merged
};

struct BrepOptions {
  /// Each connected set of coplanar patches, a single planar patch too (poles on one plane to
  /// rounding: find_planar_faces with tolerances::kSameSurface), becomes one face on a
  /// Geom_Plane, bounded by the set's outer curves (core/patch/planar_faces.h); false: one face
  /// per patch. The pipeline turns it on for packed faces (setting planar_faces).
  bool merge_planar = false;
  /// A face that closes onto itself along a seam (a packed cylinder's side, a torus, a polar
  /// cap) gets a periodic surface in that direction (the same surface and parameter range),
  /// as OCCT's own closed faces have; OCCT's shell and offset algorithms need it
  /// (docs/downstream.md). false: the clamped B-spline as the PatchSet gives it.
  bool periodic_closed_faces = true;
};

/// Builds the faces of `ps` with shared edges and vertices (coplanar patches merged into planar
/// faces, see BrepOptions), then a shell, and a solid when
/// ps.closed. Checks the result with BRepCheck_Analyzer (see BrepResult::valid).
///
/// Geometry: each patch becomes a Geom_BSplineSurface (rational when weights are given;
/// periodic in a direction the face closes in, see BrepOptions::periodic_closed_faces), each
/// BoundaryCurve a Geom_BSplineCurve (its poles; its knots mapped linearly onto the edge's
/// range), and each use of a curve a pcurve on the patch's parameter-domain side. Edges are
/// made as OCCT makes its own (BRepBuilderAPI_MakeFace, BRepPrimAPI_MakeTorus): the edge's
/// range is the face parameter's range along the iso-line it runs on, so its pcurve is a
/// unit-speed Geom2d_Line in the surface's own parameters (a degree-1 B-spline only where the
/// two faces of an edge give it different parameter lengths: a polar cap, whose side of
/// parameter length 1 meets a ring of quads of length 1 each); OCCT's offset, shell and
/// boolean algorithms rely on it (docs/downstream.md).
/// A curve used twice by one patch is a seam; a side whose curve index is -1 and whose two
/// corners are the same corner is a degenerate (collapsed) side, e.g. at a polar point.
///
/// \param progress  called with the fraction of patches done (0..1], about every 1 %.
/// \throw ExportError naming the stage and the patch when the PatchSet is inconsistent or an
///        OCCT call fails. A result that OCCT builds but BRepCheck rejects is not an error:
///        it comes back with valid == false.
BrepResult build_brep(const PatchSet& ps, const std::function<void(double)>& progress = {},
                      const BrepOptions& options = {});

/// The tolerance build_brep gives vertices, edges and faces for a model of this size:
/// 1e-9 * model_size, but never below OCCT's Precision::Confusion() (1e-7).
double brep_tolerance(double model_size);

}  // namespace subd2nurbs::occt
