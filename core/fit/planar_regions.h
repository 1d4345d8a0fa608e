// Planar regions of a triangle mesh, and a cage's limit surface made exactly planar there
// (issue #28: CAD meshes' planar faces stay flat; docs/fitting.md "Planar regions").
//
// * detect_planar_regions: maximal edge-connected sets of triangles whose vertices all lie
//   within `flatness` x the mesh's diagonal of one plane (grown from the largest triangles,
//   the plane refitted by least squares over the region's vertices and the region grown again).
//   Regions below `min_area` x the mesh's area, or narrower than `min_width` (2 area / perimeter,
//   model units; 0 by default and on the mesh path: a narrow strip holds a face only between two
//   infinitely sharp creases, see flatten_planar_regions) are dropped.
// * flatten_planar_regions: after a fit, every cage face whose four cage vertices (`on_mesh`:
//   positions on the mesh, e.g. the remesher's) lie on one region's plane and whose centroid's
//   closest triangle is in that region is that region's face, when all the vertices of its
//   support lie on the plane too. Its limit surface depends only on its support: the faces
//   around each of its vertices, within the vertex's sector bounded by infinitely sharp edges
//   (a crease vertex's faces on the face's side; a smooth vertex's or a dart's all). A face whose
//   support reaches off the plane (across a wall thinner than the cage's faces, onto a fillet
//   tangent to the plane) is left as fitted. Each vertex of the support of a region's face is moved onto that region's
//   plane, a vertex in the supports of two or three regions onto their intersection line or
//   point (the closest point of it to the fitted position). Catmull-Clark limit points are
//   affine combinations of the support, so that face's limit lies exactly in the plane (to
//   rounding). Vertices whose planes do not meet (parallel planes: a wall thinner than the
//   cage's faces; or a point farther than `max_move` from its position on the mesh) drop the faces
//   that asked for them, until every remaining constraint is met.
#pragma once

#include <array>
#include <vector>

#include "core/fit/shape_fit.h"
#include "core/refine/refiner.h"
#include "core/util/point3.h"

namespace subd2nurbs {

struct PlanarRegionOptions {
  double flatness = 1e-6;   ///< vertices within this x diagonal of the region's plane
  double min_area = 1e-3;   ///< dropped below this fraction of the mesh's area
  double min_width = 0;     ///< dropped when 2 area / perimeter is below this (model units)
};

struct PlanarRegion {
  Point3 point{};            ///< a point of the plane (the region's vertices' mean)
  Point3 normal{};           ///< unit normal (oriented as the region's triangles)
  double area = 0;
  double width = 0;          ///< 2 area / perimeter
  double deviation = 0;      ///< largest vertex distance to the plane, relative to the diagonal
  std::vector<int> triangles;
};

/// The mesh's planar regions, largest first. Deterministic (ties by triangle index).
std::vector<PlanarRegion> detect_planar_regions(const std::vector<Point3>& points,
                                                const std::vector<std::array<int, 3>>& triangles,
                                                const PlanarRegionOptions& options = {});

/// The cage vertices whose positions decide the limit surface of face f (see the file comment),
/// sorted.
std::vector<int> limit_support(const SubdivLevel& cage, int f);

struct FlattenOptions {
  double on_plane = 1e-5;   ///< a cage vertex (on_mesh position) is on a region's plane within this x diagonal
  double max_move = 1e-3;   ///< a vertex's planes must meet within this x diagonal of its position on the mesh
  int samples = 5;          ///< limit samples per face side for the flatness measure (n x n)
};

struct FlattenStats {
  int regions = 0;             ///< planar regions of the mesh
  int regions_used = 0;        ///< regions with at least one flattened cage face
  int faces = 0;               ///< cage faces flattened (their limit in a region's plane)
  int faces_off_plane = 0;     ///< faces on a region's plane whose support is not (left as fitted)
  int faces_dropped = 0;       ///< faces of a region given up (planes that do not meet)
  int vertices_moved = 0;
  /// Vertices held by one region whose position moves only that region's faces, within its plane
  /// (smooth, in the limit support of that region's faces alone), and those of them laid out
  /// again (the regions where faces were not convex in the plane: see flatten_planar_regions).
  int vertices_free = 0, vertices_untangled = 0;
  /// The regions' faces with a free vertex that are not strictly convex in the plane (inverted,
  /// folded or concave quads, whose limit can fold): after the fit, and after the untangling.
  int faces_folded_before = 0, faces_folded_after = 0;
  double max_move = 0;         ///< largest move, relative to the diagonal
  /// Largest distance of the flattened faces' limit samples to their planes, relative to the
  /// diagonal, before (the fit's) and after the vertices were moved.
  double flatness_before = 0, flatness_after = 0;
  std::vector<int> face_region;  ///< per cage face: the region it was flattened to, or -1
};

/// Which cage faces are flattened, and onto which planes each cage vertex goes (the regions'
/// indices, sorted), decided on the cage's positions on the mesh (`on_mesh`) before a fit.
struct PlanarConstraints {
  std::vector<int> face_region;                  ///< per cage face: its region, or -1
  std::vector<std::vector<int>> vertex_regions;  ///< per cage vertex: the regions whose planes hold it
  int faces_off_plane = 0, faces_dropped = 0;    ///< as FlattenStats'
};

/// `on_mesh`: the cage's positions on the mesh; `regions` from detect_planar_regions on
/// `points` / `triangles`; `diagonal` the mesh's.
PlanarConstraints planar_constraints(const SubdivLevel& cage, const std::vector<Point3>& on_mesh,
                                     const std::vector<Point3>& points, const std::vector<std::array<int, 3>>& triangles,
                                     const std::vector<PlanarRegion>& regions, double diagonal,
                                     const FlattenOptions& options = {});

/// The constraints as the fit's held vertices (ShapeFitOptions::vertex_planes): one per vertex and plane.
std::vector<ShapeFitOptions::VertexPlane> vertex_planes(const PlanarConstraints& constraints,
                                                        const std::vector<PlanarRegion>& regions);

/// Moves `positions` (the fitted cage) onto the constraints' planes, so that the faces of planar
/// regions are exactly planar; measures their flatness before and after.
FlattenStats flatten_planar_regions(const SubdivLevel& cage, const PlanarConstraints& constraints,
                                    std::vector<Point3>& positions, const std::vector<PlanarRegion>& regions,
                                    double diagonal, const FlattenOptions& options = {});

/// planar_constraints, then flatten_planar_regions.
FlattenStats flatten_planar_regions(const SubdivLevel& cage, const std::vector<Point3>& on_mesh,
                                    std::vector<Point3>& positions, const std::vector<Point3>& points,
                                    const std::vector<std::array<int, 3>>& triangles,
                                    const std::vector<PlanarRegion>& regions, double diagonal,
                                    const FlattenOptions& options = {});

}  // namespace subd2nurbs
