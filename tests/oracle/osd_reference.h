// OpenSubdiv as the independent oracle: refine a MeshInput with Far::TopologyRefiner and
// PrimvarRefinerReal<double>, and map our vertices and faces onto OpenSubdiv's.
#pragma once

#include <memory>
#include <vector>

#include <opensubdiv/far/topologyRefiner.h>

#include "core/mesh/mesh_input.h"
#include "core/refine/refiner.h"

namespace subd2nurbs::testing {

/// A point for OpenSubdiv's primvar interpolation (Clear / AddWithWeight), in double.
struct Vertex3 {
  double p[3] = {0, 0, 0};
  void Clear(void* = nullptr) { p[0] = p[1] = p[2] = 0; }
  void AddWithWeight(const Vertex3& s, double w) {
    p[0] += w * s.p[0];
    p[1] += w * s.p[1];
    p[2] += w * s.p[2];
  }
};

struct OsdRefinement {
  std::unique_ptr<OpenSubdiv::Far::TopologyRefiner> refiner;
  std::vector<std::vector<Point3>> positions;  ///< per level
  std::vector<Point3> limit;                   ///< limit positions of the last level's vertices
};

/// OpenSubdiv's unrefined TopologyRefiner for `input`: Catmark scheme, the input's boundary
/// rule, crease method and triangle rule, its crease and corner tags (sharpness as float) and
/// holes. nullptr if OpenSubdiv rejects the topology.
std::unique_ptr<OpenSubdiv::Far::TopologyRefiner> osd_create_refiner(const MeshInput& input);

/// Refines with OpenSubdiv; nullptr refiner if OpenSubdiv rejects the topology.
OsdRefinement osd_refine(const MeshInput& input, int levels, bool with_limit = false);

/// For each level, our vertex index -> OpenSubdiv's vertex index, following the origins of
/// child vertices (vertex, face, edge) level by level. Also maps faces.
struct OsdMapping {
  std::vector<std::vector<int>> vertex;  ///< [level][ours] = theirs
  std::vector<std::vector<int>> face;    ///< [level][ours] = theirs
};
OsdMapping map_to_osd(const Refinement& ours, const OpenSubdiv::Far::TopologyRefiner& theirs);

/// Length of the diagonal of the points' axis-aligned bounding box (the scale of tolerances).
double bbox_diagonal(const std::vector<Point3>& points);

}  // namespace subd2nurbs::testing

namespace subd2nurbs::testing {

/// Everything one comparison of our refinement with OpenSubdiv's measures.
struct OsdComparison {
  bool osd_accepted = false;
  int levels = 0;
  double max_relative_error = 0;  ///< max over levels and vertices of |ours - theirs| / diagonal
  int unmapped = 0;               ///< our vertices or faces with no OpenSubdiv counterpart
  int count_mismatches = 0;       ///< levels whose vertex or face counts differ
  int face_mismatches = 0;        ///< faces whose mapped vertex cycle differs
  int sharpness_mismatches = 0;   ///< edges or vertices whose sharpness differs (float-exact)
  int hole_mismatches = 0;        ///< faces whose hole flag differs
  std::string first_problem;
};

/// Refines `input` to `levels` with both implementations and compares positions,
/// topology (through the explicit origin mapping), sharpness and holes.
OsdComparison compare_with_osd(const MeshInput& input, int levels);

}  // namespace subd2nurbs::testing

namespace subd2nurbs::testing {
/// Max distance (relative to the diagonal) between our limit positions of the base vertices
/// and OpenSubdiv's Limit() at a level deep enough that every semi-sharp feature has decayed
/// and every face is a quad (so its limit masks are exact there).
/// Vertices where OpenSubdiv's Limit() is itself approximate (darts: smooth mask; smooth
/// valence 2: the vertex itself) are reported separately in `special`, -1 if there are none.
/// `extra_levels` refines further before asking OpenSubdiv (its approximation at special
/// vertices converges to the exact limit as the level grows).
struct LimitErrors {
  double regular = -1;
  double special = -1;
};
LimitErrors limit_error_vs_osd(const MeshInput& input, int extra_levels = 0);
}  // namespace subd2nurbs::testing
