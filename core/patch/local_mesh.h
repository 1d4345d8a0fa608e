// Local refinement: a small piece of a subdivision level, refined on its own.
//
// The patch builder never refines the whole cage past its coarse level. Each place that needs
// deeper levels (a coarse quad next to a semi-sharp crease, the fan of an irregular vertex)
// cuts out the faces around it, refines that piece one level, and cuts out again around the
// children it still needs (docs/patches.md, "Adaptive construction"). Memory and time then
// grow with the number of pieces actually needed, not with 4^level x faces.
//
// Why a cut-out gives the right points: a child vertex is a weighted sum over one parent
// face (face point), the two faces of an edge (edge point) or the faces around a vertex
// (vertex point), and its rule depends on the sharpness of the edges at that vertex (and, for
// Chaikin creases, of the edges at the far end of the edge). So every child point whose faces
// and vertex stars lie inside the piece is exact. A piece holding the 2-ring of faces around
// what it needs (faces touching vertices of the 1-ring) has that margin; the points near its
// cut are wrong and are never used. Edges on the cut are tagged infinitely sharp (the level's
// invariant for boundary edges); vertices whose faces inside the piece form several fans are
// split into one vertex per fan so that the piece is a valid manifold mesh.
#pragma once

#include <vector>

#include "core/refine/refiner.h"

namespace subd2nurbs {

struct LocalMesh {
  SubdivLevel level;
  std::vector<Point3> x;           ///< control points of `level`
  std::vector<int> origin_face;    ///< per face: the coarse face it lies in
  std::vector<int> origin_vertex;  ///< per vertex: the coarse vertex it is the vertex-child of, or -1
  std::vector<int> source_corner;  ///< per corner: the corner of the mesh it was cut from
};

/// The faces (ascending) touching a vertex within `rings` - 1 edges of the seed vertices:
/// rings = 1 gives the faces around the seeds, 2 adds every face touching those faces.
std::vector<int> face_rings(const PolyMesh& m, const std::vector<int>& seed_vertices, int rings);

/// The vertices of the given faces (ascending, unique).
std::vector<int> vertices_of(const PolyMesh& m, const std::vector<int>& faces);

/// Cuts `faces` out of (level, x). Face order is kept and each face keeps its corner order,
/// so corner h of the i-th listed face is corner face_begin(i) + (h - its face_begin) in the
/// piece. origin_face / origin_vertex are taken from the source's (empty source vectors mean
/// "the source is the coarse level itself": origins are the source indices).
LocalMesh cut_out(const SubdivLevel& level, const std::vector<Point3>& x, const std::vector<int>& faces,
                  const std::vector<int>& origin_face = {}, const std::vector<int>& origin_vertex = {});
LocalMesh cut_out(const LocalMesh& piece, const std::vector<int>& faces);

/// One uniform Catmull-Clark step of the whole piece (its child faces are numbered by parent
/// corner, refiner.h), with origins carried to the children.
LocalMesh refine_piece(const LocalMesh& piece);

/// The exact limit position of vertex v of (level, x): its star is cut out with v's own tags
/// only (nothing else of the star can change v's limit) and the closed-form limit masks are
/// applied. Requires that no edge at v and v itself is semi-sharp.
Point3 vertex_limit(const SubdivLevel& level, const std::vector<Point3>& x, int v);

}  // namespace subd2nurbs
